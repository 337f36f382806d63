"""Time the README's two set-up steps as a new user meets them: a fresh clone of HEAD, a plain shell (nothing
activated, PATH /usr/local/bin:/usr/bin:/bin), `make setup`, then `make test`; writes reports/test_timing.json,
which the README's commands table is rendered from (`python -m fluidfilm.reporting.readme`).

    python benchmarks/time_fresh_clone.py            # make time-tests
"""
from __future__ import annotations

import datetime
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
from fluidfilm.io import write_json  # noqa: E402
from fluidfilm.perf.benchmarking import machine  # noqa: E402


#: where a failed run's log is kept (the clone and its logs live in a temporary folder that is removed)
FAILED_LOG_DIR = ROOT / "build" / "time-tests"


def _run(cmd: list[str], cwd: Path, log: Path) -> float:
    env = {"PATH": "/usr/local/bin:/usr/bin:/bin", "HOME": os.environ.get("HOME", "/root"), "LANG": "C.UTF-8"}
    t0 = time.perf_counter()
    with open(log, "w") as f:
        proc = subprocess.run(cmd, cwd=cwd, env=env, stdout=f, stderr=subprocess.STDOUT)
    if proc.returncode != 0:
        FAILED_LOG_DIR.mkdir(parents=True, exist_ok=True)
        kept = FAILED_LOG_DIR / log.name
        shutil.copy2(log, kept)
        failed = [ln for ln in log.read_text(errors="replace").splitlines() if ln.startswith(("FAILED", "ERROR"))]
        raise SystemExit(f"{' '.join(cmd)} failed (exit {proc.returncode}); log kept in {kept}"
                         + "".join(f"\n  {ln}" for ln in failed[:20]))
    return time.perf_counter() - t0


def main() -> int:
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                            check=True).stdout.strip()
    with tempfile.TemporaryDirectory(prefix="fluidfilm-clone-") as tmp:
        clone = Path(tmp) / "fluidfilm"
        subprocess.run(["git", "clone", "--quiet", str(ROOT), str(clone)], check=True)
        logs = Path(tmp)
        setup_s = _run(["make", "setup"], clone, logs / "setup.log")
        print(f"make setup: {setup_s:.0f} s", flush=True)
        suite_s = _run(["make", "test", "PYTEST_ADDOPTS=--durations=0"], clone, logs / "test.log")
        text = (logs / "test.log").read_text()
    summary = [ln for ln in text.splitlines() if re.search(r"\d+ passed", ln)][-1]
    counts = {k: int(v) for v, k in re.findall(r"(\d+) (passed|skipped|failed|deselected|xfailed|errors?)", summary)}
    # the small-profile pipeline runs once, in test_pipeline.py's module fixture: the longest set-up there
    quick = [float(s) for s, node in re.findall(r"^([\d.]+)s setup\s+(\S+)", text, flags=re.M)
             if node.startswith("tests/test_pipeline.py")]
    out = {"what": "make setup, then make test, from a fresh clone of HEAD in a plain shell (benchmarks/time_fresh_clone.py)",
           "commit": commit, "date": datetime.date.today().isoformat(), "machine": machine(),
           "tests": counts.get("passed", 0) + counts.get("skipped", 0) + counts.get("xfailed", 0),
           "run": counts.get("passed", 0), "skipped": counts.get("skipped", 0), "suite_s": round(suite_s),
           "setup_s": round(setup_s), "quick_reproduce_s": round(max(quick)) if quick else None,
           "summary": summary.strip("= ")}
    write_json(ROOT / "reports" / "test_timing.json", out)
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
