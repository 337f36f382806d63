"""Journal states (positions X, velocities V) as every force model takes them: shapes and validation.

Shared by the reference solver and the surrogates, so that bad input gets the
same error, naming the bad value, whichever model is asked.
"""
from __future__ import annotations

import numpy as np

# The largest journal speed any force model accepts [m/s].  Orbits in a fluid film bearing move at
# about eps c omega (cm/s here); at 100 m/s a journal would cross a 0.1 mm clearance in a
# microsecond, far outside the inertia-free, incompressible film of the Reynolds equation.  Larger
# values are a units slip or a diverged integration, not a state to extrapolate a force for.
V_MAX_PHYSICAL = 100.0


def as_state_pairs(X, V, clearance: float):
    """Validate and broadcast positions and velocities to flat (N, 2) arrays.

    Parameters
    ----------
    X : array_like, shape (..., 2)
        Journal positions (X1, X2) [m], +X2 along gravity.
    V : array_like, shape (..., 2)
        Journal velocities (V1, V2) [m/s]; broadcast against ``X``.
    clearance : float
        Radial clearance c [m] the positions must stay inside.

    Returns
    -------
    x, v : ndarray, shape (N, 2)
        C-contiguous float64 copies.
    shape : tuple of int
        The broadcast leading shape (``()`` for one state), to reshape the forces back.

    Raises
    ------
    ValueError
        For a last axis other than 2, shapes that do not broadcast, or a state that
        ``check_states`` refuses (named in the message).

    Examples
    --------
    >>> from fluidfilm.core import as_state_pairs
    >>> x, v, shape = as_state_pairs([[0.0, 1e-5], [2e-5, 0.0]], [0.0, 0.0], clearance=1e-4)
    >>> x.shape, v.shape, shape
    ((2, 2), (2, 2), (2,))
    >>> as_state_pairs([0.0, 0.0, 1e-5], [0.0, 0.0], clearance=1e-4)
    Traceback (most recent call last):
    ...
    ValueError: X must have a last axis of length 2 (X1, X2) in m, got shape (3,)
    """
    X = np.asarray(X, dtype=np.float64)
    V = np.asarray(V, dtype=np.float64)
    if X.ndim == 0 or X.shape[-1] != 2:
        raise ValueError(f"X must have a last axis of length 2 (X1, X2) in m, got shape {X.shape}")
    if V.ndim == 0 or V.shape[-1] != 2:
        raise ValueError(f"V must have a last axis of length 2 (V1, V2) in m/s, got shape {V.shape}")
    try:
        X, V = np.broadcast_arrays(X, V)
    except ValueError as err:
        raise ValueError(f"X of shape {X.shape} and V of shape {V.shape} do not broadcast") from err
    shape = X.shape[:-1]
    x = np.ascontiguousarray(X.reshape(-1, 2))
    v = np.ascontiguousarray(V.reshape(-1, 2))
    check_states(x, v, clearance)
    return x, v, shape


def check_states(x: np.ndarray, v: np.ndarray, clearance: float) -> None:
    """The domain contract of every force model (reference solvers and surrogates alike).

    Raise ``ValueError`` naming the first non-finite value, an eccentricity
    >= 1 (contact: no film) or a speed |V| above ``V_MAX_PHYSICAL``.  States
    outside a surrogate's *training* range are legal; the surrogate counts
    them (``SurrogateForceModel.n_outside_domain``, ``Trajectory.n_outside_domain``).

    Parameters
    ----------
    x : ndarray, shape (N, 2)
        Positions [m].
    v : ndarray, shape (N, 2)
        Velocities [m/s].
    clearance : float
        Radial clearance c [m].

    Raises
    ------
    ValueError
        Naming the first offending state.

    Examples
    --------
    >>> import numpy as np
    >>> from fluidfilm.core import check_states
    >>> check_states(np.array([[0.0, 5e-5]]), np.zeros((1, 2)), clearance=1e-4)    # fine: nothing returned
    >>> check_states(np.array([[0.0, 1e-4]]), np.zeros((1, 2)), clearance=1e-4)
    Traceback (most recent call last):
    ...
    ValueError: eccentricity ratio 1 >= 1 at X=(...) m: the journal touches the sleeve (clearance 0.0001 m)
    """
    if not np.isfinite(x).all():
        bad = x[~np.isfinite(x).all(axis=1)][0]
        raise ValueError(f"position X must be finite, got {tuple(bad)}")
    if not np.isfinite(v).all():
        bad = v[~np.isfinite(v).all(axis=1)][0]
        raise ValueError(f"velocity V must be finite, got {tuple(bad)}")
    if v.size:
        speed = np.hypot(v[:, 0], v[:, 1])
        k = int(np.argmax(speed))
        if speed[k] > V_MAX_PHYSICAL:
            raise ValueError(f"velocity V={tuple(v[k])} m/s: |V| = {speed[k]:.6g} m/s exceeds the physical bound "
                             f"{V_MAX_PHYSICAL:g} m/s of every force model (a units slip or a diverged state?)")
    if x.size:
        eps = np.hypot(x[:, 0], x[:, 1]) / clearance
        k = int(np.argmax(eps))
        if eps[k] >= 1.0:
            raise ValueError(
                f"eccentricity ratio {eps[k]:.6g} >= 1 at X={tuple(x[k])} m: the journal touches the "
                f"sleeve (clearance {clearance} m)"
            )
