"""On-line assessment from measured orbits: journal position, static load, imbalance and oil viscosity.

| module | responsibility |
|---|---|
| ``ekf`` | the compiled extended Kalman filter (numba) over the augmented state and its RTS smoother |
| ``estimator`` | ``estimate(frame, model, mass, ...)``: runout removal, shaft angle, start, flags, bands |
| ``baseline`` | the plants' baseline: centreline position -> static (Sommerfeld) curve at an assumed viscosity |
| ``plant`` | synthetic plant records: the rotor in the reference solver (steady speed or a profile), probes with noise, runout, quantisation |
| ``bound`` | what a record holds: the Cramér-Rao bound of load, imbalance and viscosity, and the batch MAP fit that attains it |
| ``probes`` | reading and checking a recorded probe file (CSV or Parquet), the bearing's description |

See docs/online_assessment.md.
"""
from fluidfilm.estimation.estimator import EstimatorSettings, Estimates, estimate

__all__ = ["EstimatorSettings", "Estimates", "estimate"]
