"""What every part of the library shares: the bearing, the force-model contract and the journal states.

- ``bearing``      ``JournalBearing``, ``ConicalBearing``: geometry, lubricant, speed (SI units)
- ``force_model``  the protocols a force model implements (``ForceModel``, ``AdjustableForceModel``, ...)
                   and its validity domain
- ``states``       shapes and validation of journal positions X [m] and velocities V [m/s]
"""
from fluidfilm.core.bearing import ConicalBearing, JournalBearing, bearing_from_dict, paper_bearing
from fluidfilm.core.force_model import (WHOLE_FILM, AdjustableForceModel, BatchForceModel, BatchSettable,
                                        ForceModel, LinearPressureModel, PrecisionKernelModel, ReferenceModel,
                                        SpeedScalableModel, TransientFilmModel, ValidityDomain,
                                        as_adjustable)
from fluidfilm.core.states import V_MAX_PHYSICAL, as_state_pairs, check_states

__all__ = ["JournalBearing", "ConicalBearing", "bearing_from_dict", "paper_bearing", "ForceModel",
           "AdjustableForceModel", "BatchForceModel", "BatchSettable", "LinearPressureModel", "PrecisionKernelModel",
           "ReferenceModel",
           "SpeedScalableModel", "TransientFilmModel", "ValidityDomain", "WHOLE_FILM", "as_adjustable", "V_MAX_PHYSICAL", "as_state_pairs",
           "check_states"]
