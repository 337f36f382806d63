"""Generate the graded force dataset and the held-out random test set.

Work is split into chunks of grid positions.  Each chunk is one Dask task:
a Dask ``distributed`` cluster when a scheduler address is given, an
embedded ``LocalCluster`` (one single-threaded worker process per core) by
default, or ``scheduler="inline"`` to run in this process without Dask
(debugging, tests).  A task returns its rows; the client writes each chunk
as ``part-NNNNN.parquet`` atomically (temporary file + rename), so

- an interrupted run (Ctrl-C, kill, crash) leaves only complete part files,
  and running again computes only the missing chunks;
- ``_state.json`` records the hash of everything that determines the data
  (bearing, reference grid policy, dataset layout, format); a run with a
  different hash deletes the old parts instead of mixing them;
- ``_metadata.json`` is written last, so its presence means the dataset is
  complete.

With ``sleeve_positions`` (an active conical bearing) every chunk is
computed at every sleeve position, the eccentricity grid taken relative
to that position's clearance c_r(s), and a column ``S`` holds the sleeve
displacement [m].

Within a chunk, positions sharing a velocity section and a grid are solved
together: one factorisation per position serves all its velocities (the
pressure is linear in the velocity before cavitation).  Results do not
depend on how the work is scheduled: the same config gives bit-identical
forces.
"""
from __future__ import annotations

import contextlib
import functools
import json
import os
import shutil
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from fluidfilm import __version__, io
from fluidfilm.core.bearing import JournalBearing, bearing_from_dict
from fluidfilm.reynolds import GradedReynoldsModel
from fluidfilm.data.schema import COLUMNS, file_sha256, part_name, write_part
from fluidfilm.data.spec import DatasetSpec, check_reference, config_hash, example_spec

# 2: the centre (eps = 0) once instead of once per angle; per-part checksums in the manifest
FORMAT_VERSION = 2


@functools.lru_cache(maxsize=4)
def _reference(bearing_json: str, reference_json: str) -> GradedReynoldsModel:
    """Reference model, built once per process (workers reuse it across chunks)."""
    b = bearing_from_dict(json.loads(bearing_json))
    r = json.loads(reference_json)
    return GradedReynoldsModel(b, coarse=tuple(r["coarse"]), dense=tuple(r["dense"]),
                               eps_threshold=r["eps_threshold"], cavitation=r.get("cavitation", "gumbel"))


def compute_chunk(job: dict) -> dict:
    """Rows of one chunk of grid positions (runs on a worker; plain data in, arrays out)."""
    if job.get("numba_threads"):
        import numba

        numba.set_num_threads(int(job["numba_threads"]))
    model = _reference(job["bearing"], job["reference"])
    spec: DatasetSpec = job["spec"]
    if not spec.sleeve_positions:
        return {"index": job["index"], "columns": _chunk_at(model, spec, job)}
    parts = []
    for s in spec.sleeve_positions:
        model.set_sleeve(s)
        cols = _chunk_at(model, spec, job)
        cols["S"] = np.full(len(cols["X1"]), s)
        parts.append(cols)
    return {"index": job["index"], "columns": {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}}


def _chunk_at(model, spec: DatasetSpec, job: dict) -> dict:
    """Rows of one chunk at the model's current setting (eccentricities relative to its clearance)."""
    c = model.clearance
    x_all, sec_all, eps_all = spec.positions(c)
    x = x_all[job["start"]:job["stop"]]
    sec = sec_all[job["start"]:job["stop"]]
    eps = eps_all[job["start"]:job["stop"]]
    vsec = np.array([spec.velocity_section_index(e) for e in eps])
    pairs = {k: spec.velocity_pairs(k) for k in set(vsec.tolist())}
    forces: list[np.ndarray] = [np.empty(0)] * len(x)
    # positions sharing a velocity section: one batched product call (each on its grid)
    for k in pairs:
        idx = np.flatnonzero(vsec == k)
        F = model.forces_product(x[idx], pairs[k], eps=eps[idx])
        for j, row in enumerate(idx):
            forces[row] = F[j]
    grid_theta, grid_z = model.grid_for(eps)
    cols: dict[str, list[np.ndarray]] = {name: [] for name in COLUMNS}
    for i in range(len(x)):
        V = pairs[int(vsec[i])]
        n = len(V)
        cols["X1"].append(np.full(n, x[i, 0]))
        cols["X2"].append(np.full(n, x[i, 1]))
        cols["V1"].append(V[:, 0])
        cols["V2"].append(V[:, 1])
        cols["F1"].append(forces[i][:, 0])
        cols["F2"].append(forces[i][:, 1])
        cols["eps"].append(np.full(n, eps[i]))
        cols["section"].append(np.full(n, sec[i], dtype=np.int8))
        cols["n_theta"].append(np.full(n, grid_theta[i], dtype=np.int16))
        cols["n_z"].append(np.full(n, grid_z[i], dtype=np.int16))
    return {k: np.concatenate(v) for k, v in cols.items()}


# the schema module writes the files and checks them (kept under the old names for callers of this module)
_write_part = write_part
_part_name = part_name


def _read_state(out: Path) -> dict | None:
    state = out / "_state.json"
    try:
        return json.loads(state.read_text()) if state.exists() else None
    except (json.JSONDecodeError, UnicodeDecodeError):
        return None  # a damaged state file: the parts cannot be trusted


def _staging_dir(out: Path) -> Path:
    return out.with_name(f".{out.name}.new")


def _choose_dir(out: Path, digest: str) -> Path:
    """Where to build: ``out`` itself, unless it holds a finished dataset of another config.

    A finished dataset is never deleted before its replacement is complete:
    a new config is built next to it (``.<name>.new``, resumable) and swapped
    in at the end (``_swap_in``).
    """
    old = out.with_name(f".{out.name}.old")
    if old.exists():  # a swap was interrupted between its two renames
        if out.exists():
            shutil.rmtree(old)
        else:
            old.rename(out)
    state = _read_state(out)
    if (out / "_metadata.json").exists() and (state is None or state.get("hash") != digest):
        return _staging_dir(out)
    stale = _staging_dir(out)
    if stale.exists():  # the config went back to the finished one: the half-built other one is void
        shutil.rmtree(stale)
    return out


def _swap_in(work: Path, out: Path) -> None:
    if work == out:
        return
    old = out.with_name(f".{out.name}.old")
    if out.exists():
        shutil.rmtree(old, ignore_errors=True)
        out.rename(old)
    work.rename(out)
    shutil.rmtree(old, ignore_errors=True)


def _prepare_dir(out: Path, digest: str) -> dict:
    """Create ``out``; drop temporary leftovers; drop parts made under another config; return the state."""
    out.mkdir(parents=True, exist_ok=True)
    io.remove_temporaries(out, ".part-*")
    state = _read_state(out)
    if state is None or state.get("hash") != digest:
        for f in list(out.glob("part-*.parquet")) + [out / "_metadata.json"]:
            with contextlib.suppress(FileNotFoundError):
                f.unlink()
        state = {"hash": digest, "parts": {}, "seconds_spent": 0.0}
        io.write_json(out / "_state.json", state)
    state.setdefault("parts", {})
    state.setdefault("seconds_spent", 0.0)
    return state


def _damaged_parts(out: Path, state: dict) -> list[str]:
    """Parts on disk whose bytes do not match the checksum recorded when they were written."""
    bad = []
    for f in sorted(out.glob("part-*.parquet")):
        recorded = state["parts"].get(f.name)
        if recorded is None or file_sha256(f) != recorded:
            bad.append(f.name)
    return bad


@contextlib.contextmanager
def _workers_ignore_sigint():
    """Start processes that ignore SIGINT: a terminal's Ctrl-C reaches the whole process group, and each
    Dask worker would print its own KeyboardInterrupt tracebacks while this process, which closes the
    cluster itself, prints the one line that matters.  An ignored SIGINT survives the workers' spawn (a
    handler would not); this process ignores it only while the cluster starts."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


@contextlib.contextmanager
def _dask_client(scheduler: str, n_workers: int | None):
    import logging

    from dask.distributed import Client, LocalCluster

    # the scheduler's INFO chatter would bury the progress bar
    for name in ("distributed", "distributed.scheduler", "distributed.nanny", "distributed.worker", "tornado"):
        logging.getLogger(name).setLevel(logging.WARNING)
    if scheduler == "local":
        n = n_workers or os.cpu_count() or 1
        with _workers_ignore_sigint():
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
        with cluster, Client(cluster) as client:
            yield client
    else:
        with Client(scheduler) as client:
            yield client


def dataset_digest(bearing: JournalBearing, reference: dict, spec: DatasetSpec) -> str:
    """The dataset's identity: format, bearing, reference grid policy and layout (``config_hash`` in its
    metadata; the key of the grading study's dataset cache)."""
    return config_hash(FORMAT_VERSION, bearing.to_dict(), dict(reference), spec.to_dict())


def generate_dataset(bearing: JournalBearing, reference: dict, spec: DatasetSpec, out_dir, *,
                     scheduler: str = "local", n_workers: int | None = None, progress: bool = True,
                     config: dict | None = None) -> dict:
    """Generate (or finish, or repair) the grid dataset in ``out_dir``; returns its metadata.

    ``reference``: the grid policy {coarse, dense, eps_threshold, cavitation}.
    ``scheduler``: "local" (embedded LocalCluster), "inline" (no Dask) or a
    Dask scheduler address such as "tcp://10.0.0.5:8786".

    Every part's SHA-256 is recorded as it is written (``_state.json``) and
    listed in ``_metadata.json``; a rerun recomputes parts that are missing
    or whose bytes no longer match (and says so).  The returned dict adds
    what this call did: ``seconds_this_run``, ``chunks_computed_this_run``,
    ``damaged_parts_recomputed``.

    Parameters
    ----------
    bearing : JournalBearing
        The bearing (a ``ConicalBearing`` with the spec's ``sleeve_positions``).
    reference : dict
        The grid policy {coarse, dense, eps_threshold, cavitation} (``GradedReynoldsModel``).
    spec : DatasetSpec
        The layout.
    out_dir : path-like
        The dataset's folder (created; an existing one of another config is refused).
    scheduler : str, default "local"
        "local", "inline" or a Dask scheduler address.
    n_workers : int or None, default None
        Workers of the local cluster (None: Dask's default).
    progress : bool, default True
        Show a progress bar.
    config : dict or None, default None
        The config to record in the metadata (and hash).

    Returns
    -------
    dict
        The metadata (``read_metadata``) plus what this call did.

    Examples
    --------
    >>> import shutil, tempfile
    >>> from fluidfilm import paper_bearing
    >>> from fluidfilm.data import example_spec, generate_dataset
    >>> reference = {"coarse": [16, 8], "dense": [16, 8], "eps_threshold": 0.9, "cavitation": "gumbel"}
    >>> tmp = tempfile.mkdtemp()
    >>> meta = generate_dataset(paper_bearing(), reference, example_spec(), f"{tmp}/ds", scheduler="inline", progress=False)
    >>> meta["n_samples"], meta["chunks_computed_this_run"]
    (128, 1)
    >>> shutil.rmtree(tmp)
    """
    out = Path(out_dir)
    # the whole config is checked (and the model built) before anything on disk is touched
    check_reference(reference)
    _reference(json.dumps(bearing.to_dict(), sort_keys=True), json.dumps(dict(reference), sort_keys=True))
    digest = dataset_digest(bearing, reference, spec)
    work = _choose_dir(out, digest)
    state = _prepare_dir(work, digest)
    c = bearing.clearance
    n_pos = len(spec.positions(c)[0])
    step = spec.positions_per_chunk
    bearing_json = json.dumps(bearing.to_dict(), sort_keys=True)
    reference_json = json.dumps(dict(reference), sort_keys=True)
    jobs: list[dict] = [{"index": i, "start": s, "stop": min(s + step, n_pos), "spec": spec, "bearing": bearing_json,
             "reference": reference_json} for i, s in enumerate(range(0, n_pos, step))]
    damaged = _damaged_parts(work, state)
    if damaged:
        print(f"{len(damaged)} part file(s) in {work} have no recorded checksum or do not match it, and are recomputed: "
              f"{', '.join(damaged[:5])}{' ...' if len(damaged) > 5 else ''}", flush=True)
        for name in damaged:
            (work / name).unlink()
            state["parts"].pop(name, None)
    meta_path = work / "_metadata.json"
    pending = [j for j in jobs if not (work / _part_name(j["index"])).exists()]
    if pending and meta_path.exists():
        meta_path.unlink()  # metadata means complete and verified; it is not, until the parts are back
    t0 = time.perf_counter()
    spent_before = float(state["seconds_spent"])
    if pending:
        try:
            _run_jobs(pending, work, scheduler, n_workers, progress, state, t0, spent_before)
        except BaseException:
            # an interrupt that lands as a part's temporary file is handed over escapes atomic_path's own
            # cleanup; this directory has one writer, so its temporaries can go (complete parts or none)
            io.remove_temporaries(work, ".part-*")
            raise
    elapsed = time.perf_counter() - t0
    this_run = {"seconds_this_run": elapsed, "chunks_computed_this_run": len(pending),
                "damaged_parts_recomputed": damaged}
    if meta_path.exists() and not pending:
        _swap_in(work, out)
        return {**json.loads((out / "_metadata.json").read_text()), **this_run}
    n_rows = sum(pq.ParquetFile(work / _part_name(j["index"])).metadata.num_rows for j in jobs)
    columns = (["S"] if spec.sleeve_positions else []) + list(COLUMNS)
    parts = {_part_name(j["index"]): state["parts"][_part_name(j["index"])] for j in jobs}
    meta = {"n_samples": int(n_rows), "n_positions": n_pos, "n_chunks": len(jobs), "config_hash": digest,
            "fluidfilm_version": __version__, "format_version": FORMAT_VERSION, "columns": columns,
            "sleeve_positions": list(spec.sleeve_positions),
            "bearing": bearing.to_dict(), "reference": dict(reference), "spec": spec.to_dict(),
            "config": config or {}, "generation_seconds_last_run": elapsed,
            # wall time over every run that contributed parts (interrupted ones included)
            "generation_seconds_total": spent_before + elapsed,
            "chunks_computed_last_run": len(pending), "scheduler": scheduler, "parts": parts}
    io.write_json(meta_path, meta)
    _swap_in(work, out)
    return {**meta, **this_run}


def _run_jobs(jobs: list, out: Path, scheduler: str, n_workers: int | None, progress: bool,
              state: dict, t0: float, spent_before: float) -> None:
    from fluidfilm.progress import ProgressLog

    bar = ProgressLog(len(jobs), f"dataset parts ({out.name})", enabled=progress)

    def store(res):
        name = _part_name(res["index"])
        state["parts"][name] = _write_part(out / name, res["columns"])
        state["seconds_spent"] = spent_before + time.perf_counter() - t0
        # the checksum is recorded after the part: a crash in between only costs recomputing that part
        io.write_json(out / "_state.json", state)
        bar.update()

    if scheduler == "inline":
        for job in jobs:
            store(compute_chunk(job))
        return
    from dask.distributed import as_completed

    with _dask_client(scheduler, n_workers) as client:
        for job in jobs:
            job["numba_threads"] = 1  # one single-threaded worker per core
        futures = client.map(compute_chunk, jobs, pure=False)
        try:
            for fut in as_completed(futures):
                store(fut.result())
        except BaseException:
            client.cancel(futures)
            raise


def random_test_set(bearing: JournalBearing, reference: dict, spec: DatasetSpec, out_dir, n: int | None = None,
                    seed: int | None = None) -> dict:
    """Held-out test set: states drawn at random (not on the grid) over the dataset's domain.

    Each position section gets an equal share of the samples: eps uniform in
    the section's range, angle uniform, each velocity component uniform in
    +-v_max of the velocity section at that eps.  With sleeve positions, each
    sample's sleeve position is one of 33 levels spanning the grid's (most of
    them between the training levels) and eps is relative to its clearance.
    Forces from the same reference model and grid policy.  Written
    atomically as one part file.

    Parameters
    ----------
    bearing : JournalBearing
        The bearing.
    reference : dict
        The grid policy {coarse, dense, eps_threshold, cavitation}.
    spec : DatasetSpec
        The dataset's layout (its domain).
    out_dir : path-like
        The test set's folder.
    n : int or None, default None
        Number of states (None: ``spec.n_test``).
    seed : int or None, default None
        Random seed (None: ``spec.test_seed``).

    Returns
    -------
    dict
        The test set's metadata (columns, number of samples, seed, checksums).

    Examples
    --------
    >>> import shutil, tempfile
    >>> from fluidfilm import paper_bearing
    >>> from fluidfilm.data import example_spec, random_test_set
    >>> reference = {"coarse": [16, 8], "dense": [16, 8], "eps_threshold": 0.9, "cavitation": "gumbel"}
    >>> tmp = tempfile.mkdtemp()
    >>> random_test_set(paper_bearing(), reference, example_spec(), f"{tmp}/test", n=20)["n_samples"]
    20
    >>> shutil.rmtree(tmp)
    """
    n = spec.n_test if n is None else int(n)
    seed = spec.test_seed if seed is None else int(seed)
    rng = np.random.default_rng(seed)
    model = _reference(json.dumps(bearing.to_dict(), sort_keys=True), json.dumps(dict(reference), sort_keys=True))
    if spec.sleeve_positions:
        # an active bearing: each sample at a sleeve position drawn from levels spanning the grid's
        levels = np.linspace(min(spec.sleeve_positions), max(spec.sleeve_positions), N_TEST_SLEEVES)
        s_all = levels[rng.integers(0, N_TEST_SLEEVES, n)]
        settings = [(s, int(np.count_nonzero(s_all == s))) for s in levels]
        keep = model.sleeve
    else:
        settings = [(None, n)]
    parts = []
    try:
        for s, count in settings:
            if not count:
                continue
            if s is not None:
                model.set_sleeve(s)
            x, v, eps, k_sec = _random_states(spec, model.clearance, count, rng)
            F = model.forces(x, v)
            n_theta, n_z = model.grid_for(eps)
            cols = {"X1": x[:, 0], "X2": x[:, 1], "V1": v[:, 0], "V2": v[:, 1], "F1": F[:, 0], "F2": F[:, 1],
                    "eps": eps, "section": k_sec, "n_theta": n_theta, "n_z": n_z}
            parts.append(cols if s is None else {"S": np.full(count, s), **cols})
    finally:
        if spec.sleeve_positions:
            model.set_sleeve(keep)
    cols = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    return _write_test_set(out_dir, cols, n, seed, bearing, reference, spec)


N_TEST_SLEEVES = 33  # sleeve levels of the test set: between the grid's, so the test checks interpolation in s


def example_dataset(out_dir, test_set: bool = False) -> Path:
    """The ``example_spec`` dataset of ``paper_bearing()`` (16 x 8 reference grid), for examples and smoke runs.

    Parameters
    ----------
    out_dir : path-like
        Folder to write (as ``generate_dataset``, inline: no Dask cluster).
    test_set : bool, default False
        Write the random test set of the layout (``random_test_set``, 10 states) instead.

    Returns
    -------
    pathlib.Path
        ``out_dir``.

    Examples
    --------
    >>> import shutil, tempfile
    >>> from fluidfilm.data import example_dataset, read_metadata
    >>> folder = example_dataset(tempfile.mkdtemp())
    >>> read_metadata(folder)["reference"]["coarse"]
    [16, 8]
    >>> shutil.rmtree(folder)
    """
    from fluidfilm.core.bearing import paper_bearing

    reference = {"coarse": [16, 8], "dense": [16, 8], "eps_threshold": 0.9, "cavitation": "gumbel"}
    if test_set:
        random_test_set(paper_bearing(), reference, example_spec(), out_dir)
    else:
        generate_dataset(paper_bearing(), reference, example_spec(), out_dir, scheduler="inline", progress=False)
    return Path(out_dir)


def _random_states(spec: DatasetSpec, c: float, n: int, rng):
    k_sec = np.arange(n) % len(spec.position_sections)
    lo = np.array([spec.position_sections[k].eps_start for k in k_sec])
    hi = np.array([spec.position_sections[k].eps_stop for k in k_sec])
    eps = lo + (hi - lo) * rng.random(n)
    ang = 2 * np.pi * rng.random(n)
    x = c * np.stack([eps * np.sin(ang), eps * np.cos(ang)], axis=1)
    vmax = np.array([spec.velocity_sections[spec.velocity_section_index(e)].v_max for e in eps])
    v = vmax[:, None] * (2 * rng.random((n, 2)) - 1)
    return x, v, eps, k_sec


def _write_test_set(out_dir, cols, n, seed, bearing, reference, spec) -> dict:
    # written next to the old one and swapped in complete, like the dataset
    out = Path(out_dir)
    work = _staging_dir(out)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    name = _part_name(0)
    digest = _write_part(work / name, cols)
    meta = {"n_samples": n, "seed": seed, "fluidfilm_version": __version__, "columns": list(cols),
            "config_hash": config_hash(FORMAT_VERSION, bearing.to_dict(), dict(reference), spec.to_dict(), n, seed),
            "parts": {name: digest}}
    io.write_json(work / "_metadata.json", meta)
    _swap_in(work, out)
    return meta
