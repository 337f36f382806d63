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


def median_seconds(fn: Callable[[], object], repeats: int = 7, calls: int = 1, warmup: bool = True,
                   clock: Callable[[], float] | None = None) -> float:
    """Median time [s] of one call of ``fn()``: ``repeats`` samples of ``calls`` back-to-back calls each.

    The one timer of the workspace's speed figures. One untimed call first when ``warmup`` (numba
    compiles on the first call; a caller that warms up with other arguments passes ``warmup=False``).
    A median of repeats, because a busy machine adds time to some samples and never takes it away.

    Parameters
    ----------
    fn : callable
        Called with no arguments; its result is discarded.
    repeats : int, default 7
        Number of timed samples (>= 1).
    calls : int, default 1
        Back-to-back calls per sample (>= 1), for calls too short to time one by one.
    warmup : bool, default True
        Call ``fn`` once, untimed, before the samples.
    clock : callable or None, default None
        The clock: None is ``time.perf_counter``, wall time (looked up at the call); ``time.thread_time`` counts only the CPU time of the calling
        thread (work run in that thread, on a machine shared with other processes).

    Returns
    -------
    float
        The median over the samples of the time per call [s].

    Raises
    ------
    ValueError
        For ``repeats`` or ``calls`` below 1 (both named).

    Examples
    --------
    >>> import time
    >>> from fluidfilm.perf import median_seconds
    >>> 0.002 <= median_seconds(lambda: time.sleep(0.002), repeats=3) < 0.2
    True
    >>> median_seconds(lambda: None, repeats=0)
    Traceback (most recent call last):
    ...
    ValueError: repeats and calls must be positive integers, got repeats=0, calls=1
    """
    if int(repeats) < 1 or int(calls) < 1:
        raise ValueError(f"repeats and calls must be positive integers, got repeats={repeats!r}, calls={calls!r}")
    clock = time.perf_counter if clock is None else clock
    if warmup:
        fn()
    samples = []
    for _ in range(int(repeats)):
        t0 = clock()
        for _ in range(int(calls)):
            fn()
        samples.append((clock() - t0) / int(calls))
    return float(statistics.median(samples))


def machine() -> str:
    """The CPU model, core count and OS of this machine (recorded next to every timing).

    Returns
    -------
    str
        ``"<CPU model>, <n> cores, <OS> <release>"`` (the CPU from /proc/cpuinfo where there is one).

    Examples
    --------
    >>> from fluidfilm.perf import machine
    >>> "cores" in machine()
    True
    """
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
    """Write one benchmark table (cells already formatted as text) with machine and date.

    Parameters
    ----------
    name : str
        File name stem: the table goes to ``<out_dir>/<name>.json``.
    title : str
        One line saying what was timed.
    header : sequence of str
        Column titles.
    rows : sequence of sequences
        The cells, one sequence per row, each as long as ``header`` (written with ``str``).
    notes : str, default ""
        Text printed under the table.
    out_dir : path-like, default ``reports/benchmarks``
        Folder of the file (relative to the working directory).

    Returns
    -------
    pathlib.Path
        The file written (atomically; its path is also printed).

    Raises
    ------
    ValueError
        Naming the benchmark and the row whose length differs from the header's.

    Examples
    --------
    >>> import tempfile
    >>> from fluidfilm.perf import render, write_benchmark
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = write_benchmark("demo", "Demo timing", ["model", "us"], [["linear", "0.1"]], out_dir=tmp)
    ...     print(render(path).splitlines()[2:5])
    -> .../demo.json
    ['| model | us |', '|---|---|', '| linear | 0.1 |']
    """
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
    """Markdown for one benchmark file: title, command, machine and date, the table, the notes.

    Parameters
    ----------
    path : path-like
        A file written by ``write_benchmark``.

    Returns
    -------
    str
        The Markdown text, ending with a newline.

    Examples
    --------
    >>> import tempfile
    >>> from fluidfilm.perf import render, write_benchmark
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     text = render(write_benchmark("demo", "Demo", ["a"], [["1"]], notes="Two runs.", out_dir=tmp))
    -> .../demo.json
    >>> text.splitlines()[-1]
    'Two runs.'
    """
    data = json.loads(Path(path).read_text())

    def row(cells) -> str:
        # a '|' inside a cell (e.g. "max |dF|") would end the cell: Markdown escapes it
        return "| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |"

    lines = [f"{data['title']} (`{data['command']}`, {data['date']}, {data['machine']}):", "",
             row(data["header"]), "|" + "---|" * len(data["header"])]
    lines += [row(r) for r in data["rows"]]
    if data.get("notes"):
        lines += ["", data["notes"]]
    return "\n".join(lines) + "\n"


def save_or_check(argv: list[str], doc: str, evaluate) -> int:
    """The bit-for-bit scripts' command line (``benchmarks/*_bitwise.py save|check FILE``): ``save`` writes the
    arrays ``evaluate()`` returns to FILE; ``check`` compares them with FILE's by ``np.array_equal`` and prints
    each that is missing or differs (with its largest difference); exit status 1 where any does."""
    import numpy as np

    if len(argv) != 3 or argv[1] not in ("save", "check"):
        print(doc)
        return 2
    res = evaluate()
    path = Path(argv[2])
    if argv[1] == "save":
        np.savez(path, **res)
        print(f"saved {len(res)} arrays to {path}")
        return 0
    with np.load(path) as ref:
        keys = set(ref.files) | set(res)
        bad = 0
        for k in sorted(keys):
            if k not in ref.files or k not in res:
                print(f"MISSING {k}")
                bad += 1
            elif not np.array_equal(ref[k], res[k], equal_nan=True):
                a, b = ref[k], res[k]
                diff = np.nanmax(np.abs(a - b)) if a.shape == b.shape else f"shape {a.shape} vs {b.shape}"
                print(f"DIFFERS {k}: {diff}")
                bad += 1
    print(f"{len(keys) - bad} of {len(keys)} arrays equal (np.array_equal)" + ("" if bad else ": bit for bit"))
    return 1 if bad else 0
