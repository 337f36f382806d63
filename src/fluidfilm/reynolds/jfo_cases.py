"""Published mass-conserving (JFO / Elrod-Adams) test cases with exact solutions, run on this workspace's solver.

- ``ausas_squeeze``: Ausas, Jai & Buscaglia, "A mass-conserving algorithm for dynamical lubrication problems
  with cavitation", J. Tribol. 131(3) 031702 (2009), sec. 3: the oscillatory squeeze film
  2 d(phi h)/dt = d/dx(h^3 dp/dx) on 0 <= x <= 1 (dimensionless, no sliding), h(t) = 0.125 cos(4 pi t) + 0.375,
  p = p0 = 0.025 and full at both ends, full and at p0 at t = 0.  Before rupture the film is full with
  p = p0 + (h'/h^3)(x^2 - x); the film ruptures at mid-length at t = 0.2500792 (h' = 4 p0 h^3) and, while the
  cavity grows, its right edge is Sigma(t) = 1 - sqrt(p0 h^3 / h') (the paper's eqs. 19 and 21), largest,
  0.976992, at t = 0.3148259.  The paper's grid is 450 nodes with dt = 6.6e-4.

The problem runs on ``elrod_adams.ea_sweeps`` unchanged: x is the solver's axial coordinate, every theta
column alike (so nothing flows in theta) and K_omega = 0.
"""
from __future__ import annotations

import math

import numpy as np

from fluidfilm.reynolds import elrod_adams as ea

AUSAS_P0 = 0.025
#: the rupture time and the cavity's largest extent of the squeeze film (from the exact solution)
AUSAS_T_RUPTURE = 0.2500792
AUSAS_SIGMA_MAX = 0.976992


def ausas_gap(t: float) -> float:
    """h(t) of the squeeze film."""
    return 0.125 * math.cos(4.0 * math.pi * t) + 0.375


def ausas_exact(t: float, p0: float = AUSAS_P0) -> tuple[float, float]:
    """(p at x = 1/2 while the film is full, the cavity's right edge Sigma while it grows; NaN outside) at t."""
    h = ausas_gap(t)
    dh = -0.5 * math.pi * math.sin(4.0 * math.pi * t)
    sigma = 1.0 - math.sqrt(p0 * h**3 / dh) if dh > 4.0 * p0 * h**3 else math.nan
    return p0 - dh / (4.0 * h**3), sigma


def squeeze_params(nx: int, p0: float = AUSAS_P0) -> tuple[ea.EAParams, np.ndarray]:
    """The solver's parameters for the squeeze film on ``nx`` nodes over 0 <= x <= 1 (module doc), and x."""
    x = np.linspace(0.0, 1.0, nx)
    n = 8
    th = 2.0 * np.pi * np.arange(n) / n
    return ea.EAParams(n_theta=n, n_z=nx, sin_node=np.sin(th), cos_node=np.cos(th), sin_face=np.sin(th),
                       cos_face=np.cos(th), inv_c=1.0, inv_dtheta=1.0, inv_dtheta2=1.0,
                       inv_dzeta2=1.0 / (x[1] - x[0]) ** 2, k_omega=0.0, kvc=2.0, a_sin=np.zeros(n), a_cos=np.zeros(n),
                       w_z=np.zeros(nx), w_cell=1.0, p_supply=p0, p_end=p0, fixed=np.zeros(n, dtype=np.bool_),
                       sor_omega=1.9, tol=1e-10, tol_commit=1e-10, tol_steady=1e-10, max_sweeps=200_000, coarse_every=3,
                       mode_shape=np.sin(np.pi * x), rule=ea.RULE_JFO, mu=1.0, radius=1.0, clearance=1.0,
                       dz=float(x[1] - x[0])), x


def ausas_squeeze(nx: int = 151, dt: float = 6.6e-4, t_end: float = 0.3149, p0: float = AUSAS_P0) -> np.ndarray:
    """Rows (t, Sigma: the largest x with phi < 1 (NaN: no cavity), p at x = 1/2) after every time step."""
    ep, x = squeeze_params(nx, p0)
    n = ep.n_theta
    p = np.full((n, nx), p0)
    th = np.ones((n, nx))
    ea.reset_fields(ep, p, th)
    content = np.empty_like(p)
    hh = np.empty(n)
    hf = np.empty(n)
    t = 0.0
    out = []
    while t < t_end:
        h_old = ausas_gap(t)
        t += dt
        hh[:] = ausas_gap(t)
        hf[:] = hh
        content[:] = th * h_old
        _, status = ea.ea_sweeps(ep, 0.0, hh, hf, 1.0 / dt, content, p, th, 1e-10, 200_000)
        if status != ea.EA_CONVERGED:
            raise RuntimeError(f"the squeeze film's solve did not converge at t={t:.6g}")
        cav = np.flatnonzero(th[0] < 1.0)
        out.append((t, x[cav.max()] if cav.size else math.nan, p[0, nx // 2]))
    return np.array(out)


def ausas_errors(run: np.ndarray, times=(0.26, 0.28, 0.30)) -> dict:
    """Percent errors of a run against the exact solution: the cavity edge at ``times`` and at its largest, and
    the full film's mid-length pressure at t = 1/16, 1/8, 3/16."""
    t = run[:, 0]
    out = {}
    for tq in times:
        k = int(np.argmin(abs(t - tq)))
        out[f"sigma_t{tq:g}_pct"] = 100.0 * abs(run[k, 1] / ausas_exact(t[k])[1] - 1.0)
    out["sigma_max_pct"] = 100.0 * abs(np.nanmax(run[:, 1]) / AUSAS_SIGMA_MAX - 1.0)
    for tq in (0.0625, 0.125, 0.1875):
        k = int(np.argmin(abs(t - tq)))
        out[f"p_mid_t{tq:g}_pct"] = 100.0 * abs(run[k, 2] / ausas_exact(t[k])[0] - 1.0)
    return out
