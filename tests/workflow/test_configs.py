"""Every config composes (as lightning-hydra-template's smoke tests), and the objects it describes build."""
from __future__ import annotations

from pathlib import Path

import pytest
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg, solver_from_cfg
from fluidfilm.data import DatasetSpec
from fluidfilm.rotor.cases import rotor_for_case

CONF = Path(__file__).resolve().parents[2] / "conf"
PRIMARY = sorted(p.stem for p in CONF.glob("*.yaml"))
# which primary config composes each group, and under which key it lands
GROUPS = {
    "bearing": ("fig2_grid", "bearing"), "solver": ("grid_sweep", "solver"), "reference": ("make_dataset", "reference"),
    "tracking": ("train_surrogate", "tracking"), "dataset": ("make_dataset", "dataset"), "dask": ("make_dataset", "dask"),
    "model": ("train_surrogate", "model"), "split": ("train_surrogate", "split"), "scaling": ("train_surrogate", "scaling"),
    "trainer": ("train_surrogate", "trainer"), "experiment": ("train_surrogate", None), "rotor": ("trajectories", "rotor"),
    "integrator": ("trajectories", "integrator"), "case": ("trajectories", "cases.a"),
    "metrics": ("compare", "metrics"), "controller": ("train_controller", "controller"), "protocol": ("train_surrogate", "protocol"),
    "characteristics": ("characteristics", "characteristics"), "runup": ("runup", "runup"),
    "cavitation_rules": ("cavitation_rules", "cavitation_rules"),
    "jfo_surrogate": ("jfo_surrogate", "jfo_surrogate"),
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
        cmd = stage["do"]["cmd"] if "foreach" in stage else stage["cmd"]  # a foreach stage: one command per item
        assert cmd.startswith("${python} experiments/"), name
        assert cmd.endswith("${args.%s}" % name), name


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
    from fluidfilm.workflow.config_check import compare

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


def _schema_fields(schema, prefix=""):
    from dataclasses import fields, is_dataclass

    from fluidfilm.workflow.config_schema import _BY_NAME

    for f in fields(schema):
        sub = _BY_NAME.get(f.type) if isinstance(f.type, str) else (f.type if is_dataclass(f.type) else None)
        if sub is not None and f.type not in ("PositionSection", "VelocitySection"):
            yield from _schema_fields(sub, f"{prefix}{f.name}.")
        else:
            yield f"{prefix}{f.name}"


@pytest.mark.parametrize("group, option", list(_options()))
def test_every_option_validates_against_its_group_schema(group, option):
    """Composed as the entry points compose it, each option fits its schema (types, no unknown key,
    no required key left out); ``experiment`` has none (its values land in the other groups)."""
    from fluidfilm.workflow.config_schema import validate_group

    primary, key = GROUPS[group]
    package = "" if key in (None, group) else f"@{key}"
    cfg = _compose(primary, [f"{group}{package}={option}"])
    if key is None:
        assert validate_group(group, {}) is None
        return
    typed = validate_group(group, OmegaConf.to_container(OmegaConf.select(cfg, key), resolve=False), key)
    assert typed is not None
    # the typed config holds the YAML's values (the schema adds none: it has no defaults)
    plain = OmegaConf.to_container(OmegaConf.select(cfg, key), resolve=True)
    assert _given(OmegaConf.to_container(typed)) == plain


def _given(node):
    """``node`` without the fields an option leaves out (``???``)."""
    if isinstance(node, dict):
        return {k: _given(v) for k, v in node.items() if v != "???"}
    if isinstance(node, list):
        return [_given(v) for v in node]
    return node


def test_every_schema_field_is_used_by_some_option():
    """No field in a schema that no YAML file has: the schema describes conf/, nothing else."""
    from fluidfilm.workflow.config_schema import GROUPS as SCHEMAS

    for group, entry in SCHEMAS.items():
        schemas = [entry] if isinstance(entry, type) else list(entry[1].values())
        seen = set()
        for option in sorted(p.stem for p in (CONF / group).glob("*.yaml")):
            primary, key = GROUPS[group]
            package = "" if key == group else f"@{key}"
            node = OmegaConf.to_container(OmegaConf.select(_compose(primary, [f"{group}{package}={option}"]), key))

            def walk(d, prefix=""):
                for k, v in d.items():
                    if isinstance(v, dict):
                        yield from walk(v, f"{prefix}{k}.")
                    else:
                        yield f"{prefix}{k}"
            seen |= set(walk(node))
        for schema in schemas:
            unused = set(_schema_fields(schema)) - seen
            assert not unused, f"{group}: {schema.__name__} declares {sorted(unused)}, which no option has"


@pytest.mark.parametrize("override, named", [
    ("trainer.max_epochs=ten", "'trainer.max_epochs'"),
    ("+model.widht=10", "'model.widht'"),
    ("trainer.batch_size=1.5", "'trainer.batch_size'"),
    ("+trainer.lr=0.1", "'trainer.lr'"),
    ("protocol=adam", None),
    ("+protocol.min_grad=1e-7", "'protocol.min_grad'"),   # a key of the other protocol's schema
    ("split.boundaries=[0.5,x]", "'split.boundaries"),
])
def test_schema_refuses_a_mistyped_value_or_unknown_key_naming_it(override, named):
    from fluidfilm.workflow.config_check import schema_problems

    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        cfg = compose(config_name="train_surrogate", overrides=["protocol=adam", override], return_hydra_config=True)
        choices = dict(cfg.hydra.runtime.choices)  # what HydraConfig.get() gives a running job
    problems = schema_problems(cfg, choices)
    if named is None:
        assert problems == []
    else:
        assert len(problems) == 1 and named in problems[0], problems


def test_bearing_schema_is_the_library_dataclass():
    """The bearing group's fields are written once, in core/bearing.py: the schema has exactly the
    dataclass's fields with its types, plus the config's own ``name`` and ``kind``."""
    from dataclasses import fields
    from typing import get_type_hints

    from fluidfilm.core.bearing import ConicalBearing, JournalBearing
    from fluidfilm.workflow.config_schema import ConicalBearingSchema, JournalBearingSchema

    for schema, cls in ((JournalBearingSchema, JournalBearing), (ConicalBearingSchema, ConicalBearing)):
        got = {f.name: f.type for f in fields(schema)}
        assert got == {"name": str, "kind": str, **get_type_hints(cls)}


@pytest.mark.parametrize("override, named", [
    ("bearing.clearance=0.016", "c/R < 0.1"),            # 0.8 R: the dataclass's own check, before any work
    ("bearing.viscosity=-1.0", "viscosity must be a positive finite number, got -1.0"),
    ("bearing.clearance=abc", "'bearing.clearance'"),     # the type, by OmegaConf
])
def test_bearing_config_gets_the_dataclass_validation(override, named):
    from fluidfilm.workflow.config_schema import SchemaError, validate_group

    cfg = _compose("fig2_grid", [override])
    with pytest.raises(SchemaError, match=named):
        validate_group("bearing", OmegaConf.to_container(cfg.bearing, resolve=False))


def _makefile_study_commands():
    """Each Makefile recipe line that runs ``experiments/<study>.py``: (target, study, overrides), the lines
    joined at their backslashes; overrides naming a make variable (``$(CURVE_BUDGET_S)``) are left out."""
    import re
    import shlex

    text = (CONF.parent / "Makefile").read_text().replace("\\\n", " ")
    target, out = None, []
    for line in text.splitlines():
        m = re.match(r"^([a-z][a-z0-9-]*):", line)
        if m:
            target = m.group(1)
        if line.startswith("\t") and "experiments/" in line:
            words = shlex.split(line.strip())
            i = next(k for k, w in enumerate(words) if w.startswith("experiments/"))
            out.append((target, Path(words[i]).stem, [w for w in words[i + 1:] if "$(" not in w]))
    return out


@pytest.mark.parametrize("target,study,overrides", _makefile_study_commands(),
                         ids=lambda v: v if isinstance(v, str) else None)
def test_every_makefile_study_command_composes(target, study, overrides):
    """The long variants outside the pipeline (make universal-train, jfo-surrogate-seeds, train-time-ranking,
    paper-scale-ablation, ...) run the entry points with overrides no stage runs: each key exists, and the
    study's own check accepts the composed config."""
    import importlib

    cfg = _compose(study, overrides)
    mod = importlib.import_module(f"fluidfilm.studies.{study}" if study != "universal" else "fluidfilm.studies.universal_study")
    if hasattr(mod, "check"):
        mod.check(cfg)


def test_the_makefile_runs_every_long_variant():
    targets = {t for t, _, _ in _makefile_study_commands()}
    assert {"universal-train", "jfo-surrogate-seeds", "train-time-ranking", "paper-scale-ablation"} <= targets


def _dvc_outs() -> list[Path]:
    import yaml

    stages = yaml.safe_load((CONF.parent / "dvc.yaml").read_text())["stages"]
    outs = []
    for st in stages.values():
        for o in (st.get("do") or st).get("outs") or []:
            name = o if isinstance(o, str) else next(iter(o))
            if "${" not in name:
                outs.append(Path(name))
    return outs


@pytest.mark.parametrize("target,study,overrides", _makefile_study_commands(),
                         ids=lambda v: v if isinstance(v, str) else None)
def test_no_makefile_study_command_writes_into_a_stage_output(target, study, overrides):
    """A variant outside the pipeline must not write into a DVC stage's output: paper-scale-ablation once kept
    its finished models in paper_scale's persistent cache/paper_scale, and `dvc repro` then reran that stage."""
    import importlib

    cfg = _compose(study, overrides)
    mod = importlib.import_module(f"fluidfilm.studies.{study}" if study != "universal" else "fluidfilm.studies.universal_study")
    written = mod.outputs(cfg) if hasattr(mod, "outputs") else getattr(mod, "OUTPUTS", {})
    outs = _dvc_outs()
    for key in {*written, "cache_dir"}:   # what the study says it writes, and its resume cache
        value = cfg.get(key)
        if value:
            p = Path(str(value))
            assert not any(p == o or o in p.parents for o in outs), f"make {target}: {key}={value} is a stage's output"
