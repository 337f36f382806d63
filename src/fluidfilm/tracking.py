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


def child_logger_factory(parent, tracking: Mapping, name: str):
    """``r -> MLFlowLogger`` of a child run "<name>/network<r>" under the run ``parent`` (Lightning's logger)."""
    import mlflow
    from lightning.pytorch.loggers import MLFlowLogger

    client = mlflow.tracking.MlflowClient(tracking["uri"])

    def logger_for(r):
        child = client.create_run(parent.info.experiment_id, run_name=f"{name}/network{r}",
                                  tags={"mlflow.parentRunId": parent.info.run_id})
        return MLFlowLogger(experiment_name=tracking["experiment"], tracking_uri=tracking["uri"],
                            run_id=child.info.run_id)

    return logger_for


def sb3_learning_curves():
    """A stable-baselines3 callback: episode returns (from the Monitor wrapper, kept in ``.returns``)
    and SB3's training scalars, logged to the active MLflow run."""
    import numpy as np
    from stable_baselines3.common.callbacks import BaseCallback

    class MlflowCurves(BaseCallback):
        def __init__(self):
            super().__init__()
            self.returns: list[tuple[int, float]] = []

        def _on_step(self) -> bool:
            for info in self.locals.get("infos", []):
                ep = info.get("episode")
                if ep is not None:
                    self.returns.append((self.num_timesteps, float(ep["r"])))
                    log_metric("episode_return", float(ep["r"]), step=self.num_timesteps)
            return True

        def _on_rollout_end(self) -> None:
            if _active() is None:
                return
            vals = {k.replace("/", "_"): float(v) for k, v in self.model.logger.name_to_value.items()
                    if isinstance(v, (int, float, np.floating))}
            if vals:
                log_metrics(vals, step=self.num_timesteps)

    return MlflowCurves()


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
