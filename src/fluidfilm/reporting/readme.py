"""Fill the generated blocks of the README and the docs from the pipeline's outputs, so that no number
is copied by hand.

    python -m fluidfilm.reporting.readme            # rewrite the generated blocks in place
    python -m fluidfilm.reporting.readme --check    # exit 1 if a page differs from what reports/ say

The pages (``pages``): README.md (the commands' times and the headline), docs/results.md (every table)
and the other docs/*.md (the tables their discussion needs). A generated block looks like::

    <!-- generated: headline -->
    ...table...
    <!-- end generated -->

and ``RENDERERS[name](reports_dir)`` produces its content from the files under ``reports/`` that
``make reproduce`` writes (``metrics.json``, ``reproduce_timing.json``, ``control.json``, ...); the tables
the paper-comparison report shows too are drawn by the same functions (``fluidfilm.reporting.report``).
``make reproduce`` runs this after ``dvc repro``; ``tests/test_pipeline.py``
(``test_readme_tables_are_generated_from_the_reports``) checks that the committed pages agree with the
committed reports.
"""
from __future__ import annotations

import argparse
import json
import math
import re
import sys
from collections.abc import Callable, Mapping
from pathlib import Path

from fluidfilm.reporting import report

BLOCK = re.compile(r"(<!-- generated: (?P<name>[a-z_0-9]+) -->\n)(?P<body>.*?)(<!-- end generated -->)", re.S)


def _load(reports: Path, name: str) -> dict:
    path = reports / name
    if not path.exists():
        raise FileNotFoundError(f"{path} is missing: run `make reproduce` first")
    return json.loads(path.read_text())


def _num(x, spec: str = ".1f", unit: str = "") -> str:
    if x is None:
        return "n/a"
    if isinstance(x, bool):
        return "yes" if x else "no"
    return f"{format(x, spec)}{unit}"


_table = report.markdown_table


# Stages that the paper's figures and numbers do not need: the workspace's own surrogate (three seeds),
# its ensemble, error map and batched speed, the grading study, the ablation and the characteristics.
BEYOND_PAPER_STAGES = ("dataset_orbit", "train_best", "train_best_seeds", "ensemble", "error_map", "batch_speed",
                       "grading_study", "ablation", "characteristics", "runup", "cavitation_rules",
                       "jfo_surrogate")


def _untimed_stages(reports: Path, timed) -> list[str]:
    """The pipeline's stages (``dvc.yaml`` beside ``reports/``) with no time in ``reproduce_timing.json``:
    stages added since the last full ``make reproduce``, which its total leaves out."""
    return report.untimed_stages(report.pipeline_stages(reports), timed)


def render_reproduce_timing(reports: Path) -> str:
    data = _load(reports, "reproduce_timing.json")
    full = data.get("full")
    if not full:
        raise FileNotFoundError("reports/reproduce_timing.json has no full-profile run yet")
    def run_of(name: str) -> str:
        run = _stage_run(full, name)
        return run["date"] + ("" if run["machine"] == full["machine"] else f", {run['machine']}")

    rows = [[f"`{name}`", f"{sec / 60:.1f} min" if sec >= 60 else f"{sec:.0f} s", run_of(name)]
            for name, sec in full["stages"].items()]
    beyond = [k for k in full["stages"] if k.split("@")[0] in BEYOND_PAPER_STAGES]
    beyond_s = sum(full["stages"][k] for k in beyond)
    rows.append([f"the paper's stages (all but {', '.join(f'`{k}`' for k in beyond)})",
                 f"{(full['stages_total_s'] - beyond_s) / 60:.0f} min", ""])
    rows.append(["the stages beyond the paper", f"{beyond_s / 60:.0f} min", ""])
    missing = _untimed_stages(reports, full["stages"])
    rows.append(["**total**" + (" of the stages timed" if missing else ""), f"**{full['stages_total_s'] / 60:.0f} min**"
                 + (" (at least: some stages not timed)" if missing else ""), ""])
    if missing:
        rows.append([f"not timed yet (the total leaves them out): {', '.join(f'`{s}`' for s in missing)}", "-", ""])
    return (f"The wall time of each stage's last run in the full profile, on {full['machine']} unless the row "
            f"names another machine (`reports/reproduce_timing.json`, written by `make reproduce` as each stage "
            f"finishes, so a run stopped half-way keeps the times of the stages it finished; a stage that was not "
            f"rerun keeps its time). A rerun reuses finished dataset parts and a finished training checkpoint of "
            f"the same configuration, so such a stage shows the time of the resumed run, not of a run from "
            f"scratch:\n\n" + _table(["stage", "wall time", "run"], rows))


def _minutes(seconds: float) -> str:
    return f"{seconds / 60:.0f} min" if seconds >= 60 else f"{seconds:.0f} s"


def _stage_run(full: Mapping, name: str) -> dict:
    """The date and machine of a stage's last run: recorded per stage since 2026-12-04; a stage of an older
    record ran on its machine, on its date or before (a stage not rerun keeps its time)."""
    return full.get("stage_runs", {}).get(name, {"date": f"{full['date']} or before", "machine": full["machine"]})


def _stage_runs_summary(full: Mapping) -> str:
    """Where and when the pipeline's stage times were measured: 'on M, D' or, for stages run in several
    sittings, 'on M1 (D1: n stages), on M2 (D2, D3: m stages)'."""
    by_machine: dict[str, list[str]] = {}
    for k in full["stages"]:
        run = _stage_run(full, k)
        by_machine.setdefault(run["machine"], []).append(run["date"])
    if len(by_machine) == 1 and len(set(next(iter(by_machine.values())))) == 1:
        machine, dates = next(iter(by_machine.items()))
        return f"on {machine}, {dates[0]}"
    return ", ".join(f"on {m} ({', '.join(sorted(set(d)))}: {len(d)} stage{'s' if len(d) > 1 else ''})"
                     for m, d in by_machine.items())


def render_commands(reports: Path) -> str:
    """The README's commands and how long each takes: the pipeline from ``reproduce_timing.json`` (written by
    ``make reproduce``), the install and the test suite from ``test_timing.json`` (``make time-tests``: a fresh
    clone's run)."""
    full = _load(reports, "reproduce_timing.json").get("full")
    if not full:
        raise FileNotFoundError("reports/reproduce_timing.json has no full-profile run yet")
    t = _load(reports, "test_timing.json")
    rows = [["`make setup`", "creates `.venv`, installs torch (CPU) and the project; the two below run it first",
             _minutes(t["setup_s"])],
            ["`make reproduce`", "the whole pipeline (`dvc repro`): datasets, models, studies, figures, report",
             _minutes(full["stages_total_s"]) if not _untimed_stages(reports, full["stages"]) else
             f"more than {_minutes(full['stages_total_s'])} (some stages not timed yet)"],
            ["`make test`", f"the default suite ({t['tests']:,} tests, {t['skipped']} skipped), among them the pipeline "
             f"on its small profile ({_minutes(t['quick_reproduce_s'])})", _minutes(t["suite_s"])]]
    return (_table(["command", "what it does", "time"], rows)
            # each measurement names its own machine (the pipeline's and the tests' runs were on different hosts)
            + f"\nMeasured: the pipeline's stages {_stage_runs_summary(full)} (`reports/reproduce_timing.json`, "
              f"per stage in [docs/results.md](docs/results.md#how-long-make-reproduce-takes)); the install and the "
              f"tests from a fresh clone of {t['commit']} on {t.get('machine', 'an unrecorded machine')}, {t['date']} "
              f"(`reports/test_timing.json`).\n")


def render_headline(reports: Path) -> str:
    m = _load(reports, "metrics.json")
    g = m.get

    rows = [
        ["dataset samples", "4,700,000", _num(g("dataset_samples"), ",.0f")],
        ["dataset generation", "hours (not given)", _num(g("dataset_generation_s"), ".0f", " s")],
        ["training time reduction, split vs single"
         + (f" ({g('train_time_samples_per_seed'):,} samples per seed)" if g("train_time_samples_per_seed") else ""),
         "26 %",
         _num(g("train_time_reduction_pct"), ".0f", " %")
         + (f" ± {g('train_time_reduction_ci95'):.0f} (95 % CI, {g('train_time_seeds')} seeds)"
            if g("train_time_reduction_ci95") is not None else "")],
    ]
    ci = reports / "train_time_ci.json"
    if ci.exists():  # the same study at a larger subsample, to the same target: `make train-time-ci`, outside the pipeline
        t = json.loads(ci.read_text())
        rows.append([f"training time reduction, the same study at {t['train_time_samples_per_seed']:,} samples per "
                     "seed (`make train-time-ci`, outside the pipeline)",
                     "26 %", f"{t['train_time_reduction_pct']:.0f} % ± {t['train_time_reduction_ci95']:.0f} "
                     f"(95 % CI, {t['train_time_seeds']} seeds)"])
    rows += [
        ["speed-up per trajectory, split vs our reference", "12x", _num(g("speedup_trajectory_split"), ".1f", "x")],
        ["speed-up per force, split vs our reference", "12x", _num(g("speedup_force_eval_split"), ".1f", "x")],
        ["speed-up per trajectory / per force, best (ours) vs our reference", "12x",
         f"{_num(g('speedup_trajectory_best'), '.1f', 'x')} / {_num(g('speedup_force_eval_best'), '.1f', 'x')}"],
        ["cases satisfactory, single", "e only", _num(g("satisfactory_cases_single"), "d", " of 7")],
        ["cases satisfactory, split", "a-e (5 of 7)", _num(g("satisfactory_cases_split"), "d", " of 7")],
        ["cases satisfactory, best (ours)", "-", _num(g("satisfactory_cases_best"), "d", " of 7")],
    ]
    if g("satisfactory_cases_split_paper_reading") is not None:  # the paper's reading: span and shape, not position
        rows.append(["cases satisfactory by the paper's reading (span and shape after the mean offset), single / split",
                     "e only / a-e", f"{_num(g('satisfactory_cases_single_paper_reading'), 'd')} / "
                     f"{_num(g('satisfactory_cases_split_paper_reading'), 'd')} of 7"])
    sizes = sorted(int(k.rsplit("_", 1)[1]) for k in m if re.fullmatch(r"equilibrium_offset_pct_c_split_\d+", k))
    trained = [str(n) for n in sizes] + (["full_scale"] if g("equilibrium_offset_pct_c_split_full_scale") is not None
                                         else [])
    # the largest size whose networks all stopped by the validation rule, and a larger one stopped by its time
    # budget beside it, said so (a record without the flag counts as converged: reports before the flag)
    done = [s for s in trained if g(f"converged_split_{s}") in (None, 1.0)]
    shown = ([done[-1]] if done else []) + [s for s in trained[-1:] if s not in done]
    for largest in shown:  # the paper_scale study: the paper's split at the largest size trained
        n = "all" if largest == "full_scale" else f"{int(largest):,}"
        how = ("trained to the validation rule" if largest in done
               else "stopped by its LM time budget, not converged (`make paper-full-scale`, docs/paper_experiment.md)")
        rows.append([f"the paper's split at the largest size {how} ({n} samples): cases satisfactory, 2 %-of-c "
                     "rule / the paper's reading; equilibrium offset", "a-e / a-e; -",
                     f"{_num(g(f'satisfactory_cases_split_{largest}'), 'd')} / "
                     f"{_num(g(f'satisfactory_cases_split_{largest}_paper_reading'), 'd')} of 7; "
                     f"{_num(g(f'equilibrium_offset_pct_c_split_{largest}'), '.1f', ' % of c')}"])
    if g("best_seeds") is not None:  # the ensemble stage: every training seed of best, and their ensemble
        seeds = [k for k in m if k.startswith("seed_study_satisfactory_best")]
        rows.append([f"cases satisfactory, each of best's {g('best_seeds')} training seeds / their ensemble", "-",
                     ", ".join(str(m[k]) for k in sorted(seeds)) + " of 7 / "
                     + _num(g("seed_study_satisfactory_ensemble"), "d", " of 7")])
    rows += [
        ["held-out median relative force error, single / split / best", "not given",
         " / ".join(_num(g(f"test_rel_err_median_{k}"), ".2%") for k in ("paper_single", "paper_split", "best"))],
    ]
    if g("orbit_state_rel_err_p99_best") is not None:  # the error map stage
        rows.append(["99th-percentile force error of best, held-out random states / along the reference orbits",
                     "not given", _num(g("test_rel_err_p99_best"), ".0%") + " / "
                     + _num(g("orbit_state_rel_err_p99_best"), ".0%")])
    rows += [
        ["Fig. 5: largest orbit amplitude, DQN vs no control", "growth restrained (qualitative)",
         _num(g("controller_amplitude_reduction_pct"), ".0f", " % smaller")],
        ["Fig. 5: MPC vs no control", "not shown", _num(g("mpc_amplitude_reduction_pct"), ".0f", " % smaller")],
    ]
    for key, label, paper, spec, unit in (
        ("speedup_trajectory_split_vs_sparse_reference", "speed-up per trajectory, split vs a sparse direct solver",
         "12x", ".0f", "x"),
        ("kc_max_rel_err_direct_best", "stiffness/damping, best model vs converged reference, max error direct "
         "terms", "-", ".1%", ""),
        ("kc_max_rel_err_cross_best", "stiffness/damping, best model vs converged reference, max error cross terms",
         "-", ".1%", ""),
        ("whirl_threshold_rel_err_best", "whirl threshold, best model vs converged reference", "-", ".1%", ""),
        ("trajectories_per_s_batch_speedup", "batched trajectories (N = 1024), best vs reference", "-", ".1f", "x"),
        ("controller_decision_ms_mpc", "MPC time per decision (control period 20 ms)", "-", ".1f", " ms"),
        ("controller_training_speedup", "DQN training, surrogate vs reference model", ">= 10x", ".1f", "x"),
    ):
        if g(key) is not None:
            rows.append([label, paper, _num(g(key), spec, unit)])
    peer = reports / "benchmarks" / "ross_peer.json"
    if peer.exists():  # `make ross-peer`, outside the pipeline (ROSS lives in its own environment)
        p = json.loads(peer.read_text())
        if "ross_peer_speedup_lund_thomsen" in p:
            err = p.get("lund_thomsen_max_coef_err_pct")
            at = f", ours within {err:.1f} % on every row" if isinstance(err, (int, float)) else ""
            rows.append(["grooved bearing (Lund & Thomsen), time per operating point, ROSS 3.1's most accurate "
                         f"mesh / ours at equal or better accuracy{at} (`make ross-peer`)", "-",
                         _num(p["ross_peer_speedup_lund_thomsen"], ".1f", "x")])
    if g("surrogate_goals") is not None:
        rows.append(["goals of the fast, accurate surrogate met (docs/results.md)", "-",
                     f"{g('surrogate_goals_met')} of {g('surrogate_goals')}"])
    return _table(["quantity", "paper", "this workspace"], rows)


def render_control(reports: Path) -> str:
    return report.controller_table(_load(reports, "control.json")["controllers"])


def _csv_table(path: Path, columns: dict[str, str], query=None) -> str:
    import pandas as pd

    if not path.exists():
        raise FileNotFoundError(f"{path} is missing: run `make reproduce`")
    df = pd.read_csv(path)
    if query is not None:
        df = df.query(query)
    rows = [[format(r[c], spec) if spec else str(r[c]) for c, spec in columns.items()] for _, r in df.iterrows()]
    return _table(list(columns), rows)


def render_raimondi_boyd(reports: Path) -> str:
    return _csv_table(reports / "characteristics" / "raimondi_boyd.csv",
                      {"l_over_d": "g", "eps": "g", "S_pub": "g", "S": ".4g", "S_err_pct": ".2f", "phi_pub": "g",
                       "phi": ".2f", "phi_err_deg": ".2f", "fric_pub": "g", "fric": ".4g", "fric_err_pct": ".2f",
                       "flow_pub": "g", "flow": ".4g", "flow_err_pct": ".2f", "qs_ratio_pub": "g", "qs_ratio": ".3f",
                       "qs_ratio_err_pct": ".2f"}, "feed == 'max-film'")


def render_raimondi_boyd_no_feed(reports: Path) -> str:
    return _csv_table(reports / "characteristics" / "raimondi_boyd.csv",
                      {"l_over_d": "g", "eps": "g", "S_err_pct": ".2f", "phi_err_deg": ".2f", "fric_err_pct": ".2f"},
                      "feed == 'none'")


def render_short_bearing(reports: Path) -> str:
    """Our solver at L/D = 0.01 against the short-bearing closed forms, per eccentricity, with the
    largest errors under the table (``reports/characteristics/short_bearing.csv``)."""
    import numpy as np
    import pandas as pd

    path = reports / "characteristics" / "short_bearing.csv"
    if not path.exists():
        raise FileNotFoundError(f"{path} is missing: run `make reproduce`")
    df = pd.read_csv(path)
    coeffs = [f"{k}{ij}" for k in "KC" for ij in ("xx", "xy", "yx", "yy")]
    direct = [f"{k}{ij}" for k in "KC" for ij in ("xx", "yy")]
    scale_err = df[[f"{c}_err_scale_pct" for c in coeffs]].abs().max(axis=1)
    direct_err = df[[f"{c}_err_pct" for c in direct]].abs().max(axis=1)
    rows = [[f"{r.eps:g}", f"{r.load_err_pct:.2g}", f"{r.attitude_err_deg:.2g}", f"{scale_err[i]:.2g}",
             f"{direct_err[i]:.2g}", f"{r.Mcrit_closed:.4g} / {r.Mcrit:.4g}",
             f"{r.Mcrit_err_pct:.2g}" if np.isfinite(r.Mcrit_err_pct) else "nan"] for i, r in df.iterrows()]
    finite = df[np.isfinite(df.Mcrit_closed)]
    tail = (f"\nLargest errors: load {df.load_err_pct.abs().max():.2g} %, attitude {df.attitude_err_deg.abs().max():.2g} "
            f"deg, coefficients {scale_err.max():.2g} % of the matrix scale and critical mass "
            f"{finite.Mcrit_err_pct.abs().max():.2g} % (where it is finite).\n")
    return _table(["eps", "load err %", "attitude err deg", "max K/C err % (of matrix scale)", "max direct-term err %",
                   "M_crit closed / ours", "M_crit err %"], rows) + tail


def render_lund_thomsen(reports: Path) -> str:
    """Lund & Thomsen's 21 published rows beside ours (``reports/characteristics/lund_thomsen.csv``)."""
    import pandas as pd

    path = reports / "characteristics" / "lund_thomsen.csv"
    if not path.exists():
        raise FileNotFoundError(f"{path} is missing: run `make reproduce`")
    df = pd.read_csv(path)
    from fluidfilm.characteristics.published import LUND_THOMSEN_COEFFICIENTS as names

    rows = [[f"{r.l_over_d:g}", f"{r.S:g}", f"{r.eps:.3f} / {r.eps_pub:.3f}", f"{r.phi:.2f} / {r.phi_pub:.2f}"]
            + [f"{r[n]:.3f} / {r[n + '_pub']:.2f}" for n in names]
            + [f"{max(r[n + '_err_pct'] for n in names):.2f} %"] for _, r in df.iterrows()]
    return _table(["L/D", "S", "eps", "attitude °", *names, "largest error"], rows)


def render_characteristics(reports: Path) -> str:
    ch = _load(reports, "characteristics.json")
    rb, sb, lt = ch["raimondi_boyd"], ch["short_bearing"], ch["lund_thomsen"]
    thr = ch["threshold"]["reference"]
    coarse, fine = (report.grid_label(ch, k) for k in ("reference", "reference_converged"))
    lines = [
        "Validation of the reference model (limits in brackets):", "",
        _table(["check", "worst measured"], [
            ["Raimondi & Boyd 1958, L/D = 1, 1/2, 1/4, eps 0.1-0.9, Swift-Stieber, feed at max. film: "
             "S (2 %), attitude (1°), friction (3 %), flow (3 %), side-flow ratio (3 %)",
             f"{rb['S_max_err_pct']:.2f} %, {rb['phi_max_err_deg']:.2f}°, {rb['friction_max_err_pct']:.2f} %, "
             f"{rb['flow_max_err_pct']:.2f} %, {rb['side_flow_ratio_max_err_pct']:.2f} %"],
            ["same bearing, film bounded by cavitation all round (no feed line): attitude",
             f"{rb['phi_max_err_deg_no_feed']:.1f}° (the feed assumption, not the solver)"],
            [f"Lund & Thomsen 1978, two-axial-groove bearing, L/D = 0.5 and 1, {lt['rows']} rows, "
             f"{lt['grid']} grid: eps (0.01), attitude (1°), the 7 printed coefficients beyond the print's rounding (3 %)",
             f"{lt['eps_max_err']:.4f}, {lt['phi_max_err_deg']:.2f}°, {lt['kc_max_err_pct']:.2f} %"],
            [f"short bearing (Ocvirk, Gümbel), L/D = {sb['l_over_d']:g}: load, attitude, 8 coefficients, critical "
             "mass (1 %)", f"{sb['load_max_err_pct']:.2f} %, {sb['attitude_max_err_deg']:.3f}°, "
             f"{sb['kc_max_err_scale_pct']:.2f} %, {sb['critical_mass_max_err_pct']:.2f} %"],
        ]),
        f"Onset of oil whirl of the paper's rotor ({ch['rotor_mass_per_bearing_kg']:.2f} kg per bearing, reference "
        f"{coarse}): **{thr['speed_rpm']:.0f} rpm** (whirl frequency ratio {thr['whirl_ratio']:.3f}); the nonlinear "
        "model " + ("confirms it" if ch["bracket_holds"] else "does **not** confirm it") + ": "
        + "; ".join(f"{c['factor']:.2f}x ({c['speed_rpm']:.0f} rpm): {'grows' if c['ratio'] > 1 else 'decays'} "
                    f"(amplitude last/first {c['ratio']:.2g}{', contact' if c['contact'] else ''})"
                    for c in ch["nonlinear_checks"]) + ".", "",
        f"Surrogates and the paper's {coarse} grid (row `reference`) against the grid-converged reference "
        f"({fine}, {ch['threshold']['reference_converged']['speed_rpm']:.0f} rpm), eps 0.1-0.9 along the "
        "equilibrium locus; error relative to max(|K_ref|, 0.1 x matrix scale); in brackets the same against "
        f"the {coarse} grid (why two references: docs/characteristics.md, \"Which reference\"):", "",
    ]
    rows = []
    paper = ch.get("kc_max_rel_err_paper_grid", {})
    thr_paper = ch.get("whirl_threshold_rel_err_paper_grid", {})

    def both(value, other):
        cell = "n/a" if value is None else _num(100 * value, ".2f", " %")
        return cell if other is None else f"{cell} ({_num(100 * other, '.2f', ' %')})"

    for name, e in ch["kc_max_rel_err"].items():
        p = paper.get(name, {})
        rows.append([name, both(e["direct"], p.get("direct")), both(e["cross"], p.get("cross")),
                     both(e["scale"], p.get("scale")),
                     both(ch["whirl_threshold_rel_err"].get(name), thr_paper.get(name))])
    lines.append(_table(["model", "K/C max error, direct terms", "K/C max error, cross terms",
                         "K/C max error, share of the matrix", "whirl threshold error"], rows))
    unusable = [name for name, e in ch["kc_max_rel_err"].items() if (e["direct"] or 0) > 1.0]
    if unusable:
        m = _load(reports, "metrics.json")
        medians = []
        for name in unusable:
            median = m.get(f"test_rel_err_median_{name}")
            medians.append(f"{name} {'n/a' if median is None else _num(100 * median, '.0f', ' %')}")
        lines += ["", "Errors above 100 % mean no usable stiffness or damping: the median held-out force error of "
                  f"those networks is {', '.join(medians)}, and a derivative amplifies a force error, so their "
                  "equilibria and coefficients are dominated by the networks' error and change by orders of "
                  "magnitude from one training to the next. They are printed as measured, not as a ranking."]
    best = ch["kc_max_rel_err"].get("best")
    if best and "by_eps" in best:
        pb = paper.get("best", {}).get("by_eps", {})
        ref = ch["kc_max_rel_err"].get("reference", {}).get("by_eps", {})
        lines += ["", "Best model per equilibrium (largest direct / cross error; against the converged grid, in "
                  f"brackets against the {coarse} grid; last column the {coarse} grid itself against the converged "
                  "one):", ""]
        rows = []
        for eps, e in best["by_eps"].items():
            p, r = pb.get(eps, {}), ref.get(eps, {})
            rows.append([eps, both(e["direct"], p.get("direct")), both(e["cross"], p.get("cross")),
                         f"{_num(100 * r['direct'], '.2f', ' %')} / {_num(100 * r['cross'], '.2f', ' %')}" if r else "-"])
        lines.append(_table(["eps", "best: direct", "best: cross", f"{coarse} grid: direct / cross"], rows))
    return "\n".join(lines)


def _stage_outputs(root: Path) -> dict[str, tuple[str, bool]]:
    """{output path under reports/: (stage, committed to git)} from dvc.yaml (``cache: false`` outputs, and
    the files under such a folder, are committed; the others come with `make reproduce` or `dvc pull`)."""
    import yaml

    out: dict[str, tuple[str, bool]] = {}
    for name, stage in yaml.safe_load((root / "dvc.yaml").read_text())["stages"].items():
        for entry in stage.get("do", stage).get("outs", []):
            path, opts = (entry, {}) if isinstance(entry, str) else next(iter(entry.items()))
            if path.startswith("reports/"):
                out[path[len("reports/"):]] = (name, opts.get("cache", True) is False)
    return out


def render_figures(reports: Path) -> str:
    """Every figure the pipeline draws, with its caption (``reporting.captions.CAPTIONS``): the image where
    it is committed, otherwise its path and the stage that draws it."""
    from fluidfilm.reporting.captions import CAPTIONS

    outs = _stage_outputs(reports.parent)
    parts = []
    for path, caption in CAPTIONS.items():
        stage, committed = next(((st, c) for out, (st, c) in outs.items()
                                 if path == out or path.startswith(out.rstrip("/") + "/")), ("?", False))
        if committed and (reports / path).exists():  # a committed output whose stage has not run yet has no image
            parts.append(f"![{path}](../reports/{path})\n\n*{caption}* (stage `{stage}`)")
        else:
            parts.append(f"`reports/{path}` (stage `{stage}`; made by `make reproduce`, not committed): *{caption}*")
    return "\n\n".join(parts)


def render_ensemble(reports: Path) -> str:
    return report.ensemble_block(_load(reports, "ensemble.json"))


def _study(reports: Path, name: str, what: str) -> str:
    summary = _load(reports, f"{name}/summary.json")
    return (f"{what} {summary['n_jobs']} jobs (`reports/{name}/table.csv`, figure `reports/{name}/figure.png`); "
            f"the lowest 99th-percentile force error along the orbits: `{summary['lowest_orbit_p99_job']}` "
            f"({100 * summary['lowest_orbit_p99']:.0f} %).\n\n" + report.study_table(summary))


def render_grading_study(reports: Path) -> str:
    return _study(reports, "grading_study", "Stage `grading_study`, swept over the velocity values per side and the "
                  "angular positions per eccentricity:")


def render_ablation(reports: Path) -> str:
    return _study(reports, "ablation", "Stage `ablation`, swept over the force scaling and frame and the "
                  "eccentricity split:")


def render_error_map(reports: Path) -> str:
    em = _load(reports, "error_map.json")
    rows = [[name, _num(100 * m["held_out"]["median"], ".2f", " %"), _num(100 * m["held_out"]["p99"], ".0f", " %"),
             _num(100 * m["orbit_states"]["median"], ".2f", " %"), _num(100 * m["orbit_states"]["p99"], ".0f", " %")]
            for name, m in em["models"].items()]
    best = em["models"].get("best")
    worst = ""
    if best is not None:
        def where(b: dict) -> str:
            return (f"eps {b['eps_low']:g}-{b['eps_high']:g}, |V| {1e3 * b['speed_low']:g}-{1e3 * b['speed_high']:g} mm/s "
                    f"({100 * b['p99']:.0f} %, {b['n_states']:,} states)")

        worst = ("\nWorst bins of `best` (99th percentile, bins with at least 20 states): held out "
                 + "; ".join(where(b) for b in best["held_out"]["worst_bins"]) + ". Along the orbits: "
                 + "; ".join(where(b) for b in best["orbit_states"]["worst_bins"]) + ".\n")
    return (f"Relative force error |F_model - F| / max(|F|, {em['floor_N']:g} N):\n\n"
            + _table(["model", "held-out median", "held-out p99", "along the orbits, median", "along the orbits, p99"],
                     rows) + worst)


def render_runup(reports: Path) -> str:
    ru = _load(reports, "runup.json")
    lin = ru["linear"]
    sch = ru["schedule"]
    rows = []
    for name, m in ru["models"].items():
        if "onset_rpm" not in m:
            rows.append([name, m["status"], "", "", "", "", ""])
            continue
        rows.append([name, _num(m["onset_rpm"], ",.0f"), _num(100 * (m["onset_rpm"] / lin["threshold_rpm"] - 1), "+.2f", " %"),
                     _num(m["whirl_ratio_at_onset"], ".3f"), _num(m["established_rpm"], ",.0f"), _num(m["gone_rpm"], ",.0f"),
                     _num(m.get("rate_rpm_s"), ",.0f")])
    return (f"Lund's linear threshold of the reference ({lin['grid'][0]}x{lin['grid'][1]}, {lin['cavitation']}): "
            f"**{lin['threshold_rpm']:,.0f} rpm**, whirl ratio {lin['whirl_ratio']:.3f}, eps {lin['eps']:.3f}; rotor "
            f"{ru['rotor']['mass_kg']:g} kg per bearing, imbalance {ru['rotor']['imbalance_kg_m']:g} kg m; ramp "
            f"{sch['rate_rpm_s']:,.0f} rpm/s, RK4 step {sch['dt_s']:g} s. Onset: where the sub-synchronous amplitude "
            f"starts to grow; established / gone: where it crosses {ru['analysis']['whirl_level_c']:g} c on the run-up "
            f"/ run-down:\n\n"
            + _table(["run", "onset [rpm]", "vs Lund", "whirl ratio at onset", "established, up [rpm]",
                      "gone, down [rpm]", "ramp [rpm/s]"], rows))
def render_cavitation_rules(reports: Path) -> str:
    """The cavitation rules against the mass-conserving film (``reports/cavitation_rules.json``, the
    ``cavitation_rules`` stage): per case, each non-conserving rule's orbit distance from JFO's; thresholds,
    run-up onsets, the damper, flows; the JFO model's own checks."""
    import pandas as pd

    cr = _load(reports, "cavitation_rules.json")
    cases = pd.read_csv(reports / "cavitation_rules" / "cases.csv")
    st = cr["settings"]
    rows = []
    for case, g in cases.groupby("case", sort=True):
        by = {r.rule: r for r in g.itertuples()}
        cells = [case]
        for rule in ("gumbel", "swift-stieber"):
            r = by.get(rule)
            cells += ([_num(r.rms_pct, ".2f"), _num(r.hausdorff_pct, ".2f")] if r is not None and hasattr(r, "rms_pct")
                      and r.rms_pct == r.rms_pct else ["n/a", "n/a"])
        j = by.get("jfo")
        cells += [_num(j.span, ".3f") if j is not None else "n/a"]
        for rule in ("gumbel", "swift-stieber"):
            r = by.get(rule)
            cells += [_num(getattr(r, "friction_power_rel_diff_pct", None), "+.1f", " %") if r is not None else "n/a"]
        rows.append(cells)
    m = cr["metrics"]
    lund = cr["thresholds_paper_bearing"]
    lp = cr["thresholds_pfeil"]
    ru = cr["runup_pfeil"]
    dm = cr["damper"]
    th_rows = [[rule, _num(lund[rule]["speed_rpm"], ",.0f"), _num(lp[rule]["speed_rpm"], ",.0f"),
                _num(ru[rule].get("onset_rpm"), ",.0f"), _num(ru[rule].get("growth_nepers"), ".2f"),
                _num(ru[rule].get("limit_cycle_amplitude_c"), ".3f"),
                _num(dm[rule]["damping_N_s_m"], ",.1f"), _num(dm[rule]["stiffness_N_m"], ",.0f")]
               for rule in ("gumbel", "swift-stieber", "jfo")]
    over = cr["cases_over_threshold"]
    gc = cr.get("grid_check_rms_pct_c", {})
    cost = cr["step_cost"]
    return (f"Three rules on one grid ({st['grid'][0]}x{st['grid'][1]}), one feed (an axial groove at "
            f"{st['groove_angle_deg']:g} deg, {st['supply_pressure_Pa']:g} Pa) and one solver; orbits settled from "
            f"t = {st['t_settle']:g} s. Distances of each non-conserving rule's orbit from the mass-conserving one, "
            f"in % of c (RMS / Hausdorff), JFO's span, and the friction power's difference from JFO's:\n\n"
            + _table(["case", "Gümbel RMS", "Gümbel Hausdorff", "Swift-Stieber RMS", "Swift-Stieber Hausdorff",
                      "JFO span [c]", "friction, Gümbel", "friction, Swift-Stieber"], rows)
            + f"\n\nOver {st['threshold_pct']:g} % of c: " + ("; ".join(over) if over else "none") + ". Grid check "
            f"(case {cr['settings'].get('check_case', '')} on {st['check_grid'][0]}x{st['check_grid'][1]}, each rule "
            "against its own orbit on the study's grid, RMS % of c): "
            + ", ".join(f"{k} {v:.2f}" for k, v in gc.items()) + ".\n\n"
            + "Whirl thresholds (Lund, K and C with the film content at its steady value), Pfeil's run-up and the "
            "squeeze-film damper:\n\n"
            + _table(["rule", f"Lund, paper bearing {lund['mass_kg']:g} kg [rpm]", "Lund, Pfeil's bearing [rpm]",
                      "Pfeil run-up onset [rpm]", "sub-synchronous growth [nepers]", "orbit radius, last 0.05 s [c]", "damper damping [N s/m]", "damper stiffness [N/m]"],
                     th_rows)
            + f"\n\nThe JFO model's own checks: flow balance of committed steps {m['jfo_mass_balance_rel_err_max']:.1e} "
            f"(at tol_commit 1e-13: {m['jfo_mass_balance_rel_err_max_tight']:.1e}); Ausas et al. (2009)'s squeeze film "
            f"within {m['jfo_published_case_max_err_pct']:.2f} % of its exact solution ({cr['ausas_squeeze']['nodes']} "
            f"nodes); {cost['us_per_step']:.0f} us per rotor time step on 30x30 ({cost['sweeps_per_stage']:.1f} sweeps "
            f"per stage, {cost['sweeps_per_commit']:.1f} per commit).\n")


def render_cavitation_rules_summary(reports: Path) -> str:
    """The README's sentence on how far the non-conserving rules' orbits are from the mass-conserving film's."""
    cr = _load(reports, "cavitation_rules.json")
    m = cr["metrics"]
    return (f"Against the mass-conserving (JFO) film on the same grid and feed, Gümbel's orbits of the paper's seven "
            f"cases are up to {m['jfo_orbit_rms_pct_c_gumbel_max']:.1f} % of c away (RMS) and Swift-Stieber's up to "
            f"{m['jfo_orbit_rms_pct_c_swift_max']:.1f} %; Gümbel's whirl threshold differs by "
            f"{_num(100 * m['jfo_whirl_threshold_rel_diff_gumbel'], '.1f', ' %')} and its run-up onset (Pfeil's rotor) by "
            f"{_num(100 * m['jfo_runup_onset_rel_diff_gumbel'], '.1f', ' %')} "
            f"([docs/mass_conserving.md](docs/mass_conserving.md)).{_jfo_surrogate_clause(reports)}\n")


def _jfo_surrogate_clause(reports: Path) -> str:
    """The README's clause on the JFO film's surrogate with memory, where its stage ran."""
    if not (reports / "jfo_surrogate.json").exists():
        return ""
    js = report.with_variants(reports, "jfo_surrogate.json")
    m = js["metrics"]
    others = [len(v["satisfactory_cases"]) for k, v in js.get("seeds", {}).items() if k != str(js.get("seed", 0))]
    spread = (f"{min(others)}-{max(others)}" if min(others) != max(others) else f"{min(others)}") if others else ""
    seeds = (f" ({spread} of 7 from {len(others)} other training seed{'s' if len(others) > 1 else ''})"
             if others else "")
    return (f" A force surrogate of the mass-conserving film with memory (the journal's last 40 ms as input) "
            f"follows its reference in {m['satisfactory_cases_jfo_surrogate']} of 7 cases within 2 % of c{seeds}, "
            f"{m['speedup_trajectory_jfo_surrogate']:,.0f}x faster per trajectory.")


def render_jfo_surrogate(reports: Path) -> str:
    """The JFO film's surrogate with memory against its reference (``reports/jfo_surrogate.json`` and
    ``jfo_surrogate_cases.csv``, the ``jfo_surrogate`` stage): per case, the orbit distances, satisfactory or not,
    and the wall times side by side."""
    import pandas as pd

    js = report.with_variants(reports, "jfo_surrogate.json")
    cases = pd.read_csv(reports / "jfo_surrogate_cases.csv")
    st = js["settings"]
    rows = [[r.case, _num(r.ref_span, ".3f"), _num(r.rms_pct, ".2f"), _num(r.hausdorff_pct, ".2f"),
             "yes" if bool(r.satisfactory) else "no", _num(r.reference_wall_s, ".2f"), _num(1e3 * r.surrogate_wall_s, ".1f"),
             _num(r.speedup, ",.0f", "x")] for r in cases.sort_values("case").itertuples()]
    m = js["metrics"]
    return (f"The paper's bearing, JFO on {st['grid'][0]}x{st['grid'][1]} with the groove at "
            f"{st['groove_angle_deg']:g} deg; the surrogate's memory: the journal's positions {st['n_lags']} x "
            f"{1e3 * st['lag_dt']:g} ms back; a {st['width']}x{st['depth']} tanh network fitted on {js['n_paths']} "
            f"JFO paths of random rotors and the journal at rest at random positions ({js['n_samples']:,} samples; every {js['val_every']}th path held out: force "
            f"error {100 * js['val_rel_rmse']:.1f} % RMS on those). Orbits settled from t = {st['t_settle']:g} s, "
            f"satisfactory when RMS and Hausdorff distance are both within {st['threshold_pct']:g} % of c; wall times "
            f"over each case's first {st['timing_t_end']:g} s, side by side in one process (median of "
            f"{st['timing_repeats']}):\n\n"
            + _table(["case", "JFO span [c]", "RMS [% c]", "Hausdorff [% c]", "satisfactory", "JFO reference [s]",
                      "surrogate [ms]", "speed-up"], rows)
            + f"\n\n**{m['satisfactory_cases_jfo_surrogate']} of {len(rows)} cases satisfactory** "
            f"({js['satisfactory_cases'] or 'none'}); median speed-up per trajectory "
            f"{m['speedup_trajectory_jfo_surrogate']:,.0f}x. The same fit from other seeds"
            + "".join(sorted({f" (`make jfo-surrogate-seeds`: {v['from']})" for v in js.get("seeds", {}).values()
                              if "from" in v})) + ": "
            + "; ".join(f"seed {k}: {len(v['satisfactory_cases'])} of {len(rows)} ({v['satisfactory_cases'] or 'none'}), "
                        f"largest RMS {v['rms_pct_max']:.2f} % of c, held-out force error {100 * v['val_rel_rmse']:.1f} %"
                        for k, v in js.get("seeds", {}).items() if k != str(js.get("seed", 0)))
            + ".\n")


def render_universal_summary(reports: Path) -> str:
    """The README's sentence on the shipped universal model's accuracy on bearings it never saw, from
    ``reports/universal.json`` (the ``universal_evaluate`` stage)."""
    u = _load(reports, "universal.json")
    return (f"On bearings it never saw ([docs/results.md](docs/results.md#the-universal-plain-bearing-surrogate)) "
            f"its forces are within {100 * u['universal_rel_err_median']:.2g} % (median; "
            f"{100 * u['universal_rel_err_p99']:.2g} % at the 99th percentile) of the grid-converged reference and "
            f"its whirl threshold within {100 * u['universal_whirl_threshold_rel_err']:.2g} %; its stiffness and "
            f"damping along the equilibrium locus are within {100 * u['universal_kc_max_rel_err_direct']:.2g} % "
            f"(direct) and {100 * u['universal_kc_max_rel_err_cross']:.2g} % (cross).{_universal_speed(u)}\n")


def _universal_speed(u: Mapping) -> str:
    """The README's clause on the universal model's cost: one float64 force, and the least speed-up over the
    reference on a grid as accurate (the smaller of the two yardsticks' readings, when the report has them)."""
    if "force_eval_us_universal" not in u or "universal_speedup_vs_reference_equal_accuracy_min" not in u:
        return ""
    least = min(u["universal_speedup_vs_reference_equal_accuracy_min"],
                u.get("universal_speedup_vs_reference_matched_min", math.inf))
    machine = u.get("cost", {}).get("machine", "this machine")
    return (f" A force costs {1e3 * u['force_eval_us_universal']:.0f} ns (one state, float64; {machine}), "
            f"at least {least:.0f}x less than the reference on a grid as accurate "
            f"([docs/universal.md](docs/universal.md#cost-per-force)).")


def render_universal_kc(reports: Path) -> str:
    """Where along the equilibrium locus the shipped universal model's K and C miss the converged reference:
    the worst over the held-out L/D at each eccentricity, per rule (``reports/universal.json``, ``kc_by_eps``)."""
    u = _load(reports, "universal.json")
    by = u["kc_by_eps"]
    rules = sorted({k.split(":")[0] for k in by})
    eps = sorted({k.split(":")[2] for k in by}, key=float)
    rows = [[e] + [_num(100 * by[f"{r}:{kind}:{e}"], ".2f", " %") for r in rules for kind in ("direct", "cross")]
            for e in eps]
    goals = u["goals"]
    return (_table(["eps at equilibrium"] + [f"{r}, {kind}" for r in rules for kind in ("direct", "cross")], rows)
            + f"\nGoals: direct ≤ {100 * goals['kc_direct']:g} %, cross ≤ {100 * goals['kc_cross']:g} %; held-out L/D "
              f"{', '.join(f'{x:g}' for x in u['held_out_ld'])}; error |K - K_ref| / max(|K_ref|, "
              "0.1 x the largest coefficient of the matrix) at the same load.\n")


def render_universal(reports: Path) -> str:
    u = _load(reports, "universal.json")
    g = u["goals"]

    def row(what, value, goal, unit="%", scale=100.0, spec=".3g", le=True):
        v = scale * value
        met = v <= scale * goal if le else v >= goal
        return [what, f"{v:{spec}} {unit}".strip(), f"{'≤' if le else '≥'} {scale * goal if le else goal:g} {unit}".strip(),
                "yes" if met else "no"]

    rb = u["raimondi_boyd"]
    rows = [row("median relative force error, held-out L/D and bearings", u["universal_rel_err_median"],
                g["rel_err_median"]),
            row("99th-percentile relative force error", u["universal_rel_err_p99"], g["rel_err_p99"]),
            *([row("the same through the batched kernel, float32 networks: median", u["universal_rel_err_median_float32"],
                   g["rel_err_median"]),
               row("the same, float32 networks: 99th percentile", u["universal_rel_err_p99_float32"], g["rel_err_p99"])]
              if "universal_rel_err_median_float32" in u else []),
            row("K, C along the equilibrium locus (eps 0.1-0.9), direct terms", u["universal_kc_max_rel_err_direct"],
                g["kc_direct"]),
            row("K, C along the equilibrium locus, cross terms", u["universal_kc_max_rel_err_cross"], g["kc_cross"]),
            row("whirl threshold speed", u["universal_whirl_threshold_rel_err"], g["whirl_threshold"]),
            row("Raimondi & Boyd S, against our plain-bearing reference", rb["max_S_err_vs_reference_pct"] / 100,
                g["raimondi_boyd_pct"] / 100),
            row("Raimondi & Boyd attitude, against our plain-bearing reference",
                rb["max_phi_err_vs_reference_pct"] / 100, g["raimondi_boyd_pct"] / 100),
            ["Fig. 4 cases satisfactory (paper's bearing, no training on it)",
             f"{u['satisfactory_cases_universal']} of {u['n_cases']}", f"≥ {g['cases']} of 7",
             "yes" if u["satisfactory_cases_universal"] >= g["cases"] else "no"],
            [f"time per force, one state in the integrator's loop (best model's shape: "
             f"{u['cost']['force_eval_us_best_shape']:.3f} us, same run; in brackets the median of the rounds' "
             f"cost ratios, which decides)",
             f"{u['force_eval_us_universal']:.3f} us ({u['cost']['universal_vs_best_cost_ratio']:.3f}x)",
             f"≤ {u['cost']['force_eval_us_best_shape']:.3f} us (1x)",
             "yes" if u["cost"]["universal_vs_best_cost_ratio"] <= 1.0 else "no"]]
    c = u["cost"]
    if "force_eval_us_universal_float32" in c:  # evaluations before 2026-12-04 (fourth session): float64 only
        rows.append([f"time per force, one state, float32 networks (simulate(precision=\"float32\"); best model's "
                     f"shape {c['force_eval_us_best_shape_float32']:.3f} us)",
                     f"{c['force_eval_us_universal_float32']:.3f} us ({c['universal_vs_best_cost_ratio_float32']:.3f}x)",
                     f"≤ {c['force_eval_us_best_shape_float32']:.3f} us (1x)",
                     "yes" if c["universal_vs_best_cost_ratio_float32"] <= 1.0 else "no"])
    if "force_eval_us_universal_batched_float32" in c:  # evaluations before 2026-12-02 (fifth session) timed one state only
        rows.append([f"time per force, batched ({c['n_batch']} states per call, one thread, float32 networks: "
                     f"simulate_batch's stage; best model's shape {c['force_eval_us_best_shape_batched_float32']:.3f} us)",
                     f"{c['force_eval_us_universal_batched_float32']:.3f} us "
                     f"({c['universal_vs_best_cost_ratio_batched_float32']:.3f}x)",
                     f"≤ {c['force_eval_us_best_shape_batched_float32']:.3f} us (1x)",
                     "yes" if c["universal_vs_best_cost_ratio_batched_float32"] <= 1.0 else "no"])
    if "reference_equal_accuracy" in u:  # evaluations before 2026-12-02 did not time the reference
        same = u["reference_equal_accuracy"]
        goal = g.get("speedup_equal_accuracy", 100)
        # two yardsticks for "as accurate" (studies.universal_study.reference_cost_at_equal_accuracy): the
        # convergence check's grid, and the grid whose own median and p99 errors match the model's (suffix
        # _matched; evaluations since 2026-12-05, tenth session)
        floor = any(r.get("grid_at_ladder_floor") for r in same)
        for suffix, rule_words in (
                ("", "the grid the dataset's convergence check accepts at the model's median error (eps 0.8, "
                     "every direction)"),
                ("_matched", "the coarsest ladder grid whose own median and p99 errors at the held-out states are "
                             "the model's or less" + (" (some at the ladder's coarsest grid: upper bounds)" if floor
                                                      else ""))):
            grid_list = [f"{nt} x {nz}" for nt, nz in sorted({(int(r["n_theta" + suffix]), int(r["n_z" + suffix]))
                                                             for r in same if "n_theta" + suffix in r})]
            for key, how in (("speedup", "one state each"),
                             ("speedup_float32", "one state each, the model's networks in float32"),
                             ("speedup_batched", "both batched, one thread")):
                k = key + suffix
                if k not in same[0]:
                    continue
                worst = min(same, key=lambda r: r[k])
                ref_us = worst[("reference_batched_us" if key == "speedup_batched" else "reference_us") + suffix]
                nt, nz = (worst["n_theta" + suffix], worst["n_z" + suffix])
                spread = (f" (rounds {worst[k + '_lo']:.0f}-{worst[k + '_hi']:.0f}x)" if f"{k}_lo" in worst
                          else "")  # evaluations before 2026-12-04 (fifth session): one ratio of medians
                rows.append([f"speed-up per force over the reference on {rule_words}, {how} (grids "
                             f"{', '.join(grid_list)}; least: {worst['cavitation']}, L/D {worst['ld']:g}, "
                             f"{nt} x {nz}, {ref_us:.1f} us)", f"{worst[k]:.0f}x{spread}", f"≥ {goal:g}x",
                             "yes" if worst[k] >= goal else "no"])
    by_rule = "; ".join(f"{r}: median {100 * v['median']:.2f} %, p99 {100 * v['p99']:.1f} %"
                        for r, v in u["by_rule"].items())
    return (_table(["quantity", "measured", "goal", "met"], rows)
            + f"\nPer cavitation rule: {by_rule}. Against the published table (its feed at the maximum film "
              f"thickness, our plain bearing none): S within {rb['max_S_err_pct']:.1f} %, attitude within "
              f"{rb['max_phi_err_pct']:.1f} %.\n" + _weights_reproduced(_optional(reports, "universal_train.json")))


def _optional(reports: Path, name: str) -> dict | None:
    return _load(reports, name) if (reports / name).exists() else None


def _weights_reproduced(record: Mapping | None) -> str:
    """Whether the training gave the shipped weights: ``reports/universal_train.json``, committed by
    ``make universal-train`` (``weights_reproduced`` per rule, the machine and the date)."""
    if not record:
        return ""
    found = record["weights_reproduced"]

    def says(rule: str, r: Mapping) -> str:
        if r.get("missing"):
            return f"{rule}: no trained weights in models/universal"
        if r["identical"]:
            return f"{rule}: the shipped weights, bit for bit"
        if r.get("max_rel_diff") is None:
            return f"{rule}: networks of another shape (a smaller profile's)"
        return f"{rule}: other weights (differences up to {r['max_rel_diff']:.3g} x an array's largest entry)"

    return ("\nThe training (`make universal-train`, outside the pipeline's budget; "
            f"{record['machine']}, {record['date']}) against the shipped weights: "
            + "; ".join(says(rule, r) for rule, r in found.items()) + ".\n")


def render_surrogate_goals(reports: Path) -> str:
    m = _load(reports, "metrics.json")
    return (f"Met: **{m['surrogate_goals_met']} of {m['surrogate_goals']}** (`reports/metrics.json`).\n\n"
            + report.goals_table(m))


def render_characteristics_timing(reports: Path) -> str:
    ch = _load(reports, "characteristics.json")
    t = ch["timing_ms_per_coefficient_set"]
    base = t.get("reference")
    rows = [[name, f"{ms:.3g} ms", f"{base / ms:.2g}x" if base else "-"] for name, ms in t.items()]
    return _table(["model", "time per coefficient set", "vs reference 30x30"], rows)


def _paper_26_in(study: Mapping) -> str:
    """Whether the paper's 26 % reduction lies in a study's 95 % interval: "inside" or "**outside**"."""
    return ("inside" if study["train_time_reduction_ci95_low"] <= 26.0 <= study["train_time_reduction_ci95_high"]
            else "**outside**")


def render_train_time(reports: Path) -> str:
    tt = report.with_variants(reports, "train_time.json")
    lines = [
        f"Protocol `{tt['train_time_protocol']}`, {tt['train_time_samples_per_seed']:,} samples per seed drawn from the "
        f"{tt['dataset_samples']:,}-sample paper dataset, {tt['train_time_seeds']} seeds; every network stopped by the "
        f"validation rule: **{'yes' if tt['train_time_converged'] else 'no'}** (at most {tt['max_epochs']} epochs). "
        f"Reduction of the mean training time, split vs single: **{tt['train_time_reduction_pct']:.1f} %**, paired "
        f"bootstrap 95 % interval {tt['train_time_reduction_ci95_low']:.1f} to {tt['train_time_reduction_ci95_high']:.1f} % "
        f"(half-width {tt['train_time_reduction_ci95']:.1f} points; paper: 26 %, though its own times, 5 h 42 min and "
        f"4.5 h, give a 21 % reduction: 26 % is the single network's extra time over the split's)"
        + (f"; the mean of the per-seed reductions is {tt['train_time_reduction_pct_mean_of_seeds']:.1f} % "
           f"± {tt['train_time_reduction_pct_mean_of_seeds_ci95']:.1f}"
           if "train_time_reduction_pct_mean_of_seeds" in tt else "") + ". "
        + (f"The target half-width ({tt['train_time_reduction_ci95_target']:.0f} points) is reached: seeds were added two "
           "at a time until it was, and such sequential stopping favours a narrow interval slightly. "
           if tt["train_time_reduction_ci95"] <= tt["train_time_reduction_ci95_target"] else "")
        + f"The paper's 26 % is {_paper_26_in(tt)} this interval. "
        + (f"A half-width of {tt['train_time_reduction_ci95_target']:.0f} points would need about "
           f"{tt['train_time_seeds_needed_for_target']} seeds (about "
           f"{tt['train_time_study_s_needed_for_target'] / 60:.0f} min of this study on this machine). "
           if tt.get("train_time_seeds_needed_for_target") and tt["train_time_reduction_ci95"]
           > tt["train_time_reduction_ci95_target"] else "")
        + f"Median validation relative RMS force error: "
        f"single {tt['val_rel_rmse_single_median']:.3f}, split {tt['val_rel_rmse_split_median']:.3f}. Faster: "
        f"{tt['ranking']['faster']}"
        + (" (by the point estimate only: the interval contains 0, so neither structure is measurably faster)"
           if tt["train_time_reduction_ci95_low"] < 0 < tt["train_time_reduction_ci95_high"] else "")
        + f", more accurate: {tt['ranking']['more_accurate']}.", ""]
    if tt.get("ranking_check"):
        lines += [f"Ranking check at {report.ranking_line(tt)}", ""]
    rows = []
    for r in tt["runs"]:
        eq = r.get("time_to_equal_accuracy_split_s")
        rows.append([str(r["seed"]), f"{r['single']['train_time_s']:.1f} s", f"{r['split']['train_time_s']:.1f} s",
                     f"{r['reduction_pct']:+.1f} %", "not reached" if eq is None else f"{eq:.1f} s",
                     f"{r['single']['val_rel_rmse']:.3f} / "
                     + (f"{r['split']['val_rel_rmse']:.3f}" if isinstance(r['split']['val_rel_rmse'], (int, float))
                        else "/".join(f"{v:.3f}" for v in r['split']['val_rel_rmse'])),
                     ", ".join(sorted(set(r["single"]["stop_reasons"]) | set(r["split"]["stop_reasons"])))])
    lines += [f"<details><summary>Per seed ({len(rows)} seeds)</summary>", "",
              _table(["seed", "single", "split (sum of 3)", "reduction", "split to the single's accuracy",
                      "val. rel. RMSE single / split", "stop reasons"], rows), "", "</details>"]
    return "\n".join(lines)


def render_train_time_ci(reports: Path) -> str:
    """The training-time study run until its interval reaches the target (``make train-time-ci``)."""
    import numpy as np

    t = _load(reports, "train_time_ci.json")
    reached = t["train_time_reduction_ci95"] <= t["train_time_reduction_ci95_target"]
    single, split = ([r[k]["train_time_s"] for r in t["runs"]] for k in ("single", "split"))
    equal = [r["reduction_at_equal_accuracy_pct"] for r in t["runs"] if r["reduction_at_equal_accuracy_pct"] is not None]
    rows = [
        ["seeds (single and split on the same rows)", f"{t['train_time_seeds']}"],
        ["samples per seed", f"{t['train_time_samples_per_seed']:,}"],
        ["every network stopped by the validation rule", "yes" if t["train_time_converged"] else "**no**"],
        ["reduction of the mean training time, split vs single",
         f"**{t['train_time_reduction_pct']:.1f} %**, 95 % CI {t['train_time_reduction_ci95_low']:.1f} to "
         f"{t['train_time_reduction_ci95_high']:.1f} % (half-width {t['train_time_reduction_ci95']:.1f} points, "
         f"target {t['train_time_reduction_ci95_target']:.0f}: {'reached' if reached else '**not reached**'})"],
    ]
    if not reached and t.get("train_time_seeds_needed_for_target"):
        rows.append(["seeds the target would need (1/sqrt(n) law)",
                     f"about {t['train_time_seeds_needed_for_target']} (about "
                     f"{t['train_time_study_s_needed_for_target'] / 3600:.1f} h of this study on this machine)"])
    rows += [
        ["mean of the per-seed reductions", f"{t['train_time_reduction_pct_mean_of_seeds']:.1f} % ± "
         f"{t['train_time_reduction_pct_mean_of_seeds_ci95']:.1f}"],
        ["mean time to the stopping rule, single / split (sum of 3); coefficient of variation",
         f"{t['train_time_single_s_mean']:.1f} s / {t['train_time_split_s_mean']:.1f} s; "
         f"{np.std(single) / t['train_time_single_s_mean']:.2f} / {np.std(split) / t['train_time_split_s_mean']:.2f}"],
        ["longest time, single / split", f"{t['train_time_single_s_max']:.1f} s / {t['train_time_split_s_max']:.1f} s"],
        ["median time, single / split; split's 3 networks in parallel",
         f"{t['train_time_single_s']:.1f} s / {t['train_time_split_s']:.1f} s; {t['train_time_split_parallel_s']:.1f} s"],
        ["median validation rel. RMS force error, single / split",
         f"{t['val_rel_rmse_single_median']:.3f} / {t['val_rel_rmse_split_median']:.3f}"],
        ["split reaches the single's final validation error (seeds; mean reduction to that point)",
         f"{len(equal)} of {t['train_time_seeds']}" + (f"; {sum(equal) / len(equal):.0f} %" if equal else "")],
        ["training time summed over seeds and structures (the study ran 2 processes at a time)",
         f"{(sum(single) + sum(split)) / 3600:.1f} h"],
        ["machine" + (", date" if "date" in t else ""), t["machine"] + (f", {t['date']}" if "date" in t else "")],
    ]
    lo, hi = t["train_time_reduction_ci95_low"], t["train_time_reduction_ci95_high"]
    verdict = (f"The paper's 26 % is {_paper_26_in(t)} this interval; "
               + ("it contains 0, so with the paper's protocol at this size neither structure trains measurably "
                  "faster." if lo < 0 < hi else f"the split model trains {'faster' if lo > 0 else 'slower'}."))
    return _table(["`make train-time-ci` (reports/train_time_ci.json)", "measured"], rows) + "\n" + verdict + "\n"


def render_train_time_full_scale(reports: Path) -> str:
    """Single vs split trained once each on the whole dataset (``make train-time-full-scale``), or a line
    saying it has not been run (it is optional and outside the pipeline)."""
    if not (reports / "train_time_full_scale.json").exists():
        return ("Not run yet in this workspace: `make train-time-full-scale` writes "
                "`reports/train_time_full_scale.json` and fills this block.\n")
    t = _load(reports, "train_time_full_scale.json")
    f = t["full_scale"]
    r = f["runs"][0]
    rows = []
    for which in ("single", "split"):
        nets = r[which]["networks"]
        per_net = " + ".join(f"{n['train_time_s'] / 60:.1f}" for n in nets)
        rows.append([which, f"{r[which]['train_time_s'] / 60:.1f} min" + (f" ({per_net})" if len(nets) > 1 else ""),
                     ", ".join(f"{n['n_train']:,}" for n in nets),
                     ", ".join(str(n["epochs"]) for n in nets), ", ".join(n["stop_reason"] for n in nets),
                     ", ".join(f"{n['val_rel_rmse']:.3f}" for n in nets) if len(nets) > 1 else "-",
                     f"{r[which]['val_rel_rmse']:.3f}", f"{r[which]['test_rel_rmse']:.3f}"])
    p = f["protocol"]
    return (f"Protocol `{p['name']}` (batch {p.get('batch_size')}, the paper protocol's division and stopping rule), "
            f"all {f['train_time_samples_per_seed']:,} samples, one seed, {t['machine']}, {t['date']}: reduction "
            f"**{f['train_time_reduction_pct']:.0f} %** (one run per structure, so no interval); faster: "
            f"{f['ranking']['faster']}, more accurate: {f['ranking']['more_accurate']}. The split's three networks "
            f"trained in parallel would take {r['split']['train_time_parallel_s'] / 60:.1f} min (the longest of them).\n\n"
            + _table(["structure", "time to the stopping rule", "training rows per network", "epochs per network",
                      "stop reasons", "val. rel. RMSE per network", "val. rel. RMSE", "test rel. RMSE"], rows))


#: the paper_scale study's reports, first found first (``report.PAPER_SCALE_REPORTS``)
PAPER_SCALE_REPORTS = report.PAPER_SCALE_REPORTS


def paper_scale_records(reports: Path) -> tuple[list[dict], list[str]]:
    """Every record of the paper_scale reports present (one per label, the first report's), and the reports'
    sources (file, machine, date, load)."""
    seen: dict[str, dict] = {}
    sources = []
    for name in PAPER_SCALE_REPORTS:
        if not (reports / name).exists():
            continue
        t = _load(reports, name)
        load = t.get("load_average")
        sources.append(f"`reports/{name}` ({t['machine']}, {t['date']}"
                       + (f", load average {load[0]:.1f} at the end" if load else "") + ")")
        for r in t["records"]:
            if "from_report" not in r:
                seen.setdefault(r["label"], r)
    return list(seen.values()), sources


def _resolution_cell(res: Mapping | None) -> str:
    if not res:
        return "-"
    return f"{math.hypot(*res['newton_per_mapped_unit']):,.0f}; {res['expected_static_error_N']:.0f}"


def render_paper_scale(reports: Path) -> str:
    """One row per trained model of the paper_scale study: training, static force error, equilibrium offset and
    the verdicts by both readings."""
    records, sources = paper_scale_records(reports)
    if not records:
        return ("Not run yet in this workspace: the `paper_scale` stage (`make reproduce`) writes "
                "`reports/paper_scale.json` and fills this block.\n")
    rows = []
    for r in records:
        nets = r["networks"]
        eq = r["equilibrium"]["a"]
        err = eq["static_force_error_N"]
        band = r["bands"]
        rows.append([r["label"], f"{r['n_samples']:,}", ", ".join(str(n["epochs"]) for n in nets),
                     ", ".join(n["stop_reason"] for n in nets), f"{r['train_time_s']:.0f} s",
                     " / ".join(_num(band.get(f"test_rel_err_median_band_{b}"), ".1%") for b in ("0_0.5", "0.5_0.7", "0.7_1")),
                     f"({err[0]:.0f}, {err[1]:.0f}) N; {100 * math.hypot(*err) / eq['load_N']:.0f} %",
                     f"{100 * r['locus']['error_share_of_load_max']:.0f} %",
                     _resolution_cell(r.get("resolution")),
                     _num(r["equilibrium_offset_pct_c"], ".1f", " %"),
                     r["satisfactory_cases_position"] or "none", r["satisfactory_cases_paper_reading"] or "none",
                     f"{r.get('paper_verdicts_reproduced_position', '-')} / {r.get('paper_verdicts_reproduced_paper_reading', '-')}"])
    return ("From " + "; ".join(sources) + ". The paper's verdicts: single e, split a-e.\n\n"
            + _table(["model", "samples", "epochs per network", "stop reasons", "training time",
                      "held-out median rel. error, eps 0-0.5 / 0.5-0.7 / > 0.7",
                      "static force error at the reference equilibrium under the rotor's weight; share of the load",
                      "largest share along the locus (0.25-4 x the weight)",
                      "one mapped unit at that equilibrium; x the network's val. RMS [N]", "equilibrium offset [% of c]",
                      "satisfactory, 2 %-of-c rule", "satisfactory, the paper's reading (span, shape)",
                      "paper's 7 verdicts reproduced (rule / reading)"], rows))


#: the paper_scale ablation's variants in the README's words
_ABLATION_WORDS = {"whirl_frame": "the whirl frame", "map_per_speed": "the map scaled by 1 + |V|/(c omega)",
                   "polar_frame": "the journal's polar frame", "static_rows": "static rows added",
                   "boundaries_five": "five regions"}


def render_paper_scale_mechanism(reports: Path) -> str:
    """The README's paragraph on what decides the paper's verdicts, its numbers from the paper_scale study's
    40 k split and its one-ingredient variants (the records ``render_paper_scale`` tables)."""
    by_label = {r["label"]: r for r in paper_scale_records(reports)[0]}
    base = by_label.get("curve split 40000")
    if base is None:
        return ("Not run yet in this workspace: the `paper_scale` stage (`make reproduce`) writes "
                "`reports/paper_scale.json` and fills this paragraph.\n")

    def static(r: Mapping) -> tuple[str, str]:
        eq = r["equilibrium"]["a"]
        share = f"{math.hypot(*eq['static_force_error_N']) / eq['load_N']:.2g}x the load"
        off = "no equilibrium under the load" if eq.get("offset_pct_c") is None else f"offset {eq['offset_pct_c']:.1f} % of c"
        return share, off

    eq = base["equilibrium"]["a"]
    unit = base.get("resolution") or {}
    share, off = static(base)
    text = (f"At {base['n_samples']:,} samples the paper's split network misses the static film force under the "
            f"rotor's weight ({eq['load_N']:.1f} N) by {share}"
            + (f" (one mapped output unit is {math.hypot(*unit['newton_per_mapped_unit']):,.0f} N there)" if unit else "")
            + f", so the journal settles away from the reference's equilibrium: {off}. One ingredient changed at a "
            "time on the same rows: ")
    parts = []
    for name, words in _ABLATION_WORDS.items():
        r = by_label.get(f"ablation {name}")
        if r is not None:
            sh, of = static(r)
            parts.append(f"{words} {sh}, {of}")
    text += "; ".join(parts) + ". "
    larger = sorted((r for r in by_label.values() if r.get("structure") == "split" and r["label"].startswith("curve")
                     and r["n_samples"] > base["n_samples"]), key=lambda r: r["n_samples"])
    for r in larger:
        sh, of = static(r)
        text += f"At {r['n_samples']:,} samples the split misses it by {sh}, {of}. "
    text += (f"Cases satisfactory (the paper: a-e): by the 2 %-of-c rule "
             f"{base['satisfactory_cases_position'] or 'none'}, by the paper's reading (span and shape) "
             f"{base['satisfactory_cases_paper_reading'] or 'none'}.\n")
    return text


def render_paper_bands(reports: Path) -> str:
    m = _load(reports, "metrics.json")
    rows = []
    for model in ("paper_single", "paper_split"):
        rows.append([model] + [_num(m.get(f"test_rel_err_median_{model}_band_{b}"), ".1%")
                               for b in ("0_0.5", "0.5_0.7", "0.7_1")] + [_num(m.get(f"test_rel_err_median_{model}"), ".1%")])
    return _table(["model", "eps 0-0.5", "eps 0.5-0.7", "eps > 0.7", "whole domain"], rows)


def render_batch_speed(reports: Path) -> str:
    b = _load(reports, "batch_speed.json")
    by: dict[int, dict[str, dict]] = {}
    for r in b["rows"]:
        by.setdefault(r["n"], {})[r["model"]] = r
    rows = []
    for n, d in sorted(by.items()):
        ref, sur = d.get("reference", {}), d.get("surrogate", {})

        def rate(x):
            return "-" if x is None else f"{x:,.1f}/s"
        ratio = (sur.get("batched_per_s") or 0) / ref["batched_per_s"] if ref.get("batched_per_s") else None
        rows.append([str(n), rate(ref.get("one_by_one_per_s")), rate(ref.get("batched_per_s")),
                     rate(sur.get("one_by_one_per_s")), rate(sur.get("batched_per_s")), _num(ratio, ".1f", "x")])
    host = (f"Measured on {b['machine']}, {b['date']}." if b.get("machine")
            else "The host was not recorded (runs before 2026-12-04).")
    th = b.get("threads")
    if th:
        n_max = max(by)
        host += (f" Across threads (wall time, N = {n_max}): surrogate {th['surrogate']['batched_per_s']:,.0f}/s "
                 f"(x{th['surrogate']['scaling']:.2f} over one thread), reference {th['reference']['batched_per_s']:,.1f}/s "
                 f"(x{th['reference']['scaling']:.2f}): **{b['trajectories_per_s_batch_speedup_threads']:.1f}x**.")
    cs = b.get("core_scaling")
    if cs:
        host += (f" What a second thread adds on this machine at all (`fluidfilm.perf.cores`, same run): a vectorised "
                 f"FMA loop x{cs['vector_fma']:.2f}, a scalar latency chain x{cs['scalar_chain']:.2f}.")
    during = b.get("core_scaling_during_runs")
    if during:
        lo, hi = during["vector_fma_range"]
        host += (f" The same probes, short, before each pair of threads runs: vector FMA x{during['vector_fma_median']:.2f}"
                 f" (median; x{lo:.2f} to x{hi:.2f}), scalar chain x{during['scalar_chain_median']:.2f}: the surrogate's"
                 f" vector-bound networks can scale no better than the vector loop the host allows at the time.")
    return _table(["N", "reference one by one", "reference batched", "surrogate one by one", "surrogate batched",
                   "surrogate / reference, batched"], rows) + "\n" + host + "\n"


def render_controller_training(reports: Path) -> str:
    c = _load(reports, "controller_training_speed.json")
    rows = [[name, f"{c[name]['wall_s']:.1f} s", f"{1e3 * c[name]['s_per_env_step']:.1f} ms",
             f"{c[name]['full_training_s_extrapolated'] / 60:.1f} min"] for name in ("surrogate", "reference")]
    return (_table(["model driving the environment", f"{c['budget_steps']} DQN steps", "per environment step",
                    f"{c['full_training_steps']:,} steps (extrapolated)"], rows)
            + f"\nSpeed-up of controller training, surrogate vs reference: **{c['controller_training_speedup']:.1f}x**"
              f" ({c['note']}).\n")


def _pct(x) -> str:
    return _num(100.0 * x, ".2f", " %")


def render_online_assessment(reports: Path) -> str:
    """The estimator against the reference plant and the centreline baseline, per scenario: the median and the worst
    over the stage's noise seeds (docs/online_assessment.md)."""
    oa = _load(reports, "online_assessment.json")
    rows = []
    for name, r in oa["scenarios"].items():
        f, fw = r.get("filter", {}), r.get("filter_worst", {})
        fl = r["flags"]
        n = len(r.get("seeds", [0]))
        fired = [f"{label} ({fl[key + '_seeds']}/{n})" for key, label in (("mismatch", "mismatch"),
                                                                          ("out_of_domain", "out of domain"))
                 if fl.get(key + "_seeds")]
        role = "made to trip: " + r["trip"].replace("_", " ") if r.get("trip") else (
            "blind spot" if r.get("blind_spot") else "")
        both = lambda k: f"{_pct(f.get(k))} / {_pct(fw.get(k))}"   # noqa: E731
        bound = (r.get("bound") or {}).get("slow_roll_error", {}).get("window_rms")
        rows.append([f"`{name}`" + (f" ({role})" if role else ""), both("load_rel_err"), both("imbalance_rel_err"),
                     _num(f.get("imbalance_phase_err_deg"), ".2f", "°"), both("viscosity_rel_err"),
                     _pct(r["sd_end"]["viscosity_rel"]),
                     f"{_pct(bound['load_rel'])} / {_pct(bound['viscosity_rel'])}" if bound else "n/a",
                     f"{_pct(r['baseline']['load_rel_err'])} / {_pct(r['baseline'].get('load_rel_err_worst'))}",
                     ", ".join(fired) or "none", _num(r["us_per_sample"], ".1f")])
    m = oa["metrics"]
    met = oa["goals_met"]
    goals = oa["goals"]
    seeds = m.get("estimator_noise_seeds", 1)
    keys = (f"Keys (the worst scenario's median over {seeds} noise seeds): load {_pct(m['estimator_load_rel_err'])} "
            f"(goal {_pct(goals['load_rel_err'])}), imbalance {_pct(m['estimator_imbalance_rel_err'])} (goal "
            f"{_pct(goals['imbalance_rel_err'])}), viscosity {_pct(m['estimator_viscosity_rel_err'])} (goal "
            f"{_pct(goals['viscosity_rel_err'])}); the worst scenario and seed: load "
            f"{_pct(m['estimator_load_rel_err_worst'])}, imbalance {_pct(m['estimator_imbalance_rel_err_worst'])}, "
            f"viscosity {_pct(m['estimator_viscosity_rel_err_worst'])}; "
            f"{m['estimator_us_per_sample']:.1f} µs per sample (median; goal {goals['us_per_sample']:g}; the worst "
            f"record {m['estimator_us_per_sample_worst']:.0f} µs); {m['estimator_vs_centreline_load_err_ratio']:.2f}x "
            f"the centreline baseline's accuracy at the least (median over the seeds; goal {goals['vs_centreline']:g}x; "
            f"the worst seed {m['estimator_vs_centreline_load_err_ratio_worst']:.2f}x); false flags "
            f"{_pct(m['estimator_false_flag_rate'])} of the samples, trip records caught "
            f"{m['estimator_trip_flag_rate']:.0%}. Goals met: "
            + ", ".join(k.replace("_", " ") for k, v in met.items() if v) + "; missed: "
            + (", ".join(k.replace("_", " ") for k, v in met.items() if not v) or "none")
            + f". Measured on {oa['machine']}." + _bound_sentence(oa))
    return (_table(["scenario", "load: median / worst", "imbalance: median / worst", "phase (median)",
                    "viscosity: median / worst", "viscosity 1σ at the end (filter's own)",
                    "information bound 1σ, load / viscosity (window RMS)",
                    "centreline baseline, load: median / worst", "flags (seeds fired)", "µs per sample"], rows)
            + "\n\n" + keys)


def _bound_sentence(oa: dict) -> str:
    """Which accuracy goals lie beyond what the records hold (the information bound, ``estimation.bound``)."""
    ib = oa.get("information_bound") or {}
    if not ib:
        return ""
    parts = []
    for key in ("load", "imbalance", "viscosity"):
        b = ib.get(key)
        if b:
            parts.append(f"{key} {_pct(b['bound_sd'])} on `{b['scenario']}`, where an efficient estimator's median "
                         f"over noise draws would be about {_pct(b['efficient_median'])}: the goal "
                         + ("lies beyond the record" if b["goal_out_of_reach"] else "is within its reach"))
    return (" The records' information bound (Cramér-Rao, with the slow-roll vector's error; 1σ as the window's RMS, "
            "the largest over the constant-parameter scenarios): " + "; ".join(parts) + ".")


def render_online_assessment_bound(reports: Path) -> str:
    """The information bound on other records than the benchmark's: what would close the goals the benchmark's
    record cannot reach (``bound_what_if`` of the stage)."""
    oa = _load(reports, "online_assessment.json")
    # the estimators against the bound on the constant-parameter scenarios, at the record's end
    eff = []
    for name, r in oa["scenarios"].items():
        b = (r.get("bound") or {}).get("slow_roll_error")
        if not b or "batch_rms" not in r:
            continue
        fe, ba = r["filter_end_rms"], r["batch_rms"]
        eff.append([f"`{name}`", f"{_pct(b['end']['load_rel'])} / {_pct(b['end']['viscosity_rel'])}",
                    f"{_pct(fe['load_rel_err'])} / {_pct(fe['viscosity_rel_err'])}",
                    f"{_pct(ba['load_rel_err'])} / {_pct(ba['viscosity_rel_err'])}",
                    f"{_pct(r['bound']['exact_runout']['end']['viscosity_rel'])}",
                    f"{_pct(b['long']['viscosity_rel'])} / {_pct(r['bound']['exact_runout']['long']['viscosity_rel'])}"])
    seeds = oa["metrics"].get("estimator_noise_seeds", 1)
    long_s = next((r["bound"]["long_s"] for r in oa["scenarios"].values() if r.get("bound")), None)
    efficiency = (_table(["scenario", "bound 1σ at the end, load / viscosity",
                     f"filter at the end, RMS over {seeds} draws", f"batch MAP fit, RMS over {seeds} draws",
                     "bound, viscosity, exact slow-roll vector",
                     f"bound, viscosity, a {_num(long_s, 'g')} s record: with / without the slow-roll error"], eff)
             + "\n\n") if eff else ""
    what = oa.get("bound_what_if") or {}
    if not what:
        return efficiency + "(no bound_what_if in reports/online_assessment.json)"
    names = list(what)
    variants = list(what[names[0]])
    rows = []
    for v in variants:
        first = what[names[0]][v]
        cells = [f"`{v}`", first["what"], f"{first['t_end']:g} s"]
        for n in names:
            r = what[n][v]
            cells.append(f"{_pct(r['at_eval']['load_rel'])} / {_pct(r['at_eval']['viscosity_rel'])}")
            cells.append(f"{_pct(r['end']['load_rel'])} / {_pct(r['end']['viscosity_rel'])}")
        rows.append(cells)
    head = ["record", "what", "length"]
    for n in names:
        head += [f"`{n}`: load / viscosity 1σ at {oa['eval_after_s']:g} s", f"`{n}`: at the record's end"]
    goals = oa["goals"]
    return (efficiency + _table(head, rows) + "\n\n" + f"Goals: load {_pct(goals['load_rel_err'])}, viscosity "
            f"{_pct(goals['viscosity_rel_err'])}; an efficient estimator's median error over noise draws is about "
            f"0.67 of the bound's 1σ (the median of |e| for e ~ N(0, σ²)).")


def render_online_assessment_summary(reports: Path) -> str:
    """One sentence for the README: what the estimator estimates and how well, beside the baseline."""
    oa = _load(reports, "online_assessment.json")
    sc = oa["scenarios"]
    normal = [n for n, r in sc.items() if not r.get("trip") and not r.get("blind_spot")]
    worst = oa["worst_scenario"]["load_rel_err"]
    good = [n for n in normal if n != worst]
    mx = lambda names, k: max(sc[n]["filter"][k] for n in names)   # noqa: E731
    base = lambda names: min(sc[n]["baseline"]["load_rel_err"] for n in names)   # noqa: E731
    m = oa["metrics"]
    seeds = m.get("estimator_noise_seeds", 1)
    return (f"From two probes and a speed signal the on-line estimator (the universal surrogate in a compiled "
            f"extended Kalman filter) tracks the static load, the imbalance and the oil's viscosity of a rotor simulated "
            f"with the reference solver within {_pct(mx(good, 'load_rel_err'))}, {_pct(mx(good, 'imbalance_rel_err'))} "
            f"and {_pct(mx(good, 'viscosity_rel_err'))} after 0.2 s (median over {seeds} noise draws) on {len(good)} "
            f"scenarios (" + ", ".join(f"`{n}`" for n in good) + "), where the plants' centreline-to-Sommerfeld "
            f"estimate misses the load by {_pct(base([n for n in good if sc[n]['dynamic']]))} or more; on `{worst}`, "
            f"whose film outweighs the rotor's inertia, it misses by {_pct(sc[worst]['filter']['load_rel_err'])} "
            f"(the baseline, told the right viscosity, {_pct(sc[worst]['baseline']['load_rel_err'])})"
            + (f", and there the record itself resolves the load to no better than "
               f"{_pct(oa['information_bound']['load']['bound_sd'])} (1σ, the Cramér-Rao bound of any unbiased "
               f"estimator)" if (oa.get("information_bound") or {}).get("load", {}).get("scenario") == worst else "")
            + ". "
            f"{m['estimator_us_per_sample']:.0f} µs per sample on one core; the mismatch and out-of-domain flags "
            + ("fire on the scenarios made to trip them and on no other" if m["estimator_false_flag_rate"] == 0.0
               and m["estimator_trip_flag_rate"] == 1.0 else
               f"catch {m['estimator_trip_flag_rate']:.0%} of the records made to trip them and flag "
               f"{_pct(m['estimator_false_flag_rate'])} of the others' samples")
            + " ([docs/online_assessment.md](docs/online_assessment.md)).")


RENDERERS: dict[str, Callable[[Path], str]] = {
    "train_time": render_train_time,
    "train_time_ci": render_train_time_ci,
    "train_time_full_scale": render_train_time_full_scale,
    "paper_bands": render_paper_bands,
    "paper_scale": render_paper_scale,
    "batch_speed": render_batch_speed,
    "controller_training": render_controller_training,
    "characteristics_timing": render_characteristics_timing,
    "characteristics": render_characteristics,
    "ensemble": render_ensemble,
    "raimondi_boyd": render_raimondi_boyd,
    "raimondi_boyd_no_feed": render_raimondi_boyd_no_feed,
    "lund_thomsen": render_lund_thomsen,
    "short_bearing": render_short_bearing,
    "reproduce_timing": render_reproduce_timing,
    "commands": render_commands,
    "headline": render_headline,
    "paper_scale_mechanism": render_paper_scale_mechanism,
    "universal_summary": render_universal_summary,
    "grading_study": render_grading_study,
    "ablation": render_ablation,
    "error_map": render_error_map,
    "runup": render_runup,
    "cavitation_rules": render_cavitation_rules,
    "cavitation_rules_summary": render_cavitation_rules_summary,
    "jfo_surrogate": render_jfo_surrogate,
    "universal": render_universal,
    "universal_kc": render_universal_kc,
    "surrogate_goals": render_surrogate_goals,
    "control": render_control,
    "figures": render_figures,
    "online_assessment": render_online_assessment,
    "online_assessment_summary": render_online_assessment_summary,
    "online_assessment_bound": render_online_assessment_bound,
}


def _renderer(name: str) -> Callable[[Path], str]:
    if name in RENDERERS:
        return RENDERERS[name]
    if name.startswith("bench_"):
        from fluidfilm.perf.benchmarking import render

        def bench(reports: Path) -> str:
            path = reports / "benchmarks" / f"{name[len('bench_'):]}.json"
            if not path.exists():
                raise FileNotFoundError(f"{path} is missing: run `make bench`")
            return render(path)

        return bench
    raise KeyError(f"README block {name!r} has no renderer; known: {sorted(RENDERERS)} and bench_<name>")


def fill(text: str, reports: Path, strict: bool = False) -> str:
    """``text`` with every generated block re-rendered; a block whose source is missing is kept
    as it is (or raises with ``strict``)."""

    def sub(m: re.Match) -> str:
        name = m.group("name")
        renderer = _renderer(name)
        try:
            body = renderer(reports)
        except (FileNotFoundError, KeyError) as exc:
            if strict:
                raise
            print(f"README block {name!r} left as it was: {exc}", file=sys.stderr)
            return m.group(0)
        return m.group(1) + body + m.group(4)

    return BLOCK.sub(sub, text)


def pages(readme: Path) -> list[Path]:
    """The pages with generated blocks: ``readme``, then docs/results.md, then the other docs/*.md beside it."""
    docs = readme.parent / "docs"
    results = docs / "results.md"
    if not results.exists():
        raise FileNotFoundError(f"{results} is missing: the results page holds every generated table")
    return [readme, results, *sorted(p for p in docs.glob("*.md") if p != results)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m fluidfilm.reporting.readme", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--readme", default="README.md", help="the README; docs/results.md and the other docs/*.md beside it are filled too")
    parser.add_argument("--reports", default="reports")
    parser.add_argument("--check", action="store_true", help="only compare; exit 1 when a page is stale")
    args = parser.parse_args(argv)
    stale = []
    for path in pages(Path(args.readme)):
        old = path.read_text()
        new = fill(old, Path(args.reports), strict=args.check)
        if new == old:
            continue
        if args.check:
            stale.append(str(path))
            continue
        tmp = path.with_suffix(".md.tmp")
        tmp.write_text(new)
        tmp.replace(path)
        print(f"{path}: generated blocks updated from {args.reports}/")
    if stale:
        print(f"stale: {', '.join(stale)}: run `python -m fluidfilm.reporting.readme`", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
