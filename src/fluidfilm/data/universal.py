"""The dimensionless force dataset of the universal plain-bearing surrogate.

For a plain journal bearing without supply pressure and an isoviscous film, the Reynolds equation in
the journal's frame is driven by u = (eps - 2 v_t, 2 v_r) (velocities in units of c omega), over
pressure fields that depend on eps and L/D alone; the film force, Gumbel or Swift-Stieber, is
positively homogeneous of degree 1 in u (``surrogate.transforms.whirl_direction``).  So

    F = mu omega R L (R/c)^2 |u| G(eps, alpha, L/D),   u = |u| (cos alpha, sin alpha),

with G = (G_r, G_t) the force along and across the line of centres, for any speed, viscosity,
clearance and size.  This module tabulates G with the reference solver (``ReynoldsSolver``) on a
tensor grid of L/D (geometric, denser at short bearings, where G changes fastest), eps (denser
towards ``eps_max``) and alpha (uniform), one Dask task per (cavitation, L/D, eccentricity band):

- the finite-difference grid (n_theta, n_z) is chosen per L/D and band by a convergence check
  (``converged_grid``): the coarsest grid of a ladder whose forces at the band's largest eccentricity
  differ from the next finer grid's by less than ``grid_tol`` (relative, per direction), so every row
  is grid-converged to about that;
- the parts are written atomically with their SHA-256 in ``_state.json`` and ``_metadata.json``
  (``data.schema.verify_dataset`` checks them), so an interrupted run resumes and a damaged part is
  recomputed, as with the other datasets.

Columns of each row: ``ld`` (L/D), ``eps``, ``alpha`` [rad], ``G_r``, ``G_t`` (dimensionless, per unit
|u|), the derivatives ``dG_r_deps``, ``dG_t_deps``, ``dG_r_dalpha``, ``dG_t_dalpha`` (central differences of
the same solver, steps ``DERIVATIVE_STEP``), ``cavitation`` (0 Gumbel, 1 Swift-Stieber), ``n_theta``, ``n_z``.
The derivatives are what the bearing's stiffness and damping are made of: along the static line (alpha = 0,
the journal at rest) K comes from dG/deps and C from dG/dalpha and the homogeneity, so the networks are
fitted to them as well as to G (``surrogate.training.universal_fit``).
"""
from __future__ import annotations

from typing import Any

import json
import math
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from fluidfilm import __version__, io
from fluidfilm.core.bearing import JournalBearing
from fluidfilm.data.schema import part_name, verify_dataset
from fluidfilm.data.spec import config_hash
from fluidfilm.reynolds import ReynoldsSolver

__all__ = ["UniversalSpec", "canonical_bearing", "drive_states", "dimensionless_forces", "converged_grid",
           "generate_universal", "load_universal", "UNIVERSAL_CAVITATION"]

#: the cavitation rules the universal model covers (a column code each)
UNIVERSAL_CAVITATION = ("gumbel", "swift-stieber")
#: 2: the derivative columns (dG/deps, dG/dalpha) were added
FORMAT_VERSION = 2
#: central-difference steps of the derivative columns in eps and alpha [rad]: truncation error ~1e-6
#: relative at eps = 0.95, round-off ~1e-9
DERIVATIVE_STEP = 1e-4
#: the ladder of circumferential node counts the convergence check climbs
N_THETA_LADDER = (48, 72, 96, 144, 192, 288, 384)


def canonical_bearing(slenderness: float) -> JournalBearing:
    """The bearing the dimensionless forces are computed on: D = 40 mm, c/R = 0.002, 3000 rpm, 0.01 Pa s,
    L = ``slenderness`` D (any other choice gives the same G: the scaling is exact, tests/surrogate/test_universal.py).

    Parameters
    ----------
    slenderness : float
        L/D, > 0.

    Returns
    -------
    JournalBearing

    Examples
    --------
    >>> canonical_bearing(0.5).slenderness
    0.5
    """
    return JournalBearing(length=0.04 * float(slenderness), diameter=0.04, clearance=40e-6, speed_rpm=3000.0,
                          viscosity=0.01)


def drive_states(eps, alpha, clearance: float, omega: float) -> tuple[np.ndarray, np.ndarray]:
    """Journal states with eccentricity ``eps`` (along +X2) and the unit drive u = (cos alpha, sin alpha).

    u = (eps - 2 v_t, 2 v_r) with v_r, v_t in units of c omega (v_r along e_r = +X2, v_t along
    e_t = +X1), so v_r = sin(alpha) / 2 and v_t = (eps - cos(alpha)) / 2.

    Parameters
    ----------
    eps, alpha : array_like
        Eccentricity ratios and drive directions [rad], broadcast together.
    clearance : float
        Radial clearance c [m].
    omega : float
        Shaft speed [rad/s].

    Returns
    -------
    X, V : ndarray, shape (..., 2)
        Positions [m] and velocities [m/s].

    Examples
    --------
    >>> X, V = drive_states(0.5, 0.0, 1e-4, 100.0)      # the journal at rest
    >>> X.tolist(), V.round(12).tolist()
    ([0.0, 5e-05], [0.0, 0.0])
    """
    e, a = np.broadcast_arrays(np.asarray(eps, dtype=float), np.asarray(alpha, dtype=float))
    cw = clearance * omega
    X = np.stack([np.zeros_like(e), e * clearance], axis=-1)
    V = np.stack([0.5 * (e - np.cos(a)) * cw, 0.5 * np.sin(a) * cw], axis=-1)
    return X, V


def dimensionless_forces(solver: ReynoldsSolver, eps, alpha) -> np.ndarray:
    """G = (G_r, G_t) of ``solver``'s bearing at (eps, alpha): the film force at unit drive over
    mu omega R L (R/c)^2, along and across the line of centres (+X2 and +X1 for these states).

    Parameters
    ----------
    solver : ReynoldsSolver
        The reference model of a bearing without supply pressure.
    eps, alpha : array_like
        Eccentricity ratios and drive directions [rad], broadcast together.

    Returns
    -------
    ndarray, shape (..., 2)

    Examples
    --------
    >>> s = ReynoldsSolver(canonical_bearing(1.0), 48, 16)
    >>> G = dimensionless_forces(s, 0.5, 0.0)             # at rest: load along the line of centres and across
    >>> bool(G[0] > 0), bool(G[1] < 0)
    (True, True)
    """
    b = solver.bearing
    X, V = drive_states(eps, alpha, b.clearance, b.omega)
    F = solver.forces(X, V) / b.force_scale
    # e_r = +X2, e_t = (e_r2, -e_r1) = +X1
    return np.stack([F[..., 1], F[..., 0]], axis=-1)


def _n_z(n_theta: int, slenderness: float) -> int:
    """Axial nodes for a circumferential count: about square cells (dz = R dtheta), at least n_theta / 6
    (a short bearing's axial profile is refined with the ladder too), odd (a node at mid-length)."""
    n = max(n_theta // 6, int(round(n_theta * 2.0 * slenderness / (2.0 * math.pi))) + 1)
    return n + (1 - n % 2)


def converged_grid(slenderness: float, cavitation: str, eps: float, tol: float,
                   n_alpha: int = 8) -> tuple[int, int, float]:
    """The coarsest grid of the ladder (``N_THETA_LADDER``, square cells) whose forces at ``eps`` and
    ``n_alpha`` drive directions differ from the next finer grid's by less than ``tol`` (max over
    directions of |dG| / |G|).

    Parameters
    ----------
    slenderness : float
        L/D.
    cavitation : {"gumbel", "swift-stieber"}
        Cavitation rule.
    eps : float
        The eccentricity of the check (the largest of the dataset: the hardest).
    tol : float
        Relative tolerance.
    n_alpha : int, default 8
        Drive directions checked.

    Returns
    -------
    (n_theta, n_z, change)
        The grid and its measured relative change to the next finer one (the finest pair of the ladder
        when none meets ``tol``).

    Examples
    --------
    >>> n_theta, n_z, change = converged_grid(0.5, "gumbel", 0.5, 0.05, n_alpha=2)
    >>> n_theta in N_THETA_LADDER, change < 0.05
    (True, True)
    """
    b = canonical_bearing(slenderness)
    alpha = np.linspace(0.0, 2.0 * math.pi, n_alpha, endpoint=False)
    prev = None
    for k, nt in enumerate(N_THETA_LADDER):
        G = dimensionless_forces(ReynoldsSolver(b, nt, _n_z(nt, slenderness), cavitation=cavitation), eps, alpha)
        if prev is not None:
            change = float((np.hypot(*(G - prev[2]).T) / np.hypot(*G.T)).max())
            if change < tol or k == len(N_THETA_LADDER) - 1:
                return prev[0], prev[1], change
        prev = (nt, _n_z(nt, slenderness), G)
    raise AssertionError("unreachable")  # pragma: no cover


@dataclass(frozen=True)
class UniversalSpec:
    """Layout of the dimensionless dataset.

    Parameters
    ----------
    ld_min, ld_max : float
        The L/D range; ``n_ld`` values geometric in between (denser at short bearings).
    n_ld : int
        L/D values.
    eps_max : float
        The largest eccentricity ratio.
    n_eps : int
        Eccentricity values eps_max sin(pi/2 k/n), k = 1..n (denser towards eps_max), and eps = 0.02.
    n_alpha : int
        Drive directions, uniform over [0, 2 pi).
    grid_tol : float
        Tolerance of the per-L/D grid convergence check (``converged_grid``), made at ``eps_split`` for the
        rows up to it and at ``eps_max`` for the rows above.
    eps_split : float
        Where the coarser grid of the lower eccentricities ends.
    cavitation : tuple of str
        The cavitation rules.

    Examples
    --------
    >>> s = UniversalSpec(n_ld=3, n_eps=4, n_alpha=8)
    >>> s.ld_values().round(3).tolist(), s.n_samples
    ([0.2, 0.632, 2.0], 360)
    """

    ld_min: float = 0.2
    ld_max: float = 2.0
    n_ld: int = 14
    eps_max: float = 0.95
    n_eps: int = 24
    n_alpha: int = 48
    grid_tol: float = 2e-3
    eps_split: float = 0.8
    cavitation: tuple = UNIVERSAL_CAVITATION

    def __post_init__(self):
        if not 0.0 < self.ld_min < self.ld_max:
            raise ValueError(f"need 0 < ld_min < ld_max, got ld_min={self.ld_min!r}, ld_max={self.ld_max!r}")
        if not 0.0 < self.eps_max < 1.0:
            raise ValueError(f"eps_max must lie in (0, 1), got {self.eps_max!r}")
        for name in ("n_ld", "n_eps", "n_alpha"):
            if int(getattr(self, name)) < 2:
                raise ValueError(f"{name} must be an integer >= 2, got {getattr(self, name)!r}")
        if not self.grid_tol > 0.0:
            raise ValueError(f"grid_tol must be > 0, got {self.grid_tol!r}")
        object.__setattr__(self, "cavitation", tuple(self.cavitation))
        bad = [c for c in self.cavitation if c not in UNIVERSAL_CAVITATION]
        if bad or not self.cavitation:
            raise ValueError(f"cavitation must list some of {UNIVERSAL_CAVITATION}, got {self.cavitation!r}")

    def ld_values(self) -> np.ndarray:
        return np.geomspace(self.ld_min, self.ld_max, int(self.n_ld))

    def eps_values(self) -> np.ndarray:
        k = np.arange(1, int(self.n_eps) + 1)
        return np.concatenate([[0.02], self.eps_max * np.sin(0.5 * np.pi * k / int(self.n_eps))])

    def alpha_values(self) -> np.ndarray:
        return np.linspace(0.0, 2.0 * np.pi, int(self.n_alpha), endpoint=False)

    @property
    def n_samples(self) -> int:
        return len(self.cavitation) * int(self.n_ld) * (int(self.n_eps) + 1) * int(self.n_alpha)

    @classmethod
    def from_cfg(cls, cfg) -> "UniversalSpec":
        """From a mapping (a config node); unknown keys are refused, naming them."""
        known = set(cls.__dataclass_fields__)
        extra = sorted(set(cfg) - known)
        if extra:
            raise ValueError(f"unknown universal dataset keys {extra}; known: {sorted(known)}")
        kwargs: dict[str, Any] = {k: (tuple(cfg[k]) if k == "cavitation" else cfg[k]) for k in cfg}
        return cls(**kwargs)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["cavitation"] = list(self.cavitation)
        return d


def _compute_row(job: dict) -> dict:
    """One part: every eps of a band and every direction at one (cavitation, L/D) on its grid (runs on a Dask worker)."""
    import numba

    numba.set_num_threads(1)
    ld, cav = job["ld"], job["cavitation"]
    solver = ReynoldsSolver(canonical_bearing(ld), job["n_theta"], job["n_z"], cavitation=cav)
    eps = np.asarray(job["eps"])
    alpha = np.asarray(job["alpha"])
    E, A = np.meshgrid(eps, alpha, indexing="ij")
    E, A = E.ravel(), A.ravel()
    G = dimensionless_forces(solver, E, A)
    h = DERIVATIVE_STEP
    dG_deps = (dimensionless_forces(solver, E + h, A) - dimensionless_forces(solver, E - h, A)) / (2.0 * h)
    dG_dalpha = (dimensionless_forces(solver, E, A + h) - dimensionless_forces(solver, E, A - h)) / (2.0 * h)
    n = G.shape[0]
    return {"index": job["index"], "columns": {
        "ld": np.full(n, ld), "eps": E, "alpha": A, "G_r": G[:, 0], "G_t": G[:, 1],
        "dG_r_deps": dG_deps[:, 0], "dG_t_deps": dG_deps[:, 1],
        "dG_r_dalpha": dG_dalpha[:, 0], "dG_t_dalpha": dG_dalpha[:, 1],
        "cavitation": np.full(n, UNIVERSAL_CAVITATION.index(cav), dtype=np.int8),
        "n_theta": np.full(n, job["n_theta"], dtype=np.int16), "n_z": np.full(n, job["n_z"], dtype=np.int16)}}


def _write(path: Path, cols: dict) -> str:
    with io.atomic_path(path, suffix=".parquet") as tmp:
        pq.write_table(pa.table(cols), tmp, compression="zstd")
        digest = io.file_sha256(tmp)
    return digest


def _bands(spec: UniversalSpec) -> list[tuple[float, np.ndarray]]:
    """(eps of the grid check, the eccentricities of the band) for the two bands."""
    eps = spec.eps_values()
    low = eps[eps <= spec.eps_split]
    bands = [(float(spec.eps_split), low), (float(spec.eps_max), eps[eps > spec.eps_split])]
    return [(e, band) for e, band in bands if len(band)]


def _grids(spec: UniversalSpec, out: Path, progress: bool) -> dict:
    """The converged grid per (cavitation, L/D, band), cached in ``_grids.json`` (the check is itself work)."""
    path = out / "_grids.json"
    grids = json.loads(path.read_text()) if path.exists() else {}
    for cav in spec.cavitation:
        for ld in spec.ld_values():
            for eps_check, _ in _bands(spec):
                key = f"{cav}:{ld:.6f}:{eps_check:.4f}"
                if key not in grids:
                    nt, nz, change = converged_grid(float(ld), cav, eps_check, spec.grid_tol)
                    grids[key] = {"n_theta": nt, "n_z": nz, "change": change}
                    io.write_json(path, grids)
                    if progress:
                        print(f"  grid {cav} L/D={ld:.3f} eps={eps_check:g}: {nt} x {nz} (change to the next "
                              f"finer {change:.2e})", flush=True)
    return grids


def generate_universal(spec: UniversalSpec, out_dir, *, scheduler: str = "local", n_workers: int | None = None,
                       progress: bool = True) -> dict:
    """Generate (or finish, or repair) the dimensionless dataset in ``out_dir``; return its metadata.

    Parameters
    ----------
    spec : UniversalSpec
        The layout.
    out_dir : path-like
        The dataset's folder; parts of another layout there are deleted first.
    scheduler : str, default "local"
        "local" (an embedded Dask cluster), "inline" (no Dask) or a Dask scheduler address.
    n_workers : int or None, default None
        Workers of the local cluster.
    progress : bool, default True
        Print progress.

    Returns
    -------
    dict
        The metadata (also in ``_metadata.json``), with ``seconds_this_run``.

    Examples
    --------
    >>> import tempfile
    >>> spec = UniversalSpec(n_ld=2, n_eps=2, n_alpha=4, grid_tol=0.05, cavitation=("gumbel",))
    >>> meta = generate_universal(spec, tempfile.mkdtemp() + "/u", scheduler="inline", progress=False)
    >>> meta["n_samples"], len(meta["parts"])
    (24, 4)
    """
    from fluidfilm.data.generate import _damaged_parts, _dask_client, _prepare_dir

    out = Path(out_dir)
    digest = config_hash(FORMAT_VERSION, spec.to_dict())
    state = _prepare_dir(out, digest)
    t0 = time.perf_counter()
    grids = _grids(spec, out, progress)
    jobs: list[Any] = []
    for cav in spec.cavitation:
        for ld in spec.ld_values():
            for eps_check, eps in _bands(spec):
                g = grids[f"{cav}:{ld:.6f}:{eps_check:.4f}"]
                jobs.append({"index": len(jobs), "ld": float(ld), "cavitation": cav, "n_theta": g["n_theta"],
                             "n_z": g["n_z"], "eps": eps.tolist(), "alpha": spec.alpha_values().tolist()})
    for name in _damaged_parts(out, state):
        print(f"{out / name}: no recorded checksum or a damaged one; recomputed", flush=True)
        (out / name).unlink()
        state["parts"].pop(name, None)
    meta_path = out / "_metadata.json"
    pending = [j for j in jobs if not (out / part_name(j["index"])).exists()]
    if pending and meta_path.exists():
        meta_path.unlink()
    spent = float(state["seconds_spent"])

    def store(res):
        name = part_name(res["index"])
        state["parts"][name] = _write(out / name, res["columns"])
        state["seconds_spent"] = spent + time.perf_counter() - t0
        io.write_json(out / "_state.json", state)
        if progress:
            print(f"  {len(state['parts'])}/{len(jobs)} parts", flush=True)

    # the slow ones (Swift-Stieber, long bearings: fine grids) first, so the workers finish together
    pending.sort(key=lambda j: -(j["n_theta"] * j["n_z"] * (4 if j["cavitation"] == "swift-stieber" else 1)))
    if scheduler == "inline":
        for job in pending:
            store(_compute_row(job))
    elif pending:
        from dask.distributed import as_completed

        with _dask_client(scheduler, n_workers) as client:
            futures = client.map(_compute_row, pending, pure=False)
            for fut in as_completed(futures):
                store(fut.result())
    if pending or not meta_path.exists():
        n = sum(pq.ParquetFile(out / part_name(j["index"])).metadata.num_rows for j in jobs)
        meta = {"n_samples": int(n), "config_hash": digest, "format_version": FORMAT_VERSION,
                "fluidfilm_version": __version__, "spec": spec.to_dict(), "grids": grids,
                "generation_seconds_total": float(state["seconds_spent"]),
                "parts": {part_name(j["index"]): state["parts"][part_name(j["index"])] for j in jobs}}
        io.write_json(meta_path, meta)
    meta = json.loads(meta_path.read_text())
    return {**meta, "seconds_this_run": time.perf_counter() - t0}


def load_universal(path, cavitation: str | None = None) -> tuple[pd.DataFrame, dict]:
    """The rows of a complete, verified dataset (checksums checked first), optionally of one cavitation rule.

    Parameters
    ----------
    path : path-like
        The dataset's folder.
    cavitation : str or None, default None
        Keep only this rule's rows.

    Returns
    -------
    (DataFrame, dict)
        The rows and the metadata.
    """
    meta = verify_dataset(path)
    frame = pd.concat([pd.read_parquet(Path(path) / name) for name in sorted(meta["parts"])], ignore_index=True)
    if cavitation is not None:
        if cavitation not in UNIVERSAL_CAVITATION:
            raise ValueError(f"unknown cavitation {cavitation!r}; choose one of {UNIVERSAL_CAVITATION}")
        frame = frame[frame["cavitation"] == UNIVERSAL_CAVITATION.index(cavitation)].reset_index(drop=True)
    return frame, meta
