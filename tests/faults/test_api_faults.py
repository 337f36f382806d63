"""Issue #26 item 6 (library): no silent wrong answers. Each probe of the new user's trial is a test: the bad
input raises a ValueError that names the value (or the file and the field), where it once gave a number."""
from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest

import fluidfilm
from fluidfilm import (ConicalBearing, JournalBearing, ReynoldsSolver, Rotor, load_along_gravity, load_surrogate,
                       paper_bearing, simulate)
from fluidfilm.characteristics import bearing_characteristics, coefficients as coef, stability as stab
from fluidfilm.rotor import LinearBearing
from fluidfilm.rotor.batch import simulate_batch
from fluidfilm.surrogate.inference import SurrogateFileError


B = paper_bearing()
GOOD = dict(length=0.064, diameter=0.040, clearance=120e-6, speed_rpm=3000.0, viscosity=6.53e-4)


@pytest.fixture(scope="module")
def solver():
    return ReynoldsSolver(B, 30, 30)


# --- equilibria that do not exist --------------------------------------------------------------------
def test_load_beyond_the_film_capacity_raises_naming_the_load(solver):
    """1e9 N on the paper bearing: once eps = 0.995 (the solver's bound), residual 0.998, "stable"."""
    with pytest.raises(ValueError, match=r"no equilibrium under the load \(0.0, 1000000000.0\) N .*eccentricity bound"):
        fluidfilm.equilibrium(solver, load_along_gravity(1e9))
    with pytest.raises(ValueError, match=r"1000000000.0"):
        bearing_characteristics(solver, load_along_gravity(1e9))


class _HalfStrength:
    """A film whose force is half the load at every position: no equilibrium exists anywhere (the truth)."""

    def __init__(self, w):
        self.bearing, self.w = B, w

    def forces(self, X, V):
        X = np.asarray(X, dtype=float)
        r = np.linalg.norm(X, axis=-1, keepdims=True)
        return -0.5 * self.w * np.divide(X, r, out=np.zeros_like(X), where=r > 0)


def test_a_residual_above_tolerance_raises_naming_the_load():
    with pytest.raises(ValueError, match=r"no equilibrium under the load \(0.0, 50.0\) N .*residual"):
        fluidfilm.equilibrium(_HalfStrength(50.0), (0.0, 50.0))


def test_a_study_of_several_models_records_a_missing_equilibrium_as_nan_not_numbers(solver):
    from fluidfilm.studies import characteristics_study as study
    models = {"reference": solver, "half": _HalfStrength(24.5)}
    with pytest.raises(ValueError, match=r"\(0.0, 24.5\)"):
        study.coefficient_table(models, [24.5], {})
    with pytest.warns(RuntimeWarning, match=r"half: no equilibrium under the load \(0.0, 24.5\) N"):
        table = study.coefficient_table(models, [24.5], {}, on_error="nan")
    ref, half = table.iloc[0], table.iloc[1]
    assert ref.eps == pytest.approx(0.586, abs=1e-3) and np.isfinite(ref[list(coef.NAMES)].to_numpy(float)).all()
    assert np.isnan(half[["eps", "attitude_deg", *coef.NAMES]].to_numpy(float)).all()
    assert half.sommerfeld == ref.sommerfeld  # a property of the load, not of the model


@pytest.mark.parametrize("bad", [0.0, -1000.0, math.nan, math.inf, True, "24.5", None])
def test_a_load_magnitude_must_be_positive_and_finite(bad):
    with pytest.raises(ValueError, match=f"load W must be a positive finite number in N, got {bad!r}"):
        load_along_gravity(bad)


@pytest.mark.parametrize("load, match", [
    (-1000.0, "got the scalar -1000.0; for a magnitude W along gravity pass fluidfilm.load_along_gravity"),
    (1000.0, "got the scalar 1000.0"),
    ((0.0, 0.0), r"finite non-zero vector \(W1, W2\) in N, got \(0.0, 0.0\)"),
    ((0.0, math.nan), "finite non-zero vector"),
    ((1.0, 2.0, 3.0), r"must be a vector \(W1, W2\)"),
    ((True, 10.0), r"must be a vector \(W1, W2\)"),
])
def test_a_load_must_be_a_finite_vector(solver, load, match):
    """Once: equilibrium(s, 1000.0) failed in a numpy reshape, bearing_characteristics(s, -1000) gave coefficients."""
    for call in (fluidfilm.equilibrium, bearing_characteristics):
        with pytest.raises(ValueError, match=match):
            call(solver, load)


def test_sommerfeld_of_a_non_positive_load_raises():
    with pytest.raises(ValueError, match="load must be a positive finite number, got -5.0"):
        B.sommerfeld(-5.0)


def test_a_shaft_at_rest_raises_instead_of_nan():
    """speed_rpm = 0 is a legal squeeze-film bearing, but it carries no static load: once NaN with warnings."""
    b = JournalBearing(**{**GOOD, "speed_rpm": 0.0})
    s = ReynoldsSolver(b, 30, 30)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning on the way to the error
        with pytest.raises(ValueError, match="speed_rpm=0.0"):
            bearing_characteristics(s, load_along_gravity(24.5))
        with pytest.raises(ValueError, match="speed_rpm=0.0"):
            coef.coefficients(s, [0.0, 0.5 * b.clearance])


@pytest.mark.parametrize("bracket", [(1, 0.5), (0.5, 0.5), (0.0, 2.0), (math.nan, 2.0), ("a", 2.0), (1.0,)])
def test_a_reversed_or_bad_speed_bracket_raises(solver, bracket):
    """(1, 0.5) once returned inf ("stable over the whole bracket") without a word."""
    with pytest.raises(ValueError, match="speed_bracket"):
        stab.threshold_speed(solver, 2.5, load_along_gravity(24.5), speed_bracket=bracket)


@pytest.mark.parametrize("mass", [0.0, -2.5, math.nan, True])
def test_threshold_refuses_a_bad_mass(solver, mass):
    with pytest.raises(ValueError, match=f"mass must be a positive finite number in kg, got {mass!r}"):
        stab.threshold_speed(solver, mass, load_along_gravity(24.5))


# --- bearing fields ----------------------------------------------------------------------------------
@pytest.mark.parametrize("field", ["length", "diameter", "clearance", "viscosity", "density", "speed_rpm",
                                   "supply_pressure"])
@pytest.mark.parametrize("bad", ["abc", True, math.nan, math.inf, -1.0, None])
def test_every_bearing_field_is_a_finite_real_number_named_on_error(field, bad):
    with pytest.raises(ValueError, match=f"{field} must be .*got {bad!r}"):
        JournalBearing(**{**GOOD, field: bad})


@pytest.mark.parametrize("field", ["length", "diameter", "clearance", "viscosity", "density"])
def test_zero_is_refused_where_the_field_must_be_positive(field):
    with pytest.raises(ValueError, match=f"{field} must be a positive finite number, got 0.0"):
        JournalBearing(**{**GOOD, field: 0.0})


def test_a_clearance_beyond_the_thin_film_bound_is_refused():
    """c = 0.8 R was accepted: the Reynolds equation is the thin-film limit, c/R < 0.1."""
    with pytest.raises(ValueError, match=r"clearance 0.016 m is 0.8 of the radius 0.02 m; .*c/R < 0.1"):
        JournalBearing(**{**GOOD, "clearance": 0.8 * 0.02})
    assert JournalBearing(**{**GOOD, "clearance": 0.09 * 0.02}).clearance == pytest.approx(0.0018)


def test_a_squeeze_film_bearing_at_rest_is_still_legal():
    assert JournalBearing(**{**GOOD, "speed_rpm": 0}).speed_rpm == 0.0


@pytest.mark.parametrize("field, bad", [("clearance", "abc"), ("speed_rpm", True), ("sleeve_min", math.nan),
                                        ("clearance_taper", "0")])
def test_the_conical_bearing_names_its_bad_field(field, bad):
    good = dict(length=0.064, diameter_small=0.03665, diameter_large=0.04335, clearance=120e-6, speed_rpm=3000.0,
                viscosity=6.53e-4, sleeve_min=-0.8e-3, sleeve_max=0.8e-3)
    with pytest.raises(ValueError, match=f"{field} must be .*got {bad!r}"):
        ConicalBearing(**{**good, field: bad})


# --- integrator arguments ----------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, name", [
    ({"t0": math.nan}, "t0"),
    ({"record_every": 2.5}, "record_every"),
    ({"record_every": True}, "record_every"),
    ({"dt": True}, "dt"),
    ({"dt": "1e-5"}, "dt"),
    ({"t_end": True}, "t_end"),
    ({"max_substeps": 0}, "max_substeps"),
    ({"eps_stop": "0.9"}, "eps_stop"),
])
@pytest.mark.parametrize("batched", [False, True])
def test_simulate_and_simulate_batch_refuse_the_same_bad_argument_naming_it(kwargs, name, batched):
    """simulate_batch once accepted t0=nan (then "diverged at t=nan"), record_every=2.5 and dt=True."""
    model = LinearBearing(B, 1e6, 50.0)
    args = {"t_end": 1e-3, "dt": 1e-5, **kwargs}
    run = simulate_batch if batched else simulate
    with pytest.raises(ValueError, match=f"{name} must be"):
        run(model, Rotor(mass=2.5), **args)


# --- model.json ---------------------------------------------------------------------------------------
def _edit(d, change):
    f = d / "model.json"
    meta = json.loads(f.read_text())
    meta = change(meta)
    f.write_text(json.dumps(meta))
    return f


def _legacy(meta):
    meta.pop("content_sha256")  # as written before model.json was checksummed
    return meta


@pytest.mark.parametrize("change, match", [
    (lambda m: [m], "holds a JSON list, expected an object"),
    (lambda m: {k: v for k, v in m.items() if k != "activation"}, "lacks the key 'activation'"),
    (lambda m: {("activaton" if k == "activation" else k): v for k, v in m.items()},
     "unknown key 'activaton' \\(did you mean 'activation'\\?\\)"),
    (lambda m: {**m, "eps_max": "0.97"}, "key 'eps_max' must be a JSON number, got '0.97'"),
    (lambda m: {**m, "n_layers": m["n_layers"][:1]}, "key 'n_layers' must list one layer count"),
    (lambda m: {**m, "scalings": [{**s, "clearence": 1.0} for s in m["scalings"]]},
     "scalings\\[0\\]: unknown key 'clearence' \\(did you mean 'clearance'\\?\\)"),
    (lambda m: {**m, "bearing": {**m["bearing"], "clearance": 0.9 * m["bearing"]["diameter"]}},
     "bearing: clearance .* c/R < 0.1"),
    (lambda m: {**m, "bearing": {**m["bearing"], "densty": 1000.0}}, "bearing: unknown key 'densty'"),
])
@pytest.mark.parametrize("old", [False, True])
def test_a_hand_edited_model_json_is_refused_naming_the_file_and_the_field(saved, change, match, old):
    """The schema holds for files with and without the content checksum (old models)."""
    _, d = saved
    f = _edit(d, (lambda m: change(_legacy(m))) if old else change)
    with pytest.raises(SurrogateFileError, match=match) as err:
        load_surrogate(d)
    assert str(f) in str(err.value)


def test_a_changed_clearance_no_longer_matches_the_recorded_checksum(saved):
    """A plausible edit (a clearance 10 % larger, which the schema accepts) loaded silently before."""
    _, d = saved
    f = _edit(d, lambda m: {**m, "bearing": {**m["bearing"], "clearance": 1.1 * m["bearing"]["clearance"]}})
    with pytest.raises(SurrogateFileError, match="the key 'bearing' was changed after the model was saved.*retrain") as err:
        load_surrogate(d)
    assert str(f) in str(err.value)


def test_a_removed_checksummed_key_is_named(saved):
    _, d = saved
    _edit(d, lambda m: {k: v for k, v in m.items() if k != "array_shapes"})
    with pytest.raises(SurrogateFileError, match="the key 'array_shapes' recorded at save time is missing"):
        load_surrogate(d)


def test_a_model_saved_before_the_checksum_still_loads_identical(saved):
    m, d = saved
    _edit(d, _legacy)
    X = m.bearing.clearance * np.array([[0.1, 0.2], [0.0, 0.7]])
    V = np.full_like(X, 0.01)
    np.testing.assert_array_equal(load_surrogate(d).forces(X, V), m.forces(X, V))


def test_the_checksum_does_not_depend_on_the_files_layout(saved):
    """Re-indenting model.json (a JSON tool, an editor) changes no value: it still loads."""
    m, d = saved
    f = d / "model.json"
    f.write_text(json.dumps(json.loads(f.read_text()), indent=7))
    X = m.bearing.clearance * np.array([[0.3, -0.1]])
    np.testing.assert_array_equal(load_surrogate(d).forces(X, np.zeros_like(X)), m.forces(X, np.zeros_like(X)))
