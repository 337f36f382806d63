"""Writes notebooks/review.ipynb (kept as code so its source diffs cleanly): python notebooks/make_review.py"""
from pathlib import Path

import nbformat as nbf

cells = [
    nbf.v4.new_markdown_cell("# fluidfilm - review of the paper reproduction\n\n"
                             "Reads the DVC outputs (`reports/`) and the MLflow store. Run `make reproduce` first; "
                             "the environment variables below point it at another profile."),
    nbf.v4.new_code_cell("""import json, os
from pathlib import Path
import pandas as pd
from IPython.display import Image, Markdown, display

REPORT_DIR = Path(os.environ.get("FLUIDFILM_REPORT_DIR", "../reports"))
MLFLOW_URI = os.environ.get("FLUIDFILM_MLFLOW_URI", "sqlite:///../mlflow.db")
EXPERIMENT = os.environ.get("FLUIDFILM_EXPERIMENT", "fluidfilm")
pd.set_option("display.width", 200)"""),
    nbf.v4.new_markdown_cell("## Headline numbers (`reports/metrics.json`)"),
    nbf.v4.new_code_cell("""metrics = json.loads((REPORT_DIR / "metrics.json").read_text())
headline = ["train_time_single_s", "train_time_split_s", "train_time_reduction_pct", "speedup_force_eval",
            "speedup_trajectory_single", "speedup_trajectory_split", "speedup_trajectory_best"]
display(pd.Series({k: metrics[k] for k in headline}, name="ours").to_frame())"""),
    nbf.v4.new_markdown_cell("## Fig. 4: trajectory accuracy per case (% of clearance)"),
    nbf.v4.new_code_cell("""traj = pd.read_csv(REPORT_DIR / "trajectory_metrics.csv")
table = traj[traj.model != "reference"].pivot(index="case", columns="model", values=["rms_pct", "hausdorff_pct", "satisfactory"])
display(table)
fig4 = REPORT_DIR / "figures" / "fig4_comparison.png"
if fig4.exists():
    display(Image(filename=str(fig4)))"""),
    nbf.v4.new_markdown_cell("## Speed and training time"),
    nbf.v4.new_code_cell("""display(pd.read_csv(REPORT_DIR / "speed.csv"))
tt = json.loads((REPORT_DIR / "train_time.json").read_text())
display(pd.DataFrame(tt["runs"]))"""),
    nbf.v4.new_markdown_cell("## Training runs in MLflow"),
    nbf.v4.new_code_cell("""import mlflow
mlflow.set_tracking_uri(MLFLOW_URI)
runs = mlflow.search_runs(experiment_names=[EXPERIMENT])
cols = [c for c in ["tags.mlflow.runName", "metrics.test_rel_err_median", "metrics.test_rel_err_p99",
                    "metrics.train_time_s", "metrics.speedup_force_eval_vs_reference"] if c in runs.columns]
trained = runs.dropna(subset=["metrics.test_rel_err_median"]) if "metrics.test_rel_err_median" in runs else runs
display(trained[cols])
assert len(trained) > 0, "no training runs in MLflow"
"""),
    nbf.v4.new_markdown_cell("## Active conical bearing: DQN and MPC on the reference model (Fig. 5)"),
    nbf.v4.new_code_cell("""control = json.loads((REPORT_DIR / "control.json").read_text())
display(pd.DataFrame(control["controllers"]).T.drop(columns=["sleeve_schedule_m"]))
curve = runs.dropna(subset=["metrics.episode_return"]) if "metrics.episode_return" in runs else runs.iloc[:0]
if len(curve):
    run_id = curve.iloc[0]["run_id"]
    hist = mlflow.tracking.MlflowClient(MLFLOW_URI).get_metric_history(run_id, "episode_return")
    display(pd.DataFrame([(m.step, m.value) for m in hist], columns=["timestep", "episode_return"]).tail(10))
for panel in ("fig5_a_dqn", "fig5_b_none", "fig5_amplitude"):
    f = REPORT_DIR / "figures" / f"{panel}.png"
    if f.exists():
        display(Image(filename=str(f)))"""),
    nbf.v4.new_markdown_cell("## The full report"),
    nbf.v4.new_code_cell("""display(Markdown((REPORT_DIR / "paper_comparison.md").read_text()))"""),
]
nb = nbf.v4.new_notebook(cells=cells, metadata={"kernelspec": {"name": "python3", "display_name": "Python 3",
                                                                "language": "python"}})
nbf.write(nb, Path(__file__).with_name("review.ipynb"))
