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
