"""Issue 51, item 5e: the generated surrogate kernels are written as modules into a cache folder and imported
with numba's ``cache=True``, so a new process loads them instead of compiling them; the forces are the bits of
the kernels compiled from the source in the process (``FLUIDFILM_KERNEL_CACHE=off``, the former route)."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from fluidfilm import paper_bearing
from fluidfilm.perf.speed import best_shaped_surrogate
from fluidfilm.surrogate import kernels

ROOT = Path(__file__).resolve().parents[2]

# one process's forces: the best-shaped surrogate's batched kernel (float32 networks, what simulate_batch runs)
# and its one-state kernel, on fixed states; the numba cache statistics of both
_PROBE = r"""
import json, sys
import numpy as np
from fluidfilm import paper_bearing
from fluidfilm.perf.speed import best_shaped_surrogate, sample_states
from fluidfilm.surrogate import kernels
model = best_shaped_surrogate(paper_bearing())
X, V = sample_states(model.clearance, n=700, eps_max=0.93, v_max=0.1, seed=3)
fn, bp = model.batch_force_kernel("float32")
out = np.zeros((len(X), 2))
fn(bp, np.ascontiguousarray(X), np.ascontiguousarray(V), out)
one, w = kernels.fast_force_kernel(model)
single = np.array([one(w, *x, *v) for x, v in zip(X, V)])
np.save(sys.argv[1], np.concatenate([out, single], axis=1))
print(json.dumps({"hits": sum(fn.stats.cache_hits.values()) + sum(one.stats.cache_hits.values()),
                  "misses": sum(fn.stats.cache_misses.values()) + sum(one.stats.cache_misses.values()),
                  "files": sorted(str(p) for p in kernels.kernel_files.values() if p is not None),
                  "count": int(model.n_outside_domain)}))
"""


def _probe(tmp_path: Path, cache: str, name: str) -> tuple[np.ndarray, dict]:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), kernels.KERNEL_CACHE_ENV: cache}
    out = tmp_path / f"{name}.npy"
    proc = subprocess.run([sys.executable, "-W", "error::UserWarning", "-c", _PROBE, str(out)], cwd=tmp_path,
                          env=env, capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return np.load(out), json.loads(proc.stdout.strip().splitlines()[-1])


def test_a_second_process_loads_the_cached_kernels_and_gets_the_same_bits(tmp_path):
    cache = tmp_path / "kernels"
    off, off_stats = _probe(tmp_path, "off", "off")              # compiled from the source in the process
    cold, cold_stats = _probe(tmp_path, str(cache), "cold")      # writes the modules, numba compiles and caches
    warm, warm_stats = _probe(tmp_path, str(cache), "warm")      # a new process: loaded from the cache
    assert off_stats["files"] == [] and off_stats["hits"] == 0  # compiled, nothing from a cache
    assert cold_stats["misses"] >= 2 and cold_stats["hits"] == 0
    assert warm_stats["hits"] >= 2 and warm_stats["misses"] == 0   # nothing compiled in the second process
    assert warm_stats["files"] == cold_stats["files"] and len(cold_stats["files"]) == 2
    assert all(Path(f).parent == cache and Path(f).name.startswith(("batch_", "state_")) for f in warm_stats["files"])
    assert np.array_equal(cold, off) and np.array_equal(warm, off)  # bit for bit, batched and one-state
    assert warm_stats["count"] == off_stats["count"]


def test_the_module_text_names_its_dependencies_and_its_file_is_its_hash(tmp_path, monkeypatch):
    """The file's name is the hash of its text, and the text names this kernels.py's bytes and numba's version,
    so a change of either makes a new file (numba's cache does not see changes of the functions a cached one
    calls); an existing file of the right text is kept as it is (its numba cache stays valid), a damaged one
    replaced whole."""
    import numba

    monkeypatch.setenv(kernels.KERNEL_CACHE_ENV, str(tmp_path))
    model = best_shaped_surrogate(paper_bearing())
    source = kernels.batch_kernel_source(model._batch_key, "float64")
    text = kernels.kernel_module_source(source, ["import math"], ["_jit = None"])
    assert f"numba {numba.__version__}" in text and "kernels/*.py sha256 " in text and source.strip() in text
    _, path = kernels._import_kernel_module(text, tmp_path, "probe")
    stat = path.stat()
    _, again = kernels._import_kernel_module(text, tmp_path, "probe")
    assert again == path and again.stat().st_mtime_ns == stat.st_mtime_ns and again.stat().st_ino == stat.st_ino
    path.write_text(text[:100])  # damaged
    kernels._import_kernel_module(text, tmp_path, "probe")
    assert path.read_text() == text
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temporary left


def test_no_cache_folder_means_the_former_in_process_compilation(monkeypatch):
    monkeypatch.setenv(kernels.KERNEL_CACHE_ENV, "off")
    assert kernels.kernel_cache_dir() is None
    monkeypatch.delenv(kernels.KERNEL_CACHE_ENV)
    assert kernels.kernel_cache_dir().parts[-2:] == ("fluidfilm", "kernels")


def test_simulate_batch_prints_no_numba_warning(tmp_path):
    """The stage-batched loop takes the kernel as a first-class function; numba's "experimental feature"
    warning at its compilation is filtered at that call site only: a fresh process (its own numba cache, so
    everything compiles) with every warning shown prints none."""
    code = ("import numpy as np\nfrom fluidfilm import Rotor, paper_bearing\n"
            "from fluidfilm.perf.speed import best_shaped_surrogate\nfrom fluidfilm.rotor.batch import simulate_batch\n"
            "m = best_shaped_surrogate(paper_bearing())\nc = m.clearance\n"
            "t = simulate_batch(m, Rotor(mass=5.0, imbalance=1e-5), t_end=1e-4, dt=1e-5,\n"
            "                   x0=np.array([[0.0, 0.3 * c], [0.1 * c, 0.5 * c]]), threads=1, stage_batched=True)\n"
            "print('ok')\n")
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "NUMBA_CACHE_DIR": str(tmp_path / "numba"),
           kernels.KERNEL_CACHE_ENV: str(tmp_path / "kernels")}
    proc = subprocess.run([sys.executable, "-W", "always", "-c", code], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout.strip() == "ok"
    assert "Warning" not in proc.stderr, proc.stderr[-3000:]
