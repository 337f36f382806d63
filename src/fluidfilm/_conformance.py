"""Static proof that every model of the library implements the force-model contract.

Never imported at run time; ``mypy`` (``make lint``) checks these assignments: a model that
misses a member of ``ForceModel`` / ``AdjustableForceModel`` / ``BatchSettable`` / ``BatchForceModel`` /
``LinearPressureModel`` or gets a signature wrong fails it.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from fluidfilm.surrogate.ensemble import EnsembleForceModel, HybridForceModel
    from fluidfilm.core.force_model import (AdjustableForceModel, BatchForceModel, BatchSettable, ForceModel,
                                            LinearPressureModel, SpeedScalableModel)
    from fluidfilm.reynolds import ConicalReynoldsSolver, GradedReynoldsModel, ReynoldsSolver
    from fluidfilm.reynolds.feed import GroovedReynoldsSolver
    from fluidfilm.reynolds.sparse_reference import SparseReferenceModel
    from fluidfilm.rotor.linear import LinearBearing
    from fluidfilm.surrogate.inference import SurrogateForceModel

    def _force_models(a: ReynoldsSolver, b: GradedReynoldsModel, c: ConicalReynoldsSolver,
                      d: SurrogateForceModel, e: LinearBearing, f: SparseReferenceModel,
                      g: GroovedReynoldsSolver, h: EnsembleForceModel, i: HybridForceModel) -> list[ForceModel]:
        return [a, b, c, d, e, f, g, h, i]

    def _adjustable_models(b: GradedReynoldsModel, c: ConicalReynoldsSolver,
                           d: SurrogateForceModel) -> list[AdjustableForceModel]:
        return [b, c, d]

    def _batch_settable_models(d: SurrogateForceModel) -> list[BatchSettable]:
        return [d]

    def _batch_force_models(a: ReynoldsSolver, b: GradedReynoldsModel, d: SurrogateForceModel,
                            e: LinearBearing) -> list[BatchForceModel]:
        return [a, b, d, e]

    def _speed_scalable_models(a: ReynoldsSolver, d: SurrogateForceModel, e: LinearBearing) -> list[SpeedScalableModel]:
        return [a, d, e]

    def _linear_pressure_models(a: ReynoldsSolver, c: ConicalReynoldsSolver) -> list[LinearPressureModel]:
        return [a, c]
