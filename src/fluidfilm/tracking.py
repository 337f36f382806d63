"""MLflow tracking helpers (the library's only contact with MLflow).

Default store: ``sqlite:///mlflow.db`` in the project root.  MLflow 3 refuses
plain ``./mlruns`` file stores, and SQLite needs its schema created once
before parallel jobs touch it, which ``ensure_experiment`` does.
"""
from __future__ import annotations

import contextlib
import os
from collections.abc import Mapping


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


def ensure_experiment(uri: str, name: str) -> str:
    """Create the store and the experiment if needed; return the experiment id."""
    import mlflow

    mlflow.set_tracking_uri(uri)
    client = mlflow.tracking.MlflowClient(uri)
    exp = client.get_experiment_by_name(name)
    if exp is not None:
        return exp.experiment_id
    try:
        return client.create_experiment(name)
    except Exception:  # another process created it between the two calls
        exp = client.get_experiment_by_name(name)
        if exp is None:
            raise
        return exp.experiment_id


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
    with mlflow.start_run(experiment_id=exp_id, run_name=run_name, tags=all_tags, nested=nested) as active:
        if params:
            mlflow.log_params(flatten(params))
        yield active


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

    def on_multirun_start(self, config, **kwargs):
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

    def on_multirun_end(self, config, **kwargs):
        if self.parent_id is None:
            return
        import mlflow

        mlflow.tracking.MlflowClient(self._uri).set_terminated(self.parent_id)
        os.environ.pop("FLUIDFILM_PARENT_RUN_ID", None)

    # the other hooks Hydra calls
    def on_run_start(self, config, **kwargs): ...
    def on_run_end(self, config, **kwargs): ...
    def on_job_start(self, config, **kwargs): ...
    def on_job_end(self, config, job_return, **kwargs): ...
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
