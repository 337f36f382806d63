"""Ensembles of force models: a disagreement signal, and a hybrid that falls back to a reference model.

Several surrogates trained alike but from different seeds agree where the data pinned them down and
drift apart where they extrapolate or where the data were thin.  Their spread is therefore a cheap
uncertainty signal (deep ensembles; Lakshminarayanan et al., NeurIPS 2017):

- ``EnsembleForceModel`` answers the members' mean force and counts the evaluations whose spread
  exceeds a tolerance (*flagged*: the states where the surrogate should not be trusted);
- ``HybridForceModel`` answers the members' mean where they agree and the fallback model (the
  reference solver) at flagged states, so a trajectory costs a few reference solves where the
  surrogate is unsure and a network evaluation everywhere else.

The spread of the forces F_k of n members is the sample standard deviation of the force vector,
``s = sqrt(sum_k |F_k - F_mean|^2 / (n - 1))``; a state is flagged when
``s > rel_tol * max(|F_mean|, floor_N)`` (the floor keeps near-zero forces, whose relative spread is
meaningless, from being flagged everywhere near the bearing centre).

Both implement ``fluidfilm.core.force_model.ForceModel`` and run in the compiled integrator: the kernel
``ensemble_force`` calls the members' kernel on each member's parameters, and the fallback's kernel
when the hybrid flag is set.  ``ensemble_forces`` does the same for many states at once through the
members' and the fallback's batched kernels (``BatchForceModel``: ``simulate_batch`` calls it once per
RK4 stage).  The members must share one kernel (e.g. surrogates of one
architecture, whose parameters then form a homogeneous tuple for the compiled loop).
"""
from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np
from numba import njit
from numba.core.errors import NumbaExperimentalFeatureWarning
from numpy.typing import ArrayLike

from fluidfilm.core.force_model import BatchForceModel, Bearing, ForceModel, ValidityDomain, check_precision
from fluidfilm.core.states import as_state_pairs

# The members' and the fallback's kernels travel in the parameter tuple as numba first-class functions
# (any force model's kernel may be a member or the fallback); numba still labels that feature
# experimental and says so at every compilation.  The tests check the results against the members
# and the fallback evaluated on their own.
warnings.filterwarnings("ignore", message=".*First-class function type feature is experimental",
                        category=NumbaExperimentalFeatureWarning)


@njit  # not cached: a signature holding first-class functions cannot be written back (rotor.integrate)
def _mean_and_spread(member_fn, members, scratch, x1, x2, v1, v2):
    """The members' mean force and their spread s at one state (each member's force left in ``scratch``)."""
    s1 = 0.0
    s2 = 0.0
    k = 0
    for p in members:
        f1, f2 = member_fn(p, x1, x2, v1, v2)
        scratch[k, 0] = f1
        scratch[k, 1] = f2
        s1 += f1
        s2 += f2
        k += 1
    m1 = s1 / k
    m2 = s2 / k
    var = 0.0
    for j in range(k):
        var += (scratch[j, 0] - m1) ** 2 + (scratch[j, 1] - m2) ** 2
    return m1, m2, math.sqrt(var / (k - 1))


@njit  # not cached: a signature holding first-class functions cannot be written back (rotor.integrate)
def ensemble_force(params, x1, x2, v1, v2):
    """The members' mean force, or the fallback's force where the members disagree (hybrid).

    ``params``: (member kernel, members' parameters (tuple), fallback kernel, fallback parameters,
    [rel_tol, floor_N, hybrid 0/1], (n_members, 2) scratch, (2,) int64 counts [evaluations, flagged]).
    """
    member_fn, members, fallback_fn, fallback_params, tol, scratch, counts = params
    m1, m2, spread = _mean_and_spread(member_fn, members, scratch, x1, x2, v1, v2)
    counts[0] += 1
    if spread > tol[0] * max(math.hypot(m1, m2), tol[1]):
        counts[1] += 1
        if tol[2] > 0.0:
            return fallback_fn(fallback_params, x1, x2, v1, v2)
    return m1, m2


@njit  # not cached: a signature holding first-class functions cannot be written back (rotor.integrate)
def _ensemble_batch(params, x, v, out):
    for p in range(x.shape[0]):
        f1, f2 = ensemble_force(params, x[p, 0], x[p, 1], v[p, 0], v[p, 1])
        out[p, 0] = f1
        out[p, 1] = f2


@njit  # not cached: a signature holding first-class functions cannot be written back (rotor.integrate)
def ensemble_forces(params, x, v, out):
    """``ensemble_force`` of every row of x, v (m, 2) into out (m, 2), through the members' batched kernels.

    ``params``: (members' batched kernel, their batched parameters (tuple), the fallback's batched kernel,
    its parameters, [rel_tol, floor_N, hybrid 0/1], (2,) int64 counts [evaluations, flagged]).  Each member
    runs once on all m states; mean, spread and flag per state by ``_mean_and_spread``'s arithmetic in its
    order; the hybrid's flagged states go to the fallback in one call.
    """
    member_fn, members, fallback_fn, fallback_params, tol, counts = params
    n = x.shape[0]
    k = len(members)
    forces = np.empty((k, n, 2))
    j = 0
    for bp in members:
        member_fn(bp, x, v, forces[j])
        j += 1
    flagged = np.empty(n, dtype=np.int64)
    n_flag = 0
    for p in range(n):
        s1 = 0.0
        s2 = 0.0
        for j in range(k):
            s1 += forces[j, p, 0]
            s2 += forces[j, p, 1]
        m1 = s1 / k
        m2 = s2 / k
        var = 0.0
        for j in range(k):
            var += (forces[j, p, 0] - m1) ** 2 + (forces[j, p, 1] - m2) ** 2
        out[p, 0] = m1
        out[p, 1] = m2
        if math.sqrt(var / (k - 1)) > tol[0] * max(math.hypot(m1, m2), tol[1]):
            flagged[n_flag] = p
            n_flag += 1
    counts[0] += n
    counts[1] += n_flag
    if tol[2] > 0.0 and n_flag > 0:
        xf = np.empty((n_flag, 2))
        vf = np.empty((n_flag, 2))
        ff = np.empty((n_flag, 2))
        for i in range(n_flag):
            p = flagged[i]
            xf[i, 0], xf[i, 1], vf[i, 0], vf[i, 1] = x[p, 0], x[p, 1], v[p, 0], v[p, 1]
        fallback_fn(fallback_params, xf, vf, ff)
        for i in range(n_flag):
            out[flagged[i], 0] = ff[i, 0]
            out[flagged[i], 1] = ff[i, 1]


@njit  # not cached: a signature holding first-class functions cannot be written back (rotor.integrate)
def _member_spread(member_fn, members, scratch, x, v, out):
    """Per state: the members' mean force (out[:, :2]), their spread s (out[:, 2])."""
    for p in range(x.shape[0]):
        out[p, 0], out[p, 1], out[p, 2] = _mean_and_spread(member_fn, members, scratch, x[p, 0], x[p, 1],
                                                           v[p, 0], v[p, 1])


class EnsembleForceModel:
    """The mean of ``members`` (force models sharing one kernel), with a disagreement flag.

    ``rel_tol``: the spread, relative to the mean force, above which a state is flagged; ``floor_N``:
    the force below which the relative spread is measured against ``floor_N`` instead [N];
    ``fallback``: a force model answering at the flagged states (what ``HybridForceModel`` requires).
    """

    def __init__(self, members: Sequence[ForceModel], rel_tol: float = 0.02, floor_N: float = 1.0,
                 name: str = "ensemble", fallback: ForceModel | None = None):
        members = list(members)
        if len(members) < 2:
            raise ValueError(f"an ensemble needs at least 2 members, got {len(members)}")
        for m in members:
            if not isinstance(m, ForceModel):
                raise ValueError(f"{type(m).__name__} is not a force model (fluidfilm.core.force_model.ForceModel)")
        kernels = [m.force_kernel for m in members]
        fn = kernels[0][0]
        odd = [m.name for m, (f, _) in zip(members, kernels) if f is not fn]
        if odd:
            raise ValueError(f"ensemble members must share one force kernel; {odd} differ from {members[0].name}")
        c = members[0].clearance
        for m in members[1:]:
            if not math.isclose(m.clearance, c, rel_tol=1e-12) or m.bearing != members[0].bearing:
                raise ValueError(f"ensemble members must model one bearing: {m.name} differs from {members[0].name}")
        for key, value in (("rel_tol", rel_tol), ("floor_N", floor_N)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value) and value > 0):
                raise ValueError(f"{key} must be a positive number, got {value!r}")
        if fallback is not None:
            if not isinstance(fallback, ForceModel):
                raise ValueError(f"fallback {type(fallback).__name__} is not a force model")
            if fallback.bearing != members[0].bearing:
                raise ValueError(f"the fallback {fallback.name} models another bearing than the members")
        self.members = members
        self.fallback = fallback
        self.name = name
        self.rel_tol = float(rel_tol)
        self.floor_N = float(floor_N)
        self._counts = np.zeros(2, dtype=np.int64)
        self._tol = np.array([self.rel_tol, self.floor_N, 0.0 if fallback is None else 1.0])
        member_params = tuple(p for _, p in kernels)
        fb_fn, fb_params = fallback.force_kernel if fallback is not None else (fn, member_params[0])
        self._params = (fn, member_params, fb_fn, fb_params, self._tol, np.zeros((len(members), 2)), self._counts)

    # ------------------------------------------------------------------ the ForceModel contract
    @property
    def bearing(self) -> Bearing:
        return self.members[0].bearing

    @property
    def clearance(self) -> float:
        return self.members[0].clearance

    @property
    def force_kernel(self):
        return ensemble_force, self._params

    def batch_force_kernel(self, precision: str = "float64", private: bool = False):
        """``(ensemble_forces, params)`` (``core.force_model.BatchForceModel``): every member's batched kernel
        once per call, in ``precision``, and the fallback's on the flagged states; None where a member or the
        fallback has no batched kernel or the members' differ (``simulate_batch`` then steps each trajectory
        with ``force_kernel``).  ``private``: the members', the fallback's and the flag counts of their own
        (``merge_counts``)."""
        check_precision(precision)
        parts = []
        for m in self.members:
            part = m.batch_force_kernel(precision, private) if isinstance(m, BatchForceModel) else None
            if part is None:
                return None
            parts.append(part)
        fb = self.fallback
        fb_part = parts[0]  # a placeholder the kernel never calls (tol[2] = 0) without a fallback
        if fb is not None:
            part = fb.batch_force_kernel(precision, private) if isinstance(fb, BatchForceModel) else None
            if part is None:
                return None
            fb_part = part
        fn = parts[0][0]
        if any(f is not fn for f, _ in parts):
            return None
        member_bps = tuple(bp for _, bp in parts)
        fb_fn, fb_bp = fb_part
        counts = np.zeros(2, dtype=np.int64) if private else self._counts
        return ensemble_forces, (fn, member_bps, fb_fn, fb_bp, self._tol, counts)

    def merge_counts(self, bparams) -> None:
        """Add the counts of private batch parameters (members' domain, fallback's, flags) to the model's."""
        _, member_bps, _, fb_bp, _, counts = bparams
        for m, bp in zip(self.members, member_bps):
            if isinstance(m, BatchForceModel):  # every member is, where the parameters were made
                m.merge_counts(bp)
        if isinstance(self.fallback, BatchForceModel):
            self.fallback.merge_counts(fb_bp)
        if counts is not self._counts:
            self._counts += counts

    @property
    def validity(self) -> ValidityDomain:
        """The members' domain (they were trained on the same data)."""
        return self.members[0].validity

    def reset_domain_counter(self) -> None:
        for m in self.members:
            m.reset_domain_counter()
        self._counts[:] = 0

    def domain_report(self) -> str | None:
        return self.members[0].domain_report()

    @property
    def n_outside_domain(self) -> int:
        return self.members[0].n_outside_domain

    def forces(self, X: ArrayLike, V: ArrayLike) -> np.ndarray:
        x, v, shape = as_state_pairs(X, V, self.clearance)
        out = np.empty_like(x)
        if x.shape[0]:
            _ensemble_batch(self._params, x, v, out)
        return out.reshape(shape + (2,))

    # ------------------------------------------------------------------ the uncertainty signal
    @property
    def n_evaluations(self) -> int:
        """Force evaluations since the last ``reset_domain_counter`` (the integrator resets it per run)."""
        return int(self._counts[0])

    @property
    def n_flagged(self) -> int:
        """Of those, the evaluations whose members disagreed beyond the tolerance."""
        return int(self._counts[1])

    def spread(self, X: ArrayLike, V: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """(mean force (..., 2) N, spread (...) N) of the members at the given states (counts nothing)."""
        x, v, shape = as_state_pairs(X, V, self.clearance)
        out = np.empty((x.shape[0], 3))
        if x.shape[0]:
            _member_spread(self._params[0], self._params[1], self._params[5], x, v, out)
        return out[:, :2].reshape(shape + (2,)), out[:, 2].reshape(shape)

    def flagged(self, X: ArrayLike, V: ArrayLike) -> np.ndarray:
        """Boolean mask of the states the members disagree on (the rule of the module docstring)."""
        return self._flag(*self.spread(X, V))

    def _flag(self, mean: np.ndarray, s: np.ndarray) -> np.ndarray:
        return s > self.rel_tol * np.maximum(np.hypot(mean[..., 0], mean[..., 1]), self.floor_N)

    def __repr__(self) -> str:
        return (f"{type(self).__name__}({self.name!r}, members={[m.name for m in self.members]}, "
                f"rel_tol={self.rel_tol:g}, floor_N={self.floor_N:g})")


class HybridForceModel(EnsembleForceModel):
    """An ensemble that answers with ``fallback`` (the reference model) wherever its members disagree."""

    def __init__(self, members: Sequence[ForceModel], fallback: ForceModel, rel_tol: float = 0.02,
                 floor_N: float = 1.0, name: str = "hybrid"):
        if fallback is None:
            raise ValueError("a hybrid model needs a fallback force model (the reference)")
        super().__init__(members, rel_tol, floor_N, name, fallback)

    @property
    def n_fallbacks(self) -> int:
        """Evaluations answered by the fallback since the last reset (= ``n_flagged``)."""
        return self.n_flagged


def flag_calibration(model: EnsembleForceModel, X: ArrayLike, V: ArrayLike, F: ArrayLike) -> dict:
    """How well the disagreement flag marks the states where the ensemble is actually wrong.

    ``X, V, F``: held-out states and their true forces (the reference's).  The ensemble's error at a
    state is ``|F_mean - F| / max(|F|, floor_N)``; a state is *wrong* when that error exceeds
    ``rel_tol`` (the tolerance the flag uses).  Returns the share flagged, the share wrong, the recall
    (share of the wrong states that are flagged), the precision (share of the flagged states that are
    wrong), the median error of flagged and unflagged states, and the rank correlation of spread and
    error (Spearman).  Recall near 1 with a small flagged share is a flag one can act on.
    """
    from scipy.stats import spearmanr

    from fluidfilm.data.schema import relative_force_errors  # pandas and pyarrow: imported when asked for

    F = np.asarray(F, dtype=float)
    mean, s = model.spread(X, V)
    if F.shape != mean.shape:
        raise ValueError(f"F must have the shape of the states' forces {mean.shape}, got {F.shape}")
    err = relative_force_errors(mean, F, model.floor_N)
    flag = model._flag(mean, s)
    wrong = err > model.rel_tol

    def median(a):
        return float(np.median(a)) if a.size else None

    return {"n_states": int(flag.size), "flagged_share": float(flag.mean()), "wrong_share": float(wrong.mean()),
            "recall": float(flag[wrong].mean()) if wrong.any() else None,
            "precision": float(wrong[flag].mean()) if flag.any() else None,
            "median_err_flagged": median(err[flag]), "median_err_unflagged": median(err[~flag]),
            "spearman_spread_error": float(spearmanr(s.ravel(), err.ravel()).statistic)}
