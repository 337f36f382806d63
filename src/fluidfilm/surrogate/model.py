"""Trained surrogates as force models: ``SurrogateForceModel``, its files (``save``, ``load_surrogate``) and checksums.

A saved model (``models/<name>/``) holds ``surrogate.npz`` (weights and
scalings as plain arrays) and ``model.json`` (architecture, regions,
domain, bearing).  Loading needs numpy and numba only.  The network is
evaluated by the kernels of ``surrogate.kernels``, with the same signature as the reference
solver's, ``fn(params, x1, x2, v1, v2) -> (F1, F2)``, so the rotor
integrator runs a surrogate in the same compiled loop, without PyTorch's
per-call overhead.

Routing (split models): region r holds eps in [b_{r-1}, b_r).  With
``blend_width`` w > 0 the forces of the two neighbouring networks are mixed
with a smoothstep weight over eps in [b - w/2, b + w/2], so the force is
continuous across a boundary; with w = 0 the switch is hard and the force
jumps by the two networks' disagreement there.

Domain: every evaluation with eps above the training data's maximum or a
velocity component beyond the data's range at that eps counts as outside
the training domain; ``forces`` warns once, ``simulate`` reports the count
in the trajectory's status.
"""
from __future__ import annotations

import dataclasses
import difflib
import hashlib
import json
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from fluidfilm import io
from fluidfilm.core.bearing import ConicalBearing, JournalBearing, bearing_from_dict
from fluidfilm.core.force_model import ValidityDomain, check_precision
from fluidfilm.core.states import as_state_pairs
from fluidfilm.surrogate.activations import ACTIVATIONS
from fluidfilm.surrogate.kernels.folding import shape_key
from fluidfilm.surrogate.kernels.generated import COUNTER, SETTING, fast_force_kernel, pack
from fluidfilm.surrogate.kernels.generated_batch import (FastBatchParams, batch_kernel, batch_shape_key,
                                                         fast_batch_params, with_workspace)
from fluidfilm.surrogate.kernels.generic import (Structure, SurrogateParams, _stack_tables, _surrogate_batch,
                                                 pack_network, speed_scaled_force)
from fluidfilm.surrogate.kernels.generic_batch import BatchParams, batch_params, forces_batch
from fluidfilm.surrogate.scaling import Scaling, check_whirl_use, network_inputs


class SurrogateForceModel:
    """A trained network (or split set of networks) with the reference model's interface.

    ``forces(X, V)`` takes positions X [m] and velocities V [m/s] (..., 2) in the (X1, X2) frame,
    +X2 along gravity, and returns forces [N]; the compiled ``force_kernel`` runs in ``simulate``.
    States outside the training domain are legal and counted (``n_outside_domain``, a
    ``RuntimeWarning``); states outside the clearance raise a ``ValueError``.  Usually made by the
    trainers and read back with ``load_surrogate``.

    Parameters
    ----------
    bearing : JournalBearing or ConicalBearing
        The bearing the network was trained for.
    networks : list
        One network per eccentricity region, each a list of (W (out, in), b) layers, or with
        ``structure="damping"`` a pair (static layers, damping-matrix layers).
    scalings : list of Scaling
        One per network: its input and output scaling.
    activation : {"tanh", "relu", "silu", "sigmoid", "pade_tanh"}
        Hidden-layer activation (``pade_tanh``: the universal networks', ``surrogate.activations``).
    boundaries : sequence of float, default ()
        Eccentricity ratios that split the regions, increasing strictly within (0, 1).
    blend_width : float, default 0.0
        Width in eps of the blend between neighbouring regions (0: a hard switch).
    domain : array_like or None, default None
        Rows (eps_low, eps_high, v_max [m/s]) of the training domain; None: no velocity bound.
    eps_max : float, default 1.0
        Largest eccentricity ratio of the training data.
    name : str, default "surrogate"
        Display name.
    info : dict or None, default None
        What the trainer recorded (shown in reports).
    structure : {"plain", "damping"}, default "plain"
        Output structure of the networks.

    Raises
    ------
    ValueError
        For an unknown activation or structure, counts of networks, boundaries and scalings that
        do not match, boundaries out of order, or extra inputs on a bearing without a sleeve.

    Examples
    --------
    >>> import numpy as np
    >>> from fluidfilm import ReynoldsSolver, SurrogateForceModel, paper_bearing
    >>> from fluidfilm.perf.speed import sample_states
    >>> from fluidfilm.surrogate import Scaling
    >>> b = paper_bearing()
    >>> x, v = sample_states(b.clearance, n=200, v_max=0.01)
    >>> scaling = Scaling.fit("standard", x, v, ReynoldsSolver(b, 16, 8).forces(x, v), b.clearance, b.omega,
    ...                       b.force_scale)
    >>> rng = np.random.default_rng(0)                 # an untrained 4-8-2 network, for the interface only
    >>> layers = [(0.5 * rng.normal(size=(8, 4)), np.zeros(8)), (0.5 * rng.normal(size=(2, 8)), np.zeros(2))]
    >>> model = SurrogateForceModel(b, [layers], [scaling], "tanh", name="tiny")
    >>> model
    SurrogateForceModel('tiny', 1 network(s), boundaries=[], 58 parameters)
    >>> model.forces([0.0, 60e-6], [0.0, 0.0]).round(2).tolist()      # [N]
    [4.63, -2.58]
    >>> import tempfile
    >>> from fluidfilm import load_surrogate
    >>> folder = tempfile.mkdtemp()
    >>> model.save(f"{folder}/tiny")                   # model.json and surrogate.npz
    >>> again = load_surrogate(f"{folder}/tiny")
    >>> again.name, bool(np.array_equal(again.forces(x, v), model.forces(x, v)))
    ('tiny', True)
    """

    def __init__(self, bearing: JournalBearing | ConicalBearing, networks: list, scalings: list[Scaling], activation: str,
                 boundaries=(), blend_width: float = 0.0, domain=None, eps_max: float = 1.0,
                 name: str = "surrogate", info: dict | None = None, structure: str = "plain"):
        """``networks``: one per region, each a list of (W (out, in), b) layers, or with
        ``structure="damping"`` a pair (static layers, damping-matrix layers)."""
        if activation not in ACTIVATIONS:
            raise ValueError(f"unknown activation {activation!r}; choose one of {tuple(ACTIVATIONS)}")
        if len(networks) != len(boundaries) + 1 or len(scalings) != len(networks):
            raise ValueError(f"{len(networks)} networks need {len(networks) - 1} boundaries and as many scalings, "
                             f"got {len(boundaries)} boundaries and {len(scalings)} scalings")
        bounds = np.asarray(boundaries, dtype=float)
        if bounds.size and not (np.all(np.diff(bounds) > 0) and bounds[0] > 0 and bounds[-1] < 1):
            raise ValueError(f"split boundaries must increase strictly within (0, 1), got {list(bounds)}")
        if blend_width < 0 or (bounds.size > 1 and blend_width >= np.diff(bounds).min()):
            raise ValueError(f"blend_width={blend_width} must be >= 0 and narrower than the regions")
        self._bearing = bearing
        self.name = name
        self.activation = activation
        self.boundaries = bounds
        self.blend_width = float(blend_width)
        self.networks = networks
        self.scalings = scalings
        self.domain = np.asarray(domain if domain is not None else [[0.0, 1.0, np.inf]], dtype=float)
        self.eps_max = float(eps_max)
        self.info = info or {}
        if structure not in ("plain", "damping"):
            raise ValueError(f"unknown structure {structure!r}; choose 'plain' or 'damping'")
        self.structure = structure
        if structure == "plain":
            packed = [pack_network(n) for n in networks]
            damp = [(np.zeros((1, 4), dtype=np.int64), 0) for _ in networks]
            all_layers = [layer for n in networks for layer in n]
        else:
            packed, damp = [], []
            for static, damping in networks:
                ws, ts = pack_network(static)
                wd, td = pack_network(damping)
                td = td.copy()
                td[:, :2] += ws.size  # damping weights follow the static ones in one flat array
                packed.append((np.concatenate([ws, wd]), ts))
                damp.append((td, len(damping)))
            all_layers = [layer for pair in networks for n in pair for layer in n]
        max_width = max(W.shape[0] for W, _ in all_layers)
        self._n_parameters = int(sum(W.size + b.size for W, b in all_layers))
        # the clearance itself, not 1/sqrt(1/c^2): rounding there let eps = 1 pass the domain check as 0.9999...
        self._clearance = float(bearing.clearance)
        self._n_extra = len(scalings[0].extras)
        if any(len(sc.extras) != self._n_extra for sc in scalings):
            raise ValueError("all networks of a split model must take the same extra inputs")
        if self._n_extra and structure == "damping":
            raise ValueError("the damping structure takes no extra inputs")
        for sc in scalings:
            check_whirl_use(sc.frame, structure, bearing)
        if self._n_extra and not isinstance(bearing, ConicalBearing):
            raise ValueError(f"extra inputs {scalings[0].extras} need an active (conical) bearing")
        # the current setting, read by the kernel: 1/c^2 (eccentricity for routing and domain) and the
        # sleeve displacement; mutable, so a controller moves the sleeve without rebuilding anything.  It and
        # the domain counter are views of the fast kernel's parameter vector (surrogate.kernels.pack; the
        # kernel compiles on first use of force_kernel), so both kernels read and count in one place
        self._fast_key = shape_key(self)
        self._fast_weights = pack(self, self._fast_key)
        self._setting = self._fast_weights[SETTING:SETTING + 2]
        self._counter = self._fast_weights[COUNTER:COUNTER + 1]  # float64: exact to 2^53 evaluations
        self._batch_params: dict[str, BatchParams | FastBatchParams] = {}  # batch_force_kernel's, per precision
        self._batch_key = batch_shape_key(self)
        # one flat weight array for all regions: each region's table offsets shifted to its block
        offsets = np.cumsum([0] + [w.size for w, _ in packed])
        tables = [t.copy() for _, t in packed]
        damping_tables = [t.copy() for t, _ in damp]
        for r in range(len(packed)):
            tables[r][:, :2] += offsets[r]
            if structure == "damping":
                damping_tables[r][:, :2] += offsets[r]
        self.params = SurrogateParams(
            weights=np.concatenate([w for w, _ in packed]), tables=_stack_tables(tables),
            n_layers=np.array([t.shape[0] for _, t in packed], dtype=np.int64),
            activation=ACTIVATIONS[activation],
            scalings=np.stack([s.kernel_row() for s in scalings]), boundaries=bounds, blend_width=self.blend_width,
            domain=self.domain, eps_max=self.eps_max,
            counter=self._counter, setting=self._setting, max_width=max(max_width, 5),
            scratch=np.zeros((3, max(max_width, 5))),
            structure=int(Structure.DAMPING if structure == "damping" else Structure.PLAIN),
            damping_tables=_stack_tables(damping_tables),
            damping_n_layers=np.array([n for _, n in damp], dtype=np.int64),
        )

    @property
    def bearing(self) -> JournalBearing | ConicalBearing:
        return self._bearing

    @property
    def force_kernel(self):
        """The compiled one-state kernel of this model's shape (``surrogate.kernels.fast_force_kernel``),
        equal to the generic ``surrogate_force`` on ``self.params`` to round-off; compiled on first use."""
        return fast_force_kernel(self)

    def force_kernel_at(self, precision: str = "float64"):
        """``(fn, params)`` like ``force_kernel``, the networks in ``precision`` (``core.force_model.
        PrecisionKernelModel``): "float32" runs them in single precision, forces within 1e-5 of
        float64 relative to the larger of |F| and the states' RMS force (``surrogate.kernels.fast_force_kernel``); the parameters, setting and counter are shared.
        "float64" is ``force_kernel`` itself (a subclass's own included)."""
        if check_precision(precision) == "float64":
            return self.force_kernel
        return fast_force_kernel(self, precision)

    def __setstate__(self, state: dict) -> None:
        # a copied or unpickled model: numpy copies the setting and counter as arrays of their own, which
        # would cut them off from the kernels' parameter vector (a moved sleeve or a count the kernel never
        # sees); make them views of this model's vector again, and let the batch parameters be rebuilt
        # (the copied vector holds their values already: they were views of it when copied)
        self.__dict__.update(state)
        self._setting = self._fast_weights[SETTING:SETTING + 2]
        self._counter = self._fast_weights[COUNTER:COUNTER + 1]
        self.params = self.params._replace(counter=self._counter, setting=self._setting)
        self._batch_params = {}

    def speed_kernel(self):
        """``(speed_scaled_force, (kernel, params, omega_ref))`` for a network in the 'whirl' frame on a
        cylindrical bearing, whose force scales exactly with the shaft speed (``speed_scaled_force``); None
        for every other frame (its network was trained at one speed: it refuses a speed schedule)."""
        if not isinstance(self._bearing, JournalBearing) or any(sc.frame != "whirl" for sc in self.scalings):
            return None
        fn, params = self.force_kernel
        return speed_scaled_force, (fn, params, float(self._bearing.omega))

    def batch_force_kernel(self, precision: str = "float64", private: bool = False):
        """``(fn, params)`` (``core.force_model.BatchForceModel``): many states per call, the networks in
        ``precision``; ``private``: the parameters count in their own domain counter (``merge_counts`` adds it
        to the model's).  ``fn`` is the batched kernel generated for this model's shape
        (``surrogate.kernels.batch_kernel``) where it has one, else ``surrogate.kernels.forces_batch``.  The
        parameters read the model's setting (sleeve) in place and are built once per precision."""
        check_precision(precision)
        bp = self._batch_params.get(precision)
        if bp is None:
            bp = self._batch_params[precision] = (batch_params(self, precision) if self._batch_key is None
                                                  else fast_batch_params(self, precision))
        fn = forces_batch if self._batch_key is None else batch_kernel(self._batch_key, precision)
        if not private:
            return fn, bp
        bp = bp._replace(counter=np.zeros(1))
        # one thread's parameters: their own scratch too (the kernel allocates none per call up to its size)
        return fn, (with_workspace(bp, self._batch_key) if isinstance(bp, FastBatchParams) else bp)

    def merge_counts(self, bparams: BatchParams | FastBatchParams) -> None:
        """Add the domain count of private batch parameters to the model's (``BatchForceModel``)."""
        if bparams.counter is not self._counter:
            self._counter[0] += bparams.counter[0]

    @property
    def validity(self) -> ValidityDomain:
        """The training data's range, as the kernel counts it."""
        return ValidityDomain(self.eps_max, tuple((float(a), float(b), float(v)) for a, b, v in self.domain))

    # ------------------------------------------------------------------ the control input (active bearings)
    @property
    def adjustable(self) -> bool:
        """True when the network takes the sleeve as an input."""
        return bool(self._n_extra)

    @property
    def sleeve(self) -> float:
        return float(self._setting[1])

    @property
    def clearance(self) -> float:
        """Radial clearance at the current sleeve position [m]."""
        return self._clearance

    def set_sleeve(self, sleeve: float) -> None:
        """Move the sleeve [m] (a surrogate of an active bearing takes it as an input)."""
        if not self._n_extra or not isinstance(self._bearing, ConicalBearing):
            raise ValueError(f"{self.name} takes no sleeve input")
        c = self._bearing.clearance_at(sleeve)
        self._setting[0] = 1.0 / c**2
        self._setting[1] = float(sleeve)
        self._clearance = float(c)

    @property
    def setting_array(self) -> np.ndarray:
        """The kernel's mutable control setting [1/c_r^2, sleeve] (``simulate_batch`` writes per-trajectory rows)."""
        return self._setting

    def setting_for(self, sleeve: float) -> np.ndarray:
        """The setting row of a sleeve position [m], for ``simulate_batch(settings=...)``."""
        if not self._n_extra:
            raise ValueError(f"{self.name} takes no sleeve input")
        bearing: Any = self._bearing  # a ConicalBearing: only it has a sleeve input (checked above)
        return np.array([1.0 / bearing.clearance_at(sleeve) ** 2, float(sleeve)])

    @property
    def n_parameters(self) -> int:
        return self._n_parameters

    # ------------------------------------------------------------------ domain bookkeeping
    def reset_domain_counter(self) -> None:
        self._counter[0] = 0

    def domain_report(self) -> str | None:
        n = int(self._counter[0])
        if n == 0:
            return None
        return f"outside the training domain in {n} force evaluations"

    # ------------------------------------------------------------------ evaluation
    def forces(self, X, V) -> np.ndarray:
        """Film force [N] at positions X [m] and velocities V [m/s], (..., 2); counts (and warns of)
        states outside the training domain."""
        x, v, shape = as_state_pairs(X, V, self.clearance)  # the shared domain contract (states.py)
        before = int(self._counter[0])
        out = np.empty_like(x)
        if x.shape[0]:
            _surrogate_batch(self.params, x, v, out)
        n_out = int(self._counter[0]) - before
        if n_out:
            # every call says how many (the count in the text keeps Python from showing it only once)
            warnings.warn(f"{self.name}: {n_out} of {len(x)} states lie outside the training domain "
                          f"(eps <= {self.eps_max:g}, velocities within the data's range); forces there are "
                          f"extrapolated ({int(self._counter[0])} such evaluations since the last reset)",
                          RuntimeWarning, stacklevel=2)
        return out.reshape(shape + (2,))

    def exact_coefficients(self, x0) -> dict | None:
        """K and C at ``x0`` (journal at rest) from the network's exact Jacobian (forward-mode), or None for
        surrogates with extra inputs (the active bearing's sleeve), which it does not cover."""
        if self.scalings[0].extras:
            return None
        from fluidfilm.surrogate.kernels.jacobian import surrogate_coefficients
        return surrogate_coefficients(self, x0)

    @property
    def n_outside_domain(self) -> int:
        """Force evaluations outside the training domain since the last ``reset_domain_counter``."""
        return int(self._counter[0])

    def __repr__(self) -> str:
        return (f"SurrogateForceModel({self.name!r}, {len(self.networks)} network(s), boundaries="
                f"{self.boundaries.tolist()}, {self.n_parameters} parameters)")

    # ------------------------------------------------------------------ io
    def save(self, directory) -> None:
        """Write ``model.json`` and ``surrogate.npz`` (with its SHA-256) into ``directory``."""
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        arrays = {}
        for r, net in enumerate(self.networks):
            static, damping = (net, []) if self.structure == "plain" else net
            for k, (W, b) in enumerate(static):
                arrays[f"r{r}_W{k}"] = W
                arrays[f"r{r}_b{k}"] = b
            for k, (W, b) in enumerate(damping):
                arrays[f"r{r}_dW{k}"] = W
                arrays[f"r{r}_db{k}"] = b
        with io.atomic_path(d / "surrogate.npz", suffix=".npz") as tmp:
            np.savez(tmp, **arrays)
            weights_sha256 = io.file_sha256(tmp)
        meta = {"name": self.name, "activation": self.activation, "boundaries": self.boundaries.tolist(),
                "blend_width": self.blend_width, "domain": self.domain.tolist(), "eps_max": self.eps_max,
                "structure": self.structure,
                "n_layers": [len(n if self.structure == "plain" else n[0]) for n in self.networks],
                "n_layers_damping": [0 if self.structure == "plain" else len(n[1]) for n in self.networks],
                "scalings": [s.to_dict() for s in self.scalings],
                "bearing": self._bearing.to_dict(), "info": self.info,
                # checked on load: a damaged or swapped weights file is refused, naming it
                "weights_sha256": weights_sha256,
                "array_shapes": {k: list(np.shape(v)) for k, v in arrays.items()}}
        # and model.json itself, key by key (so a hand edit is refused naming the key); with weights_sha256
        # among them this covers the whole model directory
        meta["content_sha256"] = {k: _content_sha256(v) for k, v in meta.items()}
        io.write_json(d / "model.json", meta)


class SurrogateFileError(ValueError):
    """A saved surrogate is missing, damaged or inconsistent; the message names the file and the fault."""


def _content_sha256(value) -> str:
    """SHA-256 of a JSON value in canonical form (sorted keys, no spaces): what model.json records per key,
    the same before writing and after reading back (floats round-trip exactly)."""
    return hashlib.sha256(json.dumps(value, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


#: model.json: key -> (JSON type(s) it must have, required); the file written by ``save``.  Optional keys:
#: written by every save since they were introduced, absent from older files (which still load)
MODEL_JSON_SCHEMA: dict[str, tuple[Any, bool]] = {
    "name": (str, True), "activation": (str, True), "structure": (str, False),
    "boundaries": (list, True), "blend_width": ((int, float), True), "domain": (list, True),
    "eps_max": ((int, float), True), "n_layers": (list, True), "n_layers_damping": (list, False),
    "scalings": (list, True), "bearing": (dict, True), "info": (dict, False),
    "weights_sha256": (str, False), "array_shapes": (dict, False), "content_sha256": (dict, False),
}
_SCALING_KEYS = {f.name: f.default is dataclasses.MISSING for f in dataclasses.fields(Scaling)}
_OPTIONAL_SCALING_KEYS = ("frame", "extras")  # from_dict fills these for files older than them


def _unknown(key: str, known) -> str:
    close = difflib.get_close_matches(key, list(known), n=1)
    return f"unknown key {key!r}" + (f" (did you mean {close[0]!r}?)" if close else "") + \
        f"; model.json keys are {sorted(known)}"


def _check_meta(meta_file: Path, meta) -> None:
    """``meta`` (model.json parsed) against ``MODEL_JSON_SCHEMA`` and its recorded per-key checksums."""
    def bad(msg):
        return SurrogateFileError(f"{meta_file}: {msg}")

    if not isinstance(meta, dict):
        raise bad(f"holds a JSON {type(meta).__name__}, expected an object of keys (what save() writes)")
    for key in meta:
        if key not in MODEL_JSON_SCHEMA:
            raise bad(_unknown(key, MODEL_JSON_SCHEMA))
    for key, (kind, required) in MODEL_JSON_SCHEMA.items():
        if key not in meta:
            if required:
                raise bad(f"lacks the key {key!r}")
            continue
        value = meta[key]
        if isinstance(value, bool) or not isinstance(value, kind):
            raise bad(f"key {key!r} must be a JSON {_json_kind(kind)}, got {value!r}")
    n = len(meta["scalings"])
    for key in ("n_layers", "n_layers_damping"):
        counts = meta.get(key, [0] * n)
        if len(counts) != n or not all(isinstance(k, int) and not isinstance(k, bool) and k >= 0 for k in counts):
            raise bad(f"key {key!r} must list one layer count (an integer >= 0) per network ({n}), got {counts!r}")
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in meta["boundaries"]):
        raise bad(f"key 'boundaries' must be a list of numbers, got {meta['boundaries']!r}")
    if len(meta["boundaries"]) != n - 1:
        raise bad(f"key 'boundaries' lists {len(meta['boundaries'])} split boundaries for {n} networks (needs {n - 1})")
    if not all(isinstance(row, list) and len(row) == 3 for row in meta["domain"]):
        raise bad(f"key 'domain' must be a list of [eps_low, eps_high, v_max] rows, got {meta['domain']!r}")
    for r, scal in enumerate(meta["scalings"]):
        if not isinstance(scal, dict):
            raise bad(f"scalings[{r}] must be an object, got {scal!r}")
        for key in scal:
            if key not in _SCALING_KEYS:
                raise bad(f"scalings[{r}]: " + _unknown(key, _SCALING_KEYS))
        for key, required in _SCALING_KEYS.items():
            if required and key not in scal and key not in _OPTIONAL_SCALING_KEYS:
                raise bad(f"scalings[{r}] lacks the key {key!r}")
    bearing = meta["bearing"]
    kind = ConicalBearing if bearing.get("kind") == "conical" else JournalBearing
    allowed = {f.name for f in dataclasses.fields(kind)} | {"kind", "name"}
    for key in bearing:
        if key not in allowed:
            raise bad("bearing: " + _unknown(key, allowed).replace("model.json keys", "bearing keys"))
    try:
        bearing_from_dict(bearing)
    except ValueError as err:
        raise bad(f"bearing: {err}") from None
    recorded = meta.get("content_sha256")
    if recorded is None:
        return  # a file written before model.json was checksummed: loads on the schema alone
    for key in sorted(set(recorded) | set(meta) - {"content_sha256"}):
        if key not in meta:
            raise bad(f"the key {key!r} recorded at save time is missing; restore the file or retrain the model")
        if key not in recorded or _content_sha256(meta[key]) != recorded[key]:
            raise bad(f"the key {key!r} was changed after the model was saved (its SHA-256 differs from the one "
                      "recorded in content_sha256); a hand-edited model.json is not trusted: restore the file "
                      "or retrain the model")


def _json_kind(kind) -> str:
    names = {str: "string", list: "list", dict: "object", int: "number", float: "number"}
    kinds = kind if isinstance(kind, tuple) else (kind,)
    return " or ".join(sorted({names[k] for k in kinds}))


def _check_network(npz: Path, meta: dict, arrays) -> None:
    structure = meta.get("structure", "plain")
    for r, scal in enumerate(meta["scalings"]):
        n_in = network_inputs(scal.get("frame", "cartesian"), len(scal.get("extras", ())))
        chains = [("", meta["n_layers"][r], n_in, 2)]
        if structure == "damping":  # the static load S sees the position inputs only (all but the velocities)
            chains = [("", meta["n_layers"][r], n_in - 2, 2), ("d", meta["n_layers_damping"][r], n_in, 4)]
        for tag, n_layers, width_in, n_out in chains:
            for k in range(n_layers):
                wk, bk = f"r{r}_{tag}W{k}", f"r{r}_{tag}b{k}"
                for key in (wk, bk):
                    if key not in arrays:
                        raise SurrogateFileError(f"{npz}: array {key} is missing (model.json lists {n_layers} layers "
                                                 f"for network {r})")
                W, b = arrays[wk], arrays[bk]
                last = k == n_layers - 1
                if W.ndim != 2 or W.shape[1] != width_in or b.shape != (W.shape[0],) or (last and W.shape[0] != n_out):
                    want = f"({n_out if last else 'width'}, {width_in})"
                    raise SurrogateFileError(f"{npz}: {wk} has shape {W.shape} and {bk} {b.shape}; the saved "
                                             f"configuration (model.json) needs {wk} of shape {want} and a matching bias")
                if not (np.isfinite(W).all() and np.isfinite(b).all()):
                    raise SurrogateFileError(f"{npz}: {wk if not np.isfinite(W).all() else bk} holds non-finite "
                                             "values (NaN or inf); the model would give NaN forces")
                width_in = W.shape[0]
    shapes = meta.get("array_shapes")
    if shapes is not None:
        for key, shape in shapes.items():
            if key in arrays and list(arrays[key].shape) != list(shape):
                raise SurrogateFileError(f"{npz}: {key} has shape {arrays[key].shape}, saved as {tuple(shape)}")


def load_surrogate(path) -> SurrogateForceModel:
    """Load a saved surrogate (a ``models/<name>/`` directory) as a force model.

    Refuses, naming the file and the fault: a missing or unreadable file, a
    ``model.json`` that breaks ``MODEL_JSON_SCHEMA`` (not an object, a key
    missing, misspelt or of the wrong type, an invalid bearing) or whose
    content differs from the per-key SHA-256 recorded at save time (the key
    is named; files saved before that record load on the schema alone), a
    weights file whose SHA-256 differs from the one written at save time,
    arrays whose shapes disagree with the saved configuration, non-finite
    weights.

    Parameters
    ----------
    path : path-like
        The model's folder, holding ``model.json`` and ``surrogate.npz`` (``SurrogateForceModel.save``;
        the pipeline writes them under ``models/``).

    Returns
    -------
    SurrogateForceModel

    Raises
    ------
    SurrogateFileError
        A ``ValueError`` naming the file and the fault.

    Examples
    --------
    A model saved and loaded again: see ``SurrogateForceModel``.  A folder without one:

    >>> import tempfile
    >>> from fluidfilm.surrogate import load_surrogate
    >>> folder = tempfile.mkdtemp()
    >>> load_surrogate(f"{folder}/none")
    Traceback (most recent call last):
    ...
    fluidfilm.surrogate.model.SurrogateFileError: .../none/model.json is missing: ... holds no saved surrogate (model.json and surrogate.npz)
    """
    d = Path(path)
    meta_file, npz = d / "model.json", d / "surrogate.npz"
    for f in (meta_file, npz):
        if not f.exists():
            raise SurrogateFileError(f"{f} is missing: {d} holds no saved surrogate (model.json and surrogate.npz)")
    try:
        meta = json.loads(meta_file.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise SurrogateFileError(f"{meta_file} is not valid JSON ({err}); the file is damaged") from None
    _check_meta(meta_file, meta)
    recorded = meta.get("weights_sha256")
    if recorded is not None and io.file_sha256(npz) != recorded:
        raise SurrogateFileError(f"{npz} is damaged or was replaced: its SHA-256 differs from the one recorded "
                                 f"in {meta_file} at save time")
    try:
        with np.load(npz) as z:
            arrays = {k: z[k] for k in z.files}
    except Exception as err:  # zipfile/pickle/OS errors alike: say which file
        raise SurrogateFileError(f"{npz} cannot be read ({type(err).__name__}: {err})") from None
    try:
        _check_network(npz, meta, arrays)
    except KeyError as err:
        raise SurrogateFileError(f"{meta_file} lacks the key {err}") from None
    structure = meta.get("structure", "plain")
    networks: list = [[(arrays[f"r{r}_W{k}"], arrays[f"r{r}_b{k}"]) for k in range(n)]
                for r, n in enumerate(meta["n_layers"])]
    if structure == "damping":
        networks = [(net, [(arrays[f"r{r}_dW{k}"], arrays[f"r{r}_db{k}"]) for k in range(meta["n_layers_damping"][r])])
                    for r, net in enumerate(networks)]
    return SurrogateForceModel(bearing_from_dict(meta["bearing"]), networks,
                               [Scaling.from_dict(s) for s in meta["scalings"]], meta["activation"],
                               meta["boundaries"], meta["blend_width"], meta["domain"], meta["eps_max"],
                               meta["name"], meta.get("info", {}), structure)
