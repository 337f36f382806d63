"""The on-line estimator (fluidfilm.estimation): it recovers known parameters from a small synthetic plant run
made with the reference solver, its flags fire where they should and not elsewhere, bad probe files are refused
in one line naming the problem, and the user's entry point writes its estimates."""
from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pandas as pd
import pytest

from fluidfilm import JournalBearing, ReynoldsSolver, universal_bearing
from fluidfilm.estimation import EstimatorSettings, estimate
from fluidfilm.estimation.assess import assess
from fluidfilm.estimation.plant import Scenario, runout_signal, simulate_plant
from fluidfilm.estimation.probes import BearingDescription, ProbeFileError, check_probe_frame, read_probe_file

warnings.filterwarnings("ignore", message="First-class function type feature is experimental")

BEARING = JournalBearing(length=0.03, diameter=0.06, clearance=80e-6, speed_rpm=6000.0, viscosity=0.02)
MASS = 50.0
W = MASS * 9.81


def _scenario(name="steady", values=None, times=(0.0, 1.0), t_end=0.3, force_2x=0.0, noise=1e-6):
    row = (0.0, W, 1e-3 * math.cos(0.6), 1e-3 * math.sin(0.6), 1.0)
    return Scenario(name=name, times=times, values=values or (row, row), speed_rpm=6000.0, mass=MASS, t_end=t_end,
                    noise=noise, runout_known_error=0.0, force_2x=force_2x)


@pytest.fixture(scope="module")
def reference():
    return ReynoldsSolver(BEARING, 48, 8)   # coarse: a plant unlike the estimator's surrogate, and fast


@pytest.fixture(scope="module")
def model():
    return universal_bearing(BEARING)


@pytest.fixture(scope="module")
def steady_run(reference, model):
    rec = simulate_plant(reference, _scenario(), dt=2e-5, seed=1)
    est = estimate(rec.frame, model, MASS, runout=rec.runout_supplied)
    return rec, est


def test_the_estimator_recovers_load_imbalance_and_viscosity_of_a_reference_plant(steady_run):
    rec, est = steady_run
    late = est.t >= 0.2
    z = est.z[late]
    load_err = np.hypot(z[:, 4] - 0.0, z[:, 5] - W) / W
    u_err = np.hypot(z[:, 6], z[:, 7]) / 1e-3 - 1.0
    s_err = z[:, 8] - 1.0
    # the coarse plant grid differs from the converged force by ~0.5 %: a few per cent is the bound here
    assert np.sqrt(np.mean(load_err ** 2)) < 0.03
    assert np.sqrt(np.mean(u_err ** 2)) < 0.03
    assert np.sqrt(np.mean(s_err ** 2)) < 0.03
    phase = np.degrees(np.arctan2(z[:, 7], z[:, 6]))
    assert np.all(np.abs(phase - math.degrees(0.6)) < 3.0)
    # the bands: 2 sigma of the filter's own covariance, a few per cent wide at the end
    assert 0.0 < est.sd[-1, 8] < 0.03
    assert not est.mismatch.any() and not est.out_of_domain.any()
    assert est.us_per_sample < 1000.0      # the speed goal is measured by the stage; here: it is compiled


def test_the_smoother_sees_the_whole_window(steady_run):
    _, est = steady_run
    assert est.zs is not None and est.zs.shape == est.z.shape
    # at the start the smoother knows what the filter learns later: its early viscosity is closer to the truth
    early = est.t < 0.02
    assert np.mean(np.abs(est.zs[early, 8] - 1.0)) < np.mean(np.abs(est.z[early, 8] - 1.0))
    assert np.all(est.sds[early, 8] <= est.sd[early, 8] + 1e-12)


def test_a_load_step_is_followed_and_the_mismatch_flag_stays_quiet(reference, model):
    row = (0.0, W, 1e-3 * math.cos(0.6), 1e-3 * math.sin(0.6), 1.0)
    stepped = (150.0, 700.0, row[2], row[3], 1.0)
    sc = _scenario("load_step", values=(row, row, stepped), times=(0.0, 0.1, 0.1002), t_end=0.3)
    rec = simulate_plant(reference, sc, dt=2e-5, seed=2)
    est = estimate(rec.frame, model, MASS, runout=rec.runout_supplied,
                   settings=EstimatorSettings(smooth=False))
    late = est.t >= 0.25
    err = np.hypot(est.z[late, 4] - 150.0, est.z[late, 5] - 700.0) / math.hypot(150.0, 700.0)
    assert np.sqrt(np.mean(err ** 2)) < 0.03
    assert est.info["inflations"] >= 1
    assert not est.mismatch.any()


def test_a_coast_down_is_followed_with_the_speed_signal(reference, model):
    # the speed falls 25 % over the record: the film force at the measured speed, the imbalance's push with
    # (omega^2 + i alpha) in plant and filter alike; the parameters stay those of the steady run
    row = (0.0, W, 1e-3 * math.cos(0.6), 1e-3 * math.sin(0.6), 1.0)
    sc = Scenario(name="coast_down", times=(0.0, 1.0), values=(row, row), speed_rpm=6000.0, mass=MASS, t_end=0.3,
                  runout_known_error=0.0, speed_knots=((0.0, 6000.0), (0.3, 4500.0)))
    rec = simulate_plant(reference, sc, dt=2e-5, seed=4)
    assert rec.frame["speed"].iloc[0] == pytest.approx(6000.0) and rec.frame["speed"].iloc[-1] == pytest.approx(4500.0)
    est = estimate(rec.frame, model, MASS, runout=rec.runout_supplied, settings=EstimatorSettings(smooth=False))
    late = est.t >= 0.2
    z = est.z[late]
    assert np.sqrt(np.mean((np.hypot(z[:, 4], z[:, 5] - W) / W) ** 2)) < 0.03
    assert np.sqrt(np.mean((np.hypot(z[:, 6], z[:, 7]) / 1e-3 - 1.0) ** 2)) < 0.03
    assert np.sqrt(np.mean((z[:, 8] - 1.0) ** 2)) < 0.03
    assert not est.mismatch.any()
    # the imbalance's phase is tied to the speed signal's integral: a steady-speed angle would drift by radians
    phase = np.degrees(np.arctan2(z[:, 7], z[:, 6]))
    assert np.all(np.abs(phase - math.degrees(0.6)) < 3.0)


def test_the_mismatch_flag_fires_on_a_force_the_model_lacks(reference, model):
    rec = simulate_plant(reference, _scenario("misalignment", force_2x=150.0, t_end=0.3), dt=2e-5, seed=3)
    est = estimate(rec.frame, model, MASS, runout=rec.runout_supplied, settings=EstimatorSettings(smooth=False))
    assert est.mismatch[est.t >= 0.25].mean() > 0.5
    assert not est.out_of_domain.any()


def test_the_out_of_domain_flag_fires_beyond_the_models_eccentricity(model):
    # the journal parked at eps = 0.97 (the universal model answers up to 0.95)
    t = np.arange(2000) / 10000.0
    x = np.full(t.size, 0.3 * 0.97 * 80e-6)
    y = np.full(t.size, math.sqrt(1 - 0.09) * 0.97 * 80e-6)
    frame = pd.DataFrame({"time": t, "x": x, "y": y, "speed": 600.0})
    est = estimate(frame, model, MASS, settings=EstimatorSettings(smooth=False))
    assert est.out_of_domain[t >= 0.1].all()
    est2 = estimate(frame.assign(x=x * 0.5, y=y * 0.5), model, MASS, settings=EstimatorSettings(smooth=False))
    assert not est2.out_of_domain.any()


def test_runout_is_a_once_and_twice_per_rev_pattern():
    p = np.linspace(0, 2 * np.pi, 9)
    r = runout_signal((((1e-6, 0.0),), ((0.0, 0.0), (0.0, 2e-6))), p)
    assert np.allclose(r[:, 0], 1e-6 * np.cos(p))
    assert np.allclose(r[:, 1], 2e-6 * np.sin(2 * p))


# ----------------------------------------------------------------------------- bad input
def _good_frame(n=200):
    t = np.arange(n) / 10000.0
    return pd.DataFrame({"time": t, "x": 20e-6 + 1e-6 * np.sin(628 * t), "y": 30e-6 + 1e-6 * np.cos(628 * t),
                         "speed": 6000.0})


def test_a_good_frame_passes():
    out = check_probe_frame(_good_frame(), 80e-6, nominal_rpm=6000.0)
    assert list(out.columns) == ["time", "x", "y", "speed"]


@pytest.mark.parametrize("damage, named", [
    (lambda f: f.drop(index=range(50, 60)).reset_index(drop=True), "gap in time at t = 0.0049"),
    (lambda f: f.assign(x=f.x.where(f.index != 77)), "column 'x' has 1 NaN/infinite sample(s), the first at row 77"),
    (lambda f: f.assign(x=f.x * 1e6, y=f.y * 1e6), "column 'x' reaches"),
    (lambda f: f.drop(columns="speed"), "the speed signal (column 'speed', rpm) is missing"),
    (lambda f: f.assign(speed=f.speed * 2 * math.pi / 60), "must be in rpm"),
    (lambda f: f.drop(columns="y"), "column 'y' missing"),
    (lambda f: f.assign(time=f.time[::-1].to_numpy()), "time does not increase at row 1"),
])
def test_bad_input_is_refused_in_one_line_naming_it(damage, named):
    with pytest.raises(ProbeFileError) as err:
        check_probe_frame(damage(_good_frame()), 80e-6, name="rec.csv", nominal_rpm=6000.0)
    msg = str(err.value)
    assert named in msg and "\n" not in msg and msg.startswith("rec.csv: ")


def test_a_missing_speed_signal_is_accepted_with_a_steady_speed():
    out = check_probe_frame(_good_frame().drop(columns="speed"), 80e-6, speed_rpm=6000.0)
    assert (out["speed"] == 6000.0).all()


def test_files_are_read_and_named(tmp_path):
    f = _good_frame()
    f.to_csv(tmp_path / "rec.csv", index=False)
    f.to_parquet(tmp_path / "rec.parquet")
    for name in ("rec.csv", "rec.parquet"):
        out = read_probe_file(tmp_path / name, 80e-6, nominal_rpm=6000.0)
        assert np.allclose(out["x"], f["x"])
    (tmp_path / "rec.xlsx").write_text("no")
    with pytest.raises(ProbeFileError, match="unknown probe-file type"):
        read_probe_file(tmp_path / "rec.xlsx", 80e-6)
    with pytest.raises(ProbeFileError, match="no such probe file"):
        read_probe_file(tmp_path / "none.csv", 80e-6)


def test_assess_writes_estimates_bands_and_flags(tmp_path, reference, steady_run):
    rec, _ = steady_run
    rec.frame.to_csv(tmp_path / "rec.csv", index=False)
    descr = BearingDescription(length=0.03, diameter=0.06, clearance=80e-6, speed_rpm=6000.0, viscosity=0.02,
                               mass=MASS, runout=rec.runout_supplied)
    out = assess(tmp_path / "rec.csv", descr, tmp_path / "out")
    table = pd.read_csv(tmp_path / "out" / "estimates.csv")
    for col in ("load", "load_lo", "load_hi", "imbalance", "imbalance_phase", "viscosity", "viscosity_lo",
                "viscosity_hi", "flag_mismatch", "flag_out_of_domain", "baseline_load"):
        assert col in table.columns
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["load_band_N"][0] < W < summary["load_band_N"][1]
    assert abs(summary["viscosity_Pa_s"] / 0.02 - 1.0) < 0.03
    assert (tmp_path / "out" / "estimates_smoothed.csv").exists() and len(out["files"]) == 3


def test_the_description_refuses_an_unknown_key():
    with pytest.raises(ValueError, match="unknown key"):
        BearingDescription.from_mapping({"length": 0.03, "diameter": 0.06, "clearance": 8e-5, "speed_rpm": 6000.0,
                                         "viscosity": 0.02, "mass": 50.0, "viscosty": 1.0})


# ----------------------------------------------------------------------------- the stage's noise seeds
def test_noise_seeds_redraw_the_probes_and_not_the_plant(reference):
    from fluidfilm.estimation.plant import plant_orbit, probe_record

    sc = _scenario(t_end=0.02)
    orbit = plant_orbit(reference, sc, dt=2e-5)
    a, b = probe_record(orbit, 1), probe_record(orbit, 2)
    assert np.array_equal(a.x_true, b.x_true) and np.array_equal(a.truth, b.truth)
    resid = (a.frame[["x", "y"]].to_numpy() - b.frame[["x", "y"]].to_numpy())
    # two independent draws of 1 um noise (plus quantisation): their difference has a spread of sqrt(2) um
    assert 1.2e-6 < resid.std() < 1.6e-6
    same = simulate_plant(reference, sc, dt=2e-5, seed=1)
    assert np.array_equal(same.frame.to_numpy(), a.frame.to_numpy())


def test_the_keys_are_the_worst_scenarios_median_over_seeds():
    from fluidfilm.studies.online_assessment import aggregate, scenario_seeds, summarise

    assert scenario_seeds({"seed": 0, "n_seeds": 3}, 2) == [2, 102, 202]

    def seed(load, base=0.2, mismatch=None):
        errs = {"load_rel_err": load, "imbalance_rel_err": load / 2, "imbalance_phase_err_deg": 1.0,
                "viscosity_rel_err": load}
        return {"filter": errs, "baseline": {"load_rel_err": base, "viscosity_assumed": 0.02},
                "sd_end": {"viscosity_rel": 0.01}, "us_per_sample": 5.0, "estimate_s": 0.1,
                "flags": {"mismatch_fraction": 0.0 if mismatch is None else 0.5, "out_of_domain_fraction": 0.0,
                          "mismatch_first_s": mismatch, "out_of_domain_first_s": None, "nis_mean_median": 1.0}}

    results = {}
    for name, loads, extra in (("a", [0.01, 0.02, 0.09], {}), ("b", [0.03, 0.04, 0.05], {}),
                               ("trip", [0.3, 0.3, 0.3], {"trip": "mismatch"})):
        per = [seed(x, mismatch=0.2 if extra else None) for x in loads]
        results[name] = {"dynamic": True, "trip": extra.get("trip"), "blind_spot": False, "per_seed": per,
                         **aggregate(per)}
    goals = {"load_rel_err": 0.01, "imbalance_rel_err": 0.03, "viscosity_rel_err": 0.02, "us_per_sample": 50.0,
             "vs_centreline": 5.0, "false_flag_rate": 0.01}
    m = summarise(results, {"goals": goals})["metrics"]
    assert m["estimator_load_rel_err"] == pytest.approx(0.04)          # b's median beats a's (0.02)
    assert m["estimator_load_rel_err_worst"] == pytest.approx(0.09)    # a's worst seed
    assert m["estimator_vs_centreline_load_err_ratio"] == pytest.approx(0.2 / 0.04)
    assert m["estimator_vs_centreline_load_err_ratio_worst"] == pytest.approx(0.2 / 0.09)
    assert m["estimator_false_flag_rate"] == 0.0 and m["estimator_trip_flag_rate"] == 1.0
    assert m["estimator_noise_seeds"] == 3
