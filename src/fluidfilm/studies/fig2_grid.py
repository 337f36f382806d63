"""Fig. 2: film reaction against rotor position for the 30x30 and 60x60 grids (``experiments/fig2_grid.py``)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from fluidfilm import io
from fluidfilm.studies.plots import grid_comparison, plot_grid_comparison
from fluidfilm.workflow.config import bearing_from_cfg, solver_from_cfg
from fluidfilm.workflow.tracking import Logged

OUTPUTS = {"out_dir": ["fig2_grid.csv", "fig2_grid.png"]}


def tracking_run(cfg):
    return "fig2_grid", None


def run(cfg):  # unannotated: models built from a config are typed as unions; the library calls are checked
    bearing = bearing_from_cfg(cfg.bearing)
    solvers = {name: solver_from_cfg(bearing, cfg[name]) for name in ("coarse", "dense", "converged")}
    eps = np.linspace(cfg.eps_min, cfg.eps_max, cfg.n_eps)
    frame = grid_comparison(solvers, eps, cfg.angle_deg, reference="converged")
    # the table and the figure from values rounded below the solver's spread across machines: the same bytes
    # from any machine (docs/workflow.md, "Stage outputs across machines"); the logged summary is unrounded
    table = io.round_to_scale(frame, [c for c in frame.columns if c != "eps"])
    labels = {k: f"{s.n_theta}x{s.n_z}" for k, s in solvers.items()}
    out = Path(cfg.out_dir)
    with io.output_set() as outputs:
        outputs.write_csv(out / "fig2_grid.csv", table)
        outputs.save_figure(plot_grid_comparison(table, ["coarse", "dense"], labels, "converged"),
                            out / "fig2_grid.png", dpi=130)
    summary = {f"err_{k}_pct_eps_{e:g}": float(np.interp(e, frame["eps"], frame[f"err_{k}_pct"]))
               for k in ("coarse", "dense") for e in (0.5, 0.9, 0.95, 0.98)}
    print(table.iloc[:: max(1, len(table) // 10)].to_string(index=False))
    return Logged(summary, [out / "fig2_grid.png"])
