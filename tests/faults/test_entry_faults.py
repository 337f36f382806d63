"""Item 6 of issue 26, the workflow probes: what every entry point does before, around and after its study
(``fluidfilm.workflow.entry``)."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fluidfilm import io
from fluidfilm.workflow.entry import Job, check_inputs, guard_outputs

from .conftest import ROOT, interruptible, run_entry

FIG3_SET = ("fig3_velocity.csv", "fig3_velocity_radial.csv", "fig3_velocity_tangential.csv", "fig3_velocity.png")
QUICK_FIG3 = ("n_v=3", "eccentricities=[0.5]")


def test_a_misspelt_experiment_is_refused_naming_it(tmp_path):
    proc = run_entry("train_surrogate", "experiment=quik", f"out_dir={tmp_path}", f"checkpoint_dir={tmp_path}")
    assert proc.returncode != 0
    assert "experiment/quik" in proc.stderr and "paper_single" in proc.stderr  # the typo and the real options
    assert not any(tmp_path.iterdir())  # nothing trained


@pytest.mark.parametrize("override, key", [("n_v=0", "n_v=0"), ("eccentricities=[]", "eccentricities=[]"),
                                           ("eccentricities=[1.2]", "eccentricities=[1.2]"),
                                           ("v_max=-1", "v_max=-1")])
def test_fig3_refuses_an_empty_or_bad_sweep_naming_the_key(tmp_path, override, key):
    proc = run_entry("fig3_velocity", override, f"out_dir={tmp_path}")
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr
    assert proc.stderr.strip().splitlines()[-1].startswith("error: configuration refused: " + key)
    assert not any(tmp_path.iterdir())


def test_a_missing_input_is_named_with_the_stage_that_makes_it(tmp_path, monkeypatch, capsys):
    (tmp_path / "dvc.yaml").write_text("stages:\n  train_best:\n    cmd: x\n    outs:\n      - models/best\n")
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exc:
        check_inputs({"surrogate_dir": "models/best"}, ["surrogate_dir"], root=tmp_path)
    assert exc.value.code == 2
    assert capsys.readouterr().err.strip() == ("error: input surrogate_dir=models/best does not exist: make it with "
                                               "`dvc repro train_best` (or `dvc pull train_best`)")
    (tmp_path / "models" / "best").mkdir(parents=True)
    check_inputs({"surrogate_dir": "models/best", "models": {"a": "models/best"}}, ["surrogate_dir", "models"],
                 root=tmp_path)  # present: nothing said


def test_a_missing_input_fails_up_front_naming_key_path_and_stage(tmp_path):
    missing = "models/no_such_model"
    proc = run_entry("batch_speed", f"surrogate_dir={missing}", f"out_json={tmp_path / 'b.json'}")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert f"input surrogate_dir={missing} does not exist" in proc.stderr
    # a pipeline output: the message says which stage makes it
    proc = run_entry("boundary_study", "dataset_dir=data/dataset_orbit", f"out={tmp_path / 'b.json'}")
    if not (ROOT / "data" / "dataset_orbit").exists():
        assert proc.returncode == 2
        assert "input dataset_dir=data/dataset_orbit does not exist: make it with `dvc repro dataset_orbit`" in proc.stderr


def _job(tmp_path, stage=None, multirun=False):
    return Job(study="fig3_velocity", choices={}, task_overrides=[], multirun=multirun,
               output_dir=tmp_path / "outputs" / "job", sweep_dir="", stage=stage)


def test_the_guard_redirects_a_run_by_hand_and_lets_the_owning_stage_write(tmp_path, monkeypatch):
    (tmp_path / "dvc.yaml").write_text("stages:\n  fig3_velocity:\n    cmd: x\n    outs:\n"
                                       "      - reports/figures/fig3_velocity.csv\n"
                                       "  seeds:\n    foreach: [1, 2]\n    do:\n      cmd: x\n      outs:\n"
                                       "        - models/best_s${item}\n")
    monkeypatch.chdir(tmp_path)
    written = {"out_dir": ["fig3_velocity.csv"]}
    cfg = {"out_dir": "reports/figures"}
    assert guard_outputs(cfg, written, _job(tmp_path, stage="fig3_velocity"), root=tmp_path) == []
    assert cfg["out_dir"] == "reports/figures"  # the stage itself writes its outputs
    notes = guard_outputs(cfg, written, _job(tmp_path), root=tmp_path)
    assert cfg["out_dir"] == str(Path("outputs/job/reports/figures")) and "writes to outputs/job" in notes[0]
    with pytest.raises(SystemExit):  # another stage, or a sweep, may not write it at all
        guard_outputs({"out_dir": "reports/figures"}, written, _job(tmp_path, stage="seeds@1"), root=tmp_path)
    with pytest.raises(SystemExit):  # a foreach stage's outputs are tracked too
        guard_outputs({"out_dir": "models"}, {"out_dir": ["best_s2"]}, _job(tmp_path, multirun=True), root=tmp_path)
    assert guard_outputs({"out_dir": "models"}, {"out_dir": ["mine"]}, _job(tmp_path), root=tmp_path) == []
    monkeypatch.setenv("FLUIDFILM_UPDATE_TRACKED", "1")  # the explicit flag of a command outside the pipeline
    cfg = {"out_dir": "reports/figures"}
    assert guard_outputs(cfg, written, _job(tmp_path), root=tmp_path) == [] and cfg["out_dir"] == "reports/figures"


def test_a_run_by_hand_never_writes_the_pipelines_tracked_outputs():
    tracked = ROOT / "reports" / "figures"
    before = {n: (tracked / n).stat().st_mtime_ns for n in FIG3_SET if (tracked / n).exists()}
    proc = run_entry("fig3_velocity", *QUICK_FIG3)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert {n: (tracked / n).stat().st_mtime_ns for n in FIG3_SET if (tracked / n).exists()} == before
    note = next(line for line in proc.stdout.splitlines() if line.startswith("note: out_dir=reports/figures"))
    target = ROOT / note.split("writes to ", 1)[1].split(" instead")[0]
    assert sorted(p.name for p in target.iterdir()) == sorted(FIG3_SET)
    # run as another DVC stage, it is refused outright
    proc = run_entry("fig3_velocity", *QUICK_FIG3, env={"DVC_STAGE": "fig2_grid"})
    assert proc.returncode == 2 and "not of the stage fig2_grid" in proc.stderr


def test_two_runs_at_once_get_two_output_folders(tmp_path):
    runs = ROOT / "outputs" / "fig3_velocity"
    before = set(runs.iterdir()) if runs.exists() else set()
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    procs = [subprocess.Popen([sys.executable, "experiments/fig3_velocity.py", *QUICK_FIG3, f"out_dir={tmp_path / k}"],
                              cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE) for k in "ab"]
    assert [p.wait(timeout=300) for p in procs] == [0, 0]
    new = set(runs.iterdir()) - before
    assert len(new) == 2 and all((d / "fig3_velocity.log").exists() for d in new)


def test_an_output_set_is_replaced_whole_or_not_at_all(tmp_path):
    for n in FIG3_SET:
        (tmp_path / n).write_text("stale")
    with pytest.raises(KeyboardInterrupt):
        with io.output_set() as out:
            out.write_text(tmp_path / FIG3_SET[0], "new")
            out.write_text(tmp_path / FIG3_SET[1], "new")
            raise KeyboardInterrupt
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(FIG3_SET)  # no temporary left
    assert {(tmp_path / n).read_text() for n in FIG3_SET} == {"stale"}
    with io.output_set() as out:
        for n in FIG3_SET:
            out.write_text(tmp_path / n, "new")
    assert {(tmp_path / n).read_text() for n in FIG3_SET} == {"new"}


def test_ctrl_c_of_fig3_leaves_the_old_set_and_no_new_csv_beside_it(tmp_path):
    for n in FIG3_SET:
        (tmp_path / n).write_text("stale")
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    runs = ROOT / "outputs" / "fig3_velocity"
    before = set(runs.iterdir()) if runs.exists() else set()
    proc = subprocess.Popen([sys.executable, "experiments/fig3_velocity.py", "n_v=50001", f"out_dir={tmp_path}"],
                            cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=interruptible)
    deadline = time.time() + 120  # until Hydra has made the job's folder: the study is starting
    while time.time() < deadline and not any((d / ".hydra" / "config.yaml").exists()
                                             for d in (set(runs.iterdir()) if runs.exists() else set()) - before):
        time.sleep(0.05)
    time.sleep(3)  # well into the 400 000 solves
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err[-2000:]
    assert err.strip().splitlines()[-1].startswith("interrupted: the Fig. 3 velocity study")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(FIG3_SET)
    assert {(tmp_path / n).read_text() for n in FIG3_SET} == {"stale"}


@pytest.mark.parametrize("group", [False, True], ids=["main_process", "process_group"])
def test_ctrl_c_of_a_local_dask_run_is_one_line_without_worker_tracebacks(tmp_path, group):
    """SIGINT to the main process alone, or to the whole group as a terminal's Ctrl-C: the workers
    (which ignore SIGINT; the main process closes the cluster) print no KeyboardInterrupt of their own."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.Popen([sys.executable, "experiments/make_dataset.py", "dataset=quick", "dask.scheduler=local",
                             "dask.n_workers=2", "progress=false", f"out_dir={tmp_path / 'ds'}",
                             f"test_dir={tmp_path / 'ts'}"], cwd=ROOT, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=interruptible, start_new_session=True)
    deadline = time.time() + 300
    while time.time() < deadline and len(list((tmp_path / "ds").glob("part-*.parquet"))) < 2:
        time.sleep(0.05)
    if group:
        os.killpg(proc.pid, signal.SIGINT)
    else:
        proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err[-3000:]
    assert "Traceback" not in err and "KeyboardInterrupt" not in err and "AssertionError" not in err, err[-3000:]
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines[-1].startswith("interrupted: dataset generation") and len(lines) <= 3, lines


def test_every_stage_may_write_what_its_study_writes(monkeypatch):
    """Run as its own stage (``DVC_STAGE``), no pipeline command is refused or redirected: each study's
    outputs lie in its stage's ``outs`` (or in no stage's)."""
    import importlib
    import importlib.util

    import test_dvc_deps as deps
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra

    from fluidfilm.workflow import entry

    monkeypatch.chdir(ROOT)
    for name, stage in deps.STAGES.items():
        script, overrides = deps._entry_point(stage)
        # a study named apart from the library room it uses (studies/characteristics_study.py) keeps its entry
        # point's and config's name
        name_ = script.stem if importlib.util.find_spec(f"fluidfilm.studies.{script.stem}") else f"{script.stem}_study"
        study = importlib.import_module(f"fluidfilm.studies.{name_}")
        GlobalHydra.instance().clear()
        with initialize_config_dir(config_dir=str(ROOT / "conf"), version_base="1.3"):
            cfg = compose(config_name=script.stem, overrides=overrides, return_hydra_config=True)
        job = Job(study=script.stem, choices=dict(cfg.hydra.runtime.choices), task_overrides=overrides,
                  multirun=False, output_dir=Path("outputs/x"), sweep_dir="", stage=name)
        entry._set_job(job)
        written = study.outputs(cfg) if hasattr(study, "outputs") else getattr(study, "OUTPUTS", {})
        assert guard_outputs(cfg, written, job) == [], name
    entry._set_job(None)


@pytest.mark.parametrize("override, key", [("threads_repeats=0", "threads_repeats=0"),
                                           ("threads_min_seconds=-1", "threads_min_seconds=-1"),
                                           ("threads_min_seconds=inf", "threads_min_seconds=inf"),
                                           ("table_min_seconds=-0.5", "table_min_seconds=-0.5"),
                                           ("core_probe_seconds=0", "core_probe_seconds=0"),
                                           ("core_probe_interleaved_seconds=-1", "core_probe_interleaved_seconds=-1")])
def test_batch_speed_refuses_bad_repeat_rules_before_any_timing(tmp_path, override, key):
    # surrogate_dir exists (an empty folder): the rule is refused before a model is loaded or a run timed
    proc = run_entry("batch_speed", override, f"surrogate_dir={tmp_path}", f"out_json={tmp_path / 'b.json'}")
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr
    assert proc.stderr.strip().splitlines()[-1].startswith("error: configuration refused: " + key)
    assert not (tmp_path / "b.json").exists()
