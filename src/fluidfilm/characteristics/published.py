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
checks: the L/D = 1 rows at eps 0.6/0.8/0.9 match tests/reynolds/test_reynolds.py, and
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

LUND_THOMSEN_1978: J. W. Lund and K. K. Thomsen, "A calculation method and
data for the dynamic coefficients of oil-lubricated journal bearings", in
*Topics in Fluid Film Bearing and Rotor Bearing System Design and
Optimization*, ASME, New York 1978, pp. 1-28: two-axial-groove bearing (two
20 deg axial grooves at the horizontal split, i.e. centred +-90 deg from the
load line, 160 deg lands), isoviscous, Reynolds (Swift-Stieber) condition.
Columns: S = mu N L D (R/c)^2 / W (N in rev/s), eps, attitude phi [deg], and
the dimensionless Kxx, Kxy, Kyx, Kyy (k c / W), Bxx, Bxy, Byy (b c omega / W;
Byx = Bxy as printed), with x ALONG the load and y horizontal, the journal
turning from x towards y (this workspace: x = X2, y = X1, the journal turning
from +X2 towards +X1, so Kxy(L&T) = K21 here, etc.).  The printed paper was
not at hand; the values come from two independent public typings: the L/D =
0.5 table ("Table 1a") in full from a DTU course script (course 41524,
I. F. Santos, 2023), and five of its rows plus five L/D = 1 rows typed
separately in ROSS's literature tests (github.com/petrobras/ross,
``ross/tests/test_fluid_film_literature.py``, which cites Lund & Thomsen).
The five L/D = 0.5 rows both typings share agree digit for digit (except S =
0.378 / 0.379 in the row at eps 0.570; 0.378 kept).  ``LUND_THOMSEN_TWO_TYPINGS``
marks those rows; the L/D = 1 rows have one typing only (ROSS left out the row
at S = 0.358, whose printed Kyy breaks the column's trend).  Values are printed
to two decimals: half a unit of the last digit (0.005) is allowed on top of
any tolerance (``LUND_THOMSEN_PRINT_HALF_UNIT``).
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


# L/D -> rows (S, eps, phi_deg, Kxx, Kxy, Kyx, Kyy, Bxx, Bxy, Byy); x along the load (LUND_THOMSEN_1978 doc)
LUND_THOMSEN_COLUMNS = ("S", "eps", "phi", "Kxx", "Kxy", "Kyx", "Kyy", "Bxx", "Bxy", "Byy")
LUND_THOMSEN_COEFFICIENTS = LUND_THOMSEN_COLUMNS[3:]  # the seven printed (Byx = Bxy)
#: Lund & Thomsen's frame: x ALONG the load (our X2), y horizontal (our X1); their names are not ours
LUND_THOMSEN_FRAME = "Lund & Thomsen's axes: x along the load (= X2 here), y horizontal (= X1 here)"
#: their coefficient -> (matrix, i, j) of this workspace's K, C (index 0 = X1, 1 = X2): Kxy(L&T) = K[1, 0]
LUND_THOMSEN_INDEX = {"Kxx": ("K", 1, 1), "Kxy": ("K", 1, 0), "Kyx": ("K", 0, 1), "Kyy": ("K", 0, 0),
                      "Bxx": ("C", 1, 1), "Bxy": ("C", 1, 0), "Byy": ("C", 0, 0)}
LUND_THOMSEN_1978 = {
    0.5: [
        (6.430, 0.071, 81.89, 1.55, 14.41, -6.60, 1.88, 28.75, 1.89, 13.31),
        (3.937, 0.114, 77.32, 1.57, 9.27, -4.20, 1.89, 18.44, 1.93, 8.58),
        (2.634, 0.165, 72.36, 1.61, 6.74, -3.01, 1.91, 13.36, 2.00, 6.28),
        (2.030, 0.207, 68.75, 1.65, 5.67, -2.50, 1.93, 11.18, 2.07, 5.33),
        (1.656, 0.244, 65.85, 1.69, 5.06, -2.20, 1.95, 9.93, 2.15, 4.80),
        (0.917, 0.372, 57.45, 2.12, 4.01, -1.30, 1.85, 7.70, 2.06, 3.23),
        (0.580, 0.477, 51.01, 2.67, 3.70, -0.78, 1.75, 6.96, 1.94, 2.40),
        (0.378, 0.570, 45.43, 3.33, 3.64, -0.43, 1.68, 6.76, 1.87, 1.89),
        (0.244, 0.655, 40.25, 4.21, 3.74, -0.13, 1.64, 6.87, 1.82, 1.54),
        (0.194, 0.695, 37.72, 4.78, 3.84, 0.01, 1.62, 7.03, 1.80, 1.40),
        (0.151, 0.734, 35.20, 5.48, 3.98, 0.15, 1.61, 7.26, 1.79, 1.27),
        (0.133, 0.753, 33.93, 5.89, 4.07, 0.22, 1.60, 7.41, 1.79, 1.20),
        (0.126, 0.761, 33.42, 6.07, 4.11, 0.25, 1.60, 7.48, 1.79, 1.18),
        (0.116, 0.772, 32.65, 6.36, 4.17, 0.30, 1.60, 7.59, 1.79, 1.15),
        (0.086, 0.809, 30.04, 7.51, 4.42, 0.47, 1.59, 8.03, 1.79, 1.03),
        (0.042, 0.879, 24.41, 11.45, 5.23, 0.92, 1.60, 9.48, 1.80, 0.82),
    ],
    1.0: [
        (0.991, 0.150, 70.58, 1.56, 7.29, -2.16, 1.52, 14.66, 1.58, 4.49),
        (0.635, 0.224, 63.54, 1.62, 5.33, -1.57, 1.56, 10.80, 1.70, 3.41),
        (0.235, 0.460, 49.27, 2.19, 3.57, -0.80, 1.55, 7.36, 1.89, 2.19),
        (0.159, 0.559, 44.33, 2.73, 3.36, -0.48, 1.48, 6.94, 1.78, 1.74),
        (0.108, 0.650, 39.72, 3.45, 3.34, -0.23, 1.44, 6.89, 1.72, 1.43),
    ],
}
# (L/D, S) of the rows typed by both public copies
LUND_THOMSEN_TWO_TYPINGS = {(0.5, 1.656), (0.5, 0.917), (0.5, 0.580), (0.5, 0.378), (0.5, 0.244)}
LUND_THOMSEN_PRINT_HALF_UNIT = 0.005
LUND_THOMSEN_GROOVE_WIDTH_DEG = 20.0
LUND_THOMSEN_SOURCE = ("Lund & Thomsen (1978), ASME Topics in Fluid Film Bearing and Rotor Bearing System Design "
                       "and Optimization, 1-28: two-axial-groove bearing (20 deg grooves at the horizontal split), "
                       "Swift-Stieber condition")
