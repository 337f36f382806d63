"""Static proof that every model of the library implements the force-model contract.

Never imported at run time; ``mypy`` (``make lint``) checks these assignments: a model that
misses a member of ``ForceModel`` / ``AdjustableForceModel`` / ``BatchSettable`` / ``BatchForceModel`` /
``LinearPressureModel`` / ``PrecisionKernelModel`` / ``SpeedScalableModel`` / ``TransientFilmModel`` or gets a signature wrong
fails it.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from fluidfilm.surrogate.ensemble import EnsembleForceModel, HybridForceModel
    from fluidfilm.core.force_model import (AdjustableForceModel, BatchForceModel, BatchSettable, ForceModel,
                                            LinearPressureModel, PrecisionKernelModel, SpeedScalableModel,
                                            TransientFilmModel)
    from fluidfilm.reynolds import ConicalReynoldsSolver, GradedReynoldsModel, ReynoldsSolver
    from fluidfilm.reynolds.elrod_adams import ElrodAdamsSolver
    from fluidfilm.reynolds.feed import GroovedReynoldsSolver
    from fluidfilm.reynolds.sparse_reference import SparseReferenceModel
    from fluidfilm.rotor.linear import LinearBearing
    from fluidfilm.surrogate.model import SurrogateForceModel
    from fluidfilm.surrogate.universal import UniversalBearingModel

    def _force_models(a: ReynoldsSolver, b: GradedReynoldsModel, c: ConicalReynoldsSolver,
                      d: SurrogateForceModel, e: LinearBearing, f: SparseReferenceModel,
                      g: GroovedReynoldsSolver, h: EnsembleForceModel, i: HybridForceModel,
                      u: UniversalBearingModel, j: ElrodAdamsSolver) -> list[ForceModel]:
        return [a, b, c, d, e, f, g, h, i, u, j]

    def _transient_film_models(j: ElrodAdamsSolver) -> list[TransientFilmModel]:
        return [j]

    def _adjustable_models(b: GradedReynoldsModel, c: ConicalReynoldsSolver,
                           d: SurrogateForceModel) -> list[AdjustableForceModel]:
        return [b, c, d]

    def _batch_settable_models(d: SurrogateForceModel) -> list[BatchSettable]:
        return [d]

    def _batch_force_models(a: ReynoldsSolver, b: GradedReynoldsModel, d: SurrogateForceModel,
                            e: LinearBearing, u: UniversalBearingModel) -> list[BatchForceModel]:
        return [a, b, d, e, u]

    def _speed_scalable_models(a: ReynoldsSolver, d: SurrogateForceModel, e: LinearBearing,
                               u: UniversalBearingModel, j: ElrodAdamsSolver) -> list[SpeedScalableModel]:
        return [a, d, e, u, j]

    def _precision_kernel_models(d: SurrogateForceModel, u: UniversalBearingModel) -> list[PrecisionKernelModel]:
        return [d, u]

    def _linear_pressure_models(a: ReynoldsSolver, c: ConicalReynoldsSolver) -> list[LinearPressureModel]:
        return [a, c]
