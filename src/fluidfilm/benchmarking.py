"""Benchmark results as files, so the README's speed tables are generated, never copied.

Each script in ``benchmarks/`` prints its table and, unless run with ``--quick``, writes it with
``write_benchmark`` to ``reports/benchmarks/<name>.json`` together with the machine and the date;
``python -m fluidfilm.readme`` renders those files into the README's ``bench_<name>`` blocks.
"""
from __future__ import annotations

import datetime as _dt
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from . import io

OUT_DIR = Path("reports/benchmarks")


def write_benchmark(name: str, title: str, header: Sequence[str], rows: Sequence[Sequence[object]],
                    notes: str = "", out_dir: Path | str = OUT_DIR) -> Path:
    """Write one benchmark table (cells already formatted as text) with machine and date."""
    from .comparison import machine

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
