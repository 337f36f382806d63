"""Benchmark: generate the paper-scale dataset from scratch and report samples per second.

    python benchmarks/bench_dataset.py [--dataset quick] [--scheduler local|inline]
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import yaml

from fluidfilm import paper_bearing
from fluidfilm.data import DatasetSpec, generate_dataset

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--dataset", default="paper")
    ap.add_argument("--scheduler", default="local")
    ap.add_argument("--repeats", type=int, default=1)
    args = ap.parse_args()
    cfg = yaml.safe_load((ROOT / "conf" / "dataset" / f"{args.dataset}.yaml").read_text())
    reference = yaml.safe_load((ROOT / "conf" / "reference" / "paper.yaml").read_text())
    spec = DatasetSpec.from_cfg(cfg)
    times = []
    for _ in range(args.repeats):
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            meta = generate_dataset(paper_bearing(), reference, spec, Path(tmp) / "ds", scheduler=args.scheduler,
                                    progress=False)
            times.append(time.perf_counter() - t0)
    times.sort()
    med = times[len(times) // 2]
    print(f"dataset {args.dataset}: {meta['n_samples']:,} samples, scheduler {args.scheduler}, "
          f"{os.cpu_count()} cores: median {med:.1f} s wall ({meta['n_samples'] / med:,.0f} samples/s), "
          f"paper: 4.7 M samples, generation time not given (hours)")


if __name__ == "__main__":
    main()
