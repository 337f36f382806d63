"""Benchmark of the reference Reynolds solver: medians per evaluation and batch throughput.

    python benchmarks/bench_solver.py [--quick]

Prints, for the paper's grids (30x30, 55x55, 60x60):
- one force evaluation through the public Python API (``solver.forces(x, v)``),
  and through the compiled kernel alone (what the rotor integrator calls);
- the same evaluation with a plain scipy sparse direct solve of the same
  finite-difference system, measured side by side, and the ratio;
- throughput in forces per second for batches of (X, V) pairs and for the
  dataset's layout (every velocity at every position, one factorisation per
  position), on all cores.
"""
from __future__ import annotations

import argparse
import os
import platform

import numba
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from fluidfilm import ReynoldsSolver, paper_bearing
from fluidfilm.perf.benchmarking import median_seconds


def scipy_force(bearing, n_theta, n_z, x, v):
    """Same discretisation, assembled with scipy.sparse and solved by spsolve, Gumbel + Simpson."""
    r, c, mu = bearing.radius, bearing.clearance, bearing.viscosity
    dth = 2 * np.pi / n_theta
    dz = bearing.length / (n_z - 1)
    dzeta = dz / r
    th = dth * np.arange(n_theta)
    e1, e2 = x[0] / c, x[1] / c
    H = 1 - e1 * np.sin(th) - e2 * np.cos(th)
    Hf = 1 - e1 * np.sin(th + dth / 2) - e2 * np.cos(th + dth / 2)
    Hb = np.roll(Hf, 1)
    m = n_z - 2
    aw, ae, an = Hb**3 / dth**2, Hf**3 / dth**2, H**3 / dzeta**2
    rhs = 6 * mu * bearing.omega * r**2 / c**2 * (Hf - Hb) / dth + 12 * mu * r**2 / c**3 * (
        -v[0] * np.sin(th) - v[1] * np.cos(th))
    I_z = sp.identity(m, format="csr")
    D2 = sp.diags([np.ones(m - 1), -2 * np.ones(m), np.ones(m - 1)], [-1, 0, 1], format="csr")
    P = sp.csr_matrix((np.ones(n_theta), (np.arange(n_theta), (np.arange(n_theta) + 1) % n_theta)),
                      shape=(n_theta, n_theta))
    A_th = sp.diags(ae) @ P + sp.diags(aw) @ P.T - sp.diags(aw + ae)
    A = sp.kron(A_th, I_z) + sp.kron(sp.diags(an), D2)
    b = np.repeat(rhs, m)
    p = np.maximum(spla.spsolve(A.tocsc(), b), 0).reshape(n_theta, m)
    from fluidfilm.reynolds.mesh import FilmMesh

    mesh = FilmMesh(n_theta, n_z, bearing.length)
    col = p @ mesh.w_z[1:-1]
    return -r * np.array([mesh.w_theta @ (col * np.sin(th)), mesh.w_theta @ (col * np.cos(th))])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="fewer repeats (smoke run)")
    args = ap.parse_args()
    repeats, calls = (3, 200) if args.quick else (9, 2000)
    b = paper_bearing()
    c = b.clearance
    x = np.array([0.3 * c, 0.55 * c])
    v = np.array([0.02, -0.03])
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"numba threads {numba.get_num_threads()}, numpy {np.__version__}, numba {numba.__version__}")
    print(f"{'grid':>8} {'forces() us':>12} {'kernel us':>10} {'scipy spsolve us':>17} {'ratio':>7} "
          f"{'batch pairs/s':>14} {'product forces/s':>17}")
    rng = np.random.default_rng(0)
    n_pairs = 4000 if args.quick else 20000
    eps = rng.uniform(0, 0.9, n_pairs)
    ang = rng.uniform(0, 2 * np.pi, n_pairs)
    X = np.stack([eps * c * np.sin(ang), eps * c * np.cos(ang)], axis=1)
    V = rng.uniform(-0.2, 0.2, (n_pairs, 2))
    table = []
    for n in (30, 55, 60):
        s = ReynoldsSolver(b, n, n)
        t_api = median_seconds(lambda: s.forces(x, v), repeats, calls)
        fn, params = s.force_kernel
        t_kernel = median_seconds(lambda: fn(params, x[0], x[1], v[0], v[1]), repeats, calls)
        np.testing.assert_allclose(scipy_force(b, n, n, x, v), s.forces(x, v), rtol=1e-8)
        t_scipy = median_seconds(lambda: scipy_force(b, n, n, x, v), 3, 5 if args.quick else 20)
        t_batch = median_seconds(lambda: s.forces(X, V), 3, 1)
        Xp, Vq = X[: 240 if args.quick else 960], V[:80]
        t_prod = median_seconds(lambda: s.forces_product(Xp, Vq), 3, 1)
        print(f"{n}x{n:<5} {t_api * 1e6:12.1f} {t_kernel * 1e6:10.1f} {t_scipy * 1e6:17.0f} "
              f"{t_scipy / t_api:7.0f} {n_pairs / t_batch:14.0f} {Xp.shape[0] * Vq.shape[0] / t_prod:17.0f}")
        table.append([f"{n}x{n}", f"{t_api * 1e6:.1f} us", f"{t_kernel * 1e6:.1f} us", f"{t_scipy * 1e3:.1f} ms",
                      f"{t_scipy / t_api:.0f}x", f"{n_pairs / t_batch:,.0f} /s",
                      f"{Xp.shape[0] * Vq.shape[0] / t_prod:,.0f} /s"])
    if not args.quick:
        from fluidfilm.perf.benchmarking import write_benchmark

        write_benchmark("solver", "Reference solver, per force evaluation (medians of 9 x 2000 calls; batches on all cores)",
                        ["grid", "`forces(x, v)` Python call", "compiled kernel", "scipy sparse direct solve, same system",
                         "ratio", "batch of (X, V) pairs", "every V at every X"], table,
                        "The sparse solve assembles the same finite-difference system and solves it directly on every "
                        "call, as a MATLAB-style reference would; both give the same forces to 1e-8.")


if __name__ == "__main__":
    main()
