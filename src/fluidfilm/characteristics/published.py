"""Published values typed in for validation, with their sources.

RAIMONDI_BOYD: A. A. Raimondi and J. Boyd, "A solution for the finite
journal bearing and its application to analysis and design: III",
ASLE Transactions 1 (1958) 194-209, full (360 deg) bearings, Reynolds
(Swift-Stieber) boundary condition, lubricant fed at the line of maximum
film thickness (p = 0 there); the same tables are reprinted in B. J. Hamrock,
*Fundamentals of Fluid Film Lubrication* (and drawn as charts in Shigley's
*Mechanical Engineering Design*, ch. 12).  Columns: eps, Sommerfeld number S,
attitude angle phi [deg], friction variable (R/c) f, flow variable
Q/(R c N L), side-flow ratio Q_s/Q.  The printed tables were not at hand;
the values were cross-checked against two independent public copies:
S and (R/c) f of every row against the table hard-coded in PDSim
(github.com/ibell/pdsim, ``PDSim/core/bearings.py``, which cites Raimondi &
Boyd and Hamrock), and every column against a public digitisation of the full
rows (``lubrication_data.py``; one source, provenance not established).  That
check corrected four L/D = 1/4 entries first typed from memory (flow 5.02,
5.73, 6.08, 6.37 -> 4.99, 5.60, 5.91, 6.12; attitude 21.64, 12.42 -> 21.85,
12.22): the corrected flows respect the bound Q <= pi (1 + eps) (the Couette
inflow at the maximum film thickness), which the first typing broke.  Other
checks: the L/D = 1 rows at eps 0.6/0.8/0.9 match tests/test_reynolds.py, and
the rows satisfy the full-shear friction identity
(R/c) f = 2 pi^2 S / sqrt(1 - eps^2) + eps sin(phi) / 2 to 0.5 % except
L/D = 1, eps = 0.4 (1.3 %, present in every copy of the table).

SHORT_BEARING_KC: closed forms of the short-bearing (Ocvirk, Gumbel
pi-film) dynamic coefficients, M. I. Friswell, J. E. T. Penny, S. D.
Garvey, A. W. Lees, *Dynamics of Rotating Machines*, Cambridge UP 2010,
sec. 5.5 (their u horizontal, v along the load; in this workspace u = X1,
v = X2, and the cross terms change sign because the journal turns from +X2
towards +X1).  Checked against derivatives of the independently integrated
short-bearing force (``shortbearing.force``) in the tests.
"""
from __future__ import annotations

import math

# L/D -> rows (eps, S, phi_deg, friction_variable, flow_variable, side_flow_ratio)
RAIMONDI_BOYD = {
    1.0: [
        (0.1, 1.33, 79.5, 26.4, 3.37, 0.150),
        (0.2, 0.631, 74.02, 12.8, 3.59, 0.280),
        (0.4, 0.264, 63.10, 5.79, 3.99, 0.497),
        (0.6, 0.121, 50.58, 3.22, 4.33, 0.680),
        (0.8, 0.0446, 36.24, 1.70, 4.62, 0.842),
        (0.9, 0.0188, 26.45, 1.05, 4.74, 0.919),
        (0.97, 0.00474, 15.47, 0.514, 4.82, 0.973),
    ],
    0.5: [
        (0.1, 4.31, 81.62, 85.6, 3.43, 0.173),
        (0.2, 2.03, 74.94, 40.9, 3.72, 0.318),
        (0.4, 0.779, 61.45, 17.0, 4.29, 0.552),
        (0.6, 0.319, 48.14, 8.10, 4.85, 0.730),
        (0.8, 0.0923, 33.31, 3.26, 5.41, 0.874),
        (0.9, 0.0313, 23.66, 1.60, 5.69, 0.939),
        (0.97, 0.00609, 13.75, 0.610, 5.88, 0.980),
    ],
    0.25: [
        (0.1, 16.2, 82.31, 322.0, 3.45, 0.180),
        (0.2, 7.57, 75.18, 153.0, 3.76, 0.330),
        (0.4, 2.83, 60.86, 61.1, 4.37, 0.567),
        (0.6, 1.07, 46.72, 26.7, 4.99, 0.746),
        (0.8, 0.261, 31.04, 8.80, 5.60, 0.884),
        (0.9, 0.0736, 21.85, 3.50, 5.91, 0.945),
        (0.97, 0.0101, 12.22, 0.922, 6.12, 0.984),
    ],
}
RAIMONDI_BOYD_SOURCE = ("Raimondi & Boyd (1958), ASLE Trans. 1, 194-209, full journal bearing, "
                        "Swift-Stieber condition, feed at the maximum film thickness")


def short_bearing_kc(eps: float) -> dict:
    """Dimensionless short-bearing K/C (Kbar = K c/W, Cbar = C c omega/W) in this workspace's axes."""
    if not 0.0 < eps < 1.0:
        raise ValueError(f"eccentricity ratio must lie in (0, 1), got {eps!r}")
    e2 = eps * eps
    pi2 = math.pi**2
    s = math.sqrt(1.0 - e2)
    h0 = 1.0 / (pi2 * (1.0 - e2) + 16.0 * e2) ** 1.5
    return {
        "Kxx": h0 * 4.0 * (pi2 * (2.0 - e2) + 16.0 * e2),
        "Kxy": -h0 * math.pi * (pi2 * (1.0 - e2) ** 2 - 16.0 * e2 * e2) / (eps * s),
        "Kyx": h0 * math.pi * (pi2 * (1.0 - e2) * (1.0 + 2.0 * e2) + 32.0 * e2 * (1.0 + e2)) / (eps * s),
        "Kyy": h0 * 4.0 * (pi2 * (1.0 + 2.0 * e2) + 32.0 * e2 * (1.0 + e2) / (1.0 - e2)),
        "Cxx": h0 * 2.0 * math.pi * s * (pi2 * (1.0 + 2.0 * e2) - 16.0 * e2) / eps,
        "Cxy": h0 * 8.0 * (pi2 * (1.0 + 2.0 * e2) - 16.0 * e2),
        "Cyx": h0 * 8.0 * (pi2 * (1.0 + 2.0 * e2) - 16.0 * e2),
        "Cyy": h0 * 2.0 * math.pi * (pi2 * (1.0 - e2) ** 2 + 48.0 * e2) / (eps * s),
    }
