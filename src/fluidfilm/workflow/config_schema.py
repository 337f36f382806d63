"""The schema of every config group in conf/: field names and types, no values.

One plain dataclass per group (two where a group's options have different shapes: the journal and
the conical bearing, the two training protocols). The YAML files in conf/ stay the one place where
values live: every field here is required (``MISSING``, OmegaConf's ``???``) or, where an option
leaves a key out, marked ``optional`` in its metadata; none carries a default.

``validate_group(group, node)`` merges a composed group into its schema with OmegaConf
(``OmegaConf.merge(OmegaConf.structured(schema), node)``): a value that cannot be the field's type
(``trainer.max_epochs=ten``) or a key the schema lacks (``+model.widht=10``) raises, and the
message names the key. ``config_check.check_config`` (the first call of every entry point) runs it
on each group the job composed and registers the schemas in Hydra's ConfigStore; this module
imports no Hydra.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields, is_dataclass, make_dataclass
from typing import Any, Optional, get_type_hints

from fluidfilm.core import bearing as core_bearing

#: OmegaConf's marker of a value that must be given (the same string as ``omegaconf.MISSING``)
MISSING: Any = "???"


def optional() -> Any:
    """A key that some options of the group leave out (the code has the fallback)."""
    return field(default=MISSING, metadata={"optional": True})


# --- bearing -----------------------------------------------------------------------------------
def _bearing_schema(cls: type, kind_required: bool) -> type:
    """The bearing group's schema derived from the library's dataclass (its fields and type annotations,
    written once in ``core/bearing.py``), plus the config's ``name`` and ``kind``.  Every field is
    required in the YAML, also those with a default in the dataclass (the YAML is the one place of
    values); ``validate_group`` then runs the dataclass's own checks on the values."""
    hints = get_type_hints(cls)
    specs: list[Any] = [("name", str, field(default=MISSING))]
    specs += [(f.name, hints[f.name], field(default=MISSING)) for f in fields(cls)]
    specs.append(("kind", str, field(default=MISSING) if kind_required else optional()))
    return make_dataclass(f"{cls.__name__}Schema", specs)


JournalBearingSchema = _bearing_schema(core_bearing.JournalBearing, kind_required=False)  # kind "journal" if given
ConicalBearingSchema = _bearing_schema(core_bearing.ConicalBearing, kind_required=True)   # kind: "conical"
#: the group whose values the library's own dataclass checks too (bearing_from_dict)
_BUILDERS = {"bearing": core_bearing.bearing_from_dict}


# --- the Reynolds reference -----------------------------------------------------------------------
@dataclass
class SolverSchema:
    n_theta: int = MISSING
    n_z: int = MISSING
    cavitation: str = MISSING


@dataclass
class ReferenceSchema:
    coarse: list[int] = MISSING
    dense: list[int] = MISSING
    eps_threshold: float = MISSING
    cavitation: str = MISSING


# --- dataset -------------------------------------------------------------------------------------
@dataclass
class PositionSection:
    name: str = MISSING
    eps_start: float = MISSING
    eps_stop: float = MISSING
    endpoint: bool = MISSING
    n_eps: int = MISSING
    n_angle: int = MISSING


@dataclass
class VelocitySection:
    eps_low: float = MISSING
    eps_high: float = MISSING
    v_max: float = MISSING
    core: float = MISSING
    core_fraction: float = MISSING
    n_per_side: int = MISSING
    include_zero: bool = optional()


@dataclass
class DatasetSchema:
    name: str = MISSING
    position_sections: list[PositionSection] = MISSING
    velocity_sections: list[VelocitySection] = MISSING
    combine: str = MISSING
    positions_per_chunk: int = MISSING
    n_test: int = MISSING
    test_seed: int = MISSING
    sleeve_positions: list[float] = optional()   # the active bearing's extra input


@dataclass
class DaskSchema:
    scheduler: str = MISSING
    n_workers: Optional[int] = MISSING


# --- surrogate training ---------------------------------------------------------------------------
@dataclass
class ModelSchema:
    width: int = MISSING
    depth: int = MISSING
    activation: str = MISSING
    optimizer: str = MISSING
    lr: float = MISSING
    weight_decay: float = MISSING
    scheduler: str = MISSING
    structure: str = optional()


@dataclass
class ScalingSchema:
    kind: str = MISSING
    power: float = MISSING
    frame: str = optional()


@dataclass
class SplitSchema:
    boundaries: list[float] = MISSING
    blend_width: float = MISSING


@dataclass
class TrainerSchema:
    max_epochs: int = MISSING
    max_time: Optional[str] = MISSING
    batch_size: int = MISSING
    val_fraction: float = MISSING
    target_val_rel_rmse: Optional[float] = MISSING
    accelerator: str = MISSING
    progress_bar: bool = MISSING
    workers: Optional[int] = MISSING


@dataclass
class _ProtocolSchema:
    """What both training protocols share: the division, the stopping rule, the threads."""

    name: str = MISSING
    fractions: list[float] = MISSING
    max_fail: int = MISSING
    max_epochs: int = MISSING
    max_time_s: Optional[float] = MISSING
    threads: int = MISSING


@dataclass
class PaperProtocolSchema(_ProtocolSchema):
    min_grad: float = MISSING
    chunk: int = MISSING
    workers: Optional[int] = MISSING
    device: Optional[str] = MISSING
    progress_every_s: Optional[float] = MISSING


@dataclass
class AdamProtocolSchema(_ProtocolSchema):
    lr: float = MISSING
    batch_size: int = MISSING


# --- rotor and its runs ---------------------------------------------------------------------------
@dataclass
class RotorSchema:
    mass: float = MISSING
    load_share: float = MISSING
    gravity: float = MISSING
    imbalance_direction: int = MISSING


@dataclass
class IntegratorSchema:
    dt: float = MISSING
    t_end: float = MISSING
    t_settle: float = MISSING
    eps_stop: float = MISSING
    eps_substep: float = MISSING
    record_every: int = MISSING


@dataclass
class CaseSchema:
    name: str = MISSING
    label: str = MISSING
    imbalance: float = MISSING
    external_force: list[float] = MISSING


@dataclass
class MetricsSchema:
    threshold_pct: float = MISSING


@dataclass
class TrackingSchema:
    uri: str = MISSING
    experiment: str = MISSING
    enabled: bool = MISSING


# --- controller ------------------------------------------------------------------------------------
@dataclass
class ScenarioSchema:
    imbalance_start: float = MISSING
    imbalance_end: float = MISSING
    ramp_time: float = MISSING
    t_end: float = MISSING
    control_interval: float = MISSING
    settle_time: float = MISSING
    dt: float = MISSING
    record_every: int = MISSING
    eps_stop: float = MISSING
    initial_action: Optional[int] = MISSING


@dataclass
class RewardSchema:
    amplitude_ref: float = MISSING
    friction: float = MISSING
    move: float = MISSING
    contact_penalty: float = MISSING


@dataclass
class DQNSchema:
    total_timesteps: int = MISSING
    n_envs: int = MISSING
    learning_rate: float = MISSING
    buffer_size: int = MISSING
    learning_starts: int = MISSING
    batch_size: int = MISSING
    gamma: float = MISSING
    train_freq: int = MISSING
    gradient_steps: int = MISSING
    target_update_interval: int = MISSING
    exploration_fraction: float = MISSING
    exploration_final_eps: float = MISSING
    net_arch: list[int] = MISSING
    torch_threads: int = MISSING


@dataclass
class MPCSchema:
    horizon_intervals: float = MISSING
    dt: float = MISSING
    eps_substep: float = MISSING
    record_every: int = MISSING


@dataclass
class ControllerSchema:
    sleeve_positions: list[float] = MISSING
    scenario: ScenarioSchema = field(default_factory=ScenarioSchema)
    reward: RewardSchema = field(default_factory=RewardSchema)
    dqn: DQNSchema = field(default_factory=DQNSchema)
    mpc: MPCSchema = field(default_factory=MPCSchema)
    seed: int = MISSING


# --- characteristics study ---------------------------------------------------------------------------
@dataclass
class StaticSchema:
    grid: list[int] = MISSING
    cavitation: list[str] = MISSING
    feeds: list[str] = MISSING
    eps: list[float] = MISSING


@dataclass
class ShortBearingSchema:
    l_over_d: float = MISSING
    grid: list[int] = MISSING
    eps: list[float] = MISSING


@dataclass
class ThresholdSchema:
    speed_bracket: list[float] = MISSING


@dataclass
class NonlinearSchema:
    factors: list[float] = MISSING
    grid: list[int] = MISSING
    n_periods: int = MISSING
    perturbation: float = MISSING


@dataclass
class CharacteristicsSchema:
    reference_grid: list[int] = MISSING
    converged_grid: list[int] = MISSING
    kc_eps: list[float] = MISSING
    h_rel_reference: float = MISSING
    step_study_eps: float = MISSING
    step_study_steps: list[float] = MISSING
    static: StaticSchema = field(default_factory=StaticSchema)
    raimondi_boyd_grid: list[int] = MISSING
    lund_thomsen_grid: list[int] = MISSING
    short_bearing: ShortBearingSchema = field(default_factory=ShortBearingSchema)
    threshold: ThresholdSchema = field(default_factory=ThresholdSchema)
    nonlinear: NonlinearSchema = field(default_factory=NonlinearSchema)
    timing_repeats: int = MISSING


# --- run-up study ------------------------------------------------------------------------------------
@dataclass
class RunupSchema:
    grid: list[int] = MISSING
    cavitation: str = MISSING
    speed_bracket: list[float] = MISSING
    mass: float = MISSING
    gravity: float = MISSING
    imbalance: float = MISSING
    perturbation: float = MISSING
    start: float = MISSING
    top: float = MISSING
    end: float = MISSING
    rate_rpm_s: float = MISSING
    hold_s: float = MISSING
    dt: float = MISSING
    record_every: int = MISSING
    samples_per_rev: int = MISSING
    window_revs: int = MISSING
    hop_revs: int = MISSING
    band: list[float] = MISSING
    max_order: float = MISSING
    whirl_level: float = MISSING
    onset_fit_nepers: float = MISSING
    rate_check_factor: Optional[float] = MISSING
    imbalance_check: Optional[float] = MISSING


@dataclass
class CavitationRunupSchema:
    length: float = MISSING
    diameter: float = MISSING
    clearance: float = MISSING
    viscosity: float = MISSING
    supply_pressure: float = MISSING
    mass: float = MISSING
    imbalance: float = MISSING
    f_start_hz: float = MISSING
    f_end_hz: float = MISSING
    duration_s: float = MISSING
    grid: list[int] = MISSING
    dt: float = MISSING
    record_every: int = MISSING
    samples_per_rev: int = MISSING
    window_revs: int = MISSING
    hop_revs: int = MISSING
    band: list[float] = MISSING
    whirl_level: float = MISSING
    onset_fit_nepers: float = MISSING
    limit_cycle_window_s: float = MISSING


@dataclass
class DamperSchema:
    supply_pressure: float = MISSING
    eps: float = MISSING
    whirl_hz: float = MISSING
    revolutions: int = MISSING
    steps_per_rev: int = MISSING


@dataclass
class CavitationRulesSchema:
    grid: list[int] = MISSING
    check_grid: list[int] = MISSING
    check_case: str = MISSING
    groove_angle_deg: float = MISSING
    tol: float = MISSING
    tol_commit: float = MISSING
    cases: list[str] = MISSING
    t_end: float = MISSING
    t_settle: float = MISSING
    dt: float = MISSING
    record_every: int = MISSING
    threshold_pct: float = MISSING
    threshold_mass: float = MISSING
    speed_bracket: list[float] = MISSING
    workers: int = MISSING
    runup: CavitationRunupSchema = MISSING
    damper: DamperSchema = MISSING
    ausas_nodes: int = MISSING
    ausas_dt: float = MISSING
    balance_steps: int = MISSING
    cost_steps: int = MISSING
    cost_repeats: int = MISSING


#: group -> schema, or -> (key, {value of key: schema}) where the options differ in shape
GROUPS: dict[str, Any] = {
    "bearing": ("kind", {"journal": JournalBearingSchema, "conical": ConicalBearingSchema}),
    "solver": SolverSchema,
    "reference": ReferenceSchema,
    "dataset": DatasetSchema,
    "dask": DaskSchema,
    "model": ModelSchema,
    "scaling": ScalingSchema,
    "split": SplitSchema,
    "trainer": TrainerSchema,
    "protocol": ("name", {"paper": PaperProtocolSchema, "adam": AdamProtocolSchema}),
    "rotor": RotorSchema,
    "integrator": IntegratorSchema,
    "case": CaseSchema,
    "metrics": MetricsSchema,
    "tracking": TrackingSchema,
    "controller": ControllerSchema,
    "characteristics": CharacteristicsSchema,
    "runup": RunupSchema,
    "cavitation_rules": CavitationRulesSchema,
}
#: the value of the selecting key when an option leaves it out
_SELECTOR_FALLBACK = {"bearing": "journal"}


class SchemaError(ValueError):
    """A group's value of the wrong type, an unknown key or a required key left out; the message names it."""


def schema_for(group: str, node: Any) -> Any:
    """The dataclass that describes ``node`` (a composed option of ``group``), ``None`` for a group
    without a schema (Hydra's own, ``experiment``, whose values land in other groups)."""
    entry = GROUPS.get(group)
    if entry is None or is_dataclass(entry):
        return entry
    key, by_value = entry
    value = node.get(key, _SELECTOR_FALLBACK.get(group)) if isinstance(node, Mapping) else None
    if value not in by_value:
        raise SchemaError(f"{group}.{key}={value!r}: expected one of {sorted(by_value)}")
    return by_value[value]


def _required_missing(schema: Any, merged: Any, prefix: str) -> list[str]:
    out = []
    for f in fields(schema):
        value = merged._get_node(f.name)
        if is_dataclass(f.type) or (isinstance(f.type, str) and f.type in _BY_NAME):
            sub = _BY_NAME[f.type] if isinstance(f.type, str) else f.type
            out += _required_missing(sub, merged[f.name], f"{prefix}{f.name}.")
        elif value is not None and value._is_missing() and not f.metadata.get("optional"):
            out.append(f"{prefix}{f.name}")
    return out


def validate_group(group: str, node: Any, where: str | None = None) -> Any:
    """``node`` (a mapping or DictConfig, interpolations unresolved) checked against its group's schema.

    Returns the typed, merged config (or ``None`` for a group without a schema); raises
    ``SchemaError`` naming the key ``where.key`` (``where`` defaults to the group: the package the
    option was composed into, e.g. ``cases.a`` for ``case@cases.a``).
    """
    from omegaconf import OmegaConf
    from omegaconf.errors import OmegaConfBaseException

    where = group if where is None else where
    schema = schema_for(group, node)
    if schema is None:
        return None
    try:
        merged = OmegaConf.merge(OmegaConf.structured(schema), node)
    except OmegaConfBaseException as err:
        key = err.full_key  # the dotted key inside the group, set by OmegaConf
        detail = str(err).splitlines()[0]
        raise SchemaError(f"'{where}.{key}': {detail}" if key else f"'{where}': {detail}") from None
    missing = _required_missing(schema, merged, where + ".")
    if missing:
        raise SchemaError(f"required key(s) left out: {', '.join(missing)}")
    build = _BUILDERS.get(group)
    if build is not None and not _has_interpolation(merged):
        # the same validation as the library's: a bearing the dataclass refuses is refused here, before any work
        try:
            values = OmegaConf.to_container(merged)
            assert isinstance(values, dict)  # a group's node is a mapping
            build({k: v for k, v in values.items() if v != MISSING})  # an optional key left out: the fallback
        except ValueError as err:
            raise SchemaError(f"'{where}': {err}") from None
    return merged


def _has_interpolation(cfg: Any) -> bool:
    from omegaconf import OmegaConf

    return any(OmegaConf.is_interpolation(cfg, k) for k in cfg)


_BY_NAME = {name: obj for name, obj in dict(globals()).items() if isinstance(obj, type) and is_dataclass(obj)}
