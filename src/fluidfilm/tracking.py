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
