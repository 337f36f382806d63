"""The grading study's pieces against independent truth.

- a grading puts its values into every section, and the sample count follows the layout's formula
  (positions x (2 n_per_side + 1)^2 with V = 0 on the grid);
- a repeated grading is served from the cache, byte for byte the same, and any change of the layout or
  of the solver's source makes a new dataset; a damaged cached part is recomputed, not trained on;
- the reference judged on its own orbits has zero force error and passes every case; a surrogate that
  is the reference times 1.1 has exactly 10 % error;
- a sweep's summary holds that sweep's jobs only, ordered by size.
"""
from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from fluidfilm import GradedReynoldsModel, paper_bearing
from fluidfilm.studies import grading_study as grading
from fluidfilm.data import DatasetConfigError, DatasetSpec
from fluidfilm.rotor.cases import run_case

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = {"coarse": [30, 30], "dense": [55, 55], "eps_threshold": 0.9, "cavitation": "gumbel"}


def _orbit_cfg():
    return yaml.safe_load((ROOT / "conf" / "dataset" / "orbit.yaml").read_text())


def _tiny_cfg():
    return {"name": "tiny",
            "position_sections": [{"name": "low", "eps_start": 0.0, "eps_stop": 0.5, "endpoint": False, "n_eps": 2,
                                   "n_angle": 4},
                                  {"name": "high", "eps_start": 0.5, "eps_stop": 0.8, "endpoint": True, "n_eps": 2,
                                   "n_angle": 4}],
            "velocity_sections": [{"eps_low": 0.0, "eps_high": 1.0, "v_max": 0.1, "core": 0.03, "core_fraction": 0.5,
                                   "n_per_side": 2, "include_zero": True}],
            "combine": "product", "positions_per_chunk": 4, "n_test": 0, "test_seed": 1}


def test_a_grading_reaches_every_section_and_the_sample_count_follows_the_layout():
    base = _orbit_cfg()
    cfg = grading.apply_grading(base, {"n_per_side": 8, "n_angle": 24, "core_fraction": 0.5, "v_max": 0.08,
                                       "core": 0.02, "eps_density": 0.5, "eps_split": 0.85})
    assert base == _orbit_cfg()  # the input config is not touched
    assert all(s["n_per_side"] == 8 and s["core_fraction"] == 0.5 and s["v_max"] == 0.08 and s["core"] == 0.02
               for s in cfg["velocity_sections"])
    assert [s["n_angle"] for s in cfg["position_sections"]] == [24, 24]
    assert [s["n_eps"] for s in cfg["position_sections"]] == [9, 3]  # 18 and 6 halved
    assert cfg["position_sections"][0]["eps_stop"] == cfg["position_sections"][1]["eps_start"] == 0.85
    spec = DatasetSpec.from_cfg(cfg)
    c = paper_bearing().clearance
    # positions: 9 rows x 24 angles in the first section less the 23 repeats of the centre, 3 x 24 in the second
    n_pos = 9 * 24 - 23 + 3 * 24
    assert spec.n_samples(c) == n_pos * (2 * 8 + 1) ** 2
    values = spec.velocity_sections[0].values()
    assert len(values) == 17 and values.max() == pytest.approx(0.08) and np.count_nonzero(np.abs(values) <= 0.02) == 9
    # None keeps the config's values
    assert grading.apply_grading(base, {k: None for k in grading.GRADING_KEYS}) == base


@pytest.mark.parametrize("grading_cfg, named", [
    ({"n_per_sid": 8}, "grading.n_per_sid"),
    ({"eps_density": 0}, "grading.eps_density=0"),
    ({"eps_split": 0.99}, "grading.eps_split=0.99"),
    ({"v_max": "fast"}, "grading.v_max='fast'"),
    ({"core": 0.5}, "core=0.5"),                      # beyond v_max = 0.1: the spec names it
    ({"n_per_side": 2.5}, "n_per_side=2.5"),
])
def test_a_bad_grading_is_refused_naming_the_value(grading_cfg, named):
    with pytest.raises(DatasetConfigError, match=named.replace("(", r"\(").replace(")", r"\)")):
        grading.apply_grading(_orbit_cfg(), grading_cfg)


def test_a_repeated_grading_is_reused_and_a_changed_one_or_changed_solver_is_not(tmp_path, monkeypatch):
    jb = paper_bearing()
    spec = DatasetSpec.from_cfg(_tiny_cfg())
    path, meta, reused = grading.cached_dataset(jb, REFERENCE, spec, tmp_path, scheduler="inline", progress=False)
    assert not reused and meta["n_samples"] == spec.n_samples(jb.clearance)
    parts = {p.name: p.read_bytes() for p in path.glob("*.parquet")}
    again, meta2, reused2 = grading.cached_dataset(jb, REFERENCE, spec, tmp_path, scheduler="inline", progress=False)
    assert reused2 and again == path and meta2["generation_seconds_total"] == meta["generation_seconds_total"]
    assert {p.name: p.read_bytes() for p in again.glob("*.parquet")} == parts
    # another layout, another dataset
    other = DatasetSpec.from_cfg(grading.apply_grading(_tiny_cfg(), {"n_per_side": 3}))
    p3, _, r3 = grading.cached_dataset(jb, REFERENCE, other, tmp_path, scheduler="inline", progress=False)
    assert not r3 and p3 != path
    # the same layout computed by other solver source: not the old forces
    monkeypatch.setattr(grading, "source_digest", lambda: "0123456789abcdef")
    p4, _, r4 = grading.cached_dataset(jb, REFERENCE, spec, tmp_path, scheduler="inline", progress=False)
    assert not r4 and p4 not in (path, p3)


def test_a_damaged_cached_dataset_is_recomputed_before_use(tmp_path):
    jb = paper_bearing()
    spec = DatasetSpec.from_cfg(_tiny_cfg())
    path, _, _ = grading.cached_dataset(jb, REFERENCE, spec, tmp_path, scheduler="inline", progress=False)
    part = sorted(path.glob("*.parquet"))[0]
    good = part.read_bytes()
    part.write_bytes(good[:-20] + b"\0" * 20)
    again, _, reused = grading.cached_dataset(jb, REFERENCE, spec, tmp_path, scheduler="inline", progress=False)
    assert not reused and again == path and part.read_bytes() == good


class _Scaled:
    """The reference model's forces times a factor (a surrogate with a known error)."""

    def __init__(self, model, factor):
        self.model, self.factor = model, factor
        self.bearing = model.bearing

    def forces(self, x, v):
        return self.factor * np.asarray(self.model.forces(x, v))


@pytest.fixture(scope="module")
def short_orbits(tmp_path_factory):
    """Two Fig. 4 cases run briefly with the reference model, saved as the reference trajectories."""
    from hydra import compose, initialize_config_dir

    with initialize_config_dir(str(ROOT / "conf"), version_base="1.3"):
        cfg = compose("grading_study", overrides=["integrator.t_end=0.02", "integrator.t_settle=0.01"])
    ref = GradedReynoldsModel(paper_bearing())
    out = tmp_path_factory.mktemp("orbits")
    cases = {k: cfg.cases[k] for k in ("a", "e")}
    for name, case in cases.items():
        run_case(ref, cfg.rotor, case, cfg.integrator).to_npz(out / f"{name}.npz")
    return ref, out, cfg, cases


def test_the_reference_judged_on_its_own_orbits_is_exact_and_a_scaled_one_is_off_by_the_scale(short_orbits):
    ref, out, cfg, cases = short_orbits
    bench = grading.OrbitBenchmark.from_dir(ref, out, cases)
    assert len(bench.x) == sum(len(t.t) for t in bench.trajectories.values())
    assert grading.OrbitBenchmark.from_dir(ref, out, cases).force_errors(ref, 0.1)["p99"] == 0.0
    err = bench.force_errors(_Scaled(ref, 1.1), 1e-9)
    assert err["median"] == pytest.approx(0.1, rel=1e-9) and err["max"] == pytest.approx(0.1, rel=1e-9)
    v = bench.verdicts(ref, cfg.rotor, cases, cfg.integrator, 2.0)
    assert v["satisfactory_cases"] == "ae" and v["orbit_rms_pct_max"] == 0.0
    # other integrator settings than the reference run's are refused, not compared sample by sample
    longer = copy.deepcopy(cfg.integrator)
    longer.t_end = 0.03
    with pytest.raises(ValueError, match="other integrator settings"):
        bench.verdicts(ref, cfg.rotor, cases, longer, 2.0)


def test_a_missing_reference_orbit_is_named(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"a\.npz"):
        grading.OrbitBenchmark.from_dir(GradedReynoldsModel(paper_bearing()), tmp_path, ["a"])


def _result(job, n, p99, sweep_id):
    return {"job": job, "swept": {"grading.n_per_side": str(n)}, "sweep_id": sweep_id,
            "dataset": {"n_samples": n * 1000, "generation_s": n / 10},
            "training": {"train_time_s": 1.0}, "time_per_eval_us": 0.5,
            "held_out": {"median": 0.01, "p99": p99, "max": 1.0},
            "orbit_states": {"median": 0.02, "p99": 2 * p99, "max": 1.0},
            "cases": {"satisfactory_cases": "ab", "n_satisfactory": 2, "orbit_rms_pct_max": 3.0}}


def test_a_sweeps_summary_holds_its_own_jobs_in_size_order(tmp_path):
    for k, (n, p99, sid) in enumerate([(24, 0.05, "this"), (8, 0.3, "this"), (16, 0.1, "this"), (32, 0.01, "old")]):
        (tmp_path / str(k)).mkdir()
        (tmp_path / str(k) / "result.json").write_text(json.dumps(_result(f"n={n}", n, p99, sid)))
    results = grading.read_results(tmp_path, "this")
    summary = grading.write_summary(results, tmp_path / "summary", "test")
    assert [j["job"] for j in summary["jobs"]] == ["n=8", "n=16", "n=24"]  # the old sweep's job is left out
    assert summary["lowest_orbit_p99_job"] == "n=24" and summary["lowest_orbit_p99"] == pytest.approx(0.1)
    assert {p.name for p in (tmp_path / "summary").iterdir()} == {"summary.json", "table.csv", "figure.png"}
    with pytest.raises(ValueError, match="no finished jobs"):
        grading.summarise([])


def test_the_reference_has_no_stiffness_error_against_itself_and_a_coarser_grid_a_small_one():
    from fluidfilm import ReynoldsSolver

    jb = paper_bearing()
    bench = grading.StiffnessBenchmark.from_reference(ReynoldsSolver(jb, 30, 30), [0.3, 0.7])
    assert len(bench.table) == 2 and np.allclose(bench.table.eps, [0.3, 0.7], atol=2e-3)  # its equilibria (grid: symmetry to 1e-3)
    same = bench.errors(ReynoldsSolver(jb, 30, 30))
    assert same["direct_max"] == 0.0 and same["cross_max"] == 0.0 and same["status"] == "ok"
    coarse = bench.errors(ReynoldsSolver(jb, 20, 20))  # a second discretisation: close, not equal
    assert 0.0 < coarse["direct_max"] < 0.2 and 0.0 < coarse["cross_max"] < 0.3


def test_a_force_with_a_kink_at_rest_gets_the_symmetric_derivative_and_an_undefined_one_is_said(monkeypatch):
    """physics_v divides the force by (1 + |V|/(c omega)): |V| has a kink at V = 0. The exact Jacobian there is the
    symmetric derivative, which central differences converge to (the reference's K and C are central
    differences); where coefficients are not finite all the same, the study says "not differentiable"."""
    import sys

    from fluidfilm import ReynoldsSolver
    from fluidfilm.studies import characteristics_study as study
    from fluidfilm.surrogate.jacobian import surrogate_jacobian
    from fluidfilm.surrogate import SurrogateForceModel

    sys.path.insert(0, str(ROOT / "tests"))
    from golden_models import _net, _scaling

    jb = paper_bearing()
    rng = np.random.default_rng(5)
    model = SurrogateForceModel(jb, [_net(rng, 3, 8, 2)], [_scaling(rng, "physics_v", jb.clearance, jb.omega, "polar")],
                                "tanh")
    x0 = np.array([0.0, 0.4 * jb.clearance])
    _, J = surrogate_jacobian(model, x0, np.zeros(2))
    h = np.array([1e-7 * jb.clearance] * 2 + [1e-7 * jb.clearance * jb.omega] * 2)
    fd = np.empty((2, 4))
    for k in range(4):
        e = np.zeros(4)
        e[k] = h[k]
        plus = model.forces((x0 + e[:2])[None], e[None, 2:])[0]
        minus = model.forces((x0 - e[:2])[None], -e[None, 2:])[0]
        fd[:, k] = (plus - minus) / (2 * h[k])
    np.testing.assert_allclose(J, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())
    bench = grading.StiffnessBenchmark.from_reference(ReynoldsSolver(jb, 30, 30), [0.4])
    row = bench.table.assign(model="model")
    for k in ("Cxx", "Cyy"):
        row[k] = np.nan  # a model whose coefficients are not finite at its equilibrium
    monkeypatch.setattr(study, "coefficient_table", lambda models, loads, h: row)
    out = bench.errors(model)
    assert out["status"] == "not differentiable" and out["direct_max"] is None


def test_the_judges_find_no_error_in_the_reference_itself(short_orbits):
    import pandas as pd

    ref, out, cfg, cases = short_orbits
    rng = np.random.default_rng(2)
    c = ref.bearing.clearance
    X = c * rng.uniform(-0.6, 0.6, (50, 2))
    V = rng.uniform(-0.05, 0.05, (50, 2))
    F = np.asarray(ref.forces(X, V))
    held = pd.DataFrame({"X1": X[:, 0], "X2": X[:, 1], "V1": V[:, 0], "V2": V[:, 1], "F1": F[:, 0], "F2": F[:, 1]})
    judges = grading.Judges(held, grading.OrbitBenchmark.from_dir(ref, out, cases), None, cfg.rotor, cases,
                            cfg.integrator, 2.0, 0.1)
    got = judges.judge(ref)
    assert got["held_out"]["max"] == 0.0 and got["orbit_states"]["max"] == 0.0
    assert got["cases"]["satisfactory_cases"] == "ae" and got["stiffness"] is None and got["time_per_eval_us"] > 0
    from fluidfilm import ReynoldsSolver

    coarse = judges.judge(ReynoldsSolver(ref.bearing, 12, 12))  # another discretisation: close, not equal
    assert 0.0 < coarse["held_out"]["median"] < 0.2 and 0.0 < coarse["orbit_states"]["median"] < 0.2


def test_non_finite_forces_are_refused_not_tabulated():
    rel = grading.relative_errors(np.array([[1.0, 0.0], [np.nan, 0.0], [2.0, 0.0]]), np.ones((3, 2)), 0.1)
    with pytest.raises(ValueError, match="non-finite forces at 1 of 3 states"):
        grading.error_quantiles(rel, "net")
    assert grading.error_quantiles(rel[[0, 2]])["max"] == pytest.approx(np.hypot(1.0, 1.0) / np.sqrt(2))


def test_parallel_jobs_wanting_one_grading_make_it_once(tmp_path):
    """Two processes ask for the same grading at once: one generates, the other waits and reuses it."""
    import subprocess
    import sys

    here = str(Path(__file__).resolve().parent)  # this module, imported by the children
    code = ("import json, sys; sys.path.insert(0, %r)\n"
            "from fluidfilm import paper_bearing\n"
            "from fluidfilm.studies import grading_study as grading\n"
            "from fluidfilm.data import DatasetSpec\n"
            "import test_grading as t\n"
            "p, m, reused = grading.cached_dataset(paper_bearing(), t.REFERENCE, DatasetSpec.from_cfg(t._tiny_cfg()), %r,"
            " scheduler='inline', progress=False)\n"
            "print(json.dumps({'reused': reused, 'path': str(p)}))" % (here, str(tmp_path)))
    procs = [subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True) for _ in range(2)]
    outs = [json.loads(p.communicate(timeout=300)[0].strip().splitlines()[-1]) for p in procs]
    assert sorted(o["reused"] for o in outs) == [False, True] and outs[0]["path"] == outs[1]["path"]
