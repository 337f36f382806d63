"""First ``simulate_batch`` call of a new process: the surrogate's generated kernels compiled (cold) against
loaded from the kernel cache (``fluidfilm.surrogate.kernels.kernel_cache_dir``), in fresh subprocesses.

    python benchmarks/bench_kernel_cache.py [--quick] [--repeats 3] [--out-dir reports/benchmarks]

Each row is the median over ``--repeats`` fresh processes of the wall time of the first ``simulate_batch`` call
(the best-shaped surrogate, float32 networks, 2 trajectories of 0.2 ms, stage-batched, one thread), timed inside
the process from after the imports and the model's construction to the call's return:

- off: ``FLUIDFILM_KERNEL_CACHE=off``, the kernels compiled from their source in the process (the route before
  the cache);
- cold: an empty cache folder (each repeat its own): the modules are written, numba compiles and caches them;
- cached: a new process on the folder a cold run filled: the compiled kernels are loaded.

numba's own cache of the library's loops is warm in every arm (as in any installed workspace after its first
run), so the rows differ by the generated kernels alone. Writes ``<out-dir>/kernel_cache.json``.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from fluidfilm.perf.benchmarking import write_benchmark  # noqa: E402
from fluidfilm.surrogate.kernels import KERNEL_CACHE_ENV  # noqa: E402

PROBE = r"""
import json, time
import numpy as np
from fluidfilm import Rotor, paper_bearing
from fluidfilm.perf.speed import best_shaped_surrogate
from fluidfilm.rotor.batch import simulate_batch
model = best_shaped_surrogate(paper_bearing())
c = model.clearance
t = time.perf_counter()
simulate_batch(model, Rotor(mass=5.0, imbalance=1e-5), t_end=2e-4, dt=1e-5, threads=1, stage_batched=True,
               x0=np.array([[0.0, 0.3 * c], [0.1 * c, 0.5 * c]]))
print(json.dumps({"first_call_s": time.perf_counter() - t}))
"""


def first_call(cache: str) -> float:
    """Seconds of the first ``simulate_batch`` call in a fresh process with ``FLUIDFILM_KERNEL_CACHE=cache``."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), KERNEL_CACHE_ENV: cache}
    proc = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, check=True,
                          timeout=1800)
    return float(json.loads(proc.stdout.strip().splitlines()[-1])["first_call_s"])


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="one process per arm")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out-dir", default=str(ROOT / "reports" / "benchmarks"))
    args = parser.parse_args(argv)
    repeats = 1 if args.quick else args.repeats
    times: dict[str, list[float]] = {"off": [], "cold": [], "cached": []}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(repeats):
            folder = str(Path(tmp) / f"kernels{i}")
            times["off"].append(first_call("off"))
            times["cold"].append(first_call(folder))
            times["cached"].append(first_call(folder))
            print(f"repeat {i + 1}/{repeats}: " + ", ".join(f"{k} {v[-1]:.2f} s" for k, v in times.items()),
                  flush=True)
    med = {k: statistics.median(v) for k, v in times.items()}
    rows = [[arm, f"{med[arm]:.2f}", f"{min(times[arm]):.2f}", f"{max(times[arm]):.2f}", repeats,
             f"{med['off'] / med[arm]:.1f}x"] for arm in ("off", "cold", "cached")]
    write_benchmark("kernel_cache", "first simulate_batch call of a fresh process: generated kernels compiled "
                    "(off, cold) or loaded from the kernel cache (cached); best-shaped surrogate, float32",
                    ["arm", "median s", "min s", "max s", "processes", "off / arm"], rows,
                    notes="timed inside each process after imports and the model's construction; numba's cache of "
                          "the library's loops warm in every arm", out_dir=args.out_dir)


if __name__ == "__main__":
    main()
