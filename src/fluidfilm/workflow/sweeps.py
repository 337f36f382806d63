"""Sweep jobs: a distinct name and output folder per job, and the pipeline's tracked outputs kept out of reach.

Plain functions of plain data (the entry points pass what Hydra tells them), so the library stays free of Hydra.
"""
from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from pathlib import Path

# overrides that say where things go, not what is computed: never part of a job's name
_PLACE_KEYS = ("tracking.", "hydra.", "hydra/")


SWEEP_KEYS_ENV = "FLUIDFILM_SWEEP_KEYS"


def swept_keys(sweep_overrides: Iterable[str]) -> list[str]:
    """Keys a multirun sweeps over, from its command-line overrides (``model.width=8,48`` -> model.width)."""
    keys = []
    for o in sweep_overrides:
        key, _, value = o.partition("=")
        depth, top_comma = 0, False
        for ch in value:
            depth += ch in "[({"
            depth -= ch in "])}"
            top_comma |= ch == "," and depth == 0
        if top_comma or re.match(r"\s*(range|choice|interval|glob)\(", value):
            keys.append(key.lstrip("+~"))
    return keys


def swept_values(task_overrides: Iterable[str], sweep_keys: Iterable[str]) -> dict[str, str]:
    """A sweep job's value of each swept key (config groups included), from its task overrides, in order."""
    keys = set(sweep_keys)
    out = {}
    for o in task_overrides:
        key, _, value = o.partition("=")
        key = key.lstrip("+~")
        if key in keys:
            out[key] = value
    return out


def job_name(base: str, task_overrides: Iterable[str], group_choices: Mapping[str, str], multirun: bool,
             sweep_keys: Iterable[str] | None = None) -> str:
    """``base`` for a single run; in a sweep, ``base`` plus the job's values of the swept keys that ``base``
    does not already show (``model.width=8``), so two jobs of a sweep over a key that is not a config group
    get two names (and two folders).  ``sweep_keys`` None (unknown): every value override counts."""
    if not multirun:
        return base
    keys = None if sweep_keys is None else set(sweep_keys)
    parts = []
    for o in task_overrides:
        key, _, value = o.partition("=")
        key = key.lstrip("+~")
        # group choices (model=...) and the seed are in ``base`` already; paths say where, not what
        if key in group_choices or key in ("seed", "name") or key.endswith("_dir") or key.startswith(_PLACE_KEYS):
            continue
        if keys is None or key in keys:
            parts.append(f"{key}={value}")
    suffix = re.sub(r"[^A-Za-z0-9_.,=+-]", "_", ",".join(parts))
    return f"{base}-{suffix}" if suffix else base


def pipeline_outputs(root) -> dict[Path, str]:
    """Every ``outs`` path of the DVC pipeline in ``root/dvc.yaml`` (resolved) -> the stage that makes it, a
    ``foreach`` stage expanded as DVC names it (``train_best_seeds@1``); empty without a dvc.yaml."""
    import yaml

    f = Path(root) / "dvc.yaml"
    if not f.exists():
        return {}
    out: dict[Path, str] = {}
    for name, stage in ((yaml.safe_load(f.read_text()) or {}).get("stages") or {}).items():
        expanded = [(name, stage)] if "foreach" not in stage else [
            (f"{name}@{item}", yaml.safe_load(yaml.safe_dump(stage["do"]).replace("${item}", str(item))))
            for item in stage["foreach"]]
        for stage_name, body in expanded:
            for o in body.get("outs", []) or []:
                path = next(iter(o)) if isinstance(o, Mapping) else o
                out[(Path(root) / path).resolve()] = stage_name
    return out


def tracked_outputs(root) -> set[Path]:
    """Every ``outs`` path of the DVC pipeline in ``root/dvc.yaml`` (resolved), or nothing without one."""
    return set(pipeline_outputs(root))


def guard_tracked(path, root, multirun: bool) -> None:
    """Refuse to let a sweep job write a DVC-tracked output of the main pipeline (a single run may: that is
    how ``dvc repro`` makes it)."""
    if not multirun:
        return
    p = Path(path).resolve()
    for t in tracked_outputs(root):
        if p == t or t in p.parents or p in t.parents:
            raise ValueError(f"sweep job output {path} would overwrite {t}, an output of the DVC pipeline; "
                             "give the sweep its own out_dir (e.g. out_dir=multirun_models) or a distinct name")


# --- what a multirun says and leaves behind: where each job wrote, and one table of all jobs ----------------

#: set by ``SweepSummaryCallback.on_multirun_start`` in the launching process (jobs inherit it): the jobs
#: of this sweep, told apart from a former sweep's records in a reused ``hydra.sweep.dir``
SWEEP_ID_ENV = "FLUIDFILM_SWEEP_ID"
JOB_RECORD = "job_result.json"
SUMMARY_CSV = "summary.csv"


def _scalar_metrics(metrics) -> dict[str, float]:
    if not isinstance(metrics, Mapping):
        return {}
    return {str(k): float(v) for k, v in metrics.items()
            if isinstance(v, (int, float)) and not isinstance(v, bool)}


def write_job_record(job_dir, task_overrides: Iterable[str], metrics, outputs: Mapping[str, list[str]]) -> Path:
    """Record a finished sweep job in ``job_dir/job_result.json``: its overrides, its numeric metrics and
    the paths its output keys point at (atomic; the sweep's summary reads it).

    Parameters
    ----------
    job_dir : path
        The job's own Hydra output folder (``<sweep dir>/<job number>``).
    task_overrides : iterable of str
        The job's overrides, ``key=value``.
    metrics : mapping
        What the study returned; numbers (bools excluded) are kept.
    outputs : mapping
        Output key -> the path(s) it writes (after any redirection).

    Returns
    -------
    Path
        The record written.
    """
    import os

    from fluidfilm import io

    path = Path(job_dir) / JOB_RECORD
    io.write_json(path, {"sweep_id": os.environ.get(SWEEP_ID_ENV, ""), "job_dir": str(Path(job_dir).resolve()),
                         "overrides": list(task_overrides), "metrics": _scalar_metrics(metrics),
                         "outputs": {k: list(v) for k, v in outputs.items()}})
    return path


def read_job_records(sweep_dir, sweep_id: str | None = None) -> list[dict]:
    """The records of a sweep's jobs (``<sweep_dir>/<job>/job_result.json``), in job-number order; only
    those of ``sweep_id`` when given."""
    import json

    def order(p: Path):
        name = p.parent.name
        return (0, int(name), "") if name.isdigit() else (1, 0, name)

    records = []
    for f in sorted(Path(sweep_dir).glob(f"*/{JOB_RECORD}"), key=order):
        rec = json.loads(f.read_text())
        if sweep_id and rec.get("sweep_id") != sweep_id:
            continue
        rec["job"] = f.parent.name
        records.append(rec)
    return records


def summary_rows(records: Iterable[Mapping]) -> list[dict]:
    """One row per job: ``job``, each override's key as a column (its value), then each metric."""
    rows = []
    for rec in records:
        row: dict = {"job": rec["job"]}
        for o in rec.get("overrides", []):
            key, _, value = o.partition("=")
            row[key.lstrip("+~")] = re.sub(r"\\(.)", r"\1", value)  # Hydra's escapes (``\:``) undone
        row.update(rec.get("metrics", {}))
        rows.append(row)
    return rows


def write_summary_csv(records: list[dict], path) -> Path:
    """``summary_rows(records)`` as a CSV (columns: the union over jobs, in first-seen order; blank where a
    job lacks one), written atomically."""
    import csv
    import io as _io

    from fluidfilm import io

    rows = summary_rows(records)
    columns: list[str] = []
    for row in rows:
        columns += [c for c in row if c not in columns]
    buf = _io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({c: (repr(v) if isinstance(v, float) else v) for c, v in row.items()})
    io.write_text(path, buf.getvalue())
    return Path(path)


class SweepSummaryCallback:
    """Hydra callback (duck-typed, no Hydra import) that every entry point's multirun gets
    (``fluidfilm.workflow.entry`` adds it on the command line).

    ``on_multirun_start`` says where the jobs will write (``<sweep dir>/<job number>/``) and where the table
    will be; each job records its overrides, metrics and output paths (``write_job_record``);
    ``on_multirun_end`` prints each job's folder and outputs and writes ``<sweep dir>/summary.csv``, one row per
    job: its overrides and its metrics.
    """

    def __init__(self, **_):
        pass

    @staticmethod
    def _sweep_dir(config) -> Path:
        return Path(str(config.hydra.sweep.dir))

    def on_multirun_start(self, config, **kwargs):
        import os
        import uuid

        from fluidfilm.workflow.config_check import check_sweep

        check_sweep(config)  # every job's values, before any job starts
        os.environ[SWEEP_ID_ENV] = uuid.uuid4().hex
        sweep = self._sweep_dir(config)
        print(f"multirun: each job writes under {sweep}/<job number>/; the table of all jobs will be "
              f"{sweep / SUMMARY_CSV}", flush=True)

    def on_multirun_end(self, config, **kwargs):
        import os

        sweep = self._sweep_dir(config)
        records = read_job_records(sweep, os.environ.get(SWEEP_ID_ENV))
        for rec in records:
            outs = "; ".join(f"{k}={', '.join(v)}" for k, v in rec.get("outputs", {}).items() if v)
            print(f"  job {rec['job']}: {rec['job_dir']}" + (f" (outputs: {outs})" if outs else ""), flush=True)
        csv_path = write_summary_csv(records, sweep / SUMMARY_CSV)
        print(f"multirun: {len(records)} job(s) done; summary (overrides and metrics per job): {csv_path}",
              flush=True)

    # the other hooks Hydra calls
    def on_run_start(self, config, **kwargs): ...
    def on_run_end(self, config, **kwargs): ...
    def on_job_start(self, config, **kwargs): ...
    def on_job_end(self, config, job_return, **kwargs): ...
    def on_compose_config(self, config, **kwargs): ...
