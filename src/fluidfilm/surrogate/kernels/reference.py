"""The surrogate's evaluation written once to be read: plain NumPy, vectorised over states, no compiled code.

What every compiled kernel computes (``generic``, ``generated``, ``generic_batch``, ``generated_batch``,
``jacobian``), in the order a reader would explain it, for many states at once:

1. route: the eccentricity ratio eps = |X| / c of the current clearance picks the region r (regions
   split at ``model.boundaries``); within ``blend_width`` / 2 of a boundary the two neighbours' forces
   are mixed with the smoothstep weight w = t^2 (3 - 2 t);
2. scale the inputs: ``Scaling.inputs`` (the frame, clearance units, the extra inputs, standardising);
3. the network: dense layers, the activation's NumPy value (``activations.REGISTRY``) between them; the
   damping structure adds C(z) w, w the raw velocity inputs;
4. back to forces: ``Scaling.forces`` (un-standardise, the physics gain, the frame).

It does not count states outside the training domain (the kernels do).  ``tests/surrogate/test_surrogate_kernels``
checks every compiled path against it on random states of every shipped, trained and test model: equal to
round-off in float64 (1e-9 of the states' RMS force), within float32's precision (1e-5) in float32.

>>> import numpy as np
>>> from fluidfilm import paper_bearing
>>> from fluidfilm.surrogate.universal import universal_bearing
>>> model = universal_bearing(paper_bearing())
>>> X, V = np.array([[0.0, 40e-6]]), np.zeros((1, 2))
>>> bool(np.allclose(reference_forces(model, X, V), model.forces(X, V), rtol=1e-12))
True
"""
from __future__ import annotations

import numpy as np

from fluidfilm.surrogate.activations import REGISTRY

__all__ = ["reference_forces", "network"]


def network(layers, z: np.ndarray, activation: str) -> np.ndarray:
    """A dense network [(W (out, in), b)] on inputs z (n, in): the activation between layers, none after the last.
    A first layer narrower than z takes z's leading columns (the damping structure's static network)."""
    h = z[:, :np.shape(layers[0][0])[1]]
    value = REGISTRY[activation].derivatives
    for k, (W, b) in enumerate(layers):
        h = h @ np.asarray(W, dtype=float).T + np.asarray(b, dtype=float)
        if k < len(layers) - 1:
            h = np.asarray(value(h)[0], dtype=float)
    return h


def _region_forces(model, r: int, X: np.ndarray, V: np.ndarray, E) -> np.ndarray:
    sc = model.scalings[r]
    z = sc.inputs(X, V, E)
    if model.structure == "plain":
        y = network(model.networks[r], z, model.activation)
    else:
        static, damping = model.networks[r]
        n = z.shape[1]
        # the raw velocity inputs (units of c omega), 0 at rest: the standardisation undone
        w = z[:, n - 2:] * sc.in_std[n - 2:] + sc.in_mean[n - 2:]
        C = network(damping, z, model.activation)
        y = network(static, z, model.activation) + np.stack(
            [C[:, 0] * w[:, 0] + C[:, 1] * w[:, 1], C[:, 2] * w[:, 0] + C[:, 3] * w[:, 1]], axis=1)
    return sc.forces(X, V, y, E)


def reference_forces(model, X, V) -> np.ndarray:
    """Film forces [N] of a ``SurrogateForceModel`` at positions X [m] and velocities V [m/s], (n, 2) each, at
    the model's current setting (its sleeve, for a surrogate with the sleeve as an input)."""
    X = np.asarray(X, dtype=float).reshape(-1, 2)
    V = np.asarray(V, dtype=float).reshape(-1, 2)
    n = X.shape[0]
    n_extra = len(model.scalings[0].extras)
    E = np.broadcast_to(model.setting_array[1:1 + n_extra], (n, n_extra)) if n_extra else None
    eps = np.hypot(X[:, 0], X[:, 1]) * np.sqrt(model.setting_array[0])
    bounds = np.asarray(model.boundaries, dtype=float)
    region = np.searchsorted(bounds, eps, side="right")
    # the blend: the first boundary within half the blend width, as the kernels scan them
    second = np.full(n, -1)
    weight = np.zeros(n)
    if model.blend_width > 0.0:
        for b in reversed(range(len(bounds))):
            lo = bounds[b] - 0.5 * model.blend_width
            inside = (lo <= eps) & (eps < bounds[b] + 0.5 * model.blend_width)
            t = (eps - lo) / model.blend_width
            region = np.where(inside, b, region)
            second = np.where(inside, b + 1, second)
            weight = np.where(inside, t * t * (3.0 - 2.0 * t), weight)
    F = np.zeros((n, 2))
    for r in range(len(model.networks)):
        first, mixed = region == r, second == r
        for rows, share in ((first, np.where(second >= 0, 1.0 - weight, 1.0)), (mixed, weight)):
            if rows.any():
                E_rows = None if E is None else E[rows]
                F[rows] += share[rows, None] * _region_forces(model, r, X[rows], V[rows], E_rows)
    return F
