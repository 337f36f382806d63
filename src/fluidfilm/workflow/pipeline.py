"""Run the workspace's DVC pipeline and serve its MLflow runs (what ``make reproduce`` and ``make mlflow`` call).

    python -m fluidfilm.workflow.pipeline run                                 # dvc repro, the full profile
    python -m fluidfilm.workflow.pipeline run --profile quick --workdir DIR   # the small profile in a scratch copy
    python -m fluidfilm.workflow.pipeline serve --port 5000                   # MLflow UI on the workspace's store

``serve`` prints the address to open: MLflow 3's home page is its GenAI overview, and an experiment
opens on traces, so the runs are at ``http://127.0.0.1:5000/#/experiments/<id>/runs``; the printed
address adds ``?viewStateShareKey=summary``, the view ``publish`` stores on the experiment: one
``summary/<model>`` run per surrogate with its accuracy, training time and speed-ups as columns.

Why a module and not a shell line: the stages must start the workspace's interpreter whatever is
on the caller's PATH (dvc.yaml takes it from ``conf/pipeline/full.yaml``), the small profile must
run the very same ``dvc.yaml`` without touching the full outputs (so it runs in a copy of the
workspace with ``conf/pipeline/quick.yaml`` in place of the full profile), and a user should see,
line by line, which stage runs, how long each took and where the results are at the end.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
import urllib.parse
import urllib.request
from pathlib import Path

PROFILE_FILE = Path("conf/pipeline/full.yaml")
TIMING_FILE = Path("reports/reproduce_timing.json")
STAGE_LINE = re.compile(r"^Running stage '([^']+)'")


def venv_bin() -> Path:
    """The folder of the interpreter running this module (the workspace's .venv/bin under make)."""
    return Path(sys.executable).parent


def copy_workspace(src: Path, dst: Path) -> None:
    """Copy the tracked and untracked-but-not-ignored files of ``src`` to ``dst`` (fresh)."""
    listing = subprocess.run(["git", "ls-files", "-co", "--exclude-standard", "-z"], cwd=src, check=True,
                             capture_output=True).stdout.decode().split("\0")
    if dst.exists():
        shutil.rmtree(dst)
    dst.mkdir(parents=True)
    for rel in filter(None, listing):
        source = src / rel
        if not source.is_file():          # deleted but not yet committed
            continue
        target = dst / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, target)


def prepare_profile_copy(root: Path, profile: str, workdir: Path) -> Path:
    """A scratch copy of the workspace that runs ``profile`` through the unchanged dvc.yaml."""
    profile_file = root / "conf" / "pipeline" / f"{profile}.yaml"
    if not profile_file.is_file():
        known = sorted(p.stem for p in (root / "conf" / "pipeline").glob("*.yaml"))
        raise SystemExit(f"unknown pipeline profile {profile!r}: expected one of {known}")
    workdir = workdir if workdir.is_absolute() else root / workdir
    copy_workspace(root, workdir)
    shutil.copy2(profile_file, workdir / PROFILE_FILE)
    (workdir / "dvc.lock").unlink(missing_ok=True)
    # the stages start .venv/bin/python relative to the workspace: point it at this one's
    venv = root / ".venv"
    if venv.exists():
        (workdir / ".venv").symlink_to(venv.resolve(), target_is_directory=True)
    # the copy is no git repository of its own; DVC runs it without one
    subprocess.run([str(venv_bin() / "dvc"), "config", "--local", "core.no_scm", "true"], cwd=workdir, check=True,
                   capture_output=True)
    return workdir


def run_dvc_repro(workdir: Path, extra: list[str], on_stage_done=None) -> tuple[int, dict[str, float]]:
    """``dvc repro`` in ``workdir``, streaming its output; return its exit code and seconds per stage run.

    ``on_stage_done(name, seconds)`` is called as each stage finishes (when the next one starts, or dvc
    exits 0): a run stopped half-way keeps the times of the stages it finished (a full run takes longer
    than one sitting; DVC keeps their outputs, this keeps their times)."""
    cmd = [str(venv_bin() / "dvc"), "repro", *extra]
    env = dict(os.environ)
    env.setdefault("PYTHONUNBUFFERED", "1")     # stage output line by line, not in 4 kB blocks
    start = time.perf_counter()
    stage_times: dict[str, float] = {}
    current, current_start = None, start

    def finished(name: str, seconds: float) -> None:
        stage_times[name] = seconds
        if on_stage_done is not None:
            on_stage_done(name, seconds)

    proc = subprocess.Popen(cmd, cwd=workdir, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            bufsize=1)
    try:
        assert proc.stdout is not None
        for line in proc.stdout:
            m = STAGE_LINE.match(line)
            now = time.perf_counter()
            if m:
                if current is not None:
                    finished(current, now - current_start)
                current, current_start = m.group(1), now
                line = line.rstrip("\n") + f"   [pipeline {now - start:,.0f} s]\n"
            sys.stdout.write(line)
            sys.stdout.flush()
        code = proc.wait()
    except KeyboardInterrupt:
        proc.send_signal(signal.SIGINT)
        proc.wait()
        print(f"\ninterrupted during stage {current!r}: run the same command again to resume "
              "(finished stages and finished dataset parts are kept)", file=sys.stderr)
        raise SystemExit(130) from None
    if current is not None and code == 0:
        finished(current, time.perf_counter() - current_start)
    return code, stage_times


def pipeline_stage_names(workdir: Path) -> set[str]:
    """The stage names of ``workdir``'s dvc.yaml (a foreach stage by its own name), empty where there is none."""
    import yaml

    dvc_file = workdir / "dvc.yaml"
    return set(yaml.safe_load(dvc_file.read_text()).get("stages") or {}) if dvc_file.exists() else set()


def record_timing(workdir: Path, profile: str, stage_times: dict[str, float], total: float | None = None) -> None:
    """Merge the seconds of the stages that ran into reports/reproduce_timing.json (stages not rerun keep theirs),
    each with the date and machine of its run; ``total``: the wall time of a whole ``dvc repro`` that ended."""
    from fluidfilm.perf.benchmarking import machine

    path = workdir / TIMING_FILE
    data = json.loads(path.read_text()) if path.exists() else {}
    runs = data.setdefault(profile, {"stages": {}})
    today, host = _dt.date.today().isoformat(), machine()
    runs["stages"].update({k: round(v, 1) for k, v in stage_times.items()})
    if "stage_runs" not in runs:  # a record from before per-stage runs: its stages ran on its date and machine
        runs["stage_runs"] = {k: {"date": runs.get("date"), "machine": runs.get("machine")} for k in runs["stages"]}
    when = runs["stage_runs"]
    when.update({k: {"date": today, "machine": host} for k in stage_times})
    # a stage that left dvc.yaml (e.g. a long variant moved to a make target) leaves the total too
    current = pipeline_stage_names(workdir)
    if current:
        for k in [k for k in runs["stages"] if k.split("@")[0] not in current]:
            runs["stages"].pop(k)
            when.pop(k, None)
    runs["date"] = today
    runs["machine"] = host
    if total is not None:
        runs["last_run_total_s"] = round(total, 1)
    runs["stages_total_s"] = round(sum(runs["stages"].values()), 1)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(data, indent=2, sort_keys=True) + "\n")
    os.replace(tmp, path)


def where_things_are(workdir: Path) -> str:
    rel = os.path.relpath(workdir)
    prefix = "" if rel == "." else f"{rel}/"
    return "\n".join([
        "",
        "Results:",
        f"  report          {prefix}reports/paper_comparison.md   (headline values: {prefix}reports/metrics.json)",
        f"  figures         {prefix}reports/figures/",
        f"  stage timings   {prefix}{TIMING_FILE}",
        f"  MLflow runs     {prefix}mlflow.db          open with: "
        + ("make mlflow" if not prefix else f"(cd {rel} && .venv/bin/python -m fluidfilm.workflow.pipeline serve)")
        + "   then the runs-table address it prints",
        "  DVC             .venv/bin/dvc metrics show ; .venv/bin/dvc plots show   (writes reports/dvc_plots/)",
        "  review notebook .venv/bin/jupyter execute --inplace notebooks/review.ipynb",
    ])


def cmd_run(args: argparse.Namespace) -> int:
    root = Path.cwd()
    workdir = root if args.profile == "full" else prepare_profile_copy(root, args.profile, Path(args.workdir))
    print(f"fluidfilm pipeline: profile {args.profile}, in {workdir}", flush=True)
    start = time.perf_counter()
    code, stage_times = run_dvc_repro(workdir, args.dvc_args,
                                      lambda name, sec: record_timing(workdir, args.profile, {name: sec}))
    total = time.perf_counter() - start
    if code != 0:
        print(f"\ndvc repro failed (exit {code}) after {total:,.0f} s", file=sys.stderr)
        return code
    if stage_times:
        record_timing(workdir, args.profile, {}, total)
    from fluidfilm.reporting import readme

    readme.main(["--readme", str(workdir / "README.md"), "--reports", str(workdir / "reports")])
    if stage_times:
        publish(workdir)
    if stage_times:
        print(f"\n{len(stage_times)} stage(s) ran in {total / 60:.1f} min:")
        for name, sec in stage_times.items():
            print(f"  {name:<24} {sec:8.1f} s")
    else:
        print("\nevery stage is up to date")
    print(where_things_are(workdir))
    return 0


def publish(workdir: Path) -> str | None:
    """The reproduction as one MLflow run (report, figures, timings, agent) and the surrogates registered."""
    import yaml

    from fluidfilm.workflow.tracking import publish_workspace

    tracking = yaml.safe_load((workdir / "conf" / "tracking" / "default.yaml").read_text())
    cwd = Path.cwd()
    os.chdir(workdir)  # the store and its artifact folder are relative to the workspace
    try:
        run_id = publish_workspace(tracking)
    finally:
        os.chdir(cwd)
    if run_id:
        print(f"MLflow: run 'reproduce' {run_id} holds the report, figures and timings; surrogates registered "
              "as fluidfilm-<name>", flush=True)
    return run_id


def cmd_publish(args: argparse.Namespace) -> int:
    publish(Path.cwd())
    return 0


def runs_table_addresses(url: str, experiment: str) -> str:
    """What to open in the browser: the experiment's runs table (on the summary view where the store has it),
    read from the running server (``url``) so that the store is only ever opened by it."""
    from fluidfilm.workflow.tracking import SUMMARY_VIEW, VIEW_TAG, runs_table_url

    query = urllib.parse.urlencode({"experiment_name": experiment})
    try:
        with urllib.request.urlopen(f"{url}/api/2.0/mlflow/experiments/get-by-name?{query}", timeout=10) as r:
            exp = json.load(r)["experiment"]
    except OSError:  # HTTPError 404 included: no run logged yet
        return (f"  no experiment {experiment!r} in this store yet: runs appear under {url}/#/experiments "
                "once a stage has run")
    lines = []
    search = json.dumps({"experiment_ids": [exp["experiment_id"]], "max_results": 1,
                         "filter": f"tags.`{VIEW_TAG}` = '{SUMMARY_VIEW}'"}).encode()
    request = urllib.request.Request(f"{url}/api/2.0/mlflow/runs/search", data=search,
                                     headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(request, timeout=10) as r:
        has_summary = bool(json.load(r).get("runs"))
    has_view = any(t.get("key") == f"mlflow.sharedViewState.{SUMMARY_VIEW}" for t in exp.get("tags", []))
    if has_summary and has_view:
        lines.append(f"  {'one row per model (accuracy, training time, speed-up):':<58}"
                     f"{runs_table_url(url, exp['experiment_id'])}")
    else:
        lines.append("  no per-model summary runs yet: `make reproduce` (its publish step) writes them")
    lines.append(f"  {f'all runs of {experiment!r}:':<58}{runs_table_url(url, exp['experiment_id'], view=None)}")
    return "\n".join(lines)


class _StopRequested(Exception):
    """SIGTERM (or SIGHUP) reached ``serve``: stop the server's process group, then exit."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


def _raise_stop(signum, frame):
    raise _StopRequested(signum)


def group_alive(pgid: int) -> bool:
    """Whether any process of the process group ``pgid`` exists (a zombie not yet reaped counts)."""
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # a process of the group exists, owned by someone else
        return True
    return True


def stop_process_group(proc: subprocess.Popen, timeout: float = 15.0) -> None:
    """Stop ``proc`` and every process of its group (``proc`` leads it: started with ``start_new_session``).

    SIGTERM to the group, then wait until none of it is left (``proc`` reaped here; workers that outlive it
    are reparented and reaped by init); whatever is left after ``timeout`` gets SIGKILL.

    Parameters
    ----------
    proc : subprocess.Popen
        The group's leader (its pid is the group's id).
    timeout : float
        Seconds the group gets to stop on SIGTERM.
    """
    pgid = proc.pid
    for sig, wait in ((signal.SIGTERM, timeout), (signal.SIGKILL, 10.0)):
        try:
            os.killpg(pgid, sig)
        except ProcessLookupError:
            pass
        deadline = time.monotonic() + wait
        while time.monotonic() < deadline:
            proc.poll()  # reap the leader, so that its zombie does not keep the group alive
            if not group_alive(pgid):
                return
            time.sleep(0.1)


def cmd_serve(args: argparse.Namespace) -> int:
    """The MLflow UI on this workspace's store; artifacts served by the server (portable links).

    The server (``mlflow server``: gunicorn or uvicorn and their workers) runs in its own process group;
    Ctrl-C, SIGTERM and SIGHUP to this process stop that whole group and wait until none of it is left
    (nothing stays listening on the port), then this process exits 0."""
    from fluidfilm.workflow.tracking import relocate_artifacts

    url = f"http://{args.host}:{args.port}"
    moved = relocate_artifacts(args.store)   # artifact links follow the workspace if it was moved
    if moved:
        print(f"re-pointed {moved} artifact locations to {Path.cwd()}", flush=True)
    cmd = [str(venv_bin() / "mlflow"), "server", "--backend-store-uri", args.store, "--artifacts-destination",
           args.artifacts, "--host", args.host, "--port", str(args.port), "--workers", "1"]
    # a signal this process was started ignoring stays ignored (``nohup make mlflow`` survives the hangup)
    previous = {sig: signal.signal(sig, _raise_stop) for sig in (signal.SIGTERM, signal.SIGHUP)
                if signal.getsignal(sig) != signal.SIG_IGN}
    proc = None
    try:
        proc = subprocess.Popen(cmd, start_new_session=True)  # its own group: signals are forwarded, below
        print(f"starting MLflow on {url} (store {args.store}, process group {proc.pid}); Ctrl-C stops it",
              flush=True)
        deadline = time.time() + 120
        while time.time() < deadline and proc.poll() is None:
            try:
                urllib.request.urlopen(url + "/health", timeout=2)
                print(f"MLflow is up: {url}", flush=True)
                print(runs_table_addresses(url, args.experiment), flush=True)
                break
            except OSError:
                time.sleep(1)
        code = proc.wait()
        stop_process_group(proc)  # workers the server left behind, if it ended by itself
        return code
    except (KeyboardInterrupt, _StopRequested) as stop:
        if proc is not None:
            stop_process_group(proc)  # the server and its gunicorn/uvicorn workers
        why = signal.Signals(stop.signum).name if isinstance(stop, _StopRequested) else "Ctrl-C"
        print(f"MLflow stopped ({why})", flush=True)
        return 0
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m fluidfilm.workflow.pipeline", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="dvc repro on a profile")
    run.add_argument("--profile", default="full", help="conf/pipeline/<profile>.yaml (default: full)")
    run.add_argument("--workdir", default="build/quick", help="scratch copy for a profile other than full")
    run.add_argument("dvc_args", nargs="*", help="passed to dvc repro (e.g. a stage name)")
    run.set_defaults(func=cmd_run)
    pub = sub.add_parser("publish", help="log the reproduction to MLflow and register the surrogates")
    pub.set_defaults(func=cmd_publish)
    serve = sub.add_parser("serve", help="serve the workspace's MLflow runs")
    serve.add_argument("--port", type=int, default=5000)
    serve.add_argument("--host", default="127.0.0.1")
    serve.add_argument("--store", default="sqlite:///mlflow.db")
    serve.add_argument("--artifacts", default="./mlartifacts")
    serve.add_argument("--experiment", default="fluidfilm", help="whose runs-table address to print")
    serve.set_defaults(func=cmd_serve)
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
