"""The scaling row: what every compiled evaluation of a surrogate network reads of its scaling, named once.

``Scaling.kernel_row()`` flattens one network's input and output scaling (``surrogate.scaling``) into
``ROW_LENGTH`` = 22 float64 entries, the form the numba kernels take (a (R, 22) array for R regions).
This module is the only place that knows where each field sits; every other module indexes a row with
the names below (``tests/surrogate/test_surrogate_contract.py`` fails on a bare integer index into a row
anywhere else in ``src/``).

====== ====================== ===================================================================
index  name                   meaning
====== ====================== ===================================================================
0      ``ROW_KIND``           scaling kind code (``KIND_CODES``): 0 affine (standard, minmax),
                              1 physics, 2 physics_v
1      ``ROW_CLEARANCE``      radial clearance c [m]
2      ``ROW_OMEGA``          shaft speed omega [rad/s]
3      ``ROW_FORCE_SCALE``    film-force scale mu omega R L (R/c)^2 [N]
4      ``ROW_POWER``          exponent p of the physics gain (1 - eps^2)^-p
5-9    ``ROW_IN_MEAN``        centres of the raw network inputs, padded with 0 to ``MAX_INPUTS``
10-14  ``ROW_IN_STD``         spreads of the raw network inputs, padded with 1
15-16  ``ROW_OUT_MEAN``       centres of the two raw targets
17-18  ``ROW_OUT_STD``        spreads of the two raw targets
19     ``ROW_FRAME``          frame code (``FRAME_CODES``): 0 cartesian, 1 polar, 2 whirl
20     ``ROW_N_EXTRA``        number of extra inputs (the sleeve S), read from the model's setting
21     ``ROW_SLEEVE``         ``SLEEVE_AWARE`` (1) where the clearance follows the sleeve
                              (c_r = c + S tan alpha), else 0
====== ====================== ===================================================================

The frame and kind codes are ordered so that the kernels' tests read as words: ``row[ROW_KIND] >=
KIND_PHYSICS`` is "a physics scaling" (both physics kinds), ``row[ROW_FRAME] >= FRAME_POLAR`` "the
journal's frame" (polar or whirl).

The generic batch kernel's per-region row (``BatchParams.regions``, ``REGION_ROW_LENGTH`` = 8 entries)
is named here as well: [kind, frame, n_extra, sleeve-aware, c, omega, F_scale, power].

>>> ROW_LENGTH, ROW_FRAME, FRAME_CODES["whirl"]
(22, 19, 2.0)
"""
from __future__ import annotations

__all__ = ["MAX_INPUTS", "ROW_KIND", "ROW_CLEARANCE", "ROW_OMEGA", "ROW_FORCE_SCALE", "ROW_POWER", "ROW_IN_MEAN",
           "ROW_IN_STD", "ROW_OUT_MEAN", "ROW_OUT_STD", "ROW_FRAME", "ROW_N_EXTRA", "ROW_SLEEVE", "ROW_LENGTH",
           "KIND_AFFINE", "KIND_PHYSICS", "KIND_PHYSICS_V", "KIND_CODES", "FRAME_CARTESIAN", "FRAME_POLAR",
           "FRAME_WHIRL", "FRAME_CODES", "SLEEVE_AWARE", "REGION_KIND", "REGION_FRAME", "REGION_N_EXTRA",
           "REGION_SLEEVE", "REGION_CLEARANCE", "REGION_OMEGA", "REGION_FORCE_SCALE", "REGION_POWER",
           "REGION_ROW_LENGTH", "region_row"]

#: the most network inputs a compiled kernel takes (state inputs and extra inputs together)
MAX_INPUTS = 5

ROW_KIND = 0
ROW_CLEARANCE = 1
ROW_OMEGA = 2
ROW_FORCE_SCALE = 3
ROW_POWER = 4
#: first of ``MAX_INPUTS`` input centres
ROW_IN_MEAN = 5
#: first of ``MAX_INPUTS`` input spreads
ROW_IN_STD = ROW_IN_MEAN + MAX_INPUTS
#: first of two output centres
ROW_OUT_MEAN = ROW_IN_STD + MAX_INPUTS
#: first of two output spreads
ROW_OUT_STD = ROW_OUT_MEAN + 2
ROW_FRAME = ROW_OUT_STD + 2
ROW_N_EXTRA = ROW_FRAME + 1
ROW_SLEEVE = ROW_N_EXTRA + 1
ROW_LENGTH = ROW_SLEEVE + 1

# scaling kind codes (minmax is an affine map like standard, only its centre and half-range differ)
KIND_AFFINE = 0.0
KIND_PHYSICS = 1.0
KIND_PHYSICS_V = 2.0
#: scaling kind -> ``ROW_KIND`` code
KIND_CODES = {"standard": KIND_AFFINE, "physics": KIND_PHYSICS, "physics_v": KIND_PHYSICS_V, "minmax": KIND_AFFINE}

FRAME_CARTESIAN = 0.0
FRAME_POLAR = 1.0
FRAME_WHIRL = 2.0
#: frame -> ``ROW_FRAME`` code
FRAME_CODES = {"cartesian": FRAME_CARTESIAN, "polar": FRAME_POLAR, "whirl": FRAME_WHIRL}

#: ``ROW_SLEEVE``'s value for a scaling whose clearance follows the sleeve
SLEEVE_AWARE = 1.0

# the generic batch kernel's region row (``surrogate.kernels.BatchParams.regions``)
REGION_KIND = 0
REGION_FRAME = 1
REGION_N_EXTRA = 2
REGION_SLEEVE = 3
REGION_CLEARANCE = 4
REGION_OMEGA = 5
REGION_FORCE_SCALE = 6
REGION_POWER = 7
REGION_ROW_LENGTH = 8


def region_row(row, clearance: float, omega: float, force_scale: float, power: float) -> list:
    """The generic batch kernel's region row of a scaling row ``row`` and the scaling's own values."""
    return [row[ROW_KIND], row[ROW_FRAME], row[ROW_N_EXTRA], row[ROW_SLEEVE], clearance, omega, force_scale, power]
