"""Linear stability of a rigid rotor in its bearings (Lund's criterion) and its nonlinear check.

A rigid, symmetric rotor whose mass per bearing is m, linearised about its
equilibrium:  m x'' + C x' + K x = 0.  In dimensionless form (time omega t,
Kbar = K c/W, Cbar = C c omega/W, Mbar = m c omega^2/W) the onset of
instability is a pure whirl x ~ exp(i gamma omega t) with (Lund 1966/1987)

    K0      = (Kxx Cyy + Kyy Cxx - Kxy Cyx - Kyx Cxy) / (Cxx + Cyy),
    gamma^2 = ((K0 - Kxx)(K0 - Kyy) - Kxy Kyx) / (Cxx Cyy - Cxy Cyx),
    Mbar_crit = K0 / gamma^2,

gamma the whirl frequency ratio; the rotor is stable for Mbar < Mbar_crit
(gamma^2 <= 0: stable for any mass).  ``eigen_growth`` computes the largest
real part of the eigenvalues of the same linear system as a second method.

Threshold speed: for a rotor of mass m carrying a load W, increasing speed
raises S (the journal lifts to the centre) and Mbar = m c omega^2 / W, until
Mbar = Mbar_crit(eps).  The Reynolds equation is linear in omega, so a force
model built for speed omega_ref describes speed omega exactly with the load
scaled by omega_ref/omega (same eps, same dimensionless K/C): this is how
the surrogates, trained at one speed, give a threshold speed too.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.optimize import brentq

from fluidfilm.characteristics import coefficients as coef
from fluidfilm.characteristics.static import check_magnitude, equilibrium, load_along_gravity, load_vector


def lund(d: dict) -> dict:
    """Whirl ratio gamma, K0 and the dimensionless critical mass of coefficients ``d`` (dimensionless).

    Parameters
    ----------
    d : dict
        Dimensionless coefficients ``Kxx, Kxy, Kyx, Kyy`` (K c/W) and ``Cxx, Cxy, Cyx, Cyy``
        (C c omega/W), with K_ij = -dF_i/dX_j (x = X1, y = X2, +X2 along gravity).

    Returns
    -------
    dict
        ``K0``, ``whirl_ratio`` gamma and ``critical_mass_bar`` (m c omega^2/W at the onset of
        whirl); gamma = 0 and an infinite critical mass where the rotor is stable for any mass.

    Examples
    --------
    >>> from fluidfilm.characteristics import lund
    >>> iso = {"Kxx": 1.0, "Kyy": 1.0, "Cxx": 2.0, "Cyy": 2.0, "Kxy": 0.0, "Kyx": 0.0, "Cxy": 0.0, "Cyx": 0.0}
    >>> lund(iso)                                   # no cross-coupling: stable for any mass
    {'K0': 1.0, 'whirl_ratio': 0.0, 'critical_mass_bar': inf}
    >>> {k: round(v, 3) for k, v in lund({**iso, "Kxy": 1.0, "Kyx": -1.0}).items()}   # gamma = q/c, M = k c^2/q^2
    {'K0': 1.0, 'whirl_ratio': 0.5, 'critical_mass_bar': 4.0}
    """
    kxx, kxy, kyx, kyy = d["Kxx"], d["Kxy"], d["Kyx"], d["Kyy"]
    cxx, cxy, cyx, cyy = d["Cxx"], d["Cxy"], d["Cyx"], d["Cyy"]
    k0 = (kxx * cyy + kyy * cxx - kxy * cyx - kyx * cxy) / (cxx + cyy)
    g2 = ((k0 - kxx) * (k0 - kyy) - kxy * kyx) / (cxx * cyy - cxy * cyx)
    if g2 <= 0.0:
        return {"K0": k0, "whirl_ratio": 0.0, "critical_mass_bar": math.inf}
    return {"K0": k0, "whirl_ratio": math.sqrt(g2), "critical_mass_bar": k0 / g2}


def eigen_growth(d: dict, mass_bar: float) -> tuple[float, float]:
    """(largest real part, its |imaginary part|) of Mbar x'' + Cbar x' + Kbar x = 0, in units of omega."""
    K = np.array([[d["Kxx"], d["Kxy"]], [d["Kyx"], d["Kyy"]]])
    C = np.array([[d["Cxx"], d["Cxy"]], [d["Cyx"], d["Cyy"]]])
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-K / mass_bar, -C / mass_bar]])
    lam = np.linalg.eigvals(A)
    k = int(np.argmax(lam.real))
    return float(lam[k].real), float(abs(lam[k].imag))


def operating_point(model, load, h_rel: float = 1e-4) -> dict:
    """Equilibrium under ``load``, its K/C and Lund's stability numbers.

    Parameters
    ----------
    model : force model
        Anything with ``.forces(X, V)`` and ``.bearing``.
    load : array_like, shape (2,)
        The load vector (W1, W2) [N]; ``load_along_gravity(W)`` for a magnitude along +X2.
    h_rel : float
        Relative finite-difference step where the model has no exact derivatives.

    Returns
    -------
    dict
        The equilibrium's keys (``eps``, ``X``, ``X1``, ``X2``, ``attitude_deg``, ``residual``,
        ``load_N`` = |W|, ``sommerfeld``), ``K`` [N/m] and ``C`` [N s/m] with K[i, j] = -dF_i/dX_j
        (``coefficients`` module), the dimensionless ``Kxx``..``Cyy`` (x = X1, y = X2) and Lund's
        ``K0``, ``whirl_ratio``, ``critical_mass_bar``.

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> op = operating_point(ReynoldsSolver(paper_bearing(), 30, 30), load_along_gravity(24.5))
    >>> round(op["eps"], 2), op["K"].shape
    (0.59, (2, 2))
    """
    eq = equilibrium(model, load)
    kc = coef.reference_coefficients(model, eq["X"], h_rel)
    d = coef.dimensionless(kc, model.bearing, eq["load_N"])
    return {"eps": eq["eps"], "attitude_deg": eq["attitude_deg"], "sommerfeld": eq["sommerfeld"],
            "load_N": eq["load_N"], "X": eq["X"], "X1": eq["X1"], "X2": eq["X2"], "residual": eq["residual"],
            "K": kc["K"], "C": kc["C"], **d, **lund(d)}


def threshold_speed(model, mass: float, load, speed_bracket=(0.05, 20.0), h_rel: float = 1e-4) -> dict:
    """Onset speed of oil whirl for a rigid rotor of ``mass`` [kg] per bearing carrying ``load``.

    Uses ``model`` only at its own speed (see module doc): at trial speed
    omega the load seen by the model is W omega_ref/omega.

    Parameters
    ----------
    model : force model
        Anything with ``.forces(X, V)`` and ``.bearing``.
    mass : float
        Rotor mass per bearing [kg].
    load : array_like, shape (2,)
        The load vector (W1, W2) [N] (``load_along_gravity(mass * g)`` for the weight alone).
    speed_bracket : (low, high)
        The speeds searched, in multiples of the model's speed, 0 < low < high.
    h_rel : float
        Relative finite-difference step where the model has no exact derivatives.

    Returns
    -------
    dict
        ``speed_rad_s``, ``speed_rpm``, and there ``eps``, ``whirl_ratio``,
        ``critical_mass_bar``, ``sommerfeld``; ``speed_rad_s`` is inf if the
        rotor is stable over the whole bracket.

    Raises
    ------
    ValueError
        For a bad mass, load or bracket (the message names it), or when the
        rotor is already unstable at the bracket's low end.

    Examples
    --------
    The paper's bearing under a 2.5 kg rotor whirls from about 6,700 rpm, at half the shaft speed:

    >>> from fluidfilm import ReynoldsSolver, load_along_gravity, paper_bearing
    >>> out = threshold_speed(ReynoldsSolver(paper_bearing(), 30, 30), mass=2.5, load=load_along_gravity(2.5 * 9.81))
    >>> round(out["speed_rpm"], -2), round(out["whirl_ratio"], 2)
    (6700.0, 0.49)
    """
    mass = check_magnitude("mass", mass, "kg")
    W = load_vector(load)
    w = float(np.hypot(*W))
    try:
        lo_f, hi_f = (float(v) for v in speed_bracket)
    except (TypeError, ValueError):
        raise ValueError(f"speed_bracket must be two numbers (low, high), got {speed_bracket!r}") from None
    if not (math.isfinite(lo_f) and math.isfinite(hi_f) and 0.0 < lo_f < hi_f):
        raise ValueError(f"speed_bracket must be (low, high) multiples of the model's speed with 0 < low < high, "
                         f"got {tuple(speed_bracket)!r}")
    b = model.bearing
    om_ref = b.omega
    c = b.clearance
    cache = {}

    def point(om):
        if om not in cache:
            cache[om] = operating_point(model, W * om_ref / om, h_rel)  # as (W om_ref) / om: same rounding as before
        return cache[om]

    def f(log_om):
        om = math.exp(log_om)
        pt = point(om)
        mbar = mass * c * om**2 / w
        mc = pt["critical_mass_bar"]
        return math.log(mbar / mc) if math.isfinite(mc) else -50.0

    lo, hi = math.log(lo_f * om_ref), math.log(hi_f * om_ref)
    flo, fhi = f(lo), f(hi)
    if fhi < 0.0:
        return {"speed_rad_s": math.inf, "speed_rpm": math.inf}
    if flo > 0.0:
        raise ValueError(f"rotor already unstable at {lo_f} x the model speed; widen speed_bracket")
    root = brentq(f, lo, hi, xtol=1e-10)
    om = math.exp(root)
    pt = point(om)
    return {"speed_rad_s": om, "speed_rpm": om * 60.0 / (2.0 * math.pi), "eps": pt["eps"],
            "whirl_ratio": pt["whirl_ratio"], "critical_mass_bar": pt["critical_mass_bar"],
            "sommerfeld": b.sommerfeld(w) * om / om_ref}


def at_speed(bearing, speed_rpm: float):
    """The same bearing at another shaft speed."""
    return dataclasses.replace(bearing, speed_rpm=float(speed_rpm))


def nonlinear_check(make_model, bearing, mass: float, speed_rpm: float, perturbation: float = 0.05,
                    n_periods: float = 400.0, dt_per_period: int = 200) -> dict:
    """Trajectory of the rigid rotor (``fluidfilm.simulate``, gravity load m g) from its equilibrium
    displaced by ``perturbation`` * c, at ``speed_rpm``.  ``make_model(bearing)`` builds the force model.

    Returns the deviation amplitude from the equilibrium in the first and last tenth of the run and
    their ratio (< 1: the orbit decays, > 1: it grows), and whether it ended in contact.
    """
    from fluidfilm.rotor import Rotor, simulate
    b = at_speed(bearing, speed_rpm)
    model = make_model(b)
    rotor = Rotor(mass=mass)
    load = mass * rotor.gravity
    eq = equilibrium(model, load_along_gravity(load))
    x_eq = eq["X"]
    c = b.clearance
    period = 2.0 * math.pi / b.omega
    dt = period / dt_per_period
    t_end = n_periods * period
    x0 = x_eq + perturbation * c * np.array([1.0, 0.0])
    traj = simulate(model, rotor, t_end=t_end, dt=dt, x0=x0, v0=np.zeros(2), record_every=10)
    dev = np.hypot(*(traj.x - x_eq).T) / c
    n = len(dev)
    first = float(dev[: max(n // 10, 1)].max())
    last = float(dev[-max(n // 10, 1):].max())
    return {"speed_rpm": speed_rpm, "eps_eq": eq["eps"], "amp_first": first, "amp_last": last,
            "ratio": last / first, "status": traj.status,
            "contact": not traj.completed, "t": traj.t[::5], "dev": dev[::5]}
