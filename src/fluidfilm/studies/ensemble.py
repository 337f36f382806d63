"""The best surrogate's seeds, their ensemble and the hybrid with the reference, through the seven cases
(``experiments/ensemble.py``; the study's parts are in fluidfilm.studies.compare)."""
from __future__ import annotations

from pathlib import Path

from fluidfilm import io, load_surrogate
from fluidfilm.data import load_test_set
from fluidfilm.perf.benchmarking import machine
from fluidfilm.studies.compare import ensemble_study
from fluidfilm.studies.plots import plot_ensemble
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
from fluidfilm.workflow.tracking import Logged

INPUTS = ("members", "testset_dir")
OUTPUTS = {"report_dir": ["ensemble_cases.csv", "ensemble.json"], "figure_dir": ["ensemble.png"]}


def tracking_run(cfg):
    return "ensemble", None


def run(cfg) -> Logged:
    reference = reference_from_cfg(bearing_from_cfg(cfg.bearing), cfg.reference)
    members = {name: load_surrogate(path) for name, path in cfg.members.items()}
    cases = {k: cfg.cases[k] for k in sorted(cfg.cases)}
    table, summary = ensemble_study(reference, members, cfg.rotor, cases, cfg.integrator, cfg.metrics.threshold_pct,
                                    cfg.rel_tol, list(cfg.hybrid_rel_tols), cfg.floor_N, cfg.timing_repeats,
                                    held_out=load_test_set(cfg.testset_dir))
    summary["machine"] = machine()
    report = Path(cfg.report_dir)
    io.write_csv(report / "ensemble_cases.csv", table)
    io.save_figure(plot_ensemble(table, cfg.metrics.threshold_pct), Path(cfg.figure_dir) / "ensemble.png", dpi=120)
    io.write_json(report / "ensemble.json", summary)
    cal = summary["flag_calibration"]
    print(f"flag on the held-out set ({cal['n_states']} states): {100 * cal['flagged_share']:.1f} % flagged, "
          f"{100 * cal['wrong_share']:.1f} % with the ensemble's error above rel_tol, recall {cal['recall']}, "
          f"precision {cal['precision']}")
    for name, m in summary["models"].items():
        share = f", flagged {100 * m['flagged_share_mean']:.2f} % of evaluations" if "flagged_share_mean" in m else ""
        print(f"{name}: satisfactory in {m['n_satisfactory']}/{summary['n_cases']} ({m['satisfactory_cases'] or '-'}), "
              f"worst orbit RMS {m['orbit_rms_pct_max']:.2f} % of c, {m['speedup_trajectory']:.1f}x the reference{share}")
    metrics = {f"{k}_{name}": float(v) for name, m in summary["models"].items() for k, v in m.items()
               if not isinstance(v, str)}
    return Logged(metrics, [report / "ensemble.json", Path(cfg.figure_dir) / "ensemble.png"])
