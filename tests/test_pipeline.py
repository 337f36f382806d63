"""The user's route, end to end: ``make reproduce PROFILE=quick`` from a shell where no environment is active.

This is the same ``dvc.yaml`` as the full reproduction (every stage, the same commands), run by
``make`` on the small profile (``conf/pipeline/quick.yaml``) in a scratch copy of the workspace.
The environment handed to ``make`` has no virtual environment on PATH and no VIRTUAL_ENV, so a
stage that relied on the caller's ``python`` would fail here exactly as it fails for a user.
The review notebook then runs on the pipeline's outputs.
"""
from __future__ import annotations

import json
import re
import os
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest
import yaml
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parents[1]


def clean_env() -> dict:
    """The caller's environment with every trace of an activated virtual environment removed."""
    venv_bin = str(Path(sys.executable).parent)
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONHOME", "CONDA_PREFIX")}
    env["PATH"] = os.pathsep.join(p for p in os.environ.get("PATH", "").split(os.pathsep)
                                  if p and Path(p).resolve() != Path(venv_bin).resolve()) or "/usr/bin:/bin"
    return env


@pytest.fixture(scope="module")
def quick_reproduce(tmp_path_factory):
    workdir = tmp_path_factory.mktemp("reproduce") / "quick"
    env = clean_env()
    proc = subprocess.run(["make", "reproduce", "PROFILE=quick", f"QUICK_DIR={workdir}"], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=1800)
    assert proc.returncode == 0, f"make reproduce PROFILE=quick failed:\n{proc.stdout[-6000:]}\n{proc.stderr[-4000:]}"
    return workdir, proc.stdout


def test_every_stage_of_the_pipeline_ran_with_the_workspace_interpreter(quick_reproduce):
    workdir, out = quick_reproduce
    stages = [f"{name}@{item}" for name, st in yaml.safe_load((ROOT / "dvc.yaml").read_text())["stages"].items()
              for item in st.get("foreach", [None])]
    stages = [s.removesuffix("@None") for s in stages]  # DVC names a foreach stage's items name@item
    for name in stages:
        assert f"Running stage '{name}'" in out, f"stage {name} did not run"
    lock = yaml.safe_load((workdir / "dvc.lock").read_text())["stages"]
    assert set(lock) == set(stages)
    for name, entry in lock.items():
        assert entry["cmd"].startswith(".venv/bin/python "), (name, entry["cmd"])
    timing = json.loads((workdir / "reports" / "reproduce_timing.json").read_text())["quick"]
    assert set(timing["stages"]) == set(stages)
    assert "Results:" in out and "MLflow runs" in out and "fluidfilm.workflow.pipeline serve" in out


def test_pipeline_writes_every_headline_number(quick_reproduce):
    workdir, _ = quick_reproduce
    metrics = json.loads((workdir / "reports" / "metrics.json").read_text())
    for key in ("train_time_single_s", "train_time_split_s", "train_time_reduction_pct", "speedup_trajectory_single",
                "speedup_trajectory_split", "speedup_force_eval"):
        assert isinstance(metrics[key], float), key
    for case in "abcdefg":
        assert f"orbit_rms_pct_single_{case}" in metrics and f"orbit_rms_pct_split_{case}" in metrics
    # the paper's experiment: protocol, CI, seeds, per-band error, paper-like reference
    assert metrics["train_time_protocol"] == "paper" and metrics["train_time_seeds"] == 2
    assert metrics["train_time_samples_per_seed"] == 1500
    assert metrics["train_time_converged"] in (True, False) and metrics["train_time_reduction_ci95"] >= 0
    assert 0 <= metrics["test_rel_err_median_paper_split_eps_below_0.7"] < 100
    for m in ("single", "split"):
        assert metrics[f"speedup_force_{m}_vs_sparse_reference"] > 1
        assert metrics[f"speedup_trajectory_{m}_vs_sparse_reference"] > 1
    md = (workdir / "reports" / "paper_comparison.md").read_text()
    assert "| case | single: paper | single: ours | split: paper | split: ours |" in md
    assert "| training time reduction, split vs single | 26 % |" in md
    assert (workdir / "reports" / "figures" / "fig4_comparison.png").stat().st_size > 10_000
    assert metrics["speedup_trajectory_split"] > 0
    assert isinstance(metrics["controller_amplitude_reduction_pct"], float)
    # conf/dataset/active_quick.yaml: (5 x 12 positions, the 12 at eps = 0 kept once, + 2 x 12) x 3 sleeves x 9 x 9
    assert metrics["active_dataset_samples"] == (5 * 12 - 11 + 2 * 12) * 3 * 9 * 9 == 17_739
    for panel in ("a_dqn", "b_none", "c_mpc"):
        assert (workdir / "reports" / "figures" / f"fig5_{panel}.png").stat().st_size > 10_000
    assert "Active conical bearing" in md
    # the characteristics stage: surrogate K/C and whirl-threshold errors, the nonlinear bracket
    for key in ("kc_max_rel_err_direct_best", "kc_max_rel_err_cross_best", "whirl_threshold_rel_err_best"):
        assert key in metrics
    for key in ("kc_max_rel_err_direct_best_vs_paper_grid", "kc_max_rel_err_cross_reference",
                "whirl_threshold_rel_err_best_vs_paper_grid", "lund_thomsen_kc_max_err_pct"):
        assert key in metrics
    ch = json.loads((workdir / "reports" / "characteristics.json").read_text())
    assert ch["kc_against"]["kc_max_rel_err"] == "reference_converged"
    assert ch["lund_thomsen"]["rows"] == 21 and ch["lund_thomsen"]["rows_two_typings"] == 5
    assert ch["bracket_holds"]
    assert ch["raimondi_boyd"]["S_max_err_pct"] < 2.0
    assert (workdir / "reports" / "figures" / "characteristics_stability_map.png").stat().st_size > 10_000
    assert "Bearing characteristics" in md
    # the ensemble stage: three seeds of best, their ensemble and the hybrids, through the seven cases
    ens = json.loads((workdir / "reports" / "ensemble.json").read_text())
    assert ens["members"] == ["best", "best_s1", "best_s2"] and metrics["best_seeds"] == 3
    assert set(ens["models"]) == {"best", "best_s1", "best_s2", "ensemble", "hybrid_0.01", "hybrid_0.03", "hybrid_0.1",
                                  "hybrid_0.3"}
    for name in ("ensemble", "hybrid_0.01"):
        assert 0.0 <= metrics[f"flagged_share_mean_{name}"] <= 1.0
    assert (workdir / "reports" / "figures" / "ensemble.png").stat().st_size > 10_000
    assert "their ensemble, and the hybrid" in md
    # fast surrogates: per-force cost, batched trajectories, controller training, MPC
    for key in ("force_eval_us_best", "trajectories_per_s_batch_speedup", "controller_training_speedup",
                "controller_decision_ms_mpc", "mpc_amplitude_reduction_pct"):
        assert isinstance(metrics[key], float) and metrics[key] == metrics[key], key
    # the grading study and the ablation: Hydra multiruns whose jobs each made (or reused) a dataset, trained
    # and were judged; the summary holds exactly the sweep's jobs
    for study, jobs in (("grading_study", {"grading.n_per_side=3", "grading.n_per_side=5"}),
                        ("ablation", {"scaling=physics_whirl", "scaling=standard"})):
        summary = json.loads((workdir / "reports" / study / "summary.json").read_text())
        assert {j["job"] for j in summary["jobs"]} == jobs and metrics[f"{study}_jobs"] == 2
        assert all(0 <= j["n_satisfactory"] <= 7 and j["n_samples"] > 0 for j in summary["jobs"])
        assert (workdir / "reports" / study / "figure.png").stat().st_size > 10_000
    # a finished job's training checkpoint is gone (it is there to resume an interrupted job, not to skip a later one)
    assert not list((workdir / "checkpoints" / "grading_study").glob("*"))
    sizes = {j["job"]: j["n_samples"] for j in json.loads((workdir / "reports" / "grading_study" / "summary.json")
                                                           .read_text())["jobs"]}
    # the quick layout's positions times (2 n + 1)^2 velocity pairs (no V = 0 on that grid: (2 n)^2)
    assert sizes["grading.n_per_side=5"] * 6 ** 2 == sizes["grading.n_per_side=3"] * 10 ** 2
    # the error map: every seed, held out and along the orbits; the goals table in the report
    for name in ("best", "best_s1", "best_s2"):
        assert 0 <= metrics[f"orbit_state_rel_err_median_{name}"] <= metrics[f"orbit_state_rel_err_p99_{name}"]
    assert (workdir / "reports" / "figures" / "error_map.png").stat().st_size > 10_000
    from fluidfilm.reporting.report import SURROGATE_GOALS

    n_goals = len(SURROGATE_GOALS)
    assert metrics["surrogate_goals"] == n_goals >= 17 and 0 <= metrics["surrogate_goals_met"] <= n_goals
    # the pipeline's total time: each stage's last full-profile time (the copy's record), and this run's stages
    # recorded as they finished, each with its date
    assert metrics["reproduce_total_min"] > 0 and isinstance(metrics["reproduce_total_min_partial"], bool)
    quick = json.loads((workdir / "reports" / "reproduce_timing.json").read_text())["quick"]
    assert set(quick["stage_runs"]) == set(quick["stages"]) and "report" in quick["stages"]
    assert 0 <= metrics["satisfactory_cases_best_min_over_seeds"] <= 7
    assert "## The best surrogate against its goals" in md


def test_a_second_reproduce_finds_every_stage_up_to_date(quick_reproduce):
    workdir, _ = quick_reproduce
    proc = subprocess.run([str(Path(sys.executable).parent / "dvc"), "status"], cwd=workdir, env=clean_env(),
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "up to date" in proc.stdout, proc.stdout


def test_review_notebook_runs_on_the_quick_profile(quick_reproduce):
    workdir, _ = quick_reproduce
    nb = nbformat.read(ROOT / "notebooks" / "review.ipynb", as_version=4)
    env = {"FLUIDFILM_REPORT_DIR": str(workdir / "reports"), "FLUIDFILM_MLFLOW_URI": f"sqlite:///{workdir / 'mlflow.db'}"}
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        NotebookClient(nb, timeout=300, kernel_name="python3",
                       resources={"metadata": {"path": str(ROOT / "notebooks")}}).execute()
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"]
    assert any("train_time_reduction_pct" in json.dumps(o) for o in outputs)


#: pages whose python blocks run as written in a workspace that `make reproduce` made (docs/api.md loads
#: models/best); docs/adding_a_model.md's example has its own tests (tests/test_docs.py)
EXAMPLE_PAGES = ("README.md", "docs/api.md")


def readme_python_blocks() -> list[str]:
    return [block for page in EXAMPLE_PAGES
            for block in re.findall(r"```python\n(.*?)```", (ROOT / page).read_text(), flags=re.S)]


def test_readme_has_python_examples():
    assert len(readme_python_blocks()) >= 1


@pytest.mark.parametrize("index", range(len(readme_python_blocks())))
def test_readme_python_example_runs_as_written(quick_reproduce, index):
    """Each ```python block of the README runs as written, in a workspace that `make reproduce` made
    (here the quick one: its models/ and data/ stand in for the full ones)."""
    workdir, _ = quick_reproduce
    code = readme_python_blocks()[index]
    proc = subprocess.run([sys.executable, "-c", code], cwd=workdir, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, f"README example {index} failed:\n{code}\n{proc.stderr[-3000:]}"


def test_readme_tables_are_generated_from_the_reports():
    """The README's (and docs/'s) result tables equal what `python -m fluidfilm.reporting.readme` renders from the
    committed reports: no number is copied by hand."""
    from fluidfilm.reporting import readme

    assert readme.pages(ROOT / "README.md")[:2] == [ROOT / "README.md", ROOT / "docs" / "results.md"]
    for path in readme.pages(ROOT / "README.md"):
        text = path.read_text()
        assert readme.fill(text, ROOT / "reports", strict=True) == text, f"{path} is stale: python -m fluidfilm.reporting.readme"
    # the README shows the headline and four generated sentences (the universal model's accuracy, what decides the
    # paper's verdicts, the cavitation rules against the mass-conserving film, the on-line estimator) only; the results page every table of the renderers (bench_* aside)
    readme_blocks = [m["name"] for m in readme.BLOCK.finditer((ROOT / "README.md").read_text())]
    assert readme_blocks == ["commands", "universal_summary", "headline", "paper_scale_mechanism",
                             "cavitation_rules_summary", "online_assessment_summary"]
    results = {m["name"] for m in readme.BLOCK.finditer((ROOT / "docs" / "results.md").read_text())}
    readme_only = {"commands", "universal_summary", "paper_scale_mechanism", "online_assessment_summary",
                   "cavitation_rules_summary"}
    assert set(readme.RENDERERS) - readme_only <= results, set(readme.RENDERERS) - readme_only - results


def test_readme_and_docs_point_nowhere_outside_the_repository():
    for page in [ROOT / "README.md", ROOT / "CHANGELOG.md", ROOT / "CITATION.cff", *sorted((ROOT / "docs").glob("*.md"))]:
        text = page.read_text()
        for bad in ("/work/", "../shared", "CONVENTIONS.md", "TOTAL_MIN", "(issue", "Issue targets"):
            assert bad not in text, f"{page.name}: {bad}"
        for link in re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", text):
            if not link.startswith(("http://", "https://")):
                assert (page.parent / link).exists(), f"{page.name} links to missing {link}"


def test_readme_is_short_and_has_no_dated_history():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    # dates belong to CHANGELOG.md (a generated block may say when its numbers were measured)
    prose = readme_without_generated_blocks(text)
    assert not re.search(r"\b20\d\d-\d\d-\d\d\b", prose), re.search(r".*\b20\d\d-\d\d-\d\d\b.*", prose)
    for page in sorted((ROOT / "docs").glob("*.md")):
        assert not re.search(r"\b(until|since) 20\d\d", readme_without_generated_blocks(page.read_text()), re.I), page


def readme_without_generated_blocks(text: str) -> str:
    from fluidfilm.reporting import readme

    return readme.BLOCK.sub("", text)


def test_reproduction_is_one_mlflow_run_and_the_surrogates_are_registered(quick_reproduce):
    import mlflow

    workdir, out = quick_reproduce
    client = mlflow.tracking.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    exp = client.get_experiment_by_name("fluidfilm")
    assert exp.tags["mlflow.experimentKind"] == "custom_model_development"
    runs = client.search_runs([exp.experiment_id], filter_string="tags.mlflow.runName = 'reproduce'")
    assert len(runs) == 1
    artifacts = {a.path for a in client.list_artifacts(runs[0].info.run_id)}
    assert {"paper_comparison.md", "metrics.json", "figures", "controller", "models"} <= artifacts
    figures = {a.path for a in client.list_artifacts(runs[0].info.run_id, "figures")}
    for fig in ("fig2_grid.png", "fig3_velocity.png", "fig4_comparison.png", "fig5_a_dqn.png"):
        assert f"figures/{fig}" in figures
    registered = {m.name for m in client.search_registered_models()}
    assert {"fluidfilm-paper_single", "fluidfilm-paper_split", "fluidfilm-best", "fluidfilm-active"} <= registered
    # every run of the reproduction ended (none left RUNNING)
    assert not client.search_runs([exp.experiment_id], filter_string="attributes.status = 'RUNNING'")
