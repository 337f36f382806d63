"""Build library objects from plain mappings (Hydra/OmegaConf nodes, dicts, YAML).

The library imports no Hydra; entry points pass their config nodes here.
"""
from __future__ import annotations

from collections.abc import Mapping

from fluidfilm.core.bearing import JournalBearing, bearing_from_dict
from fluidfilm.reynolds import ConicalReynoldsSolver, GradedReynoldsModel, ReynoldsSolver, make_solver


def bearing_from_cfg(cfg: Mapping):
    """A ``JournalBearing``, or a ``ConicalBearing`` for ``kind: conical``."""
    return bearing_from_dict(cfg)


def solver_from_cfg(bearing, cfg: Mapping) -> ReynoldsSolver | ConicalReynoldsSolver:
    return make_solver(bearing, cfg["n_theta"], cfg["n_z"], cavitation=cfg.get("cavitation", "gumbel"))


def reference_from_cfg(bearing: JournalBearing, cfg: Mapping) -> GradedReynoldsModel:
    """The paper's graded reference model (coarse grid below eps_threshold, dense above)."""
    return GradedReynoldsModel(bearing, coarse=tuple(cfg["coarse"]), dense=tuple(cfg["dense"]),
                               eps_threshold=cfg["eps_threshold"],
                               cavitation=cfg.get("cavitation", "gumbel"))
