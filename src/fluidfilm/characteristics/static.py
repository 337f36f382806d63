"""Static characteristics: equilibrium under load, and eps, attitude, friction and flows against Sommerfeld.

``film_solver(bearing, cavitation, feed, n_theta, n_z)`` builds the reference
model for a feed assumption:

- ``feed="none"``: the film is bounded by cavitation all the way round
  (``ReynoldsSolver``; the paper's model);
- ``feed="max-film"``: an axial groove at the supply pressure on the line of
  maximum film thickness of the journal position analysed (Raimondi & Boyd's
  assumption).  For a table at eccentricity eps the journal is placed on +X2,
  so the groove sits at theta = pi;
- ``feed=<angle in degrees>``: a groove fixed in the bearing at that angle.

``static_point`` gives one row of the table; ``sommerfeld_sweep`` the table;
``equilibrium`` the journal position under a load vector for any force
model (reference or surrogate), started from the short-bearing solution.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.optimize import brentq, least_squares

from fluidfilm.core.force_model import ForceModel
from fluidfilm.reynolds.feed import GroovedReynoldsSolver
from fluidfilm.reynolds.solver import ReynoldsSolver
from fluidfilm.characteristics import shortbearing
from fluidfilm.characteristics.film import film_flows_and_friction, raimondi_boyd_variables

FEEDS = ("none", "max-film")


def film_solver(bearing, cavitation: str = "gumbel", feed="none", n_theta: int = 90, n_z: int = 41):
    """The reference film model for a feed assumption (see module doc).

    Parameters
    ----------
    bearing : JournalBearing
        The bearing.
    cavitation : str, default "gumbel"
        Cavitation rule (see ``ReynoldsSolver``).
    feed : {"none", "max-film"} or float, default "none"
        No groove, a groove at the supply pressure on the line of maximum film thickness
        (theta = pi for a journal on +X2), or a groove fixed at this angle [deg] from +X2
        towards +X1.
    n_theta : int, default 90
        Circumferential nodes (even where there is a groove).
    n_z : int, default 41
        Axial nodes.

    Returns
    -------
    ReynoldsSolver or GroovedReynoldsSolver

    Raises
    ------
    ValueError
        For an unknown ``feed`` or an odd ``n_theta`` with a groove (both named).

    Examples
    --------
    >>> from fluidfilm import paper_bearing
    >>> from fluidfilm.characteristics import film_solver
    >>> film_solver(paper_bearing(), n_theta=24, n_z=12)
    ReynoldsSolver(24x12, cavitation='gumbel')
    >>> type(film_solver(paper_bearing(), feed="max-film", n_theta=24, n_z=12)).__name__
    'GroovedReynoldsSolver'
    >>> film_solver(paper_bearing(), feed="top")
    Traceback (most recent call last):
    ...
    ValueError: feed must be one of ('none', 'max-film') or a groove angle in degrees, got 'top'
    """
    if feed == "none":
        return ReynoldsSolver(bearing, n_theta, n_z, cavitation=cavitation)
    if feed == "max-film":
        angle = math.pi
    else:
        try:
            angle = math.radians(float(feed))
        except (TypeError, ValueError):
            raise ValueError(f"feed must be one of {FEEDS} or a groove angle in degrees, got {feed!r}") from None
    if n_theta % 2:
        raise ValueError(f"a grooved bearing needs an even n_theta, got {n_theta}")
    return GroovedReynoldsSolver(bearing, n_theta, n_z, cavitation=cavitation, groove_angle=angle)


def attitude_deg(x, force) -> float:
    """Attitude angle [deg]: from the load line (-F, the load the film carries) to the line of centres X,
    positive in the direction of rotation (from +X2 towards +X1), in (-180, 180]."""
    w = -np.asarray(force, dtype=float)
    x = np.asarray(x, dtype=float)
    # angles in this frame are atan2(v1, v2); sin of (angle of x - angle of w) is x1 w2 - x2 w1
    return math.degrees(math.atan2(x[0] * w[1] - x[1] * w[0], x @ w))


def static_point(solver, eps: float) -> dict:
    """Load, Sommerfeld number, attitude, friction, power loss, flows with the journal at eps on +X2.

    One row of a design table: the journal is placed at eccentricity ``eps`` on +X2 (at rest) and
    the load is what the film carries there.

    Parameters
    ----------
    solver : ReynoldsSolver or GroovedReynoldsSolver
        The film model (``film_solver``); it needs ``pressure`` and ``mesh``.
    eps : float
        Eccentricity ratio in [0, 1).

    Returns
    -------
    dict
        ``eps``, ``load_N`` [N], ``attitude_deg`` (angle between load line and line of centres
        [deg], >= 0; NaN at no load), ``friction_N`` [N], ``power_W`` [W], ``side_flow_m3s`` and
        ``feed_flow_m3s`` [m^3/s]; where the load is positive also ``sommerfeld`` and Raimondi &
        Boyd's ``friction_variable``, ``flow_variable`` and ``side_flow_ratio``.

    Raises
    ------
    ValueError
        For ``eps`` outside [0, 1) (named).

    Examples
    --------
    >>> from fluidfilm import JournalBearing, ReynoldsSolver
    >>> from fluidfilm.characteristics import static_point
    >>> b = JournalBearing(length=0.02, diameter=0.04, clearance=50e-6, speed_rpm=6000, viscosity=0.02)
    >>> row = static_point(ReynoldsSolver(b, 24, 12), 0.5)
    >>> round(row["load_N"], 1), round(row["sommerfeld"], 3), round(row["attitude_deg"], 1)
    (476.4, 0.537, 58.1)
    """
    if not 0.0 <= eps < 1.0:
        raise ValueError(f"eccentricity ratio must lie in [0, 1), got {eps!r}")
    b = solver.bearing
    x = np.array([0.0, eps * b.clearance])
    zero = np.zeros(2)
    F = np.asarray(solver.forces(x, zero))
    W = float(np.hypot(*F))
    p = solver.pressure(x, zero)
    if isinstance(solver, GroovedReynoldsSolver):
        xg = solver.to_groove_frame(x)
        ff = film_flows_and_friction(p, solver.mesh, b, xg, feed_index=0)
    else:
        ff = film_flows_and_friction(p, solver.mesh, b, x)
    row = {"eps": eps, "load_N": W, "attitude_deg": attitude_deg(x, F) if W > 0 else float("nan"),
           "friction_N": ff["friction_N"], "power_W": ff["power_W"], "side_flow_m3s": ff["side_flow_m3s"],
           "feed_flow_m3s": ff["feed_flow_m3s"]}
    if W > 0:
        row.update(raimondi_boyd_variables(b, W, ff["friction_N"], ff["feed_flow_m3s"], ff["side_flow_m3s"]))
    return row


def sommerfeld_sweep(solver, eps_values) -> list[dict]:
    """``static_point`` at every eccentricity (the eps- and attitude-vs-S tables).

    Parameters
    ----------
    solver : ReynoldsSolver or GroovedReynoldsSolver
        The film model (``film_solver``).
    eps_values : iterable of float
        Eccentricity ratios in [0, 1).

    Returns
    -------
    list of dict
        One ``static_point`` row per eccentricity, in the given order.

    Examples
    --------
    >>> from fluidfilm import JournalBearing, ReynoldsSolver
    >>> from fluidfilm.characteristics import sommerfeld_sweep
    >>> b = JournalBearing(length=0.02, diameter=0.04, clearance=50e-6, speed_rpm=6000, viscosity=0.02)
    >>> rows = sommerfeld_sweep(ReynoldsSolver(b, 24, 12), [0.3, 0.6])
    >>> rows[0]["sommerfeld"] > rows[1]["sommerfeld"]        # S falls as eps grows
    True
    """
    return [static_point(solver, float(e)) for e in eps_values]


def eccentricity_at_sommerfeld(solver, s: float, eps_lo: float = 0.01, eps_hi: float = 0.97) -> float:
    """Eccentricity at which the reference model gives Sommerfeld number ``s`` (S falls monotonically with eps)."""
    b = solver.bearing
    zero = np.zeros(2)

    def g(e):
        F = solver.forces(np.array([0.0, e * b.clearance]), zero)
        return math.log(b.sommerfeld(float(np.hypot(*F))) / s)

    return brentq(g, eps_lo, eps_hi, xtol=1e-10)


def load_along_gravity(W) -> tuple[float, float]:
    """The load vector (0, W) [N] of a magnitude ``W`` [N] along gravity (+X2).

    Every public function that takes a load takes a vector (W1, W2) in N;
    this helper turns the usual magnitude into one.

    Parameters
    ----------
    W : float
        Load magnitude [N], positive and finite.

    Returns
    -------
    tuple of float
        ``(0.0, W)``.

    Raises
    ------
    ValueError
        If ``W`` is not a positive finite number (the message names it).

    Examples
    --------
    >>> load_along_gravity(24.5)
    (0.0, 24.5)
    """
    return (0.0, check_magnitude("load W", W, "N"))


def check_magnitude(name: str, value, unit: str) -> float:
    """``value`` as a float if it is a positive finite number (not a bool); else ValueError naming ``name``."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a positive finite number in {unit}, got {value!r}")
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be a positive finite number in {unit}, got {value!r}")
    return v


def load_vector(load) -> np.ndarray:
    """``load`` as a finite non-zero vector (W1, W2) [N]; a scalar is refused with a pointer to the helper."""
    if np.ndim(load) == 0:
        raise ValueError(f"load must be a vector (W1, W2) in N, got the scalar {load!r}; for a magnitude W "
                         "along gravity pass fluidfilm.load_along_gravity(W)")
    if np.shape(load) != (2,) or any(isinstance(v, (bool, np.bool_)) for v in load):
        raise ValueError(f"load must be a vector (W1, W2) in N, got {load!r}")
    W = np.asarray(load, dtype=float)
    if not (np.isfinite(W).all() and np.hypot(*W) > 0.0):
        raise ValueError(f"load must be a finite non-zero vector (W1, W2) in N, got {tuple(W.tolist())}")
    return W


def _polar(eps, psi, c):
    """Position at eccentricity ratio eps and angle psi (from +X2 towards +X1, the direction of rotation)."""
    return c * eps * np.array([math.sin(psi), math.cos(psi)])


#: keys every equilibrium returns (``equilibrium``); ``X`` is the position as an array, X1, X2 its parts
EQUILIBRIUM_KEYS = ("eps", "X", "X1", "X2", "attitude_deg", "residual", "load_N", "sommerfeld",
                    "short_bearing_start_eps")


def equilibrium(model, load, guess: tuple[float, float] | None = None, eps_max: float = 0.995,
                tol: float = 1e-12, residual_tol: float = 1e-6) -> dict:
    """Journal position where the film force of ``model`` (at rest) balances ``load`` = (W1, W2) [N].

    The one equilibrium solver of the workspace (``fluidfilm.equilibrium`` and
    ``characteristics.equilibrium`` are this function; ``equilibrium_locus``
    follows it over load magnitudes).  A trust-region least-squares solve (scipy) of
    F_film(X, 0) + W = 0 in polar unknowns (eps, psi), eps bounded in
    [0, eps_max], started from ``guess`` if given, then from the
    short-bearing (Ocvirk) solution at the same Sommerfeld number, then from
    fall-back starts.  Robust to eps ~ 0.95.

    Parameters
    ----------
    model : force model
        Anything with ``.forces(X, V)`` and ``.bearing`` (a ``JournalBearing``).
    load : array_like, shape (2,)
        The load vector (W1, W2) [N] the film carries; for a magnitude W along
        gravity use ``load_along_gravity(W)`` = (0, W).
    guess : (eps, psi), optional
        A start (eccentricity ratio, position angle [rad] from +X2 towards +X1),
        e.g. the previous point of a continuation.
    eps_max : float
        Upper bound of the eccentricity ratio searched (and at most the model's ``validity.eps_max``).
    tol : float
        ``xtol``, ``ftol`` and ``gtol`` of ``scipy.optimize.least_squares``.
    residual_tol : float
        Largest accepted |F_film + W| / |W| at the solution.

    Returns
    -------
    dict
        ``eps``; ``X`` (array [m]) and its components ``X1``, ``X2``;
        ``attitude_deg``, the angle [deg] from the load line to the line of
        centres (bearing centre to journal centre), positive in the direction
        of rotation (from +X2 towards +X1), as in Raimondi & Boyd and Hamrock
        (about +60 deg for a lightly loaded bearing, falling towards 0 as eps -> 1);
        ``residual`` |F_film + W| / |W|; ``load_N`` |W|; ``sommerfeld``;
        ``short_bearing_start_eps``.

    Raises
    ------
    ValueError
        For a load that is not a finite non-zero vector, or when no
        equilibrium is found: the solution sits at the bound ``eps_max`` (the
        film cannot carry the load inside the clearance) or its residual
        exceeds ``residual_tol``; the message names the load.

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> eq = equilibrium(ReynoldsSolver(paper_bearing(), 30, 30), load_along_gravity(24.5))
    >>> round(eq["eps"], 2), eq["attitude_deg"] > 0, eq["residual"] < 1e-8
    (0.59, True, True)
    """
    W = load_vector(load)
    w = float(np.hypot(*W))
    b = model.bearing
    if not b.speed_rpm > 0.0:
        raise ValueError(f"no equilibrium under the load {tuple(W.tolist())} N: the bearing's speed_rpm="
                         f"{b.speed_rpm!r}, and a film that does not turn (a pure squeeze film) carries no static load")
    c = b.clearance
    # searched inside the model's validity domain too (a surrogate refuses or extrapolates beyond its data)
    if isinstance(model, ForceModel):
        eps_max = min(eps_max, float(model.validity.eps_max))
    psi_load = math.atan2(W[0], W[1])
    zero = np.zeros(2)
    # short-bearing start: Ocvirk's eps at this load (it under-predicts the finite bearing's capacity,
    # so its eps is an upper bound; the line of centres leads the load by phi in the direction of rotation)
    s = b.sommerfeld(w)
    try:
        e0 = min(shortbearing.eccentricity_at_sommerfeld(b, s), 0.97, 0.98 * eps_max)
    except ValueError:
        e0 = 0.5
    phi0 = shortbearing.attitude_angle_rad(max(e0, 1e-6))

    def residual(q):
        return (np.asarray(model.forces(_polar(q[0], q[1], c), zero)) + W) / w

    starts = [(e0, psi_load + phi0), (0.7 * e0, psi_load + phi0), (0.5, psi_load + 0.8),
              (min(0.85, 0.9 * eps_max), psi_load + 0.5)]
    if guess is not None:
        starts.insert(0, (float(guess[0]), float(guess[1])))
    best = None
    for start in starts:
        sol = least_squares(residual, x0=list(start), bounds=([0.0, -np.inf], [eps_max, np.inf]),
                            xtol=tol, ftol=tol, gtol=tol, method="trf")
        if best is None or sol.cost < best.cost:
            best = sol
        if best.cost < 1e-20:
            break
    assert best is not None  # the loop ran at least once
    eps, psi = float(best.x[0]), float(best.x[1])
    X = _polar(eps, psi, c)
    F = np.asarray(model.forces(X, zero))
    res = float(np.hypot(*(F + W)) / w)
    at_bound = eps >= eps_max * (1.0 - 1e-9)
    if at_bound or not res <= residual_tol:
        why = (f"the solve ended at the eccentricity bound eps_max={eps_max}: the film cannot carry it there"
               if at_bound else f"the best position found (eps={eps:.4g}) does not balance it")
        raise ValueError(f"no equilibrium under the load {tuple(W.tolist())} N (|W| = {w:.6g} N) for "
                         f"{getattr(model, 'name', type(model).__name__)}: {why} (residual |F + W|/|W| = "
                         f"{res:.3g}, tolerance {residual_tol:g})")
    return {"eps": eps, "X": X, "X1": float(X[0]), "X2": float(X[1]), "attitude_deg": attitude_deg(X, F),
            "residual": res, "load_N": w, "sommerfeld": s, "short_bearing_start_eps": e0}


#: the columns of ``equilibrium_locus`` (the scalar keys of ``equilibrium``)
LOCUS_COLUMNS = ("eps", "X1", "X2", "attitude_deg", "residual", "load_N", "sommerfeld")


def equilibrium_locus(model, loads, direction_deg: float = 0.0) -> pd.DataFrame:
    """Equilibrium positions for load magnitudes ``loads`` [N] along ``direction_deg``.

    Parameters
    ----------
    model : force model
        Anything with ``.forces(X, V)`` and ``.bearing``.
    loads : sequence of float
        Load magnitudes [N], each positive and finite; solved by continuation
        from the smallest.
    direction_deg : float
        Direction of the load [deg] from +X2 towards +X1 (0 = gravity).

    Returns
    -------
    pandas.DataFrame
        One row per load, columns ``LOCUS_COLUMNS`` (as ``equilibrium``).

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> locus = equilibrium_locus(ReynoldsSolver(paper_bearing(), 30, 30), [5.0, 50.0])
    >>> bool(locus.eps.is_monotonic_increasing)
    True
    """
    a = math.radians(direction_deg)
    rows = []
    guess = None
    c = model.bearing.clearance
    for load in sorted(check_magnitude("load", v, "N") for v in loads):
        r = equilibrium(model, (load * math.sin(a), load * math.cos(a)), guess=guess)
        guess = (r["eps"], math.atan2(r["X1"] / c, r["X2"] / c))
        rows.append({k: r[k] for k in LOCUS_COLUMNS})
    return pd.DataFrame(rows, columns=list(LOCUS_COLUMNS))
