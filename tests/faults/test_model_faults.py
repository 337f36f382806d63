"""Items 6-8: damaged surrogate files, one domain contract for every force model, out-of-range counts."""
from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from fluidfilm import Rotor, load_surrogate, simulate
from fluidfilm.core.states import V_MAX_PHYSICAL
from fluidfilm.surrogate.inference import SurrogateFileError

from . import models
from .models import C

MODELS = models.all_models()


# --------------------------------------------------------------------------- item 6
def _rewrite_npz(path, change):
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    change(arrays)
    np.savez(path, **arrays)


def test_saved_surrogate_loads_back_identical(saved):
    m, d = saved
    X = C * np.array([[0.1, 0.2], [0.0, 0.7], [0.6, -0.5]])
    V = np.full_like(X, 0.01)
    np.testing.assert_array_equal(load_surrogate(d).forces(X, V), m.forces(X, V))


@pytest.mark.parametrize("fault, match", [
    ("nan_weight", "r1_W0 holds non-finite values"),
    ("wrong_shape", r"r0_W1 has shape \(2, 49\)"),
    ("flipped_byte", "surrogate.npz is damaged or was replaced"),
    ("truncated_npz", "surrogate.npz"),
    ("missing_npz", "surrogate.npz is missing"),
    ("damaged_json", "model.json is not valid JSON"),
])
def test_damaged_surrogate_is_refused_naming_the_file(saved, fault, match):
    _, d = saved
    npz, meta_file = d / "surrogate.npz", d / "model.json"
    meta = json.loads(meta_file.read_text())
    if fault in ("nan_weight", "wrong_shape"):
        # a consistent but wrong file (checksum updated too): only the content checks can see it
        def change(a):
            if fault == "nan_weight":
                a["r1_W0"][3, 2] = np.nan
            else:
                a["r0_W1"] = a["r0_W1"][:, :49]
        _rewrite_npz(npz, change)
        from fluidfilm.io import file_sha256 as _sha256
        meta["weights_sha256"] = _sha256(npz)
        meta.pop("array_shapes")
        meta.pop("content_sha256")  # as a file written before model.json was checksummed
        meta_file.write_text(json.dumps(meta))
    elif fault == "flipped_byte":
        data = bytearray(npz.read_bytes())
        data[len(data) // 2] ^= 0x04
        npz.write_bytes(bytes(data))
    elif fault == "truncated_npz":
        npz.write_bytes(npz.read_bytes()[:100])
        meta.pop("weights_sha256")  # an old file without a checksum: the reader itself must name the file
        meta.pop("content_sha256")
        meta_file.write_text(json.dumps(meta))
    elif fault == "missing_npz":
        npz.unlink()
    else:
        meta_file.write_text(meta_file.read_text()[:-40])
    with pytest.raises(SurrogateFileError, match=match) as err:
        load_surrogate(d)
    assert str(d) in str(err.value)
    assert isinstance(err.value, ValueError)


# --------------------------------------------------------------------------- item 7
@pytest.mark.parametrize("name", list(MODELS))
@pytest.mark.parametrize("state, match", [
    (([0.0, 1.0 * C], [0.0, 0.0]), "eccentricity ratio 1 >= 1"),
    (([0.0, 1.5 * C], [0.0, 0.0]), "eccentricity ratio 1.5 >= 1"),
    (([np.nan, 0.0], [0.0, 0.0]), "position X must be finite"),
    (([0.0, 0.2 * C], [np.inf, 0.0]), "velocity V must be finite"),
    (([0.0, 0.2 * C], [1e300, 0.0]), "exceeds the physical bound"),
    (([0.0, 0.2 * C], [0.0, -1.01 * V_MAX_PHYSICAL]), "exceeds the physical bound"),
])
def test_every_force_model_enforces_the_same_domain_contract(name, state, match):
    model, _ = MODELS[name]
    X, V = state
    for shape in ((2,), (1, 2)):  # the single-state fast path and the batched one
        with pytest.raises(ValueError, match=match):
            model.forces(np.reshape(X, shape), np.reshape(V, shape))


@pytest.mark.parametrize("name", list(MODELS))
def test_every_force_model_answers_inside_the_domain_and_surrogates_warn_outside_training(name):
    model, has_domain = MODELS[name]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # inside the training range: a finite force and not a word
        F = model.forces([0.0, 0.5 * C], [0.001, 0.0])
    assert np.isfinite(F).all()
    outside = ([0.0, 0.99 * C], [0.0, 0.0])  # beyond the data's eps_max = 0.97, still a legal state
    if has_domain:
        for _ in range(3):  # every call, not once per process
            with pytest.warns(RuntimeWarning, match="1 of 1 states lie outside the training domain"):
                model.forces(*outside)
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            # item 24: a reference grid too coarse at eps 0.99 says so (once per solver), nothing else
            warnings.filterwarnings("ignore", message=".*off a converged grid", category=RuntimeWarning)
            assert np.isfinite(model.forces(*outside)).all()


# --------------------------------------------------------------------------- item 8
def test_out_of_range_evaluations_are_counted_per_trajectory():
    model = models.single()
    rotor = Rotor(mass=2.5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        fast = simulate(model, rotor, t_end=2e-3, dt=1e-5, x0=[0.0, 0.3 * C], v0=[0.0, 5.0])  # |V| >> data's 0.5
        slow = simulate(model, rotor, t_end=2e-3, dt=1e-5, x0=[0.0, 0.3 * C], v0=[0.0, 0.0])
        again = simulate(model, rotor, t_end=2e-3, dt=1e-5, x0=[0.0, 0.3 * C], v0=[0.0, 5.0])
    # each trajectory its own count: the second fast run is not silenced by the first
    assert fast.n_outside_domain > 0 and again.n_outside_domain == fast.n_outside_domain
    assert f"outside the training domain in {fast.n_outside_domain} force evaluations" in fast.status
    assert fast.n_outside_domain <= fast.n_force_evals
    assert slow.n_outside_domain == 0 and slow.status == "ok"


def test_trajectory_count_survives_saving(tmp_path):
    from fluidfilm.rotor.integrate import Trajectory

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        traj = simulate(models.single(), Rotor(mass=2.5), t_end=1e-3, x0=[0.0, 0.3 * C], v0=[0.0, 5.0])
    traj.to_npz(tmp_path / "t.npz")
    assert Trajectory.from_npz(tmp_path / "t.npz").n_outside_domain == traj.n_outside_domain > 0


def test_case_summary_carries_the_count():
    from fluidfilm.rotor.cases import case_summary

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        traj = simulate(models.single(), Rotor(mass=2.5), t_end=5e-3, x0=[0.0, 0.3 * C], v0=[0.0, 5.0])
    assert case_summary(traj, C, 0.0)["n_outside_domain"] == traj.n_outside_domain > 0
