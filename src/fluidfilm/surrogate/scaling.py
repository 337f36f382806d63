"""Input and output scaling of the force networks, fitted on training data and saved with the model.

Two kinds:

- ``standard``: inputs (X1, X2, V1, V2) and outputs (F1, F2) standardised
  with the training data's mean and standard deviation;
- ``physics``: inputs in clearance units (X/c, V/(c omega)) and forces
  divided by the film-force scale mu omega R L (R/c)^2 and multiplied by
  (1 - eps^2)^p before standardising.  The forces span orders of magnitude
  across eps (squeeze damping grows like (1 - eps^2)^-1.5); the factor
  flattens that growth so one network's error is spread evenly over eps.
- ``physics_v``: as ``physics``, and the force also divided by
  (1 + |V|/(c omega)).  Squeeze forces grow with |V| and at |V| >> c omega
  dwarf the static (wedge) force; without this factor the network's error
  budget goes to them and the static load - what decides where the journal
  settles - gets a poor relative accuracy.

Two frames for the inputs and outputs:

- ``cartesian``: (X1, X2, V1, V2) -> (F1, F2);
- ``polar``: the journal's own frame.  A cylindrical bearing is
  rotationally symmetric, so F(X, V) = R(phi) G(eps, v_r, v_t) exactly, with
  v_r, v_t the velocity along and across the line of centres (in units of
  c omega) and G the force in that frame.  Learning G is a 3-D problem
  instead of 4-D, the static force is a function of eps alone, and the
  symmetry holds exactly for the surrogate too.
- ``whirl``: the journal's frame and the film's homogeneity in velocity.  In
  that frame the Reynolds equation is driven by u = (eps - 2 v_t, 2 v_r)
  (wedge with the whirl's relative speed, squeeze) over pressure fields of
  eps alone, so F = |u| R(phi) G(eps, u/|u|) exactly (``transforms.
  whirl_direction``).  The network sees (eps, u1/|u|, u2/|u|), a smooth
  function on a cylinder; |u| multiplies the force scale.  At rest u =
  (eps, 0): the static load, the stiffness and the damping are values and
  first derivatives of G near one smooth direction, instead of a corner of a
  velocity range the network spends most of its weights on.  It holds for a
  film without supply pressure (the workspace's default); the force model
  and the training refuse a bearing with one.

Extra inputs (``extras``, e.g. ``("S",)`` the sleeve displacement of an
active bearing) follow the state inputs and are standardised like them.
With ``sleeve_gain`` = dc_r/dS (tan(alpha) of a conical bearing) the
clearance used everywhere above is the sleeve position's own,
c_r = c + S tan(alpha), and the physics force scale carries (c/c_r)^2: by the
film's similarity law (tests/reynolds/test_conical.py) the scaled target then hardly
depends on S at all, and the network only learns what the law leaves over.

How the compiled kernels read a scaling (``Scaling.kernel_row``: 22 float64 entries) is laid out and
documented once, in ``surrogate.contract``.

Pure numpy, so that inference needs no torch.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from fluidfilm.surrogate import contract as row
from fluidfilm.surrogate import transforms as tf
from fluidfilm.surrogate.contract import FRAME_CODES, KIND_CODES

SCALINGS = ("standard", "physics", "physics_v", "minmax")
FRAMES = ("cartesian", "polar", "whirl")
AFFINE = ("standard", "minmax")


def network_inputs(frame: str, n_extras: int = 0) -> int:
    """Inputs of a network in ``frame``: (X1, X2, V1, V2) in the cartesian frame, three in the journal's
    (eps and two velocity or drive-direction components), then the extra inputs."""
    return (4 if frame == "cartesian" else 3) + int(n_extras)


def check_whirl_use(frame: str, structure: str, bearing) -> None:
    """The frame 'whirl' rests on the film's homogeneity in its drive and gives the network no velocities:
    refused for a bearing with supply pressure (no homogeneity) and for the damping structure (it needs
    velocity inputs).  One check for training and for building a force model."""
    if frame != "whirl":
        return
    supply = getattr(bearing, "supply_pressure", 0.0)
    if supply != 0.0:
        raise ValueError(f"frame 'whirl' assumes no supply pressure (the film force is then homogeneous in its "
                         f"drive); this bearing has supply_pressure={supply!r} Pa: use frame 'polar'")
    if structure == "damping":
        raise ValueError("the damping structure needs velocity inputs; frame 'whirl' gives the network the "
                         "drive's direction instead (use structure 'plain' with it)")


def _centre_half_range(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(max + min)/2 and (max - min)/2 per column: (a - centre)/half maps [min, max] onto [-1, 1]."""
    lo, hi = a.min(axis=0), a.max(axis=0)
    half = 0.5 * (hi - lo)
    # a constant column maps to 0 (mapminmax passes it through unchanged)
    return 0.5 * (hi + lo), np.where(half > 0, half, 1.0)


@dataclass
class Scaling:
    """Input and output scaling of one force network (module doc), fitted with ``Scaling.fit``.

    Parameters
    ----------
    kind : {"standard", "physics", "physics_v", "minmax"}
        The scaling (module doc).
    clearance : float
        Radial clearance c [m].
    omega : float
        Shaft speed [rad/s].
    force_scale : float
        Film-force scale mu omega R L (R/c)^2 [N].
    power : float
        Exponent p of the (1 - eps^2)^p factor of the physics scalings.
    in_mean, in_std : ndarray
        Centre and spread of the raw network inputs.
    out_mean, out_std : ndarray, shape (2,)
        Centre and spread of the raw targets.
    frame : {"cartesian", "polar", "whirl"}, default "cartesian"
        Input and output frame.
    extras : tuple of str, default ()
        Extra inputs after the state (``("S",)``: the sleeve displacement [m]).
    sleeve_gain : float, default 0.0
        dc_r/dS (tan alpha) where the sleeve is an input of a physics scaling.

    Raises
    ------
    ValueError
        For the whirl frame with an affine kind or extra inputs; ``fit`` also for an unknown kind
        or frame, or too many inputs for the compiled kernel.

    Examples
    --------
    >>> import numpy as np
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> from fluidfilm.surrogate import Scaling
    >>> bearing = paper_bearing()
    >>> X = np.array([[0.0, 30e-6], [40e-6, 0.0], [0.0, -80e-6]])   # [m]
    >>> V = np.array([[0.0, 0.0], [0.01, 0.0], [0.0, -0.02]])       # [m/s]
    >>> F = ReynoldsSolver(bearing, 16, 8).forces(X, V)
    >>> s = Scaling.fit("physics", X, V, F, bearing.clearance, bearing.omega, bearing.force_scale)
    >>> s.kind, s.in_mean.shape, s.out_std.shape
    ('physics', (4,), (2,))
    >>> Scaling.fit("log", X, V, F, bearing.clearance, bearing.omega, bearing.force_scale)
    Traceback (most recent call last):
    ...
    ValueError: unknown scaling 'log'; choose one of ('standard', 'physics', 'physics_v', 'minmax')
    """

    kind: str
    clearance: float
    omega: float
    force_scale: float
    power: float
    in_mean: np.ndarray
    in_std: np.ndarray
    out_mean: np.ndarray
    out_std: np.ndarray
    frame: str = "cartesian"
    extras: tuple = ()
    sleeve_gain: float = 0.0

    MAX_INPUTS = row.MAX_INPUTS

    def __post_init__(self):
        # the kernel applies |u| with the physics gain only: an affine whirl scaling would silently drop it
        if self.frame == "whirl" and (self.kind in AFFINE or tuple(self.extras)):
            raise ValueError(f"frame 'whirl' needs a physics scaling kind without extra inputs, got kind "
                             f"{self.kind!r}, extras {tuple(self.extras)}: the drive u is in clearance units and "
                             "the homogeneity holds for a cylindrical film")

    # ------------------------------------------------------------------ fit
    @classmethod
    def fit(cls, kind: str, X: np.ndarray, V: np.ndarray, F: np.ndarray, clearance: float, omega: float,
            force_scale: float, power: float = 1.5, frame: str = "cartesian", E: np.ndarray | None = None,
            extras=(), sleeve_gain: float = 0.0) -> "Scaling":
        if kind not in SCALINGS:
            raise ValueError(f"unknown scaling {kind!r}; choose one of {SCALINGS}")
        if frame not in FRAMES:
            raise ValueError(f"unknown frame {frame!r}; choose one of {FRAMES}")
        extras = tuple(extras)
        if extras and kind not in AFFINE and not (extras == ("S",) and sleeve_gain > 0):
            raise ValueError(f"extra inputs {extras} with scaling kind {kind!r} need the sleeve input S and "
                             f"sleeve_gain = dc/dS > 0 (got {sleeve_gain!r}): the physics scalings need the "
                             "clearance of each sample")
        n = network_inputs(frame, len(extras))
        if n > cls.MAX_INPUTS:
            raise ValueError(f"{n} network inputs; the compiled kernel takes at most {cls.MAX_INPUTS}")
        s = cls(kind, float(clearance), float(omega), float(force_scale), float(power),
                np.zeros(n), np.ones(n), np.zeros(2), np.ones(2), frame, extras,
                float(sleeve_gain) if extras == ("S",) else 0.0)
        z = s._raw_inputs(X, V, E)
        y = s._raw_targets(X, V, F, E)
        if kind == "minmax":
            s.in_mean, s.in_std = _centre_half_range(z)
            s.out_mean, s.out_std = _centre_half_range(y)
        else:
            s.in_mean, s.in_std = z.mean(axis=0), z.std(axis=0) + 1e-12
            s.out_mean, s.out_std = y.mean(axis=0), y.std(axis=0) + 1e-12
        return s

    # ------------------------------------------------------------------ transforms
    def _clear(self, E=None):
        """Clearance of each sample: c, or c + S tan(alpha) for a sleeve-aware scaling."""
        if self.sleeve_gain:
            if E is None:
                raise ValueError("a sleeve-aware scaling needs the sleeve input S")
            return self.clearance + np.asarray(E, dtype=float)[..., 0] * self.sleeve_gain
        return self.clearance

    def _eps2(self, X, E=None):
        return tf.eps2(X[..., 0], X[..., 1], 1.0 / self._clear(E) ** 2)

    def gain(self, X, V, E=None) -> np.ndarray:
        """Force per unit of raw network target at each state (1 for standard scaling)."""
        if self.kind in AFFINE:
            return np.ones(np.shape(X)[:-1])
        c = self._clear(E)
        inv_c2 = 1.0 / c**2
        fscale = tf.sleeve_force_scale(self.force_scale, self.clearance, inv_c2) if self.sleeve_gain \
            else self.force_scale
        g = tf.film_gain(fscale, tf.eps2(X[..., 0], X[..., 1], inv_c2), self.power)
        if self.kind == "physics_v":
            g = g * tf.velocity_factor(tf.speed(V[..., 0], V[..., 1]), c, self.omega)
        if self.frame == "whirl":
            g = g * self._whirl(X, V)[0]
        return g

    def _whirl(self, X, V):
        """(|u|, u1/|u|, u2/|u|) of each state (``transforms.whirl_direction``)."""
        er1, er2 = tf.radial_axis(X[..., 0], X[..., 1])
        vr, vt = tf.to_polar(er1, er2, V[..., 0], V[..., 1])
        cw = self.clearance * self.omega
        return tf.whirl_direction(tf.speed(X[..., 0], X[..., 1]) / self.clearance, vr / cw, vt / cw)

    @property
    def n_inputs(self) -> int:
        return network_inputs(self.frame, len(self.extras))

    def _axes(self, X):
        """Unit vectors along (e_r) and across (e_t) the line of centres; e_r = +X2 at the centre."""
        er1, er2 = tf.radial_axis(X[..., 0], X[..., 1])
        return np.stack([er1, er2], axis=-1), np.stack([er2, -er1], axis=-1)

    def to_frame(self, X, F) -> np.ndarray:
        """Forces (or velocities) in the model's frame."""
        if self.frame == "cartesian":
            return F
        er1, er2 = tf.radial_axis(X[..., 0], X[..., 1])
        return np.stack(tf.to_polar(er1, er2, F[..., 0], F[..., 1]), axis=-1)

    def from_frame(self, X, G) -> np.ndarray:
        if self.frame == "cartesian":
            return G
        er1, er2 = tf.radial_axis(X[..., 0], X[..., 1])
        return np.stack(tf.from_polar(er1, er2, G[..., 0], G[..., 1]), axis=-1)

    def _raw_inputs(self, X, V, E=None):
        c = self._clear(E)
        c = c[..., None] if np.ndim(c) else c
        if self.frame == "whirl":
            _, d1, d2 = self._whirl(X, V)
            z = np.stack([tf.speed(X[..., 0], X[..., 1]) / self.clearance, d1, d2], axis=-1)
        elif self.frame == "polar":
            eps = tf.speed(X[..., 0], X[..., 1])[..., None] / c  # |X| / c
            vf = self.to_frame(X, V) / (c * self.omega)
            z = np.concatenate([eps, vf], axis=-1)
        elif self.kind not in AFFINE:
            z = np.concatenate([X / c, V / (c * self.omega)], axis=-1)
        else:
            z = np.concatenate([X, V], axis=-1)
        if self.extras:
            if E is None or np.shape(E)[-1] != len(self.extras):
                raise ValueError(f"this scaling needs the extra inputs {self.extras}, got "
                                 f"{None if E is None else np.shape(E)}")
            z = np.concatenate([z, np.asarray(E, dtype=float)], axis=-1)
        return z

    def _raw_targets(self, X, V, F, E=None):
        g = self.gain(X, V, E)[..., None]
        # frame 'whirl': no drive (u = 0), no film force: any target fits, 0 is the neutral one
        return np.divide(self.to_frame(X, F), g, out=np.zeros(np.shape(F)), where=g != 0.0)

    def inputs(self, X, V, E=None) -> np.ndarray:
        return tf.standardise(self._raw_inputs(X, V, E), self.in_mean, self.in_std)

    def targets(self, X, V, F, E=None) -> np.ndarray:
        return tf.standardise(self._raw_targets(X, V, F, E), self.out_mean, self.out_std)

    def forces(self, X, V, y, E=None) -> np.ndarray:
        """Inverse of ``targets``: network outputs -> forces [N]."""
        return self.from_frame(X, tf.unstandardise(y, self.out_mean, self.out_std) * self.gain(X, V, E)[..., None])

    # ------------------------------------------------------------------ io
    def to_dict(self) -> dict:
        d = asdict(self)
        for k in ("in_mean", "in_std", "out_mean", "out_std"):
            d[k] = np.asarray(d[k]).tolist()
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "Scaling":
        d = dict(d)
        d.setdefault("frame", "cartesian")
        d["extras"] = tuple(d.get("extras", ()))
        for k in ("in_mean", "in_std", "out_mean", "out_std"):
            d[k] = np.asarray(d[k], dtype=float)
        return cls(**d)

    def kernel_row(self) -> np.ndarray:
        """The scaling as the compiled kernels read it: ``contract.ROW_LENGTH`` (22) float64 entries, laid
        out and documented in ``surrogate.contract`` (the input centres and spreads padded to
        ``MAX_INPUTS`` with 0 and 1)."""
        out = np.zeros(row.ROW_LENGTH)
        n = len(self.in_mean)
        out[row.ROW_KIND] = KIND_CODES[self.kind]
        out[row.ROW_CLEARANCE] = self.clearance
        out[row.ROW_OMEGA] = self.omega
        out[row.ROW_FORCE_SCALE] = self.force_scale
        out[row.ROW_POWER] = self.power
        out[row.ROW_IN_MEAN:row.ROW_IN_MEAN + n] = self.in_mean
        out[row.ROW_IN_STD:row.ROW_IN_STD + row.MAX_INPUTS] = 1.0
        out[row.ROW_IN_STD:row.ROW_IN_STD + n] = self.in_std
        out[row.ROW_OUT_MEAN:row.ROW_OUT_MEAN + 2] = self.out_mean
        out[row.ROW_OUT_STD:row.ROW_OUT_STD + 2] = self.out_std
        out[row.ROW_FRAME] = FRAME_CODES[self.frame]
        out[row.ROW_N_EXTRA] = float(len(self.extras))
        out[row.ROW_SLEEVE] = row.SLEEVE_AWARE if self.sleeve_gain else 0.0
        return out
