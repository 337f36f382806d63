"""ROSS side of the external-peer benchmark (runs INSIDE the ROSS environment, not the project's;
imports only ross, numpy and the standard library).

    .venv-ross/bin/python benchmarks/ross_peer_ross_side.py [--mesh 30x10 ...] [--method lund] [--rows 0.580 ...]
                                                          [--repeats 3] [--max-repeat-s 20]

Started by ``benchmarks/bench_ross_peer.py`` (``make ross-peer``); imports only ross, numpy and the
standard library, and prints ONE JSON object on stdout (ROSS's REFPROP warnings and the rest go to
stderr).

The bearing: ROSS 2.3.0's ``ross.bearings.plain_journal.PlainJournal`` (finite-volume, THD) set up as
Lund & Thomsen's (1978) two-axial-groove bearing, L/D = 0.5: ``n_pad=2``, ``pad_arc_length=160``,
``geometry="circular"``, ``preload=0``.  PlainJournal puts its pad centres at 90 and 270 deg from its +x
axis (pads 10-170 and 190-350 deg), i.e. the 20 deg gaps ("grooves") sit on the +-x axis; the load is
applied along -y (``fys_load=-W``), so the grooves are at the split normal to the load, as in L&T.
Isoviscous: the lubricant dict has the same viscosity at both reference temperatures, so ROSS's fitted
law mu = a T^b has b = 0 and the THD loop (still run) cannot change the viscosity.  The journal turns
from +x towards +y in ROSS (the Couette source is +dh/dtheta), so with L&T's x along the load (ROSS -y)
and y horizontal, turning from x towards y (ROSS +x):
    Kxx(L&T) = kyy,  Kxy(L&T) = -kyx,  Kyx(L&T) = -kxy,  Kyy(L&T) = kxx   (the same for damping),
scaled K = k c / W and B = b c omega / W (checked against the published numbers, see the report).
What ROSS 2.3.0 does NOT share with L&T: its flooded pressure solve is the full linear (Sommerfeld)
solution with negative pressures clipped to zero afterwards (a Gumbel / half-Sommerfeld condition),
not the Reynolds (Swift-Stieber) condition; the lands' edges at the grooves are at zero pressure in both.
Its equilibrium is a Nelder-Mead search with tol = 0.8 (an absolute 0.8 N force tolerance here).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

# The bearing of ROSS 3.x's literature test (the dimensionless results depend on L/D only)
D, C, MU, RPM, L_OVER_D = 0.1, 100e-6, 0.02, 3000.0, 0.5
LUBRICANT = {"liquid_viscosity1": MU, "temperature1": 313.15, "liquid_viscosity2": MU, "temperature2": 373.15,
             "liquid_density": 860, "liquid_specific_heat": 1951, "liquid_thermal_conductivity": 0.13}


def build(S: float, n_circ: int, n_axial: int, method: str):
    from ross.bearings.plain_journal import PlainJournal

    L, R = L_OVER_D * D, D / 2
    W = MU * RPM / 60.0 * L * D * (R / C) ** 2 / S
    omega = RPM * np.pi / 30.0
    b = PlainJournal(n=0, axial_length=L, journal_radius=R, radial_clearance=C,
                     elements_circumferential=n_circ, elements_axial=n_axial, n_pad=2, pad_arc_length=160,
                     preload=0, geometry="circular", reference_temperature=40.0, frequency=[omega],
                     fxs_load=0, fys_load=-W, lubricant=LUBRICANT, groove_factor=[0.5, 0.5], method=method,
                     operating_type="flooded", oil_supply_pressure=0)
    return b, W, omega


def lt_frame(b, W: float, omega: float) -> dict:
    eps, ang = (float(v) for v in b.equilibrium_pos)
    k = {n: float(getattr(b, n)[0]) * C / W for n in ("kxx", "kxy", "kyx", "kyy")}
    c = {n: float(getattr(b, n)[0]) * C * omega / W for n in ("cxx", "cxy", "cyx", "cyy")}
    # journal centre at angle ang from ROSS +x; the load line is -y (-90 deg); attitude measured from it
    phi = float(np.degrees(np.arctan2(np.sin(ang + np.pi / 2), np.cos(ang + np.pi / 2))))
    return {"eps": eps, "phi": phi,
            "Kxx": k["kyy"], "Kxy": -k["kyx"], "Kyx": -k["kxy"], "Kyy": k["kxx"],
            "Bxx": c["cyy"], "Bxy": -c["cyx"], "Byx": -c["cxy"], "Byy": c["cxx"],
            "ross_raw": {**k, **c, "equilibrium_pos": [eps, ang]}}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--mesh", nargs="+", default=["11x3", "30x10"],
                    help="elements_circumferential x elements_axial per pad (11x3: ROSS 2.3's own tests)")
    ap.add_argument("--method", default="lund", choices=["lund", "perturbation"])
    ap.add_argument("--rows", nargs="+", type=float, required=True,
                    help="Sommerfeld numbers S = mu N L D (R/c)^2 / W of the rows to compute")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--max-repeat-s", type=float, default=20.0,
                    help="a call slower than this is not repeated (single timing)")
    args = ap.parse_args()
    # only the JSON goes to stdout: ROSS/CoolProp print REFPROP notices from C on import, so fd 1 itself is
    # pointed at stderr until the end
    sys.stdout.flush()
    stdout = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    import ross

    out = {"ross_version": getattr(ross, "__version__", "?"), "numpy_version": np.__version__, "python": sys.version.split()[0],
           "method": args.method, "bearing": {"D": D, "c": C, "mu": MU, "rpm": RPM, "L_over_D": L_OVER_D,
                                              "n_pad": 2, "pad_arc_deg": 160, "geometry": "circular"},
           "results": []}
    # warm-up (numba compiles ROSS's kernels on the first call): one small untimed construction
    t0 = time.perf_counter()
    build(args.rows[0], 11, 3, args.method)
    out["warmup_s"] = time.perf_counter() - t0
    for mesh in args.mesh:
        n_circ, n_axial = (int(v) for v in mesh.lower().split("x"))
        for sommerfeld in args.rows:
            samples = []
            while True:
                t0 = time.perf_counter()
                b, W, omega = build(sommerfeld, n_circ, n_axial, args.method)
                samples.append(time.perf_counter() - t0)
                if len(samples) >= args.repeats or samples[0] > args.max_repeat_s:
                    break
            res = lt_frame(b, W, omega)
            # the coefficient step alone, at the equilibrium the constructor found (PlainJournal.coefficients
            # re-runs its Lund perturbation solve on the stored field)
            coef_samples = []
            while True:
                t0 = time.perf_counter()
                b.coefficients(omega)
                coef_samples.append(time.perf_counter() - t0)
                if len(coef_samples) >= args.repeats or coef_samples[0] > args.max_repeat_s:
                    break
            opt = getattr(b, "_opt_results", None)  # private in ROSS 2.3: recorded only where present
            nfev = int(next(iter(opt.values())).nfev) if isinstance(opt, dict) and opt else None
            res.update({"S": sommerfeld, "mesh": f"{n_circ}x{n_axial}", "elements_circumferential": n_circ,
                        "elements_axial": n_axial, "n_pad": 2, "load_N": W,
                        "seconds": float(np.median(samples)), "samples_s": samples,
                        "timing": "median of %d" % len(samples) if len(samples) > 1 else "single call",
                        "coef_seconds": float(np.median(coef_samples)), "coef_samples_s": coef_samples,
                        "nfev_equilibrium": nfev})
            out["results"].append(res)
            print(f"ROSS {res['mesh']} S={sommerfeld}: {res['seconds']:.2f} s, eps {res['eps']:.3f}", file=sys.stderr)
    stdout.write(json.dumps(out) + "\n")
    stdout.flush()


if __name__ == "__main__":
    main()
