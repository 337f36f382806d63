"""The paper-comparison report's pieces (fluidfilm.reporting.report), on small hand-made inputs.

The whole report was checked byte for byte against the entry point it replaced (the same inputs, old
and new code); here each piece against what its input says.
"""
from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

from fluidfilm.reporting import report

ROOT = Path(__file__).resolve().parents[2]


def _traj(verdicts: dict) -> pd.DataFrame:
    """Trajectory rows: per case a reference and the three surrogates, ``verdicts[model]`` the satisfactory cases."""
    rows = []
    for case in "abcdefg":
        rows.append({"case": case, "model": "reference", "span": 0.25, "rms_pct": None, "hausdorff_pct": None,
                     "satisfactory": None})
        for m in ("single", "split", "best"):
            ok = case in verdicts[m]
            rows.append({"case": case, "model": m, "span": 0.25, "rms_pct": 1.0 if ok else 7.5,
                         "hausdorff_pct": 1.5 if ok else 9.0, "satisfactory": ok})
    return pd.DataFrame(rows)


def test_verdicts_put_the_papers_beside_ours():
    traj = _traj({"single": "e", "split": "abc", "best": "abcdefg"})
    rows = report.verdict_rows(traj)
    assert len(rows) == 7
    # the paper: single satisfactory only in e, split in a-e
    assert rows[0] == "| a | no | no | yes | yes |"
    assert rows[3] == "| d | no | no | yes | no |"
    assert rows[4] == "| e | yes | yes | yes | no |"
    assert rows[6] == "| g | no | no | no | no |"


def test_case_rows_show_each_models_distances_and_verdict():
    rows = report.case_rows(_traj({"single": "", "split": "a", "best": "a"}))
    assert rows[0] == "| a | 0.250 | 7.50 / 9.00 (no) | 1.00 / 1.50 (yes) | 1.00 / 1.50 (yes) |"


def _model(median=0.01, bands=True, networks=()):
    mt = {"test_rel_err_median": median, "test_rel_err_p99": 0.2}
    if bands:
        mt.update({k: 0.5 * (i + 1) / 100 for i, k in enumerate(report.BAND_KEYS)})
    return {"metrics": mt, "report": {"networks": list(networks), "train_time_s": 12.0},
            "config": {"model": {"width": 8}, "split": {"boundaries": [0.5]}, "scaling": {"kind": "standard"}}}


def test_bands_in_percent_and_missing_ones_said():
    rows = report.band_rows({"paper_single": _model(), "paper_split": _model(bands=False)})
    assert rows[0] == "| paper_single | 0.5 | 1.0 | 1.5 | 2.0 |"
    assert rows[1] == "| paper_split | n/a | n/a | n/a | n/a |"
    assert report.band_rows({})[0] == "| paper_single | n/a | n/a | n/a | n/a |"   # model not trained


def test_network_rows_say_n_a_for_what_a_network_did_not_record():
    net = {"eps_low": 0.0, "eps_high": 0.5, "n_train": 12345, "epochs": 7, "train_time_s": 3.25}
    rows = report.network_rows({"paper_split": _model(networks=[net, {**net, "stop_reason": "max_fail",
                                                                           "val_rel_rmse": 0.01234}])})
    assert rows[0] == "| paper_split | 0 | 0-0.5 | 12,345 | 7 | n/a | n/a | n/a | 3.2 |"
    assert rows[1].startswith("| paper_split | 1 | 0-0.5 | 12,345 | 7 | max_fail | 0.0123 | n/a |")


def test_generation_time_prefers_the_total_over_resumed_runs():
    assert report.generation_seconds({"generation_seconds_total": 90.0, "generation_seconds_last_run": 10.0}) == 90.0
    assert report.generation_seconds({"generation_seconds_last_run": 10.0}) == 10.0


def test_sparse_and_ranking_lines_when_not_measured():
    assert report.sparse_line({}) == "not measured"
    assert report.ranking_line({}) == "not run."


def test_characteristics_section_reads_the_study():
    ch = json.loads((ROOT / "reports" / "characteristics.json").read_text())
    md = report.characteristics_section(ch)
    ref = ch["threshold"]["reference"]
    assert f"{ref['speed_rpm']:.0f} rpm" in md
    for name, e in ch["kc_max_rel_err"].items():
        thr = ch["whirl_threshold_rel_err"].get(name)
        cell = "n/a" if thr is None else f"{100 * thr:.2f}"
        assert f"| {name} | {100 * e['direct']:.2f} | {100 * e['cross']:.2f} | {cell} |" in md
    assert len([ln for ln in md.splitlines() if ln.startswith("| 0.") or ln.startswith("| 1.")]) == \
        len(ch["nonlinear_checks"])


@pytest.fixture
def inputs(tmp_path):
    """The committed reports/ beside minimal model reports and dataset metadata (not in git: DVC outputs)."""
    rd = ROOT / "reports"
    for m in ("paper_single", "paper_split", "best", "active"):
        (tmp_path / "models" / m).mkdir(parents=True)
        (tmp_path / "models" / m / "report.json").write_text(json.dumps(_model(median=0.02)))
    for d, n in (("dataset", 4704000), ("active_dataset", 1234)):
        (tmp_path / "data" / d).mkdir(parents=True)
        (tmp_path / "data" / d / "_metadata.json").write_text(json.dumps({"n_samples": n,
                                                                          "generation_seconds_last_run": 5.0}))
    return report.load_inputs(rd, tmp_path / "models", tmp_path / "data" / "dataset",
                              ["paper_single", "paper_split", "best"], "active", tmp_path / "data" / "active_dataset")


def test_headline_metrics_carry_the_stages_numbers(inputs):
    m = report.headline_metrics(inputs)
    comp, tt, traj = inputs.comparison, inputs.train_time, inputs.trajectories
    assert m["speedup_force_eval"] == comp["speedup_force_eval_split"]
    assert m["train_time_reduction_pct"] == tt["train_time_reduction_pct"]
    for model in ("single", "split", "best"):
        assert m[f"satisfactory_cases_{model}"] == int(traj[traj.model == model].satisfactory.astype(bool).sum())
    assert m["dataset_samples"] == 4704000 and m["dataset_generation_s"] == 5.0
    assert m["test_rel_err_median_paper_split_band_0.5_0.7"] == pytest.approx(0.01)
    assert set(inputs.characteristics["metrics"]) <= set(m)
    assert m["force_eval_us_best"] == float(inputs.speed.set_index("model").time_per_eval_us["best"])


def test_write_report_writes_both_files(inputs, tmp_path):
    paper = {"machine": "M", "samples": 4700000, "train_time_single_s": 20520, "train_time_split_s": 16200,
             "train_time_reduction_pct": 26, "speedup_force_model": 12}
    metrics = report.write_report(inputs, tmp_path / "out", paper, 2.0, "active")
    assert json.loads((tmp_path / "out" / "metrics.json").read_text()) == json.loads(json.dumps(metrics))
    md = (tmp_path / "out" / "paper_comparison.md").read_text()
    assert "| dataset samples | 4,700,000 | 4,704,000 |" in md
    assert "| training time, single network | 5.70 h |" in md
    assert "within 2.0 % of c" in md
    assert "## Bearing characteristics" in md     # the characteristics section is appended


def _ensemble_study():
    entry = {"satisfactory_cases": "bcdef", "n_satisfactory": 5, "orbit_rms_pct_max": 2.5,
             "orbit_hausdorff_pct_max": 3.1, "trajectory_wall_time_s": 1.0, "speedup_trajectory": 9.0}
    hybrid = dict(entry, satisfactory_cases="abcdefg", n_satisfactory=7, flagged_share_mean=0.04,
                  flagged_share_max=0.2, speedup_trajectory=2.0)
    return {"members": ["best", "best_s1"], "rel_tol": 0.01, "floor_N": 1.0, "n_cases": 7, "n_seeds_all_cases": 0,
            "hybrid_rel_tols": [0.01], "models": {"best": entry, "best_s1": entry, "hybrid_0.01": hybrid}}


def test_ensemble_stage_adds_its_numbers_without_replacing_the_compare_stages(inputs):
    import dataclasses

    before = report.headline_metrics(dataclasses.replace(inputs, ensemble=None))
    m = report.headline_metrics(dataclasses.replace(inputs, ensemble=_ensemble_study()))
    # the compare stage's count of satisfactory cases stays a count (a string once replaced it)
    assert m["satisfactory_cases_best"] == before["satisfactory_cases_best"]
    assert m["seed_study_satisfactory_best"] == 5 and m["seed_study_cases_hybrid_0.01"] == "abcdefg"
    assert m["flagged_share_mean_hybrid_0.01"] == 0.04 and m["best_seeds_all_seven"] == 0
    md = report.ensemble_section(_ensemble_study())
    assert "| hybrid_0.01 | 7 of 7 (abcdefg) | 2.50 % | 3.10 % | 4.00 % | 2.0x |" in md
    assert "| best | 5 of 7 (bcdef) | 2.50 % | 3.10 % | - | 9.0x |" in md   # a seed alone flags nothing


def test_the_report_and_the_results_page_draw_each_shared_table_with_one_renderer(tmp_path):
    """The paper-comparison report and docs/results.md show the ensemble, goals, study and controller
    tables; each is drawn by one function, so the two cannot disagree in columns or numbers."""
    import json

    from fluidfilm.reporting import readme

    ens = dict(_ensemble_study(), flag_calibration={
        "n_states": 1000, "flagged_share": 0.2, "wrong_share": 0.1, "recall": 0.9, "precision": None,
        "median_err_flagged": 0.05, "median_err_unflagged": 0.002, "spearman_spread_error": 0.4})
    ctl = {"none": {"max_amplitude_m": 8e-5, "amplitude_reduction_pct": 0.0, "final_amplitude_m": 7e-5,
                    "mean_friction_power_W": 1.5, "sleeve_travel_m": 0.0, "decision_ms_median": 0.0,
                    "axial_force_N_mean_last_rev": 6.7}}
    (tmp_path / "ensemble.json").write_text(json.dumps(ens))
    (tmp_path / "control.json").write_text(json.dumps({"controllers": ctl}))
    page = readme.render_ensemble(tmp_path)
    assert page in report.ensemble_section(ens)
    assert "| best_s1 | 5 of 7 (bcdef) |" in page and "recall" in page and "n/a of the flagged" in page
    control = readme.render_control(tmp_path)
    assert control == report.controller_table(ctl)
    assert "| none (sleeve held at 0) | 80.0 µm | 0.0 % | 70.0 µm | 1.50 W | 0.0 mm | 0.00 ms | 6.7 N |" in control
    metrics = {"surrogate_goals_met": 0, "surrogate_goals": len(report.SURROGATE_GOALS)}
    (tmp_path / "metrics.json").write_text(json.dumps(metrics))
    goals = readme.render_surrogate_goals(tmp_path)
    assert report.goals_table(metrics) in goals and report.goals_table(metrics) in report.goals_section(metrics)


def test_the_worst_seed_decides_the_seeds_verdict():
    ens = _ensemble_study()
    ens["models"]["best_s1"] = dict(ens["models"]["best_s1"], n_satisfactory=3, satisfactory_cases="deg")
    assert report.ensemble_metrics(ens)["satisfactory_cases_best_min_over_seeds"] == 3  # min of 5 and 3, not the hybrid's 7


def test_goals_are_met_missed_or_not_measured_in_the_units_shown():
    metrics = {"satisfactory_cases_best_min_over_seeds": 7, "test_rel_err_median_best": 0.004,   # 0.4 % <= 0.5 %
               "test_rel_err_p99_best": 2.5, "force_eval_us_best": 0.31, "controller_decision_ms_mpc": 2.0,
               "mpc_amplitude_reduction_pct": 56.9}
    goals = {g["key"]: g for g in report.surrogate_goals(metrics)}
    assert len(goals) == len(report.SURROGATE_GOALS)
    assert goals["satisfactory_cases_best_min_over_seeds"]["met"] is True
    assert goals["test_rel_err_median_best"]["met"] is True and goals["test_rel_err_median_best"]["measured"] == "0.4 %"
    assert goals["test_rel_err_p99_best"]["met"] is False and goals["test_rel_err_p99_best"]["measured"] == "250 %"
    assert goals["force_eval_us_best"]["met"] is False                 # 0.31 > 0.2 (the speed issue's limit)
    assert goals["controller_decision_ms_mpc"]["met"] is True          # the bound itself (2 ms) is within
    over = {g["key"]: g for g in report.surrogate_goals(metrics | {"controller_decision_ms_mpc": 2.07})}
    assert over["controller_decision_ms_mpc"]["met"] is False          # the 2 ms, not 10
    assert goals["mpc_amplitude_reduction_pct"]["met"] is False        # 56.9 < 57
    assert goals["controller_training_speedup"]["met"] is None         # not in the metrics: not measured
    md = report.goals_section(metrics)
    assert "| 99th-percentile force error, held-out random states | ≤ 10 % | 250 % | **missed** (25x the limit) |" in md
    assert "| MPC amplitude reduction on the reference model | ≥ 57 % | 56.9 % | **missed** (99.8 % of it) |" in md
    assert "not measured" in md


def test_the_pipelines_total_time_is_a_lower_bound_while_stages_are_untimed():
    timing = {"full": {"stages": {"dataset": 1800.0, "train_best_seeds@1": 1200.0, "train_best_seeds@2": 900.0}}}
    stages = ("dataset", "train_best_seeds", "universal_train")
    m = report.reproduce_time_metrics(timing, stages)
    assert m["reproduce_total_min"] == pytest.approx(65.0)        # (1800 + 1200 + 900) s, every foreach run counted
    assert m["reproduce_total_min_partial"] is True and m["reproduce_stages_untimed"] == ["universal_train"]
    goal = {g["key"]: g for g in report.surrogate_goals(m)}["reproduce_total_min"]
    assert goal["met"] is False and goal["measured"].startswith("≥ 65 min")  # a lower bound already over 60
    short = report.reproduce_time_metrics({"full": {"stages": {"dataset": 1800.0}}}, stages)
    assert {g["key"]: g for g in report.surrogate_goals(short)}["reproduce_total_min"]["met"] is None  # unknown
    whole = report.reproduce_time_metrics({"full": {"stages": {"dataset": 1800.0}}}, ("dataset",))
    assert whole["reproduce_total_min_partial"] is False
    assert {g["key"]: g for g in report.surrogate_goals(whole)}["reproduce_total_min"]["met"] is True
    assert report.reproduce_time_metrics(None, stages) == {} and report.reproduce_time_metrics({"quick": {}}, stages) == {}


def test_error_map_metrics_take_the_worst_seed():
    em = {"models": {name: {"held_out": {"median": 0.01, "p99": p}, "orbit_states": {"median": 0.04, "p99": 2 * p}}
                     for name, p in (("best", 2.5), ("best_s1", 3.9), ("best_s2", 3.1), ("other", 9.0))}}
    m = report.error_map_metrics(em)
    assert m["test_rel_err_p99_best_max_over_seeds"] == 3.9 and m["orbit_state_rel_err_p99_best_max_over_seeds"] == 7.8
    assert m["orbit_state_rel_err_p99_other"] == 18.0 and m["orbit_state_rel_err_median_best"] == 0.04


def test_study_rows_show_each_job_in_per_cent():
    job = {"job": "grading.n_per_side=8", "n_samples": 330000, "generation_s": 2.4, "train_time_s": 31.0,
           "held_out_rel_err_median": 0.0212, "held_out_rel_err_p99": 8.7, "orbit_states_rel_err_median": 0.1,
           "orbit_states_rel_err_p99": 0.75, "n_satisfactory": 1, "satisfactory_cases": "e", "time_per_eval_us": 0.7,
           "kc_max_rel_err_direct": 0.141, "kc_max_rel_err_cross": 0.062, "kc_status": "ok"}
    rows = report.study_rows({"jobs": [job, dict(job, job="x", n_satisfactory=float("nan"), kc_max_rel_err_direct=None,
                                                 kc_status="no equilibrium"),
                                       {k: v for k, v in job.items() if not k.startswith("kc_")}]})
    assert rows[0] == ["`grading.n_per_side=8`", "330,000", "2", "31", "2.12", "870", "10.00", "75", "1/7 (e)", "14 / 6",
                       "0.70"]
    assert rows[1][8] == "-" and rows[1][9] == "no equilibrium"  # a job run without the cases; no equilibrium found
    assert rows[2][9] == "-"                                        # K/C not measured


def test_the_readmes_mechanism_paragraph_states_the_records_own_numbers(tmp_path):
    """The paragraph on what decides the paper's verdicts is generated from the paper_scale records: its
    shares of the load are |static force error| / load of each record, its offsets the records' offsets, and
    a variant that found no equilibrium says so instead of a number."""
    from fluidfilm.reporting.readme import render_paper_scale_mechanism

    def record(label, err, offset):
        return {"label": label, "n_samples": 40000, "structure": "split",
                "equilibrium": {"a": {"load_N": 20.0, "static_force_error_N": list(err), "offset_pct_c": offset}},
                "resolution": {"newton_per_mapped_unit": [300.0, 400.0]},
                "satisfactory_cases_position": "", "satisfactory_cases_paper_reading": "ab"}

    assert "Not run yet" in render_paper_scale_mechanism(tmp_path)
    (tmp_path / "paper_scale.json").write_text(json.dumps({
        "machine": "m", "date": "d", "records": [record("curve split 40000", (60.0, 80.0), 27.0),
                                                 record("ablation whirl_frame", (0.6, 0.8), 1.5),
                                                 record("ablation map_per_speed", (30.0, 40.0), None)]}))
    text = render_paper_scale_mechanism(tmp_path)
    assert "by 5x the load (one mapped output unit is 500 N there)" in text  # |(60, 80)| / 20, |(300, 400)|
    assert "offset 27.0 % of c" in text
    assert "the whirl frame 0.05x the load, offset 1.5 % of c" in text
    assert "1 + |V|/(c omega) 2.5x the load, no equilibrium under the load" in text
    assert "by the 2 %-of-c rule none, by the paper's reading (span and shape) ab" in text


def test_the_readmes_universal_sentence_states_the_evaluations_numbers(tmp_path):
    """The README's sentence on the universal model reads its numbers from reports/universal.json, in per cent."""
    from fluidfilm.reporting.readme import render_universal_summary

    (tmp_path / "universal.json").write_text(json.dumps({
        "universal_rel_err_median": 0.0012, "universal_rel_err_p99": 0.034, "universal_whirl_threshold_rel_err": 0.005,
        "universal_kc_max_rel_err_direct": 0.021, "universal_kc_max_rel_err_cross": 0.4}))
    text = render_universal_summary(tmp_path)
    assert "within 0.12 % (median; 3.4 % at the 99th percentile)" in text
    assert "whirl threshold within 0.5 %" in text and "within 2.1 % (direct) and 40 % (cross)" in text
    assert "A force costs" not in text                     # no cost in the report: no clause
    # with the cost: one float64 force in ns, and the smaller of the two yardsticks' least speed-ups
    for check, matched, least in ((128.4, 141.0, "128x"), (150.0, 97.6, "98x")):
        (tmp_path / "universal.json").write_text(json.dumps({
            "universal_rel_err_median": 0.0012, "universal_rel_err_p99": 0.034, "universal_whirl_threshold_rel_err": 0.005,
            "universal_kc_max_rel_err_direct": 0.021, "universal_kc_max_rel_err_cross": 0.4,
            "force_eval_us_universal": 0.0394, "universal_speedup_vs_reference_equal_accuracy_min": check,
            "universal_speedup_vs_reference_matched_min": matched, "cost": {"machine": "Box X"}}))
        text = render_universal_summary(tmp_path)
        assert f"A force costs 39 ns (one state, float64; Box X), at least {least} less than the reference" in text


def test_the_universal_table_gives_the_least_speed_up_of_each_yardstick(tmp_path):
    """The accuracy table's speed-up rows: for the convergence check's grids and for the matched grids, each
    reading's least speed-up over the held-out rows, with its grid, met or not against the goal; no matched
    rows for an evaluation without them; the ladder-floor caveat only when a matched grid sits there."""
    from fluidfilm.reporting.readme import render_universal

    u = json.loads((ROOT / "reports" / "universal.json").read_text())
    rows = u["reference_equal_accuracy"]
    goal = u["goals"]["speedup_equal_accuracy"]

    def table(report):
        (tmp_path / "universal.json").write_text(json.dumps(report))
        return [line for line in render_universal(tmp_path).splitlines() if line.startswith("| speed-up per force")]

    lines = table(u)
    assert len(lines) == 6
    for line, (suffix, key) in zip(lines, [(s, k) for s in ("", "_matched")
                                           for k in ("speedup", "speedup_float32", "speedup_batched")]):
        worst = min(rows, key=lambda r: r[key + suffix])
        assert ("convergence check" in line) == (suffix == "")
        assert f"least: {worst['cavitation']}, L/D {worst['ld']:g}, " \
               f"{worst['n_theta' + suffix]} x {worst['n_z' + suffix]}" in line
        cells = [c.strip() for c in line.strip("|").split("|")]
        assert cells[1].startswith(f"{worst[key + suffix]:.0f}x")
        assert cells[3] == ("yes" if worst[key + suffix] >= goal else "no")
    assert any("upper bounds" in line for line in lines) == any(r["grid_at_ladder_floor"] for r in rows)
    floor = {**u, "reference_equal_accuracy": [{**rows[0], "grid_at_ladder_floor": True}, *rows[1:]]}
    assert all("upper bounds" in line for line in table(floor)[3:])
    older = {**u, "reference_equal_accuracy": [{k: v for k, v in r.items() if "matched" not in k and "floor" not in k}
                                               for r in rows]}
    assert len(table(older)) == 3


def test_the_headline_reads_the_largest_converged_split_and_flags_a_larger_one_stopped_by_its_budget(tmp_path):
    """The README's headline: the paper's split at the largest size trained to the validation rule, and a larger
    one stopped by its LM time budget beside it, said to be unconverged (never passed off as the verdict)."""
    import json

    from fluidfilm.reporting.readme import render_headline

    m = {}
    for size, conv, sat, off in (("40000", 1.0, 0, 27.2), ("160000", 1.0, 1, 24.3), ("2560000", 0.0, 2, 40.0),
                                 ("full_scale", 0.0, 3, 50.0)):
        m |= {f"satisfactory_cases_split_{size}": sat, f"satisfactory_cases_split_{size}_paper_reading": sat + 1,
              f"equilibrium_offset_pct_c_split_{size}": off, f"converged_split_{size}": conv}
    (tmp_path / "metrics.json").write_text(json.dumps(m))
    text = render_headline(tmp_path)
    rows = [line for line in text.splitlines() if "the paper's split at the largest size" in line]
    assert len(rows) == 2, rows
    assert "trained to the validation rule (160,000 samples)" in rows[0] and "1 / 2 of 7; 24.3 % of c" in rows[0]
    assert "not converged" in rows[1] and "(all samples)" in rows[1] and "3 / 4 of 7; 50.0 % of c" in rows[1]
    # everything converged: one row, the largest
    (tmp_path / "metrics.json").write_text(json.dumps({k: (1.0 if k.startswith("converged_") else v)
                                                       for k, v in m.items()}))
    rows = [line for line in render_headline(tmp_path).splitlines() if "the paper's split at the largest" in line]
    assert len(rows) == 1 and "(all samples)" in rows[0] and "validation rule" in rows[0]


def test_paper_scale_keys_join_the_runs_beyond_the_pipeline_with_the_pipelines_own_first():
    from fluidfilm.reporting.report import paper_scale_all_metrics

    own = {"satisfactory_cases_split_40000": 0, "equilibrium_offset_pct_c_split_40000": 27.2, "machine": "x"}
    curve = {"satisfactory_cases_split_40000": 5, "satisfactory_cases_split_160000": 1, "converged_split_160000": 1.0}
    full = {"equilibrium_offset_pct_c_split_full_scale": 40.0, "train_time_reduction_pct_full_scale_lm": -3.0}
    m = paper_scale_all_metrics(own, [curve, full])
    assert m["satisfactory_cases_split_40000"] == 0  # the pipeline's own, not the curve report's copy of it
    assert m["satisfactory_cases_split_160000"] == 1 and m["converged_split_160000"] == 1.0
    assert m["equilibrium_offset_pct_c_split_full_scale"] == 40.0 and "machine" not in m
    assert paper_scale_all_metrics(None, [full]) == full and paper_scale_all_metrics(None) == {}


def test_the_pipeline_time_says_which_stages_its_total_leaves_out(tmp_path):
    from fluidfilm.reporting.readme import render_commands, render_reproduce_timing

    (tmp_path / "dvc.yaml").write_text("stages:\n  dataset:\n    cmd: a\n  train_best_seeds:\n    cmd: b\n"
                                       "  universal_train:\n    cmd: c\n")
    reports = tmp_path / "reports"
    reports.mkdir()
    timing = {"full": {"date": "2026-12-01", "machine": "m", "stages_total_s": 600.0,
                       "stages": {"dataset": 300.0, "train_best_seeds@1": 300.0}}}
    (reports / "reproduce_timing.json").write_text(json.dumps(timing))
    (reports / "test_timing.json").write_text(json.dumps({"setup_s": 60, "suite_s": 600, "tests": 10, "skipped": 0,
                                                          "quick_reproduce_s": 100, "commit": "abc", "date": "d"}))
    text = render_commands(reports)
    assert "more than 10 min" in text and "not timed" in text
    per_stage = render_reproduce_timing(reports)
    assert "`universal_train`" in per_stage and "`train_best_seeds`" not in per_stage.split("not timed")[1]
    # every stage timed: the total, plainly
    timing["full"]["stages"]["universal_train"] = 120.0
    timing["full"]["stages_total_s"] = 720.0
    (reports / "reproduce_timing.json").write_text(json.dumps(timing))
    assert "| 12 min |" in render_commands(reports) and "not timed" not in render_reproduce_timing(reports)
    # stages recorded with their own run: the row names its date, and its machine where it is another
    timing["full"]["stage_runs"] = {"dataset": {"date": "2026-12-04", "machine": "other"},
                                    "universal_train": {"date": "2026-12-03", "machine": "m"}}
    (reports / "reproduce_timing.json").write_text(json.dumps(timing))
    per_stage = render_reproduce_timing(reports)
    assert "| `dataset` | 5.0 min | 2026-12-04, other |" in per_stage
    assert "| `universal_train` | 2.0 min | 2026-12-03 |" in per_stage
    assert "| `train_best_seeds@1` | 5.0 min | 2026-12-01 or before |" in per_stage


def test_a_stopped_pipeline_keeps_the_times_of_the_stages_it_finished(tmp_path, monkeypatch):
    from fluidfilm.workflow import pipeline

    # a stand-in for dvc: two stages finish, the third fails (as a run stopped by the end of a sitting)
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    (bin_dir / "dvc").write_text("#!/bin/sh\necho \"Running stage 'dataset':\"\nsleep 0.2\n"
                                 "echo \"Running stage 'train_best':\"\nsleep 0.1\n"
                                 "echo \"Running stage 'universal_train':\"\nexit 3\n")
    (bin_dir / "dvc").chmod(0o755)
    monkeypatch.setattr(pipeline, "venv_bin", lambda: bin_dir)
    (tmp_path / "reports").mkdir()
    (tmp_path / "reports" / "reproduce_timing.json").write_text(json.dumps(
        {"full": {"date": "2026-12-01", "machine": "m", "stages": {"dataset": 999.0, "ablation": 60.0}}}))
    code, times = pipeline.run_dvc_repro(tmp_path, [], lambda name, sec: pipeline.record_timing(
        tmp_path, "full", {name: sec}))
    assert code == 3 and set(times) == {"dataset", "train_best"}   # the failed stage has no time
    full = json.loads((tmp_path / "reports" / "reproduce_timing.json").read_text())["full"]
    assert 0.15 < full["stages"]["dataset"] < 5.0 and 0.05 < full["stages"]["train_best"] < 5.0
    assert full["stages"]["ablation"] == 60.0 and "universal_train" not in full["stages"]  # others keep theirs
    # the record's older stages keep the run they had (its date and machine); the new ones name theirs
    assert full["stage_runs"]["ablation"] == {"date": "2026-12-01", "machine": "m"}
    assert full["stage_runs"]["dataset"]["date"] != "2026-12-01" and set(full["stage_runs"]) == {
        "dataset", "train_best", "ablation"}
    assert full["stages_total_s"] == pytest.approx(sum(full["stages"].values()), abs=0.05)


def test_a_stage_that_left_dvc_yaml_leaves_the_pipelines_total(tmp_path):
    """A long variant moved out of dvc.yaml (to a make target) must not count in make reproduce's total."""
    from fluidfilm.workflow import pipeline

    (tmp_path / "dvc.yaml").write_text("stages:\n  dataset:\n    cmd: c\n  train_best_seeds:\n    foreach: [1]\n"
                                       "    do:\n      cmd: c\n")
    (tmp_path / "reports").mkdir()
    (tmp_path / "reports" / "reproduce_timing.json").write_text(json.dumps(
        {"full": {"stages": {"dataset": 10.0, "train_best_seeds@1": 20.0, "universal_train": 900.0},
                  "stage_runs": {k: {"date": "d", "machine": "m"} for k in ("dataset", "train_best_seeds@1",
                                                                              "universal_train")}}}))
    pipeline.record_timing(tmp_path, "full", {"dataset": 12.0})
    full = json.loads((tmp_path / "reports" / "reproduce_timing.json").read_text())["full"]
    assert full["stages"] == {"dataset": 12.0, "train_best_seeds@1": 20.0} and set(full["stage_runs"]) == set(full["stages"])
    assert full["stages_total_s"] == 32.0
