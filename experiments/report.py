"""reports/metrics.json and reports/paper_comparison.md: our numbers beside the paper's.

    python experiments/report.py

The report itself is fluidfilm.reporting.report; this entry point composes the config and calls it.
"""
import json

import hydra
from omegaconf import DictConfig, OmegaConf

from fluidfilm import io
from fluidfilm.workflow import tracking
from fluidfilm.workflow.config_check import check_config
from fluidfilm.reporting.report import load_inputs, write_report


@hydra.main(config_path="../conf", config_name="report", version_base="1.3")
def main(cfg: DictConfig) -> None:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    inputs = load_inputs(cfg.report_dir, cfg.models_dir, cfg.dataset_dir, list(cfg.models), cfg.active_model,
                         cfg.active_dataset_dir)
    metrics = write_report(inputs, cfg.report_dir, OmegaConf.to_container(cfg.paper), cfg.metrics.threshold_pct,
                           cfg.active_model)
    with tracking.run(cfg.tracking, "paper_comparison", OmegaConf.to_container(cfg, resolve=True)):
        tracking.log_metrics({k: float(v) for k, v in metrics.items() if isinstance(v, (int, float))})
        tracking.log_artifact(f"{cfg.report_dir}/paper_comparison.md")
    print(json.dumps(metrics, indent=1))


if __name__ == "__main__":
    io.run_interruptible(main, "the report", "run the same command again")
