"""Bit-for-bit evidence for refactors of the active-set solver (``reynolds.kernels.active_set_field``, issue #50).

Fields and forces of the plain and the grooved bearing through every path that reaches the solver: the
solver's ``forces`` (Swift-Stieber, supply pressure, odd and even interior rows), the grooved solver's
``forces`` (warm-started from the last cavitation set), ``grooved_field`` cold and warm, and the kernel
itself with and without the axial sine transform, with and without the projection; and the solve counts.

    python benchmarks/active_set_bitwise.py save  OUT.npz   # before a change
    python benchmarks/active_set_bitwise.py check OUT.npz   # after it: every array equal (np.array_equal)
"""
from __future__ import annotations

import math
import sys

import numpy as np

from fluidfilm.perf.benchmarking import save_or_check

C = 120e-6


def _states(count, seed, eps_max=0.9):
    rng = np.random.default_rng(seed)
    out = []
    for k in range(count):
        e, a = rng.uniform(0.05, eps_max), rng.uniform(0.0, 2.0 * math.pi)
        v = rng.uniform(-0.3, 0.3, 2) if k % 3 else np.zeros(2)
        out.append((np.array([e * C * math.sin(a), e * C * math.cos(a)]), v))
    return out


def _kernel_field(params, n, nz, x, v, fixed, project, transform):
    """As tests/reynolds/test_active_set.py's fields_both_ways: the linear field, clipped, the held columns set."""
    from fluidfilm.reynolds import kernels

    p = np.empty((n, params.full_basis.shape[0] + 2))
    kernels.linear_field(params, x[0], x[1], v[0], v[1], params.full_basis, params.p_supply, p)
    if project:
        np.maximum(p, 0.0, out=p)
    p[fixed] = params.p_supply
    if hasattr(kernels, "ActiveSetOptions"):   # the packed parameter list
        it = kernels.active_set_field(params, (x[0], x[1], v[0], v[1]), p, fixed,
                                      kernels.ActiveSetOptions(project, 10_000, transform))
    else:
        it = kernels.active_set_field(params, x[0], x[1], v[0], v[1], p, fixed, project, 10_000, transform)
    return p, it


def evaluate() -> dict[str, np.ndarray]:
    from fluidfilm import JournalBearing, ReynoldsSolver, bearing_from_dict, paper_bearing
    from fluidfilm.reynolds.feed import GroovedReynoldsSolver, grooved_field

    res = {}
    jb = paper_bearing()
    for n_theta, n_z in ((30, 30), (24, 15), (60, 31)):
        s = ReynoldsSolver(jb, n_theta, n_z, cavitation="swift-stieber")
        X = np.array([x for x, _ in _states(10, n_z, 0.95)])
        V = np.array([v for _, v in _states(10, n_z, 0.95)])
        res[f"plain_{n_theta}x{n_z}/forces"] = s.forces(X, V)
        no_groove = np.zeros(n_theta, dtype=bool)
        for k, (x, v) in enumerate(_states(4, n_z + 1, 0.95)):
            for project in (True, False):
                for transform in (True, False):
                    p, it = _kernel_field(s.params, n_theta, n_z, x, v, no_groove, project, transform)
                    res[f"plain_{n_theta}x{n_z}/field{k}_{project}_{transform}"] = p
                    res[f"plain_{n_theta}x{n_z}/solves{k}_{project}_{transform}"] = np.array([it])
    sup = ReynoldsSolver(bearing_from_dict({**jb.to_dict(), "supply_pressure": 2e4}), 16, 17)
    X = np.array([x for x, _ in _states(8, 3)])
    V = np.array([v for _, v in _states(8, 3)])
    res["supply/forces"] = sup.forces(X, V)
    b = JournalBearing(length=0.05, diameter=0.1, clearance=C, speed_rpm=3000.0, viscosity=0.02)
    for cav in ("swift-stieber", "none"):
        g = GroovedReynoldsSolver(b, 72, 31, cavitation=cav, groove_angle=math.pi / 2, n_grooves=2,
                                  groove_width=math.radians(20.0))
        seq = _states(8, 9)
        res[f"grooved_{cav}/forces_sequence"] = np.array([g.forces(x, v) for x, v in seq])
        for k, (x, v) in enumerate(seq[:3]):
            for transform in (True, False):
                p, it = _kernel_field(g.gparams.film, 72, 31, g.to_groove_frame(x), g.to_groove_frame(v),
                                      g.gparams.fixed, cav == "swift-stieber", transform)
                res[f"grooved_{cav}/field{k}_{transform}"] = p
                res[f"grooved_{cav}/solves{k}_{transform}"] = np.array([it])
    g = GroovedReynoldsSolver(b, 96, 21, groove_angle=math.pi / 2, n_grooves=2, groove_width=math.radians(20.0))
    x0 = np.array([0.2 * C, 0.6 * C])
    p = np.empty((96, 21))
    g.forces(x0, np.zeros(2))   # (allocates the solver's warm-start set, whose shape the kernel's takes)
    warm = np.zeros_like(g._warm)
    res["warm/cold_solves"] = np.array([grooved_field(g.gparams, *x0, 0.0, 0.0, p, warm, False)])
    res["warm/cold_field"] = p.copy()
    res["warm/free_set"] = warm.copy()
    res["warm/warm_solves"] = np.array([grooved_field(g.gparams, *(x0 + [1e-4 * C, 0.0]), 0.0, 0.0, p, warm, True)])
    res["warm/warm_field"] = p.copy()
    return res


def main(argv: list[str]) -> int:
    return save_or_check(argv, __doc__, evaluate)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
