"""Trained surrogates as force models: ``load_surrogate(path)`` and the compiled kernel behind it.

A saved model (``models/<name>/``) holds ``surrogate.npz`` (weights and
scalings as plain arrays) and ``model.json`` (architecture, regions,
domain, bearing).  Loading needs numpy and numba only.  The network is
evaluated by a numba kernel with the same signature as the reference
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
import math
import warnings
from enum import IntEnum
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from fluidfilm import io
from fluidfilm.core.bearing import ConicalBearing, JournalBearing, bearing_from_dict
from fluidfilm.core.force_model import ValidityDomain, check_precision
from fluidfilm.core.states import as_state_pairs
from fluidfilm.surrogate.activations import ACTIVATIONS, exact64
from fluidfilm.surrogate.contract import (FRAME_POLAR, FRAME_WHIRL, KIND_PHYSICS, KIND_PHYSICS_V, ROW_CLEARANCE,
                                         ROW_FORCE_SCALE, ROW_FRAME, ROW_IN_MEAN, ROW_IN_STD, ROW_KIND, ROW_N_EXTRA,
                                         ROW_OMEGA, ROW_OUT_MEAN, ROW_OUT_STD, ROW_POWER, ROW_SLEEVE, SLEEVE_AWARE)
from fluidfilm.surrogate.kernels import (COUNTER, SETTING, BatchParams, FastBatchParams, batch_kernel, batch_params,
                                        batch_shape_key, fast_batch_params, fast_force_kernel, forces_batch, pack,
                                        shape_key, with_workspace)
from fluidfilm.surrogate.scaling import Scaling, check_whirl_use, network_inputs
from fluidfilm.surrogate.transforms import (eps2_nb, film_gain_nb, from_polar_nb, radial_axis_nb, sleeve_force_scale_nb, speed_nb,
                         standardise_nb, to_polar_nb, unstandardise_nb, velocity_factor_nb, whirl_direction_nb)

class Structure(IntEnum):
    """PLAIN: the network gives the force; DAMPING: y = S(position) + C(position, velocity) v."""

    PLAIN = 0
    DAMPING = 1


# plain ints for the compiled code
_DAMPING = int(Structure.DAMPING)


class SurrogateParams(NamedTuple):
    """Parameters of ``surrogate_force``: R networks (regions) and their routing, scaling and domain."""

    # Every region's weights sit in ONE flat array and the layer tables in one (R, L, 4) array: a
    # tuple of per-region arrays indexed by a runtime region number cost ~0.5 us per call in numba
    # (the tuple is materialised and every member reference-counted), more than the network itself.
    weights: np.ndarray       # flat weights of all regions' networks (each W stored transposed)
    tables: np.ndarray        # (R, L, 4) int: per region and layer [weight offset, bias offset, n_in, n_out]
    n_layers: np.ndarray      # (R,) int
    activation: int           # the activation's code (``surrogate.activations.ACTIVATIONS``)
    scalings: np.ndarray      # (R, ROW_LENGTH) ``Scaling.kernel_row()`` of each region (``surrogate.contract``)
    boundaries: np.ndarray    # (R-1,) eccentricity ratios between regions
    blend_width: float        # smoothstep blend across each boundary (0: hard switch)
    domain: np.ndarray        # (S, 3) [eps_low, eps_high, v_max] of the training data
    eps_max: float            # largest eccentricity ratio of the training data
    counter: np.ndarray       # (1,) float64: evaluations outside the domain (mutable; a view of the fast kernel's vector)
    setting: np.ndarray       # (2,) [1/c^2 of the current clearance, sleeve] (mutable)
    max_width: int            # widest layer
    scratch: np.ndarray       # (3, max_width) work rows: two layer buffers and the inputs
    structure: int            # a ``Structure`` value
    damping_tables: np.ndarray  # (R, L, 4) layer tables of the damping-matrix networks (same flat weights)
    damping_n_layers: np.ndarray  # (R,) int


@njit(cache=True, fastmath={"reassoc", "contract"}, inline="always")
def _dense(w, b, src, dst, n_in, n_out):
    """dst = W src + b with W stored transposed (n_in, n_out): axpy updates, vectorised over outputs."""
    for o in range(n_out):
        dst[o] = b[o]
    for i in range(n_in):
        ci = src[i]
        base = i * n_out
        for o in range(n_out):
            dst[o] += w[base + o] * ci


@njit(cache=True, inline="always")
def _activate(buf, n, act):
    """The activation ``act`` (a registry code) over a layer, in its form exact to rounding (``exact64``)."""
    for o in range(n):
        buf[o] = exact64(act, buf[o])


@njit(cache=True, inline="always")
def _mlp(weights, table, n_layers, act, z, buf_a, buf_b):
    """Evaluate one network on the first n_in scaled inputs ``z``; returns the buffer holding its outputs.

    Weights are stored transposed (n_in, n_out) so each layer is a sum of
    axpy updates whose inner loop over outputs is independent and vectorises.
    """
    for k in range(table[0, 2]):
        buf_a[k] = z[k]
    for layer in range(n_layers):
        w_off, b_off, n_in, n_out = table[layer, 0], table[layer, 1], table[layer, 2], table[layer, 3]
        # even layers read buf_a and write buf_b, odd ones the other way round
        src = buf_a if layer % 2 == 0 else buf_b
        dst = buf_b if layer % 2 == 0 else buf_a
        _dense(weights[w_off:b_off], weights[b_off:b_off + n_out], src, dst, n_in, n_out)
        if layer < n_layers - 1:
            _activate(dst, n_out, act)
    return buf_b if n_layers % 2 == 1 else buf_a


@njit(cache=True, inline="always")
def _region_force(params, r, x1, x2, v1, v2, e2, buf_a, buf_b):
    weights, tables, n_layers, act, scal = (params.weights, params.tables, params.n_layers, params.activation,
                                            params.scalings)
    s = scal[r]
    physics = s[ROW_KIND] >= KIND_PHYSICS  # physics or physics_v
    c, omega, fscale, power = s[ROW_CLEARANCE], s[ROW_OMEGA], s[ROW_FORCE_SCALE], s[ROW_POWER]
    if s[ROW_SLEEVE] == SLEEVE_AWARE:
        # sleeve-aware: normalise by the current clearance c_r; forces scale as (c/c_r)^2
        inv_c2 = params.setting[0]
        fscale = sleeve_force_scale_nb(fscale, c, inv_c2)
        c = 1.0 / math.sqrt(inv_c2)
    polar = s[ROW_FRAME] >= FRAME_POLAR  # polar, or whirl (polar with the drive's direction as input)
    z = params.scratch[2]
    er1, er2 = 0.0, 1.0
    drive = 1.0
    if polar:
        # the journal's frame: along (e_r) and across (e_t) the line of centres
        er1, er2 = radial_axis_nb(x1, x2)
        cw = c * omega
        vr, vt = to_polar_nb(er1, er2, v1, v2)
        z[0] = speed_nb(x1, x2) / c  # |X| / c
        z[1] = vr / cw
        z[2] = vt / cw
        if s[ROW_FRAME] == FRAME_WHIRL:
            # the film is homogeneous in its drive u: the network sees u's direction, |u| scales the force
            drive, z[1], z[2] = whirl_direction_nb(z[0], z[1], z[2])
        n_in = 3
    else:
        if physics:
            z[0], z[1], z[2], z[3] = x1 / c, x2 / c, v1 / (c * omega), v2 / (c * omega)
        else:
            z[0], z[1], z[2], z[3] = x1, x2, v1, v2
        n_in = 4
    # extra inputs (the sleeve displacement of an active bearing) come from the control array
    for k in range(int(s[ROW_N_EXTRA])):
        z[n_in] = params.setting[1 + k]
        n_in += 1
    for k in range(n_in):
        z[k] = standardise_nb(z[k], s[ROW_IN_MEAN + k], s[ROW_IN_STD + k])
    out = _mlp(weights, tables[r], n_layers[r], act, z, buf_a, buf_b)
    y1 = out[0]
    y2 = out[1]
    if params.structure == _DAMPING:
        # damping structure: y = S(position) + C(position, velocity) v, v the velocity in units of c omega
        out = _mlp(weights, params.damping_tables[r], params.damping_n_layers[r], act, z, buf_a, buf_b)
        vo = n_in - 2
        w1 = z[vo] * s[ROW_IN_STD + vo] + s[ROW_IN_MEAN + vo]
        w2 = z[vo + 1] * s[ROW_IN_STD + 1 + vo] + s[ROW_IN_MEAN + 1 + vo]
        y1 += out[0] * w1 + out[1] * w2
        y2 += out[2] * w1 + out[3] * w2
    f1 = unstandardise_nb(y1, s[ROW_OUT_MEAN], s[ROW_OUT_STD])
    f2 = unstandardise_nb(y2, s[ROW_OUT_MEAN + 1], s[ROW_OUT_STD + 1])
    if physics:
        g = film_gain_nb(fscale, e2, power)
        if s[ROW_KIND] == KIND_PHYSICS_V:
            g *= velocity_factor_nb(speed_nb(v1, v2), c, omega)
        g *= drive
        f1 *= g
        f2 *= g
    if polar:
        # back to (X1, X2): F = f_r e_r + f_t e_t
        return from_polar_nb(er1, er2, f1, f2)
    return f1, f2


@njit(cache=True)
def surrogate_force(params, x1, x2, v1, v2):
    """Force kernel of a (possibly split) network: same signature as the reference solver's
    (``params``: a ``SurrogateParams``)."""
    bounds = params.boundaries
    blend = params.blend_width
    domain = params.domain
    eps_max = params.eps_max
    counter = params.counter
    inv_c2 = params.setting[0]
    e2 = eps2_nb(x1, x2, inv_c2)
    eps = math.sqrt(e2)
    # training-domain check (counted, never fatal)
    outside = eps > eps_max
    if not outside:
        for s in range(domain.shape[0]):
            if domain[s, 0] <= eps < domain[s, 1] or (s == domain.shape[0] - 1 and eps >= domain[s, 1]):
                if abs(v1) > domain[s, 2] or abs(v2) > domain[s, 2]:
                    outside = True
                break
    if outside:
        counter[0] += 1
    # preallocated scratch rows (the integrator and the batch loop are serial)
    buf_a = params.scratch[0]
    buf_b = params.scratch[1]
    nb = bounds.shape[0]
    r = 0
    while r < nb and eps >= bounds[r]:
        r += 1
    if blend > 0.0:
        # nearest boundary within half the blend width mixes the two neighbours
        for b in range(nb):
            lo = bounds[b] - 0.5 * blend
            hi = bounds[b] + 0.5 * blend
            if lo <= eps < hi:
                t = (eps - lo) / blend
                w = t * t * (3.0 - 2.0 * t)
                fa1, fa2 = _region_force(params, b, x1, x2, v1, v2, e2, buf_a, buf_b)
                fb1, fb2 = _region_force(params, b + 1, x1, x2, v1, v2, e2, buf_a, buf_b)
                return (1.0 - w) * fa1 + w * fb1, (1.0 - w) * fa2 + w * fb2
    return _region_force(params, r, x1, x2, v1, v2, e2, buf_a, buf_b)


@njit(cache=True)
def _surrogate_batch(params, x, v, out):
    # serial: numba's parallel loops take no nested parameter tuples (and a
    # network evaluation costs well under a microsecond anyway)
    for p in range(x.shape[0]):
        f1, f2 = surrogate_force(params, x[p, 0], x[p, 1], v[p, 0], v[p, 1])
        out[p, 0] = f1
        out[p, 1] = f2


# not cached: its parameters hold a compiled kernel (numba's cache must not see such types)
@njit
def speed_scaled_force(sparams, omega, x1, x2, v1, v2):
    """A speed kernel from the exact speed scaling: F(X, V; omega) = s F(X, V/s; omega_ref), s = omega/omega_ref.

    ``sparams``: (the one-state kernel, its parameters, omega_ref [rad/s]).  For a network whose inputs are
    dimensionless (X/c, V/(c omega)) and whose force scale is mu omega R L (R/c)^2, this is exactly the
    network with omega and the force scale of its scaling row set to the new speed (the 'whirl' frame:
    u = (eps - 2 v_t, 2 v_r) in units of c omega, |u| and the force scale, both linear in 1/omega and omega);
    at omega = omega_ref it is the kernel's own force to the bit.
    """
    kernel, params, w_ref = sparams
    s = omega / w_ref
    f1, f2 = kernel(params, x1, x2, v1 / s, v2 / s)
    return s * f1, s * f2


def pack_network(layers: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """[(W (out, in), b (out,)), ...] -> flat weights (each W stored transposed) and a
    (n_layers, 4) table of [weight offset, bias offset, n_in, n_out]."""
    flat, table, off = [], [], 0
    for W, b in layers:
        W = np.asarray(W, dtype=np.float64)
        b = np.asarray(b, dtype=np.float64)
        table.append([off, off + W.size, W.shape[1], W.shape[0]])
        flat += [W.T.ravel(), b.ravel()]
        off += W.size + b.size
    return np.concatenate(flat), np.asarray(table, dtype=np.int64)


def _stack_tables(tables: list[np.ndarray]) -> np.ndarray:
    """Per-region (n_layers, 4) tables -> one (R, max n_layers, 4) array (short ones zero-padded)."""
    out = np.zeros((len(tables), max(t.shape[0] for t in tables), 4), dtype=np.int64)
    for r, t in enumerate(tables):
        out[r, :t.shape[0]] = t
    return out


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
        from fluidfilm.surrogate.jacobian import surrogate_coefficients
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
    fluidfilm.surrogate.inference.SurrogateFileError: .../none/model.json is missing: ... holds no saved surrogate (model.json and surrogate.npz)
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
