"""Benchmark results as files, so the README's speed tables are generated, never copied.

Each script in ``benchmarks/`` prints its table and, unless run with ``--quick``, writes it with
``write_benchmark`` to ``reports/benchmarks/<name>.json`` together with the machine and the date;
``python -m fluidfilm.reporting.readme`` renders those files into the README's ``bench_<name>`` blocks.
"""
from __future__ import annotations

import datetime as _dt
import json
import platform
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from fluidfilm import io

OUT_DIR = Path("reports/benchmarks")


def median_seconds(fn: Callable[[], object], repeats: int = 7, calls: int = 1, warmup: bool = True) -> float:
    """Median wall time [s] of one call of ``fn()``: ``repeats`` samples of ``calls`` back-to-back calls each.

    The one timer of the workspace's speed figures. One untimed call first when ``warmup`` (numba
    compiles on the first call; a caller that warms up with other arguments passes ``warmup=False``).
    A median of repeats, because a busy machine adds time to some samples and never takes it away.
    """
    if int(repeats) < 1 or int(calls) < 1:
        raise ValueError(f"repeats and calls must be positive integers, got repeats={repeats!r}, calls={calls!r}")
    if warmup:
        fn()
    samples = []
    for _ in range(int(repeats)):
        t0 = time.perf_counter()
        for _ in range(int(calls)):
            fn()
        samples.append((time.perf_counter() - t0) / int(calls))
    return float(statistics.median(samples))


def machine() -> str:
    """The CPU model, core count and OS of this machine (recorded next to every timing)."""
    import os

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"


def write_benchmark(name: str, title: str, header: Sequence[str], rows: Sequence[Sequence[object]],
                    notes: str = "", out_dir: Path | str = OUT_DIR) -> Path:
    """Write one benchmark table (cells already formatted as text) with machine and date."""
    for row in rows:
        if len(row) != len(header):
            raise ValueError(f"benchmark {name!r}: row {list(row)} has {len(row)} cells, header has {len(header)}")
    data = {"name": name, "title": title, "header": list(header), "rows": [[str(c) for c in r] for r in rows],
            "notes": notes, "machine": machine(), "date": _dt.date.today().isoformat(),
            "command": "python " + " ".join(Path(a).as_posix() for a in sys.argv[:1]) if sys.argv[0] else ""}
    path = Path(out_dir) / f"{name}.json"
    io.write_json(path, data)
    print(f"-> {path}")
    return path


def render(path: Path) -> str:
    """Markdown for one benchmark file: title, command, machine and date, the table, the notes."""
    data = json.loads(Path(path).read_text())
    lines = [f"{data['title']} (`{data['command']}`, {data['date']}, {data['machine']}):", "",
             "| " + " | ".join(data["header"]) + " |", "|" + "---|" * len(data["header"])]
    lines += ["| " + " | ".join(r) + " |" for r in data["rows"]]
    if data.get("notes"):
        lines += ["", data["notes"]]
    return "\n".join(lines) + "\n"
