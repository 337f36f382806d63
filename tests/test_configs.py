"""Every config composes (as lightning-hydra-template's smoke tests), and the objects it describes build."""
from __future__ import annotations

from pathlib import Path

import pytest
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

from fluidfilm.config import bearing_from_cfg, reference_from_cfg, solver_from_cfg
from fluidfilm.data import DatasetSpec
from fluidfilm.rotor.cases import rotor_for_case

CONF = Path(__file__).resolve().parents[1] / "conf"
PRIMARY = sorted(p.stem for p in CONF.glob("*.yaml"))
# which primary config composes each group, and under which key it lands
GROUPS = {
    "bearing": ("fig2", "bearing"), "solver": ("grid_sweep", "solver"), "reference": ("make_dataset", "reference"),
    "tracking": ("train", "tracking"), "dataset": ("make_dataset", "dataset"), "dask": ("make_dataset", "dask"),
    "model": ("train", "model"), "split": ("train", "split"), "scaling": ("train", "scaling"),
    "trainer": ("train", "trainer"), "experiment": ("train", None), "rotor": ("trajectories", "rotor"),
    "integrator": ("trajectories", "integrator"), "case": ("trajectories", "cases.a"),
    "metrics": ("compare", "metrics"), "controller": ("control", "controller"), "protocol": ("train", "protocol"),
    "characteristics": ("characteristics", "characteristics"),
}


def _compose(name, overrides=()):
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        return compose(config_name=name, overrides=list(overrides))


@pytest.mark.parametrize("name", PRIMARY)
def test_primary_config_composes_and_resolves(name):
    cfg = _compose(name)
    OmegaConf.to_container(cfg, resolve=True)
    if "bearing" in cfg:
        bearing = bearing_from_cfg(cfg.bearing)
        if "reference" in cfg:
            reference_from_cfg(bearing, cfg.reference)
        for key in ("solver", "coarse", "dense", "converged"):
            if key in cfg:
                solver_from_cfg(bearing, cfg[key])
    if "dataset" in cfg:
        DatasetSpec.from_cfg(cfg.dataset)
    if "cases" in cfg and "rotor" in cfg:
        for case in cfg.cases.values():
            rotor_for_case(cfg.rotor, case)
    if "controller" in cfg:
        _controller_objects(cfg)


def _controller_objects(cfg):
    from fluidfilm.control import RewardWeights
    from fluidfilm.control.build import scenario_from_cfg

    scenario_from_cfg(cfg.controller.scenario)
    RewardWeights(**cfg.controller.reward)
    bearing = bearing_from_cfg(cfg.bearing)
    for s in cfg.controller.sleeve_positions:
        bearing.clearance_at(s)


def _options():
    # conf/pipeline holds DVC's pipeline profiles (dvc.yaml `vars`), not a Hydra group
    for group in sorted(p.name for p in CONF.iterdir() if p.is_dir() and p.name not in ("hydra", "pipeline")):
        for option in sorted(p.stem for p in (CONF / group).glob("*.yaml")):
            yield group, option


def test_every_group_is_covered():
    groups = {g for g, _ in _options()}
    assert groups <= set(GROUPS), f"add {groups - set(GROUPS)} to GROUPS"


@pytest.mark.parametrize("group, option", list(_options()))
def test_every_option_composes(group, option):
    primary, key = GROUPS[group]
    if primary not in PRIMARY:
        pytest.fail(f"primary config {primary}.yaml is missing")
    package = "" if key in (None, group) else f"@{key}"
    cfg = _compose(primary, [f"{group}{package}={option}"])
    OmegaConf.to_container(cfg, resolve=True)
    if group == "dataset":
        DatasetSpec.from_cfg(cfg.dataset)
    if group == "bearing":
        bearing_from_cfg(cfg.bearing)
    if group == "controller":
        _controller_objects(cfg)


@pytest.mark.parametrize("profile", sorted(p.stem for p in (CONF / "pipeline").glob("*.yaml")))
def test_pipeline_profile_names_every_stage(profile):
    """Each pipeline profile gives overrides for exactly the stages of dvc.yaml, and the workspace interpreter."""
    import yaml

    prof = yaml.safe_load((CONF / "pipeline" / f"{profile}.yaml").read_text())
    stages = yaml.safe_load((CONF.parent / "dvc.yaml").read_text())["stages"]
    assert prof["python"] == ".venv/bin/python"
    assert prof["profile"] == profile
    assert set(prof["args"]) == set(stages)
    for name, stage in stages.items():
        assert stage["cmd"].startswith("${python} experiments/"), name
        assert stage["cmd"].endswith("${args.%s}" % name), name


def _plain_values(d: dict) -> dict:
    """The file's own values: no Hydra directives, no interpolations."""
    return {k: v for k, v in d.items() if k != "defaults" and not (isinstance(v, str) and "${" in v)}


@pytest.mark.parametrize("group, option", list(_options()))
def test_every_option_lands_with_its_values_under_its_key(group, option):
    """The composed config holds what the option's YAML file says (read here with plain yaml, not Hydra)."""
    import yaml

    path = CONF / group / f"{option}.yaml"
    text = path.read_text()
    primary, key = GROUPS[group]
    if key is None or "@package" in text:
        pytest.skip("a global package: it spreads over the primary config")
    own = _plain_values(yaml.safe_load(text) or {})
    assert own, f"{path} holds no values"
    package = "" if key == group else f"@{key}"
    composed = OmegaConf.to_container(OmegaConf.select(_compose(primary, [f"{group}{package}={option}"]), key),
                                      resolve=True)
    _assert_holds(composed, own, f"{group}={option}: {key}")


def _assert_holds(composed, own, where):
    """Every value of ``own`` is in ``composed`` (nested mappings may carry more keys from their defaults)."""
    for k, v in own.items():
        if isinstance(v, dict):
            _assert_holds(composed[k], _plain_values(v), f"{where}.{k}")
        else:
            assert composed[k] == v, f"{where}.{k} is {composed[k]!r}, the file says {v!r}"


def test_config_check_names_unknown_keys_and_wrong_types():
    from fluidfilm.config_check import compare

    ref = {"trainer": {"max_epochs": 12, "lr": 1e-3, "max_time": None, "deterministic": True},
           "seeds": [0, 1], "name": "x"}
    assert compare({"trainer": {"max_epochs": 30, "lr": 1, "max_time": "00:01:00", "deterministic": False},
                    "seeds": [3], "name": "y"}, ref) == []          # int for a float, anything for null
    problems = compare({"trainer": {"max_epochs": "ten", "widht": 3, "deterministic": 1}, "seeds": 5}, ref)
    text = " ".join(problems)
    assert "trainer.max_epochs" in text and "expected int" in text
    assert "unknown key 'trainer.widht'" in text
    assert "trainer.deterministic" in text and "expected bool" in text     # 1 is not a bool
    assert "seeds=5" in text and "expected list" in text
    assert compare({"name": "${other}"}, {"name": 3}) == []                # interpolations resolve later
