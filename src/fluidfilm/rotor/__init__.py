"""Point-mass rotor in a fluid film bearing (the paper's eq. 4), its integrator and orbit metrics.

- ``model``        ``Rotor``: what one bearing carries (mass, imbalance, external load);
                   ``SpeedSchedule``: the shaft speed against time (run-ups)
- ``integrate``    ``simulate``: one compiled RK4 loop for every force model
- ``film_memory``  the loop for a film with memory (mass-conserving cavitation): the film content carried
                   between RK4 steps (``simulate`` dispatches to it)
- ``linear``       ``LinearBearing``: an isotropic spring-damper force model (analytic checks)
- ``metrics``      settled-orbit statistics and model-vs-reference distances

The static equilibrium (``equilibrium``, ``equilibrium_locus``, ``load_along_gravity``) lives in
``characteristics.static``, above the rotor (``fluidfilm.equilibrium`` is that one function).
"""
from fluidfilm.rotor.integrate import Trajectory, simulate
from fluidfilm.rotor.linear import LinearBearing
from fluidfilm.rotor.metrics import compare_orbits, orbit_stats
from fluidfilm.rotor.model import Rotor, SpeedSchedule

__all__ = ["Rotor", "SpeedSchedule", "simulate", "Trajectory", "LinearBearing", "orbit_stats", "compare_orbits"]
