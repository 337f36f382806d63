"""Grid-density study: force error against the converged grid and time per evaluation, to MLflow.

    python experiments/grid_sweep.py -m solver.n_theta=20,30,55,60,90 solver.n_z=20,30,55,60

The study is fluidfilm.studies.grid_sweep; config conf/grid_sweep.yaml.
"""
from fluidfilm.studies import grid_sweep
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(grid_sweep, "the grid-density sweep")
