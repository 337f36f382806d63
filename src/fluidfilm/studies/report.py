"""reports/metrics.json and reports/paper_comparison.md: our numbers beside the paper's (``experiments/report.py``;
the report itself is fluidfilm.reporting.report); and the curve of the paper's networks against data size,
reports/figures/paper_scale_curve.png, from every size on record: the pipeline's own (paper_scale) and the
committed runs beyond it (make paper-scale-curve, make paper-full-scale)."""
from __future__ import annotations

import json
from pathlib import Path

from fluidfilm.reporting.report import PAPER_SCALE_REPORTS, load_inputs, write_report
from fluidfilm.workflow.entry import plain
from fluidfilm.workflow.tracking import Logged

OUTPUTS = {"report_dir": ["metrics.json", "paper_comparison.md"], "figure_dir": ["paper_scale_curve.png"]}


def tracking_run(cfg):
    return "paper_comparison", None


def run(cfg) -> Logged:
    inputs = load_inputs(cfg.report_dir, cfg.models_dir, cfg.dataset_dir, list(cfg.models), cfg.active_model,
                         cfg.active_dataset_dir)
    metrics = write_report(inputs, cfg.report_dir, plain(cfg)["paper"], cfg.metrics.threshold_pct, cfg.active_model)
    print(json.dumps(metrics, indent=1))
    artifacts = [f"{cfg.report_dir}/paper_comparison.md"]
    if draw_paper_scale_curve(cfg.report_dir, Path(cfg.figure_dir) / "paper_scale_curve.png"):
        artifacts.append(f"{cfg.figure_dir}/paper_scale_curve.png")
    return Logged({k: float(v) for k, v in metrics.items() if isinstance(v, (int, float))}, artifacts)


def draw_paper_scale_curve(report_dir, figure) -> bool:
    """Draw the paper's networks against data size from every paper_scale report in ``report_dir`` (each size
    once, the pipeline's own report first); False, and nothing drawn, where no report holds a size."""
    from fluidfilm.studies.paper_scale import included_records, plot_curve

    records, labels = [], set()
    for r in included_records([Path(report_dir) / name for name in PAPER_SCALE_REPORTS]):
        if r["label"] not in labels:
            records.append(r)
            labels.add(r["label"])
    if not records:
        return False
    plot_curve(records, figure)
    return True
