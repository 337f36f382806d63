"""Every kind of force model the workspace has, built small (random weights where weights do not matter)."""
from __future__ import annotations

import numpy as np
import yaml

from fluidfilm import GradedReynoldsModel, ReynoldsSolver, paper_bearing
from fluidfilm.core.bearing import bearing_from_dict
from fluidfilm.reynolds import ConicalReynoldsSolver
from fluidfilm.surrogate import Scaling, SurrogateForceModel

from .conftest import ROOT

C = 120e-6
DOMAIN = [[0.0, 0.5, 0.2], [0.5, 1.0, 0.5]]  # [eps_low, eps_high, v_max] as the quick dataset


def _net(n_in, width, depth, n_out, rng):
    sizes = [n_in] + [width] * depth + [n_out]
    return [(0.3 * rng.standard_normal((b, a)), 0.1 * rng.standard_normal(b)) for a, b in zip(sizes, sizes[1:])]


def _scaling(kind, frame, n_in, bearing, extras=(), sleeve_gain=0.0):
    return Scaling(kind, bearing.clearance, bearing.omega, bearing.force_scale, 1.5, np.zeros(n_in), np.ones(n_in),
                   np.zeros(2), np.ones(2), frame, extras, sleeve_gain)


def single(seed=0):
    """The paper's single network: 1 x 50 tanh, standard scaling, Cartesian inputs."""
    b = paper_bearing()
    return SurrogateForceModel(b, [_net(4, 50, 1, 2, np.random.default_rng(seed))],
                               [_scaling("standard", "cartesian", 4, b)], "tanh", domain=DOMAIN, eps_max=0.97,
                               name="single")


def paper_split(seed=0):
    """The paper's split model: three networks by eccentricity, hard switch."""
    b = paper_bearing()
    rng = np.random.default_rng(seed)
    return SurrogateForceModel(b, [_net(4, 50, 1, 2, rng) for _ in range(3)],
                               [_scaling("standard", "cartesian", 4, b)] * 3, "tanh", boundaries=[0.5, 0.9],
                               domain=DOMAIN, eps_max=0.97, name="paper_split")


def best(seed=0):
    """The best model's structure: five blended ReLU regions, physics scaling in the journal's frame."""
    b = paper_bearing()
    rng = np.random.default_rng(seed)
    return SurrogateForceModel(b, [_net(3, 64, 1, 2, rng) for _ in range(5)],
                               [_scaling("physics", "polar", 3, b)] * 5, "relu", boundaries=[0.3, 0.6, 0.8, 0.9],
                               blend_width=0.04, domain=DOMAIN, eps_max=0.97, name="best")


def conical_bearing():
    return bearing_from_dict(yaml.safe_load((ROOT / "conf" / "bearing" / "conical.yaml").read_text()))


def conical_surrogate(seed=0):
    """The active bearing's surrogate: the sleeve displacement as a fifth input."""
    b = conical_bearing()
    return SurrogateForceModel(b, [_net(5, 32, 2, 2, np.random.default_rng(seed))],
                               [_scaling("standard", "cartesian", 5, b, extras=("S",))], "tanh", domain=DOMAIN,
                               eps_max=0.97, name="conical_surrogate")


def all_models():
    """name -> (model, is a surrogate with a training domain)."""
    b = paper_bearing()
    return {
        "reference_30x30": (ReynoldsSolver(b, 30, 30), False),
        "reference_graded": (GradedReynoldsModel(b), False),
        "reference_conical": (ConicalReynoldsSolver(conical_bearing(), 30, 30), False),
        "single": (single(), True),
        "paper_split": (paper_split(), True),
        "best": (best(), True),
        "conical_surrogate": (conical_surrogate(), True),
    }
