"""One definition of each scaling transform, two execution paths: NumPy (training) and numba (inference).

Random networks, random scalings of every kind, frame and with the sleeve input; random states.
The compiled kernel's forces must equal NumPy's ``Scaling.forces(X, V, net(Scaling.inputs(X, V)))``
to round-off.
"""
from __future__ import annotations

import numpy as np
import pytest

import golden_models as gm
from fluidfilm import bearing_from_dict, paper_bearing
from fluidfilm.surrogate import SurrogateForceModel
from fluidfilm.surrogate import transforms as tf

ACT = {"tanh": np.tanh, "relu": lambda a: np.maximum(a, 0.0), "silu": lambda a: a / (1.0 + np.exp(-a)),
       "sigmoid": lambda a: 1.0 / (1.0 + np.exp(-a)),
       "pade_tanh": lambda a: a * (945 + 105 * a**2 + a**4) / (945 + 420 * a**2 + 15 * a**4)}


def _numpy_net(layers, act, z):
    for k, (W, b) in enumerate(layers):
        z = z @ W.T + b
        if k < len(layers) - 1:
            z = ACT[act](z)
    return z


CASES = [(kind, frame, sleeve) for kind in ("standard", "physics", "physics_v") for frame in ("cartesian", "polar")
         for sleeve in (False, True) if not (sleeve and kind == "standard")]
CASES += [("physics", "whirl", False), ("physics_v", "whirl", False)]


@pytest.mark.parametrize("kind,frame,sleeve", CASES)
@pytest.mark.parametrize("act", ["tanh", "silu", "pade_tanh"])
def test_numpy_and_compiled_paths_agree_to_round_off(kind, frame, sleeve, act):
    rng = np.random.default_rng(11)
    b = bearing_from_dict(gm.CONICAL) if sleeve else paper_bearing()
    extras = ("S",) if sleeve else ()
    sc = gm._scaling(rng, kind, b.clearance, b.omega, frame, extras, b.tan_half_angle if sleeve else 0.0)
    net = gm._net(rng, sc.n_inputs, 12, 2)
    model = SurrogateForceModel(b, [net], [sc], act)
    s = -0.4e-3 if sleeve else 0.0
    if sleeve:
        model.set_sleeve(s)
    X, V = gm.states(model, n=300, seed=5)
    X[0] = 0.0  # the centre: the polar frame's special case
    E = np.full((len(X), 1), s) if sleeve else None
    F_numpy = sc.forces(X, V, _numpy_net(net, act, sc.inputs(X, V, E)), E)
    F_kernel = model.forces(X, V)
    scale = np.abs(F_numpy).max()
    np.testing.assert_allclose(F_kernel, F_numpy, rtol=1e-11, atol=1e-13 * scale)


def test_the_transforms_invert_each_other():
    rng = np.random.default_rng(0)
    x1, x2, a1, a2 = rng.normal(size=(4, 1000))
    er1, er2 = tf.radial_axis(x1, x2)
    np.testing.assert_allclose(np.hypot(er1, er2), 1.0, rtol=1e-15)
    back = tf.from_polar(er1, er2, *tf.to_polar(er1, er2, a1, a2))
    np.testing.assert_allclose(back, [a1, a2], rtol=1e-13, atol=1e-15)
    # along e_r the position itself is its length
    np.testing.assert_allclose(tf.to_polar(er1, er2, x1, x2)[0], np.hypot(x1, x2), rtol=1e-14)
    assert tf.radial_axis(0.0, 0.0) == (0.0, 1.0)
