"""reports/metrics.json and reports/paper_comparison.md: our numbers beside the paper's (``experiments/report.py``;
the report itself is fluidfilm.reporting.report)."""
from __future__ import annotations

import json

from fluidfilm.reporting.report import load_inputs, write_report
from fluidfilm.workflow.entry import plain
from fluidfilm.workflow.tracking import Logged

OUTPUTS = {"report_dir": ["metrics.json", "paper_comparison.md"]}


def tracking_run(cfg):
    return "paper_comparison", None


def run(cfg) -> Logged:
    inputs = load_inputs(cfg.report_dir, cfg.models_dir, cfg.dataset_dir, list(cfg.models), cfg.active_model,
                         cfg.active_dataset_dir)
    metrics = write_report(inputs, cfg.report_dir, plain(cfg)["paper"], cfg.metrics.threshold_pct, cfg.active_model)
    print(json.dumps(metrics, indent=1))
    return Logged({k: float(v) for k, v in metrics.items() if isinstance(v, (int, float))},
                  [f"{cfg.report_dir}/paper_comparison.md"])
