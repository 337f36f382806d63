"""The schema of every config group in conf/: field names and types, no values.

One plain dataclass per group (two where a group's options have different shapes: the journal and
the conical bearing, the two training protocols). The YAML files in conf/ stay the one place where
values live: every field here is required (``MISSING``, OmegaConf's ``???``) or, where an option
leaves a key out, marked ``optional`` in its metadata; none carries a default.

``validate_group(group, node)`` merges a composed group into its schema with OmegaConf
(``OmegaConf.merge(OmegaConf.structured(schema), node)``): a value that cannot be the field's type
(``trainer.max_epochs=ten``) or a key the schema lacks (``+model.widht=10``) raises, and the
message names the key.  A field may also declare the values it admits (``ranged``: bounds, or a set of
names taken from the library, e.g. the solver's cavitation rules and its minimum grid); a value outside
them (``solver.n_theta=2``, ``solver.cavitation=gumble``, ``rotor.mass=-5``) is refused the same way,
naming the key and the value. ``config_check.check_config`` (the first call of every entry point) runs it
on each group the job composed and registers the schemas in Hydra's ConfigStore; this module
imports no Hydra.
"""
from __future__ import annotations

from collections.abc import Mapping
import math
from dataclasses import dataclass, field, fields, is_dataclass, make_dataclass
from dataclasses import replace as dataclass_replace
from typing import Any, Optional, get_type_hints

from fluidfilm.core import bearing as core_bearing
from fluidfilm.reynolds.mesh import MIN_N_THETA, MIN_N_Z
from fluidfilm.reynolds.solver import CAVITATION_MODELS
from fluidfilm.surrogate.scaling import FRAMES, SCALINGS

#: OmegaConf's marker of a value that must be given (the same string as ``omegaconf.MISSING``)
MISSING: Any = "???"


def optional() -> Any:
    """A key that some options of the group leave out (the code has the fallback)."""
    return field(default=MISSING, metadata={"optional": True})


@dataclass(frozen=True)
class Range:
    """The values a config field admits: bounds (``ge``/``gt``/``le``/``lt``) or a set of names
    (``choices``); ``each``: the bounds hold for every element of a list; ``grid``: a list
    ``[n_theta, n_z]`` of the Reynolds solver's grid sizes (each at least the scheme's minimum)."""

    ge: float | None = None
    gt: float | None = None
    le: float | None = None
    lt: float | None = None
    choices: tuple | None = None
    each: bool = False
    grid: bool = False
    why: str = ""

    def problem(self, value: Any) -> str | None:
        """What is wrong with ``value`` (``None``: nothing; ``None`` values are the type check's business)."""
        if value is None:
            return None
        if self.grid:
            if not isinstance(value, (list, tuple)) or len(value) != 2:
                return "must be a grid [n_theta, n_z]"
            lows = (MIN_N_THETA, MIN_N_Z)
            for name, v, lo in zip(("n_theta", "n_z"), value, lows):
                if v < lo:
                    return f"{name}={v} is below the scheme's minimum {lo}"
            return None
        if self.each and isinstance(value, (list, tuple)):
            for i, v in enumerate(value):
                bad = dataclass_replace(self, each=False).problem(v)
                if bad:
                    return f"element {i} ({v!r}) {bad}"
            return None
        if self.choices is not None:
            return None if value in self.choices else f"must be one of {', '.join(map(str, self.choices))}"
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return None  # the type check names it
        if not math.isfinite(value):
            return "must be a finite number"
        for op, bound, text in (("ge", self.ge, ">="), ("gt", self.gt, ">"), ("le", self.le, "<="),
                                ("lt", self.lt, "<")):
            if bound is None:
                continue
            ok = {"ge": value >= bound, "gt": value > bound, "le": value <= bound, "lt": value < bound}[op]
            if not ok:
                return f"must be {text} {bound:g}" + (f" ({self.why})" if self.why else "")
        return None


def ranged(*, optional_key: bool = False, **bounds: Any) -> Any:
    """A required field (or ``optional_key``) whose values are limited by ``Range(**bounds)``."""
    return field(default=MISSING, metadata={"optional": optional_key, "range": Range(**bounds)})


#: the values the library admits, read from it (one place of truth) where it says them without heavy imports
_CAVITATION = tuple(CAVITATION_MODELS)
_POS: dict[str, Any] = {"gt": 0}                      # a positive physical quantity
_COUNT: dict[str, Any] = {"ge": 1}                    # a count
_FRACTION: dict[str, Any] = {"ge": 0, "le": 1}
_ECC: dict[str, Any] = {"ge": 0, "lt": 1, "why": "an eccentricity, 0 <= eps < 1"}


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


#: the training's names (``surrogate.training`` imports torch, so they are written here; a test holds them equal)
MODEL_ACTIVATIONS = ("tanh", "relu", "silu", "sigmoid")
MODEL_OPTIMIZERS = ("adam", "adamw", "sgd")
MODEL_SCHEDULERS = ("none", "cosine", "plateau")
MODEL_STRUCTURES = ("plain", "damping")


# --- the Reynolds reference -----------------------------------------------------------------------
@dataclass
class SolverSchema:
    n_theta: int = ranged(ge=MIN_N_THETA, why="the scheme's minimum")
    n_z: int = ranged(ge=MIN_N_Z, why="the scheme's minimum")
    cavitation: str = ranged(choices=_CAVITATION)


@dataclass
class ReferenceSchema:
    coarse: list[int] = ranged(grid=True)
    dense: list[int] = ranged(grid=True)
    eps_threshold: float = ranged(**_ECC)
    cavitation: str = ranged(choices=_CAVITATION)


# --- dataset -------------------------------------------------------------------------------------
@dataclass
class PositionSection:
    name: str = MISSING
    eps_start: float = ranged(**_ECC)
    eps_stop: float = ranged(**_ECC)
    endpoint: bool = MISSING
    n_eps: int = ranged(**_COUNT)
    n_angle: int = ranged(**_COUNT)


@dataclass
class VelocitySection:
    eps_low: float = ranged(ge=0, le=1)
    eps_high: float = ranged(gt=0, le=1)
    v_max: float = ranged(**_POS)
    core: float = ranged(**_POS)
    core_fraction: float = ranged(**_FRACTION)
    n_per_side: int = ranged(**_COUNT)
    include_zero: bool = optional()


@dataclass
class DatasetSchema:
    name: str = MISSING
    position_sections: list[PositionSection] = MISSING
    velocity_sections: list[VelocitySection] = MISSING
    combine: str = ranged(choices=("product", "zip"))
    positions_per_chunk: int = ranged(**_COUNT)
    n_test: int = ranged(ge=0)
    test_seed: int = ranged(ge=0)
    sleeve_positions: list[float] = optional()   # the active bearing's extra input


@dataclass
class DaskSchema:
    scheduler: str = MISSING
    n_workers: Optional[int] = ranged(**_COUNT)


# --- surrogate training ---------------------------------------------------------------------------
@dataclass
class ModelSchema:
    width: int = ranged(**_COUNT)
    depth: int = ranged(**_COUNT)
    activation: str = ranged(choices=MODEL_ACTIVATIONS)
    optimizer: str = ranged(choices=MODEL_OPTIMIZERS)
    lr: float = ranged(**_POS)
    weight_decay: float = ranged(ge=0)
    scheduler: str = ranged(choices=MODEL_SCHEDULERS)
    structure: str = ranged(choices=MODEL_STRUCTURES, optional_key=True)


@dataclass
class ScalingSchema:
    kind: str = ranged(choices=tuple(SCALINGS))
    power: float = MISSING
    frame: str = ranged(choices=tuple(FRAMES), optional_key=True)


@dataclass
class SplitSchema:
    boundaries: list[float] = ranged(gt=0, lt=1, each=True, why="an eccentricity between 0 and 1")
    blend_width: float = ranged(ge=0)


@dataclass
class TrainerSchema:
    max_epochs: int = ranged(**_COUNT)
    max_time: Optional[str] = MISSING
    batch_size: int = ranged(**_COUNT)
    val_fraction: float = ranged(gt=0, lt=1)
    target_val_rel_rmse: Optional[float] = ranged(**_POS)
    accelerator: str = MISSING
    progress_bar: bool = MISSING
    workers: Optional[int] = ranged(**_COUNT)


@dataclass
class _ProtocolSchema:
    """What both training protocols share: the division, the stopping rule, the threads."""

    name: str = MISSING
    fractions: list[float] = ranged(each=True, **_FRACTION)
    max_fail: int = ranged(**_COUNT)
    max_epochs: int = ranged(**_COUNT)
    max_time_s: Optional[float] = ranged(**_POS)
    threads: int = ranged(**_COUNT)


@dataclass
class PaperProtocolSchema(_ProtocolSchema):
    min_grad: float = ranged(ge=0)
    chunk: int = ranged(**_COUNT)
    workers: Optional[int] = ranged(**_COUNT)
    device: Optional[str] = MISSING
    progress_every_s: Optional[float] = MISSING


@dataclass
class AdamProtocolSchema(_ProtocolSchema):
    lr: float = ranged(**_POS)
    batch_size: int = ranged(**_COUNT)


# --- rotor and its runs ---------------------------------------------------------------------------
@dataclass
class RotorSchema:
    mass: float = ranged(**_POS)
    load_share: float = ranged(gt=0, le=1)
    gravity: float = MISSING
    imbalance_direction: int = ranged(choices=(1, -1))


@dataclass
class IntegratorSchema:
    dt: float = ranged(**_POS)
    t_end: float = ranged(**_POS)
    t_settle: float = ranged(ge=0)
    eps_stop: float = ranged(gt=0, lt=1, why="an eccentricity")
    eps_substep: float = ranged(gt=0, lt=1, why="an eccentricity")
    record_every: int = ranged(**_COUNT)


@dataclass
class CaseSchema:
    name: str = MISSING
    label: str = MISSING
    imbalance: float = ranged(ge=0)
    external_force: list[float] = MISSING


@dataclass
class MetricsSchema:
    threshold_pct: float = ranged(**_POS)


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
    ramp_time: float = ranged(ge=0)
    t_end: float = ranged(**_POS)
    control_interval: float = ranged(**_POS)
    settle_time: float = MISSING
    dt: float = ranged(**_POS)
    record_every: int = ranged(**_COUNT)
    eps_stop: float = ranged(gt=0, lt=1, why="an eccentricity")
    initial_action: Optional[int] = MISSING


@dataclass
class RewardSchema:
    amplitude_ref: float = MISSING
    friction: float = MISSING
    move: float = MISSING
    contact_penalty: float = MISSING


@dataclass
class DQNSchema:
    total_timesteps: int = ranged(**_COUNT)
    n_envs: int = ranged(**_COUNT)
    learning_rate: float = ranged(**_POS)
    buffer_size: int = ranged(**_COUNT)
    learning_starts: int = MISSING
    batch_size: int = ranged(**_COUNT)
    gamma: float = ranged(**_FRACTION)
    train_freq: int = MISSING
    gradient_steps: int = MISSING
    target_update_interval: int = MISSING
    exploration_fraction: float = MISSING
    exploration_final_eps: float = MISSING
    net_arch: list[int] = MISSING
    torch_threads: int = ranged(**_COUNT)


@dataclass
class MPCSchema:
    horizon_intervals: float = MISSING
    dt: float = ranged(**_POS)
    eps_substep: float = MISSING
    record_every: int = ranged(**_COUNT)


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
    grid: list[int] = ranged(grid=True)
    cavitation: list[str] = ranged(choices=_CAVITATION, each=True)
    feeds: list[str] = MISSING
    eps: list[float] = ranged(each=True, **_ECC)


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
    reference_grid: list[int] = ranged(grid=True)
    converged_grid: list[int] = ranged(grid=True)
    kc_eps: list[float] = ranged(each=True, **_ECC)
    h_rel_reference: float = MISSING
    step_study_eps: float = MISSING
    step_study_steps: list[float] = MISSING
    static: StaticSchema = field(default_factory=StaticSchema)
    raimondi_boyd_grid: list[int] = MISSING
    lund_thomsen_grid: list[int] = MISSING
    short_bearing: ShortBearingSchema = field(default_factory=ShortBearingSchema)
    threshold: ThresholdSchema = field(default_factory=ThresholdSchema)
    nonlinear: NonlinearSchema = field(default_factory=NonlinearSchema)
    timing_repeats: int = ranged(**_COUNT)


# --- run-up study ------------------------------------------------------------------------------------
@dataclass
class RunupSchema:
    grid: list[int] = ranged(grid=True)
    cavitation: str = ranged(choices=_CAVITATION)
    speed_bracket: list[float] = MISSING
    mass: float = ranged(**_POS)
    gravity: float = MISSING
    imbalance: float = MISSING
    perturbation: float = MISSING
    start: float = MISSING
    top: float = MISSING
    end: float = MISSING
    rate_rpm_s: float = MISSING
    hold_s: float = MISSING
    dt: float = ranged(**_POS)
    record_every: int = ranged(**_COUNT)
    samples_per_rev: int = ranged(**_COUNT)
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


@dataclass
class JfoRangesSchema:
    mass: list[float] = MISSING
    imbalance: list[float] = MISSING
    force_max: float = ranged(ge=0)
    eps0_max: float = ranged(**_ECC)


@dataclass
class JfoFitSchema:
    width: int = ranged(**_COUNT)
    depth: int = ranged(**_COUNT)
    activation: str = ranged(choices=MODEL_ACTIVATIONS)
    gain_power: float = ranged(ge=0)
    lr: float = ranged(**_POS)
    weight_decay: float = ranged(ge=0)
    batch_size: int = ranged(**_COUNT)
    max_epochs: int = ranged(**_COUNT)


@dataclass
class JfoSurrogateSchema:
    grid: list[int] = ranged(grid=True)
    groove_angle_deg: float = MISSING
    tol: float = ranged(**_POS)
    tol_commit: float = ranged(**_POS)
    n_paths: int = ranged(ge=2, why="one path at least for training and one for validation")
    n_static_paths: int = ranged(ge=0)
    n_rest_states: int = ranged(ge=0)
    rest_eps_max: float = ranged(**_ECC)
    rest_weight: int = ranged(ge=0)
    seed: int = MISSING
    other_seeds: list[int] = MISSING
    ranges: JfoRangesSchema = MISSING
    path_t_end: float = ranged(**_POS)
    cache_dir: str = MISSING
    val_fraction: float = ranged(gt=0, lt=1)
    lag_dt: float = ranged(**_POS)
    n_lags: int = ranged(**_COUNT)
    fit: JfoFitSchema = MISSING
    cases: list[str] = MISSING
    t_end: float = ranged(**_POS)
    t_settle: float = ranged(ge=0)
    dt: float = ranged(**_POS)
    record_every: int = ranged(**_COUNT)
    threshold_pct: float = ranged(**_POS)
    timing_repeats: int = ranged(**_COUNT)
    timing_t_end: float = ranged(**_POS)
    workers: int = ranged(**_COUNT)


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
    "jfo_surrogate": JfoSurrogateSchema,
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


def _sub_schema(f: Any) -> Any:
    """The dataclass a field holds (``scenario: ScenarioSchema``), or the element's of a list of them."""
    t = f.type
    if isinstance(t, str):
        inner = t[len("list["):-1] if t.startswith("list[") else t
        return _BY_NAME.get(inner), t.startswith("list[")
    return (t, False) if is_dataclass(t) else (None, False)


def _out_of_range(schema: Any, merged: Any, prefix: str) -> list[str]:
    """``'key=value': why`` for every value of ``merged`` outside its field's ``Range`` (interpolations,
    resolved later, and keys an option leaves out are skipped)."""
    from omegaconf import OmegaConf

    out = []
    for f in fields(schema):
        node = merged._get_node(f.name)
        if node is None or node._is_missing() or OmegaConf.is_interpolation(merged, f.name):
            continue
        sub, is_list = _sub_schema(f)
        if sub is not None:
            items = list(enumerate(merged[f.name])) if is_list else [(None, merged[f.name])]
            for i, item in items:
                if item is not None:
                    out += _out_of_range(sub, item, f"{prefix}{f.name}{'' if i is None else f'[{i}]'}.")
            continue
        rng = f.metadata.get("range")
        if rng is None:
            continue
        value = OmegaConf.to_container(node) if OmegaConf.is_config(node) else node._value()
        if isinstance(value, list) and any(isinstance(v, str) and "${" in v for v in value):
            continue
        why = rng.problem(value)
        if why:
            out.append(f"'{prefix}{f.name}={value}': {why}")
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
    bad = _out_of_range(schema, merged, where + ".")
    if bad:
        raise SchemaError(bad[0])
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
