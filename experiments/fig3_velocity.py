"""Fig. 3: film reaction against rotor velocity at several eccentricities.

    python experiments/fig3_velocity.py        # writes reports/figures/fig3_velocity{.png,.csv,_radial.csv,_tangential.csv}

The study is fluidfilm.studies.fig3_velocity; config conf/fig3_velocity.yaml.
"""
from fluidfilm.studies import fig3_velocity
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(fig3_velocity, "the Fig. 3 velocity study")
