"""The JFO film's surrogate with memory (``surrogate.film_memory``): the carried path history, its features
against the training features, files, refusals and the domain status.  Its accuracy against the JFO reference
is the study's (``studies.jfo_surrogate``, reports/jfo_surrogate.json); here a network with known weights
makes the kernels' inputs visible as forces."""
from __future__ import annotations

import numpy as np
import pytest

from fluidfilm import paper_bearing
from fluidfilm.rotor.integrate import OutsideDomainError, simulate
from fluidfilm.rotor.model import Rotor, SpeedSchedule
from fluidfilm.surrogate.film_memory import MemorySurrogate, memory_commit, memory_inputs, memory_stage

N_LAGS = 5
LAG_DT = 2e-3


def _probe(k: int, bearing=None, eps_max: float = 0.9, sign: float = 1.0) -> MemorySurrogate:
    """A linear 'network' whose force / force_scale is the k-th input pair (k = 0: x/c, 1: v/(c w), 1 + j:
    lag j), unstandardised: the kernels' raw inputs come out as the force."""
    bearing = bearing or paper_bearing()
    n_in = 4 + 2 * N_LAGS
    W = np.zeros((2, n_in))
    W[0, 2 * k] = sign
    W[1, 2 * k + 1] = sign
    ones, zeros = np.ones(n_in), np.zeros(n_in)
    return MemorySurrogate(bearing, [(W, np.zeros(2))], "tanh", zeros, ones, np.zeros(2), np.ones(2), LAG_DT,
                           N_LAGS, eps_max)


def _path(t, c):
    """A smooth journal path that is not periodic in the lag spacing."""
    return np.stack([0.3 * c * np.sin(2 * np.pi * 37.0 * t) + 0.1 * c * t / t[-1],
                     0.2 * c + 0.25 * c * np.cos(2 * np.pi * 23.0 * t)], axis=1)


@pytest.mark.parametrize("dt", [1e-5, 3e-5])
def test_carried_history_gives_the_training_features(dt):
    """Committing a path step by step and evaluating a stage gives, for every lag, the input that
    ``memory_inputs`` computes from the recorded path (the features the network is trained on), to round-off;
    the steps need not divide the lag spacing (3e-5 s does not divide 2e-3 s)."""
    b = paper_bearing()
    c = b.clearance
    n = int(round(0.03 / dt))
    t = np.arange(n + 1) * dt
    x = _path(t, c)
    v = np.gradient(x, dt, axis=0)
    for k in range(2, 2 + N_LAGS):
        m = _probe(k, b)
        _, hist = m.steady_field(x[0])
        new = hist.copy()
        got = np.empty((n + 1, 2))
        for i in range(n + 1):
            got[i] = memory_stage(m.params, 1.0, x[i, 0], x[i, 1], v[i, 0], v[i, 1], dt, 0.0, hist, None, None, None)[:2]
            if i < n:
                memory_commit(m.params, 1.0, x[i, 0], x[i, 1], x[i + 1, 0], x[i + 1, 1], dt, hist, None, None, new)
                hist[:] = new
        want = memory_inputs(t, x, v, c, b.omega, LAG_DT, N_LAGS)[:, 2 * k:2 * k + 2] * b.force_scale
        scale = np.abs(want).max()
        assert scale > 0.05 * b.force_scale  # the lag features are not trivially zero along this path
        # the samples are taken by interpolation inside a step when dt does not divide the spacing: exact for
        # dt | lag_dt, and within the path's curvature over one step otherwise
        tol = 1e-9 if dt == 1e-5 else 2e-3
        np.testing.assert_allclose(got, want, rtol=0, atol=tol * scale)


def test_memory_inputs_by_hand():
    """A journal moving at a constant rate: the lagged offsets are -k lag_dt times the speed; at rest before
    t = 0 (the steady film), so a lag before the path's start sees the starting point."""
    c, w = 1e-4, 100.0
    t = np.linspace(0.0, 0.02, 2001)
    x = np.stack([1e-5 * t / 0.02, np.zeros_like(t)], axis=1)
    z = memory_inputs(t, x, np.zeros_like(x), c, w, LAG_DT, N_LAGS)
    rate = 1e-5 / 0.02 / c
    np.testing.assert_allclose(z[-1, 4::2], -rate * LAG_DT * np.arange(1, N_LAGS + 1), rtol=1e-9)
    np.testing.assert_allclose(z[0, 4:], 0.0, atol=1e-15)  # at rest at x[0] before the start
    # one lag step in: the lags beyond the first reach back before t = 0, where the journal rested at x[0]
    i = int(np.searchsorted(t, LAG_DT))
    np.testing.assert_allclose(z[i, 6::2], -x[i, 0] / c, rtol=1e-9)


def test_a_rotor_at_rest_in_it_sees_no_memory():
    """Started at rest where the (linear) film carries the load, the journal stays there: the history is at
    rest, so the transient force is the steady one, and the run agrees with the one-state force kernel."""
    b = paper_bearing()
    m = _probe(0, b)  # F / force_scale = x / c: a spring of stiffness force_scale / c, no damping
    rotor = Rotor(mass=0.2 * b.force_scale / 9.81)  # rests at eps 0.2
    w = rotor.mass * rotor.gravity
    x0 = np.array([0.0, -w / b.force_scale * b.clearance])  # F2 = force_scale x2 / c = -m g
    tr = simulate(m, rotor, t_end=0.01, dt=1e-5, x0=x0, check_step=False)
    assert tr.status == "ok"
    np.testing.assert_allclose(tr.x[-1], x0, atol=1e-12 * b.clearance)
    np.testing.assert_allclose(m.forces(x0, [0.0, 0.0]), [0.0, -w], rtol=1e-12)


def test_save_load_round_trip(tmp_path):
    b = paper_bearing()
    rng = np.random.default_rng(1)
    n_in = 4 + 2 * N_LAGS
    layers = [(rng.normal(size=(8, n_in)), rng.normal(size=8)), (rng.normal(size=(2, 8)), rng.normal(size=2))]
    m = MemorySurrogate(b, layers, "tanh", rng.normal(size=n_in), 1 + rng.random(n_in), rng.normal(size=2),
                        1 + rng.random(2), LAG_DT, N_LAGS, 0.8, meta={"note": "test"})
    m.save(tmp_path / "m")
    m2 = MemorySurrogate.load(tmp_path / "m")
    X = rng.uniform(-0.5, 0.5, size=(20, 2)) * b.clearance
    V = rng.normal(size=(20, 2)) * b.clearance * b.omega * 0.1
    assert np.array_equal(m.forces(X, V), m2.forces(X, V))
    assert m2.meta["note"] == "test" and m2.n_lags == N_LAGS and m2.lag_dt == LAG_DT
    with pytest.raises(ValueError, match="missing"):
        MemorySurrogate.load(tmp_path / "nothing")


def test_refusals():
    b = paper_bearing()
    m = _probe(0, b)
    rotor = Rotor(mass=0.1 * b.force_scale / 9.81)
    with pytest.raises(ValueError, match="one shaft speed"):
        simulate(m, rotor, t_end=0.001, dt=1e-5, speed=SpeedSchedule.ramp(3000.0, 4000.0, 0.001),
                 check_step=False)
    with pytest.raises(ValueError, match="film_content must be a finite history of shape"):
        simulate(m, rotor, t_end=0.001, dt=1e-5, film_content=np.zeros((3, 3)), check_step=False)
    with pytest.raises(ValueError, match="lags need"):
        MemorySurrogate(b, [(np.zeros((2, 6)), np.zeros(2))], "tanh", np.zeros(14), np.ones(14), np.zeros(2),
                        np.ones(2), LAG_DT, N_LAGS, 0.9)


def test_outside_its_paths_is_not_ok():
    """A run that leaves the training paths' eccentricities gets the 'outside-domain' status and a warning;
    strict=True raises."""
    b = paper_bearing()
    m = _probe(0, b, eps_max=0.05, sign=-1.0)  # a spring: the journal swings to eps ~ 0.2 under its weight
    rotor = Rotor(mass=0.1 * b.force_scale / 9.81)
    with pytest.warns(RuntimeWarning, match="outside the training domain"):
        tr = simulate(m, rotor, t_end=0.005, dt=1e-5, check_step=False)
    assert tr.status.startswith("outside-domain") and tr.n_outside_domain > 0 and not tr.ok
    with pytest.raises(OutsideDomainError):
        simulate(m, rotor, t_end=0.005, dt=1e-5, check_step=False, strict=True)
