"""MLflow tracking helpers (the library's only contact with MLflow).

Default store: ``sqlite:///mlflow.db`` in the project root.  MLflow 3 refuses
plain ``./mlruns`` file stores, and SQLite needs its schema created once
before parallel jobs touch it, which ``ensure_experiment`` does.
"""
from __future__ import annotations

import contextlib
import dataclasses
import functools
import json
import os
import sys
from collections.abc import Mapping
from pathlib import Path


def flatten(cfg: Mapping, prefix: str = "") -> dict:
    """Nested mapping -> {"a.b.c": value} with values as strings MLflow accepts."""
    out = {}
    for key, value in cfg.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out.update(flatten(value, name + "."))
        else:
            out[name] = value if isinstance(value, (int, float, str, bool)) else str(value)
    return out


# What the MLflow UI shows for the experiment: the runs table of a model-training experiment (the
# UI otherwise guesses, and may open the GenAI traces view), and a description.
EXPERIMENT_TAGS = {
    "mlflow.experimentKind": "custom_model_development",
    "mlflow.note.content": (
        "fluidfilm: finite-difference Reynolds reference model, graded force datasets, neural surrogates "
        "(single vs split by eccentricity), rotor trajectories, the active conical bearing's controllers. "
        "Relative force errors (test_rel_err_*) are fractions (0.01 = 1 %); *_pct metrics are percent; "
        "*_s seconds; *_us microseconds; *_m metres; *_N newtons."),
}
WORKSPACE_TAG = "fluidfilm.workspace"

# The runs table a researcher should meet first: one summary run per surrogate (tag fluidfilm.view =
# summary) whose metrics answer the workspace's questions: accuracy, training time, speed-up.  MLflow 3
# has no setting for an experiment's default view, but it opens a view stored as the experiment tag
# ``mlflow.sharedViewState.<key>`` when the runs page's address carries ``?viewStateShareKey=<key>``
# (what its "Share" button makes); ``runs_table_url`` builds that address.
SUMMARY_VIEW = "summary"
VIEW_TAG = "fluidfilm.view"
SUMMARY_COLUMNS = {  # summary metric -> what it says (units as in the experiment's description)
    "test_rel_err_median": "median relative force error on the held-out test set (fraction)",
    "test_rel_err_p99": "99th-percentile relative force error on the held-out test set (fraction)",
    "satisfactory_cases": "Fig. 4 cases whose orbit lies within 2 % of c of the reference (of 7)",
    "train_time_s": "wall time of the model's training [s]",
    "speedup_force_eval_vs_reference": "one force evaluation: reference time / surrogate time",
    "speedup_trajectory": "one Fig. 4 trajectory: reference time / surrogate time",
}
# short names the comparison stage gives the models in reports/metrics.json
_COMPARISON_NAMES = {"paper_single": "single", "paper_split": "split", "best": "best"}


def summary_view_state() -> dict:
    """The runs-table view stored on the experiment: the summary runs only, the ``SUMMARY_COLUMNS`` shown,
    most accurate first.  Keys as MLflow's UI writes them (search facets and the table's UI state)."""
    columns = [f"metrics.`{key}`" for key in SUMMARY_COLUMNS]
    return {"searchFilter": f"tags.`{VIEW_TAG}` = '{SUMMARY_VIEW}'",
            "orderByKey": "metrics.`test_rel_err_median`", "orderByAsc": True, "lifecycleFilter": "Active",
            "selectedColumns": ["tags.`fluidfilm.model`", *columns]}


def runs_table_url(base_url: str, experiment_id: str, view: str | None = SUMMARY_VIEW) -> str:
    """Address of the experiment's runs table in the MLflow UI; with ``view``, opened on that stored view.

    Examples
    --------
    >>> runs_table_url("http://127.0.0.1:5000", "1")
    'http://127.0.0.1:5000/#/experiments/1/runs?viewStateShareKey=summary'
    >>> runs_table_url("http://127.0.0.1:5000/", "1", view=None)
    'http://127.0.0.1:5000/#/experiments/1/runs'
    """
    url = f"{base_url.rstrip('/')}/#/experiments/{experiment_id}/runs"
    return f"{url}?viewStateShareKey={view}" if view else url


def _sqlite_path(uri: str) -> Path | None:
    if not uri.startswith("sqlite:///"):
        return None
    return Path(uri[len("sqlite:///"):])


def relocate_artifacts(uri: str, workspace: Path | None = None) -> int:
    """Re-point the artifact paths of a workspace's SQLite store after the workspace folder moved.

    MLflow stores absolute artifact paths.  Every experiment made here records the workspace folder
    it was made in (tag ``fluidfilm.workspace``); when the store is opened from another folder, the
    recorded prefix is replaced by the current one in the experiments' artifact locations and the
    runs' artifact URIs, so that artifact links keep working after ``mv``/``cp -r`` of the clone.
    Returns the number of rows changed.  Stores on a server (http://, postgresql://) are left alone:
    there the server owns the artifacts.
    """
    import sqlite3

    db = _sqlite_path(uri)
    if db is None or not db.exists():
        return 0
    new_root = str((workspace or Path.cwd()).resolve())
    changed = 0
    with sqlite3.connect(db) as con:
        try:
            rows = con.execute("SELECT experiment_id, value FROM experiment_tags WHERE key = ?",
                               (WORKSPACE_TAG,)).fetchall()
        except sqlite3.OperationalError:  # store not initialised yet
            return 0
        for exp_id, old_root in rows:
            if old_root == new_root:
                continue
            cur = con.execute("UPDATE experiments SET artifact_location = ? || substr(artifact_location, ?) "
                              "WHERE experiment_id = ? AND artifact_location LIKE ? || '%'",
                              (new_root, len(old_root) + 1, exp_id, old_root))
            changed += cur.rowcount
            cur = con.execute("UPDATE runs SET artifact_uri = ? || substr(artifact_uri, ?) "
                              "WHERE experiment_id = ? AND artifact_uri LIKE ? || '%'",
                              (new_root, len(old_root) + 1, exp_id, old_root))
            changed += cur.rowcount
            con.execute("UPDATE experiment_tags SET value = ? WHERE experiment_id = ? AND key = ?",
                        (new_root, exp_id, WORKSPACE_TAG))
    return changed


def ensure_experiment(uri: str, name: str) -> str:
    """Create the store and the experiment if needed; return the experiment id.

    A new experiment keeps its artifacts in ``mlartifacts/<name>`` of the workspace (the folder the
    entry points run in), tagged so that ``relocate_artifacts`` can follow the workspace if it moves.
    """
    import mlflow

    mlflow.set_tracking_uri(uri)
    client = mlflow.tracking.MlflowClient(uri)
    relocate_artifacts(uri)
    exp = client.get_experiment_by_name(name)
    if exp is not None:
        return exp.experiment_id
    tags = dict(EXPERIMENT_TAGS) | {f"mlflow.sharedViewState.{SUMMARY_VIEW}": json.dumps(summary_view_state())}
    location = None
    if _sqlite_path(uri) is not None:
        tags[WORKSPACE_TAG] = str(Path.cwd().resolve())
        location = str(Path.cwd().resolve() / "mlartifacts" / name)
    try:
        return client.create_experiment(name, artifact_location=location, tags=tags)
    except Exception:  # another process created it between the two calls
        exp = client.get_experiment_by_name(name)
        if exp is None:
            raise
        return exp.experiment_id


def _release_interrupted_transactions(exc: BaseException) -> None:
    """Release the SQLite locks that a Ctrl-C left held in this process.

    A KeyboardInterrupt can land inside an MLflow call while SQLAlchemy is reading rows.  SQLAlchemy
    then invalidates (closes) that connection, but SQLite cannot close a connection whose statement is
    still open: the half-read cursor, kept alive by the frames of the interrupt's traceback, keeps the
    connection as a zombie that holds the store's shared lock.  Every later write in this process -
    ending the run as KILLED - then waits SQLite's 20 s busy timeout and fails with "database is
    locked" (about 1 interrupt in 15 of a logging loop).  Clearing the finished frames of the
    interrupt's traceback (and of the exceptions chained to it) and collecting frees the cursor and
    the connection, which finalises the statement and closes the zombie (or rolls back a transaction
    the interrupt left open): what the interrupted call was doing is abandoned anyway.
    """
    import gc
    import traceback

    pending: list[BaseException | None] = [exc]
    seen: set[int] = set()
    while pending:
        e = pending.pop()
        if e is None or id(e) in seen:
            continue
        seen.add(id(e))
        traceback.clear_frames(e.__traceback__)  # frames still running (ours) are skipped
        pending += [e.__context__, e.__cause__]
    gc.collect()


@contextlib.contextmanager
def run(tracking: Mapping | None, run_name: str, params: Mapping | None = None,
        tags: Mapping | None = None, nested: bool = False):
    """Context manager yielding an active MLflow run, or ``None`` when tracking is disabled.

    A parent run id in the environment variable ``FLUIDFILM_PARENT_RUN_ID``
    makes this run a child of it (how a sweep groups its jobs).
    """
    if not tracking or not tracking.get("enabled", True):
        yield None
        return
    import mlflow

    exp_id = ensure_experiment(tracking["uri"], tracking["experiment"])
    all_tags = dict(tags or {})
    parent = os.environ.get("FLUIDFILM_PARENT_RUN_ID")
    if parent:
        all_tags["mlflow.parentRunId"] = parent
    active = mlflow.start_run(experiment_id=exp_id, run_name=run_name, tags=all_tags, nested=nested)
    try:
        if params:
            mlflow.log_params(flatten(params))
        yield active
    except KeyboardInterrupt as exc:
        # the user stopped it: not a failure of the code
        _release_interrupted_transactions(exc)
        mlflow.end_run(status="KILLED")
        raise
    except BaseException:
        mlflow.end_run(status="FAILED")
        raise
    else:
        mlflow.end_run(status="FINISHED")


@dataclasses.dataclass
class Logged:
    """What a study hands back to the entry wrapper for its MLflow run (``fluidfilm.workflow.entry``).

    ``metrics``: name -> number, logged once at the end (a non-number or a bool is skipped);
    ``artifacts``: files or folders, or ``(folder, artifact_path)`` pairs; ``value``: what the Hydra job
    returns (a sweep's job return), by default the metrics.
    """

    metrics: Mapping = dataclasses.field(default_factory=dict)
    artifacts: list = dataclasses.field(default_factory=list)
    value: object = None


def log_record(record: Logged) -> None:
    """Log a study's record to the active run (nothing without one)."""
    log_metrics({k: float(v) for k, v in record.metrics.items()
                 if isinstance(v, (int, float)) and not isinstance(v, bool)})
    for a in record.artifacts:
        path, where = a if isinstance(a, tuple) else (a, None)
        if Path(path).is_dir():
            log_artifacts(path, artifact_path=where)
        else:
            log_artifact(path)


def active_run():
    """The active MLflow run, or None (tracking disabled, or no run open)."""
    mlflow = _active()
    return None if mlflow is None else mlflow.active_run()


def _active():
    import mlflow

    return mlflow if mlflow.active_run() is not None else None


def log_metrics(metrics: Mapping, step: int | None = None) -> None:
    """Log ``metrics`` to the active run (nothing when no run is active, e.g. tracking disabled)."""
    mlflow = _active()
    if mlflow is not None and metrics:
        mlflow.log_metrics(dict(metrics), step=step)


def log_metric(key: str, value: float, step: int | None = None) -> None:
    mlflow = _active()
    if mlflow is not None:
        mlflow.log_metric(key, value, step=step)


def log_artifact(path) -> None:
    mlflow = _active()
    if mlflow is not None:
        mlflow.log_artifact(str(path))


def log_artifacts(directory, artifact_path: str | None = None) -> None:
    mlflow = _active()
    if mlflow is not None:
        mlflow.log_artifacts(str(directory), artifact_path=artifact_path)


@functools.cache
def _interruptible_logger_class():
    """Lightning's MLflow logger, with Ctrl-C ending the run KILLED; built on first use, so that importing
    this module does not import Lightning."""
    from lightning.pytorch.loggers import MLFlowLogger

    class InterruptibleMLFlowLogger(MLFlowLogger):
        """Lightning ends its logger's run inside its own Ctrl-C handler, before ours: the SQLite locks the
        interrupt left held are released first (``_release_interrupted_transactions``), and the run ends
        KILLED, as the job's run does, rather than FAILED."""

        def finalize(self, status: str = "success") -> None:
            exc = sys.exc_info()[1]
            if isinstance(exc, KeyboardInterrupt):
                _release_interrupted_transactions(exc)
                status = "KILLED"
            super().finalize(status)

    return InterruptibleMLFlowLogger


@dataclasses.dataclass(frozen=True)
class ChildRun:
    """One network's MLflow child run, made in the job's process: a plain, picklable record, so the network
    can train in another process and log there (``logger()``)."""

    uri: str
    experiment: str
    run_id: str

    def logger(self):
        """Lightning's MLflow logger of this run."""
        return _interruptible_logger_class()(experiment_name=self.experiment, tracking_uri=self.uri, run_id=self.run_id)

    def end_if_running(self, status: str = "KILLED") -> None:
        """End the run if its process was stopped before Lightning could (a worker terminated on Ctrl-C)."""
        import mlflow

        client = mlflow.tracking.MlflowClient(self.uri)
        if client.get_run(self.run_id).info.status == "RUNNING":
            client.set_terminated(self.run_id, status)


@dataclasses.dataclass(frozen=True)
class ChildRunFactory:
    """``r -> ChildRun``: a child run "<name>/network<r>" under the run ``parent_run_id``.  A plain,
    picklable record, so a worker process can make its network's run when (and only if) that network
    trains; ``logger_for(r)`` is Lightning's logger of a new such run."""

    uri: str
    experiment: str
    experiment_id: str
    parent_run_id: str
    name: str

    def __call__(self, r) -> ChildRun:
        import mlflow

        child = mlflow.tracking.MlflowClient(self.uri).create_run(
            self.experiment_id, run_name=f"{self.name}/network{r}", tags={"mlflow.parentRunId": self.parent_run_id})
        return ChildRun(self.uri, self.experiment, child.info.run_id)

    def logger_for(self, r):
        """Lightning's MLflow logger of a new child run for network ``r``."""
        return self(r).logger()

    def end_open_runs(self, status: str = "KILLED") -> None:
        """End this factory's child runs still marked running (their worker was stopped before Lightning
        could end them)."""
        import mlflow

        client = mlflow.tracking.MlflowClient(self.uri)
        query = f"tags.mlflow.parentRunId = '{self.parent_run_id}' and attributes.status = 'RUNNING'"
        for run in client.search_runs([self.experiment_id], query):
            if (run.info.run_name or "").startswith(f"{self.name}/"):
                client.set_terminated(run.info.run_id, status)


def child_logger_factory(parent, tracking: Mapping, name: str) -> ChildRunFactory:
    """``r -> ChildRun``: a child run "<name>/network<r>" under the run ``parent``; its ``logger()`` is
    Lightning's logger of it (``ChildRunFactory``)."""
    return ChildRunFactory(tracking["uri"], tracking["experiment"], parent.info.experiment_id, parent.info.run_id,
                           name)


def learning_curve_hooks() -> dict:
    """``on_episode``/``on_rollout`` hooks for ``control.dqn.train_dqn``: each episode's return and SB3's
    training scalars logged to the active MLflow run (nothing when none is active)."""

    def on_episode(timestep: int, ret: float) -> None:
        log_metric("episode_return", ret, step=timestep)

    def on_rollout(scalars: dict, timestep: int) -> None:
        if _active() is not None:
            log_metrics(scalars, step=timestep)

    return {"on_episode": on_episode, "on_rollout": on_rollout}


class MlflowSweepCallback:
    """Hydra callback (duck-typed, no Hydra import): one MLflow parent run per multirun.

    ``on_multirun_start`` creates the store, the experiment and a parent run,
    and exports its id in ``FLUIDFILM_PARENT_RUN_ID``; the jobs (in this
    process or in joblib/submitit workers, which inherit the environment)
    nest their runs under it.  Creating the SQLite store here, before any
    job starts, avoids parallel jobs racing to create its schema.
    """

    def __init__(self, **_):
        self.parent_id = None
        self.failed_jobs = 0

    def on_multirun_start(self, config, **kwargs):
        from fluidfilm.workflow.config_check import check_sweep
        from fluidfilm.workflow.sweeps import SWEEP_KEYS_ENV, swept_keys

        check_sweep(config)  # every job's values, before the parent run exists

        # which keys the sweep varies, for the jobs' names (jobs inherit the environment)
        task = list(config.hydra.overrides.task) if "hydra" in config else []
        os.environ[SWEEP_KEYS_ENV] = ",".join(swept_keys(task))
        tr = config.get("tracking")
        if not tr or not tr.get("enabled", True):
            return
        import mlflow

        exp_id = ensure_experiment(tr["uri"], tr["experiment"])
        client = mlflow.tracking.MlflowClient(tr["uri"])
        sweep = config.hydra.sweep.dir if "hydra" in config else "sweep"
        run = client.create_run(exp_id, run_name=f"sweep {sweep}", tags={"sweep_dir": str(sweep)})
        self.parent_id = run.info.run_id
        self._uri = tr["uri"]
        os.environ["FLUIDFILM_PARENT_RUN_ID"] = self.parent_id
        # Hydra skips on_multirun_end when a job raises or the user presses Ctrl-C; the parent must not
        # stay RUNNING for ever, so whatever ends the process ends it too (FAILED or KILLED)
        import atexit

        atexit.register(self._end_parent_at_exit)

    def _end(self, status: str) -> None:
        if self.parent_id is None:
            return
        import mlflow

        mlflow.tracking.MlflowClient(self._uri).set_terminated(self.parent_id, status=status)
        self.parent_id = None
        os.environ.pop("FLUIDFILM_PARENT_RUN_ID", None)

    def _end_parent_at_exit(self) -> None:
        # reached only if on_multirun_end was not: a failed job or an interruption.  Jobs may have run in
        # other processes (joblib, submitit), so their own runs say which: any FAILED child makes it FAILED
        if self.parent_id is None:
            return
        failed = self.failed_jobs
        if not failed:
            import mlflow

            client = mlflow.tracking.MlflowClient(self._uri)
            exp_id = client.get_run(self.parent_id).info.experiment_id
            failed = len(client.search_runs([exp_id], f"tags.mlflow.parentRunId = '{self.parent_id}' "
                                                      "and attributes.status = 'FAILED'"))
        self._end("FAILED" if failed else "KILLED")

    def on_multirun_end(self, config, **kwargs):
        self._end("FAILED" if self.failed_jobs else "FINISHED")

    # the other hooks Hydra calls
    def on_run_start(self, config, **kwargs): ...
    def on_run_end(self, config, **kwargs): ...
    def on_job_start(self, config, **kwargs): ...
    def on_job_end(self, config, job_return, **kwargs):
        status = getattr(getattr(job_return, "status", None), "name", None)
        if status == "FAILED":
            self.failed_jobs += 1
    def on_compose_config(self, config, **kwargs): ...


def log_child_run(parent, run_name: str, metrics: Mapping, history: Mapping | None = None,
                  params: Mapping | None = None, uri: str | None = None) -> None:
    """A nested run under ``parent`` (an active run, or None: nothing logged) with final ``metrics``
    and per-epoch ``history`` {name: [value per epoch]} (one training network of a model)."""
    if parent is None:
        return
    import mlflow

    client = mlflow.tracking.MlflowClient(uri or mlflow.get_tracking_uri())
    child = client.create_run(parent.info.experiment_id, run_name=run_name,
                              tags={"mlflow.parentRunId": parent.info.run_id})
    rid = child.info.run_id
    for k, v in (params or {}).items():
        client.log_param(rid, k, v)
    for k, v in metrics.items():
        if isinstance(v, (int, float)) and not isinstance(v, bool) and v is not None:
            client.log_metric(rid, k, float(v))
    for k, values in (history or {}).items():
        for step, v in enumerate(values, start=1):
            client.log_metric(rid, k, float(v), step=step)
    client.set_terminated(rid)


def publish_workspace(tracking: Mapping, reports_dir: Path | str = "reports", models_dir: Path | str = "models",
                      models: tuple[str, ...] = ("paper_single", "paper_split", "best", "active")) -> str | None:
    """One MLflow run ``reproduce`` that holds what ``make reproduce`` produced, and the trained surrogates
    registered in the model registry (``fluidfilm-<name>``, a new version per reproduction).

    The run carries the headline metrics (``reports/metrics.json``), the report, the stage timings, the
    training-time study, every figure and the DQN agent as artifacts, so that the MLflow UI shows the
    whole reproduction in one place, and one summary run per model (``log_model_summaries``) for the
    runs table's first view.  Returns the run id (None with tracking disabled).
    """
    if not tracking or not tracking.get("enabled", True):
        return None
    import mlflow

    reports, model_root = Path(reports_dir), Path(models_dir)
    metrics_file = reports / "metrics.json"
    metrics = json.loads(metrics_file.read_text()) if metrics_file.exists() else {}
    description = ("The paper reproduction as `make reproduce` left it: headline metrics (see the experiment's "
                   "description for units), the report, stage timings, figures, the DQN agent; the surrogates "
                   "are registered as fluidfilm-<name>.")
    with run(tracking, "reproduce", tags={"mlflow.note.content": description, "stage": "reproduce"}) as active:
        log_metrics({k: float(v) for k, v in metrics.items()
                     if isinstance(v, (int, float)) and not isinstance(v, bool) and v == v})
        for name in ("paper_comparison.md", "metrics.json", "reproduce_timing.json", "train_time.json",
                     "characteristics.json", "control.json", "batch_speed.json", "controller_training_speed.json"):
            if (reports / name).exists():
                log_artifact(reports / name)
        if (reports / "figures").is_dir():
            for fig in sorted((reports / "figures").glob("*.png")):
                mlflow.log_artifact(str(fig), artifact_path="figures")
        agent = model_root / "dqn_active.zip"
        if agent.exists():
            mlflow.log_artifact(str(agent), artifact_path="controller")
        client = mlflow.tracking.MlflowClient(tracking["uri"])
        for name in models:
            folder = model_root / name
            if not (folder / "model.json").exists():
                continue
            mlflow.log_artifacts(str(folder), artifact_path=f"models/{name}")
            registered = f"fluidfilm-{name}"
            if not _registered(client, registered):
                client.create_registered_model(registered, description=(
                    f"fluidfilm surrogate '{name}' of the bearing forces; load the artifact folder with "
                    "fluidfilm.load_surrogate(path)"))
            report_file = folder / "report.json"
            tags = {}
            if report_file.exists():
                rep = json.loads(report_file.read_text()).get("metrics", {})
                tags = {k: str(v) for k, v in rep.items() if k.startswith("test_rel_err")}
            client.create_model_version(registered, source=f"{active.info.artifact_uri}/models/{name}",
                                        run_id=active.info.run_id, tags=tags)
        run_id = active.info.run_id
    log_model_summaries(tracking, metrics, model_root, models, source_run=run_id)
    return run_id


def model_summary(name: str, metrics: Mapping, report: Mapping) -> dict[str, float]:
    """The ``SUMMARY_COLUMNS`` of one model: from its ``models/<name>/report.json`` metrics (``report``)
    and the pipeline's headline metrics (``metrics``, reports/metrics.json); a value neither holds is left out.

    Examples
    --------
    >>> model_summary("paper_split", {"speedup_trajectory_split": 9.1, "satisfactory_cases_split": 0},
    ...               {"test_rel_err_median": 0.2, "train_time_s": 40.0})
    {'test_rel_err_median': 0.2, 'satisfactory_cases': 0.0, 'train_time_s': 40.0, 'speedup_trajectory': 9.1}
    """
    short = _COMPARISON_NAMES.get(name, name)
    headline = {"test_rel_err_median": f"test_rel_err_median_{name}", "test_rel_err_p99": f"test_rel_err_p99_{name}",
                "satisfactory_cases": f"satisfactory_cases_{short}", "speedup_trajectory": f"speedup_trajectory_{short}"}
    out = {}
    for key in SUMMARY_COLUMNS:
        value = report.get(key, metrics.get(headline.get(key, "")))
        if isinstance(value, (int, float)) and not isinstance(value, bool) and value == value:
            out[key] = float(value)
    return out


def log_model_summaries(tracking: Mapping, metrics: Mapping, models_dir: Path | str,
                        models: tuple[str, ...], source_run: str | None = None) -> list[str]:
    """One run ``summary/<model>`` per trained model (tags ``fluidfilm.view = summary``, ``fluidfilm.model``)
    whose metrics are ``model_summary``'s: the rows of the runs table's first view (``runs_table_url``).

    The summaries of an earlier reproduction are re-tagged ``fluidfilm.view = superseded`` (kept, not shown
    in that view), and the experiment's stored view is rewritten, so an experiment made before the view
    existed gets it too.  Returns the new runs' ids.
    """
    if not tracking or not tracking.get("enabled", True):
        return []
    import mlflow

    exp_id = ensure_experiment(tracking["uri"], tracking["experiment"])
    client = mlflow.tracking.MlflowClient(tracking["uri"])
    client.set_experiment_tag(exp_id, f"mlflow.sharedViewState.{SUMMARY_VIEW}", json.dumps(summary_view_state()))
    for old in client.search_runs([exp_id], f"tags.`{VIEW_TAG}` = '{SUMMARY_VIEW}'", max_results=1000):
        client.set_tag(old.info.run_id, VIEW_TAG, "superseded")
    ids = []
    for name in models:
        report_file = Path(models_dir) / name / "report.json"
        if not report_file.exists():
            continue
        values = model_summary(name, metrics, json.loads(report_file.read_text()).get("metrics", {}))
        tags = {VIEW_TAG: SUMMARY_VIEW, "fluidfilm.model": name,
                "mlflow.note.content": "Summary of model '%s': %s" % (name, "; ".join(
                    f"{k}: {v}" for k, v in SUMMARY_COLUMNS.items()))}
        if source_run:
            tags["fluidfilm.source_run"] = source_run
        row = client.create_run(exp_id, run_name=f"summary/{name}", tags=tags)
        for key, value in values.items():
            client.log_metric(row.info.run_id, key, value)
        client.set_terminated(row.info.run_id)
        ids.append(row.info.run_id)
    return ids


def _registered(client, name: str) -> bool:
    try:
        client.get_registered_model(name)
        return True
    except Exception:  # MlflowException(RESOURCE_DOES_NOT_EXIST)
        return False
