"""Refuse a mistyped or misspelt configuration before any work starts, naming the key.

Hydra already refuses an override of a key that does not exist (``model.widht=10``) and a config
group option that does not exist. Two mistakes get through it: a value of the wrong type
(``trainer.max_epochs=ten`` composes and fails deep inside training, or never) and a new key added
with ``+`` (``+model.widht=10`` is accepted and silently ignored). ``check_config`` catches both by
comparing the job's configuration with the *reference* one: the same primary config and the same
config-group choices, composed without the value overrides. Every key must exist in the reference,
and every value must have the reference's type (ints where ints were, numbers where numbers were,
mappings where mappings were; a reference value of ``null`` accepts anything).

Before that comparison every config group the job composed is checked against its schema
(``fluidfilm.workflow.config_schema``: one dataclass per group, registered in Hydra's ConfigStore here), so a
key or type is judged by a declared type, not only by the reference's value; the comparison still
covers the primary configs' own keys, which have no schema.

``compare`` is plain Python on nested mappings; ``check_config`` is the one function of the library
that asks Hydra for something (the reference composition), and imports it only when called, from an
entry point's ``main`` (where Hydra is running).
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any


class ConfigError(ValueError):
    """A configuration value of the wrong type or an unknown key; the message names them."""


def _type_name(v: Any) -> str:
    if isinstance(v, bool):
        return "bool"
    if isinstance(v, int):
        return "int"
    if isinstance(v, float):
        return "float"
    if isinstance(v, str):
        return "string"
    if isinstance(v, Mapping):
        return "mapping"
    if isinstance(v, (list, tuple)):
        return "list"
    return type(v).__name__


def _compatible(value: Any, ref: Any) -> bool:
    if ref is None or value is None:
        return True
    if isinstance(ref, bool):
        return isinstance(value, bool)
    if isinstance(ref, int):
        return isinstance(value, int) and not isinstance(value, bool)
    if isinstance(ref, float):  # an int is a valid float (e.g. t_end=1)
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if isinstance(ref, str):
        return isinstance(value, str)
    if isinstance(ref, Mapping):
        return isinstance(value, Mapping)
    if isinstance(ref, (list, tuple)):
        return isinstance(value, (list, tuple))
    return True


def compare(actual: Mapping, reference: Mapping, prefix: str = "") -> list[str]:
    """Problems of ``actual`` against ``reference``: unknown keys and values of another type."""
    problems = []
    for key, value in actual.items():
        path = f"{prefix}{key}"
        if key not in reference:
            known = ", ".join(sorted(map(str, reference))[:12])
            problems.append(f"unknown key '{path}' (not in the configuration; keys here: {known})")
            continue
        ref = reference[key]
        if isinstance(value, str) and "${" in value:  # an interpolation: checked when it resolves
            continue
        if not _compatible(value, ref):
            problems.append(f"'{path}={value!r}': expected {_type_name(ref)} (like the default {ref!r}), "
                            f"got {_type_name(value)}")
        elif isinstance(value, Mapping) and isinstance(ref, Mapping) and ref:
            problems.extend(compare(value, ref, path + "."))
    return problems


def register_schemas() -> None:
    """Put every group's schema in Hydra's ConfigStore, as ``fluidfilm_schema/<group>: <Schema>``
    (what a structured-config user composes or extends; the YAML in conf/ keeps the values)."""
    from hydra.core.config_store import ConfigStore

    from fluidfilm.workflow.config_schema import GROUPS

    cs = ConfigStore.instance()
    for group, entry in GROUPS.items():
        schemas = [entry] if isinstance(entry, type) else list(entry[1].values())
        for schema in schemas:
            cs.store(group=f"fluidfilm_schema/{group}", name=schema.__name__, node=schema)


def schema_problems(cfg, choices: Mapping[str, Any]) -> list[str]:
    """Each composed group of ``cfg`` (``choices``: Hydra's ``group[@package] -> option``) against its schema."""
    from omegaconf import OmegaConf

    from fluidfilm.workflow.config_schema import SchemaError, validate_group

    problems = []
    for choice, option in choices.items():
        group, _, package = choice.partition("@")
        if option is None or group.startswith("hydra"):
            continue
        where = package or group.replace("/", ".")
        node = OmegaConf.select(cfg, where, throw_on_missing=False)
        if node is None:
            continue
        try:
            validate_group(group, OmegaConf.to_container(node, resolve=False), where)
        except SchemaError as err:
            problems.append(f"{err} ({choice}={option})")
    return problems


def check_config(cfg, exit_on_error: bool = True) -> None:
    """Check the running Hydra job's config; every unknown key and mistyped value is named.

    From an entry point (``exit_on_error``): one line on stderr and exit status 2, as for a bad
    command-line option (a traceback would bury the one line that matters). Otherwise ``ConfigError``.
    """
    from hydra import compose
    from hydra.core.hydra_config import HydraConfig
    from omegaconf import OmegaConf

    register_schemas()
    hc = HydraConfig.get()
    problems = schema_problems(cfg, hc.runtime.choices)
    choices = set(hc.runtime.choices)
    group_overrides = []
    for ov in hc.overrides.task:
        key = ov.split("=", 1)[0].lstrip("+~")
        if key in choices:
            group_overrides.append(ov)
    reference = compose(config_name=hc.job.config_name, overrides=group_overrides)
    actual = OmegaConf.to_container(cfg, resolve=False)
    ref = OmegaConf.to_container(reference, resolve=False)
    assert isinstance(actual, dict) and isinstance(ref, dict)
    actual.pop("hydra", None)
    ref.pop("hydra", None)
    if not problems:  # the schema's message is the more precise one where both see a mistake
        problems = compare(actual, ref)
    if problems:
        message = "configuration refused before any work: " + "; ".join(problems)
        if exit_on_error:
            import sys

            print(f"error: {message}", file=sys.stderr, flush=True)
            raise SystemExit(2)
        raise ConfigError(message)


def sweep_job_overrides(config) -> list[list[str]] | None:
    """Every job's overrides of the multirun ``config`` (Hydra's own expansion, ``BasicSweeper``), or ``None``
    where another sweeper decides the jobs as it goes (an optimiser)."""
    from hydra._internal.core_plugins.basic_sweeper import BasicSweeper
    from hydra.core.override_parser.overrides_parser import OverridesParser

    target = str(config.hydra.sweeper.get("_target_", ""))
    if not target.endswith("BasicSweeper"):
        return None
    overrides = OverridesParser.create().parse_overrides(list(config.hydra.overrides.task))
    return [list(job) for batch in BasicSweeper.split_arguments(overrides, None) for job in batch]


def check_sweep(config) -> None:
    """Before a multirun starts anything (its MLflow parent run included): each job's config against the
    schemas (types, unknown keys, ranges); the first bad job's problems in one line on stderr, exit status 2.

    Called from the sweep callbacks' ``on_multirun_start`` (``tracking.MlflowSweepCallback``,
    ``sweeps.SweepSummaryCallback``), while Hydra is initialised; once per multirun."""
    import os
    import sys

    from hydra import compose

    marker = f"{os.getpid()}:{config.hydra.sweep.dir}"  # both callbacks call it: the second one skips
    if os.environ.get(_SWEEP_CHECKED_ENV) == marker:
        return
    os.environ[_SWEEP_CHECKED_ENV] = marker
    register_schemas()
    jobs = sweep_job_overrides(config) or []
    for job in jobs:
        cfg = compose(config_name=config.hydra.job.config_name, overrides=job, return_hydra_config=True)
        problems = schema_problems(cfg, cfg.hydra.runtime.choices)
        if problems:
            print("error: configuration refused before any work: " + "; ".join(problems) +
                  f" (sweep job: {' '.join(job)})", file=sys.stderr, flush=True)
            raise SystemExit(2)


_SWEEP_CHECKED_ENV = "FLUIDFILM_SWEEP_CHECKED"
