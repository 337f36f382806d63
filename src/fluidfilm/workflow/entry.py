"""The one entry wrapper: what every ``experiments/<study>.py`` does around ``fluidfilm.studies.<study>.run(cfg)``.

In the spirit of lightning-hydra-template's ``task_wrapper``, failure and logging are handled once, here:

1. Hydra composes ``conf/<study>.yaml`` (the entry point, its config and its study module share one name);
   each run gets its own output folder ``outputs/<study>/<date>_<time>_<pid>`` (``multirun/...`` for ``-m``),
   so two runs started in the same second never share one (set on the command line, never in a config
   file that DVC hashes);
2. ``check_config`` refuses a mistyped key or value, naming it;
3. the study's input paths (``INPUTS``: config keys) are checked up front: a missing one is named, with the
   DVC stage that makes it;
4. the study's outputs (``OUTPUTS``, or ``outputs(cfg)``) are checked against the pipeline's tracked outputs
   (every ``outs`` of dvc.yaml, and the git-tracked files under reports/): only the DVC stage that makes one
   (``DVC_STAGE``, which ``dvc repro`` exports to every command it runs) writes it; a run by hand writes
   under its own output folder instead and says where (``FLUIDFILM_UPDATE_TRACKED=1``: writes them, for
   the Makefile's commands that update a committed report outside the pipeline); a run as another stage,
   or a sweep job, is refused;
5. the MLflow run, where the study has one (``tracking_run(cfg)``): opened around the study, ended
   FINISHED / FAILED / KILLED, and the study's returned ``tracking.Logged`` record logged into it;
6. Ctrl-C: one line, exit status 130 (``io.run_interruptible``); every output is written atomically.

A study module provides ``run(cfg)`` and, as it needs them, ``check(cfg)`` (raises ``ConfigError``),
``INPUTS``, ``OUTPUTS`` / ``outputs(cfg)`` and ``tracking_run(cfg) -> (run name, tags)``.  ``cfg`` is the composed config (attribute access); the
study reads Hydra's runtime facts through ``current_job()`` and plain containers through ``plain(cfg)``.
"""
from __future__ import annotations

import dataclasses
import os
import sys
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from types import ModuleType

from fluidfilm import io

ROOT = Path(__file__).resolve().parents[3]  # the workspace: conf/, dvc.yaml, experiments/
STAGE_ENV = "DVC_STAGE"  # dvc/stage/run.py: set for every stage command `dvc repro` runs
# the explicit "yes, update the committed report" of a command outside the pipeline (the Makefile's
# train-time-ci / train-time-full-scale write git-tracked reports no stage makes)
UPDATE_ENV = "FLUIDFILM_UPDATE_TRACKED"


@dataclasses.dataclass(frozen=True)
class Job:
    """What Hydra knows about the running job, as plain data (studies never import Hydra)."""

    study: str
    choices: dict
    task_overrides: list
    multirun: bool
    output_dir: Path
    sweep_dir: str
    stage: str | None  # the DVC stage this runs as, None by hand


_JOB: Job | None = None


def current_job() -> Job:
    """The running job (inside ``main``)."""
    if _JOB is None:
        raise RuntimeError("current_job() is only known inside an entry point run by fluidfilm.workflow.entry.main")
    return _JOB


def _set_job(job: Job | None) -> None:
    # a module-level function, so that a job run in a launcher's worker process (joblib pickles the task by
    # value) sets this module's job there, not a copy of the name
    global _JOB
    _JOB = job


def plain(cfg) -> dict:
    """The composed config as plain, resolved containers."""
    from omegaconf import OmegaConf

    out = OmegaConf.to_container(cfg, resolve=True)
    assert isinstance(out, dict)
    return out


def _refuse(message: str) -> None:
    print(f"error: {message}", file=sys.stderr, flush=True)
    raise SystemExit(2)


def _makers(root: Path) -> dict[Path, str]:
    from fluidfilm.workflow.sweeps import pipeline_outputs

    return pipeline_outputs(root)


def _git_tracked_reports(root: Path) -> set[Path]:
    import subprocess

    try:
        out = subprocess.run(["git", "ls-files", "reports"], cwd=root, capture_output=True, text=True,
                             timeout=30).stdout
    except (OSError, subprocess.SubprocessError):  # no git: the dvc.yaml outs still guard
        return set()
    return {(root / line).resolve() for line in out.splitlines() if line}


def _values(cfg, key: str) -> list[str]:
    """The path(s) under a dotted key: a string, or every value of a mapping (``models``); none for null."""
    node = cfg
    for part in key.split("."):
        node = node[part] if node is not None and part in node else None
    if node is None:
        return []
    if isinstance(node, (str, Path)):
        return [str(node)]
    return [str(v) for v in (node.values() if hasattr(node, "values") else node) if v is not None]


def check_inputs(cfg, keys, root: Path = ROOT) -> None:
    """Every input path exists, or one line names the key, the path and how to make it."""
    makers = None
    for key in keys:
        for value in _values(cfg, key):
            path = Path(value)
            if path.exists():
                continue
            makers = _makers(root) if makers is None else makers
            p = (Path.cwd() / path).resolve()
            stage = next((s for out, s in makers.items() if p == out or out in p.parents), None)
            how = (f"make it with `dvc repro {stage}` (or `dvc pull {stage}`)" if stage else
                   f"give {key}=<an existing path>")
            _refuse(f"input {key}={value} does not exist: {how}")


def guard_outputs(cfg, written: Mapping[str, list[str]], job: Job, root: Path = ROOT) -> list[str]:
    """Keep the pipeline's tracked outputs for the stages that make them (see the module docstring).

    ``written``: config key -> the paths it writes, relative to the key's path ("" for the path itself).
    Returns the lines said about redirected keys (empty when nothing was redirected)."""
    makers = _makers(root)
    tracked = dict(makers) | {p: "git" for p in _git_tracked_reports(root) if p not in makers}
    notes = []
    for key, rels in written.items():
        values = _values(cfg, key)
        if len(values) != 1:
            continue
        base = Path(values[0])
        hits = set()
        for rel in rels:
            p = (Path.cwd() / base / rel).resolve()
            hits |= {(t, s) for t, s in tracked.items() if p == t or t in p.parents or p in t.parents}
        if not hits:
            continue
        stages = sorted({s for _, s in hits})
        if job.stage is not None and job.stage in stages:
            continue
        if job.stage is None and not job.multirun and os.environ.get(UPDATE_ENV) == "1":
            continue
        shown = ", ".join(sorted(str(t.relative_to(root)) if root in t.parents else str(t) for t, _ in hits)[:3])
        makers_text = " / ".join(s for s in stages if s != "git") or "git (a committed report)"
        if job.stage is not None:
            _refuse(f"{key}={base} would overwrite {shown}, an output of {makers_text}, not of the stage "
                    f"{job.stage} running now")
        if job.multirun:  # a sweep's jobs would overwrite each other's redirected outputs too: refused
            _refuse(f"sweep job output {key}={base} would overwrite {shown}, an output of the DVC pipeline "
                    f"({makers_text}); give the sweep its own {key} (e.g. {key}=multirun_{base.name}) or a "
                    "distinct name")
        target = job.output_dir / (base if not base.is_absolute() else Path(*base.parts[1:]))
        if target.is_absolute() and Path.cwd() in target.parents:
            target = target.relative_to(Path.cwd())
        _set(cfg, key, str(target))
        notes.append(f"note: {key}={base} would overwrite {shown} (tracked: {makers_text}); this run by hand "
                     f"writes to {target} instead (`dvc repro` updates the pipeline's own)")
    return notes


def _set(cfg, key: str, value: str) -> None:
    node = cfg
    *parents, last = key.split(".")
    for part in parents:
        node = node[part]
    node[last] = value


def _overrides_with_own_dirs(argv: list[str], study: str) -> list[str]:
    """The command line plus a run (sweep) folder of its own, unless the command names one."""
    if any(a.startswith(("hydra.run.dir=", "hydra.sweep.dir=", "--help", "-h", "--hydra-help")) for a in argv[1:]):
        return argv
    stamp = f"{time.strftime('%Y-%m-%d_%H-%M-%S')}_{os.getpid()}"
    return [*argv, f"hydra.run.dir=outputs/{study}/{stamp}", f"hydra.sweep.dir=multirun/{study}/{stamp}"]


SUMMARY_CALLBACK = "hydra.callbacks.fluidfilm_sweep_summary._target_=fluidfilm.workflow.sweeps.SweepSummaryCallback"


def _with_sweep_summary(argv: list[str]) -> list[str]:
    """A multirun (``-m``) gets ``sweeps.SweepSummaryCallback``: it says where the jobs write and ends with
    ``<sweep dir>/summary.csv`` (one row per job: its overrides and metrics).  Added on the command line, so
    that no config file (which DVC hashes) changes and every entry point has it."""
    args = argv[1:]
    if not any(a in ("-m", "--multirun") for a in args) or any(a in ("--help", "-h", "--hydra-help") for a in args):
        return argv
    if any(SUMMARY_CALLBACK.split("=", 1)[0] in a for a in args):
        return argv
    return [*argv, "+" + SUMMARY_CALLBACK]


def _job(study: str) -> Job:
    from hydra.core.hydra_config import HydraConfig
    from hydra.types import RunMode

    hc = HydraConfig.get()
    multirun = hc.mode == RunMode.MULTIRUN
    return Job(study=study, choices=dict(hc.runtime.choices), task_overrides=list(hc.overrides.task),
               multirun=multirun, output_dir=Path(hc.runtime.output_dir),
               sweep_dir=str(hc.sweep.dir) if multirun else "", stage=os.environ.get(STAGE_ENV) or None)


def _task(study: ModuleType, name: str, root: Path) -> Callable:
    def task(cfg):
        from fluidfilm.workflow import tracking
        from fluidfilm.workflow.config_check import ConfigError, check_config

        check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
        job = _job(name)
        _set_job(job)
        if hasattr(study, "check"):  # the study's own keys (ranges, non-empty lists), named when wrong
            try:
                study.check(cfg)
            except ConfigError as err:
                _refuse(f"configuration refused: {err}")
        check_inputs(cfg, getattr(study, "INPUTS", ()), root)
        outputs = getattr(study, "outputs", None)
        written = outputs(cfg) if callable(outputs) else getattr(study, "OUTPUTS", {})
        for line in guard_outputs(cfg, written, job, root):
            print(line, flush=True)
        out_paths = {key: _values(cfg, key) for key in written}  # after any redirection
        run_spec = getattr(study, "tracking_run", None)
        try:
            if run_spec is None or "tracking" not in cfg:
                record = study.run(cfg)
            else:
                run_name, tags = run_spec(cfg)
                with tracking.run(cfg.tracking, run_name, plain(cfg), tags=tags):
                    record = study.run(cfg)
                    if isinstance(record, tracking.Logged):
                        tracking.log_record(record)
        except ConfigError as err:  # a study's own check of its keys: one line, as check_config's
            _refuse(f"configuration refused: {err}")
        if job.multirun:  # for the sweep's summary table (sweeps.SweepSummaryCallback)
            from fluidfilm.workflow.sweeps import write_job_record

            write_job_record(job.output_dir, job.task_overrides,
                             record.metrics if isinstance(record, tracking.Logged) else record, out_paths)
        if isinstance(record, tracking.Logged):
            return record.value if record.value is not None else dict(record.metrics)
        return record

    # Hydra names the job (and its log file) after the task's module: the study's own name.  The qualified
    # name must not be one the study module has (``run``): a launcher that pickles the task would then send
    # the study's bare ``run`` by reference, without this wrapper
    task.__module__ = study.__name__
    task.__qualname__ = task.__name__ = "entry_task"
    return task


def main(study: ModuleType, what: str, resume: str = "run the same command again", name: str | None = None) -> None:
    """Run ``study.run(cfg)`` as the entry point ``experiments/<name>.py`` with the config ``conf/<name>.yaml``
    (``name``: the study module's own by default; a study module named apart from the library room it uses
    passes its entry point's: ``experiments/characteristics.py`` runs ``studies.characteristics_study``)."""
    import hydra

    name = name or study.__name__.rsplit(".", 1)[-1]
    # the workspace of the entry point that runs (a scratch copy of it, too: the pipeline's quick profile),
    # else the one this package lies in
    script = Path(sys.argv[0]).resolve()
    root = script.parents[1] if script.parent.name == "experiments" and (script.parents[1] / "conf").is_dir() else ROOT
    conf = root / "conf"
    if not (conf / f"{name}.yaml").exists():
        raise FileNotFoundError(f"no config {conf / name}.yaml for the study {study.__name__}")
    sys.argv = _with_sweep_summary(_overrides_with_own_dirs(sys.argv, name))
    entry = hydra.main(config_path=str(conf), config_name=name, version_base="1.3")(_task(study, name, root))
    io.run_interruptible(entry, what, resume)
