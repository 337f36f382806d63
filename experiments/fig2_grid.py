"""Fig. 2: film reaction against rotor position for the 30x30 and 60x60 grids.

    python experiments/fig2_grid.py            # writes reports/figures/fig2_grid.{png,csv}

The study is fluidfilm.studies.fig2_grid; config conf/fig2_grid.yaml.
"""
from fluidfilm.studies import fig2_grid
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(fig2_grid, "the Fig. 2 grid study")
