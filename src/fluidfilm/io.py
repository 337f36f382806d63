"""Atomic output: a crash or Ctrl-C never leaves a half-written file behind.

Everything is written to a temporary file in the destination directory and
moved into place with ``os.replace`` (atomic on POSIX within a filesystem).
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import os
import tempfile
from pathlib import Path


def _process_umask() -> int:
    mask = os.umask(0)  # the only way to read it is to set it: done once, at import, not per file
    os.umask(mask)
    return mask


_UMASK = _process_umask()


@contextlib.contextmanager
def atomic_path(path, suffix: str | None = None):
    """Yield a temporary path next to ``path``; on success it replaces ``path``.

    The temporary file is created inside the guarded block, so an exception
    (Ctrl-C included) once its name is known removes it.  A Ctrl-C can still
    land in the bytecodes between ``mkstemp`` returning and its name being
    stored, or where ``contextlib`` hands the path to the ``with`` body;
    callers that own a directory sweep its ``.<name>.*`` leftovers (see
    ``remove_temporaries``).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix or path.suffix, dir=path.parent)
        os.close(fd)
        os.chmod(tmp, 0o666 & ~_UMASK)  # mkstemp makes 0600; outputs are ordinary files
        yield Path(tmp)
        os.replace(tmp, path)
    except BaseException:
        if tmp is not None:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)
        raise


def remove_temporaries(directory, pattern: str) -> int:
    """Delete the temporary files ``atomic_path`` left in ``directory`` (names matching ``pattern``, e.g.
    ``.part-*``); return how many.  Only for directories one writer owns."""
    n = 0
    for tmp in Path(directory).glob(pattern):
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
            n += 1
    return n


def file_sha256(path) -> str:
    """SHA-256 of a file's bytes, read in 1 MiB blocks (the checksum datasets and surrogates record)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def write_text(path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def write_json(path, obj) -> None:
    write_text(path, json.dumps(obj, indent=2, sort_keys=True) + "\n")


#: significant digits (of each column's largest magnitude) that the figure tables keep: the reference solver's
#: spread across machines (its fastmath kernels compiled for another CPU) is below 1e-14 of a force column's
#: largest value and 1e-11 of an error column's (docs/workflow.md, "Stage outputs across machines")
TABLE_DIGITS = 6


def round_to_scale(frame, columns, digits: int = TABLE_DIGITS):
    """A copy of ``frame`` with each of ``columns`` rounded to ``digits`` significant digits of the column's
    largest finite magnitude (an absolute step per column, so near-zero values that are round-off noise
    become 0 instead of keeping noisy digits).

    Parameters
    ----------
    frame : pandas.DataFrame
        The table.
    columns : iterable of str
        Float columns to round (a column of zeros or non-finite values only is left as it is).
    digits : int
        Significant digits kept, relative to the column's largest magnitude.

    Returns
    -------
    pandas.DataFrame
        The rounded copy; ``frame`` is not changed.

    Examples
    --------
    >>> import pandas as pd
    >>> round_to_scale(pd.DataFrame({"F": [123.456789, 1.2e-13]}), ["F"], 4)["F"].tolist()
    [123.5, 0.0]
    """
    import numpy as np

    out = frame.copy()
    for col in columns:
        values = out[col].to_numpy(dtype=float)
        finite = np.abs(values[np.isfinite(values)])
        if finite.size == 0 or finite.max() == 0:
            continue
        decimals = digits - 1 - int(np.floor(np.log10(finite.max())))
        out[col] = np.round(values, decimals) + 0.0  # + 0.0: no negative zero in the table
    return out


def write_csv(path, frame) -> None:
    """Write a pandas DataFrame as CSV atomically."""
    with atomic_path(path) as tmp:
        frame.to_csv(tmp, index=False)


def save_figure(fig, path, **kwargs) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=Path(path).suffix.lstrip(".") or "png", **kwargs)


class OutputSet:
    """Files written as one set (``output_set``): each is staged in a temporary file beside its destination
    and all are moved into place together when the block ends without an error."""

    def __init__(self):
        self._staged: list[tuple[Path, Path]] = []

    def _stage(self, path) -> Path:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
        self._staged.append((Path(tmp), path))  # first, so that an error below still removes it
        os.close(fd)
        os.chmod(tmp, 0o666 & ~_UMASK)
        return Path(tmp)

    def write_text(self, path, text: str) -> None:
        self._stage(path).write_text(text)

    def write_json(self, path, obj) -> None:
        self.write_text(path, json.dumps(obj, indent=2, sort_keys=True) + "\n")

    def write_csv(self, path, frame) -> None:
        frame.to_csv(self._stage(path), index=False)

    def save_figure(self, fig, path, **kwargs) -> None:
        fig.savefig(self._stage(path), format=Path(path).suffix.lstrip(".") or "png", **kwargs)


@contextlib.contextmanager
def output_set():
    """Write a study's outputs as one set: an error or Ctrl-C before the end leaves every old file as it was
    and no new one beside it.

    The moves into place run with SIGINT blocked (a Ctrl-C then arrives right after them), so the set is
    replaced whole; a crash of the machine in those few renames is the one window left.
    """
    import signal
    import threading

    staged = OutputSet()
    try:
        yield staged
    except BaseException:
        for tmp, _ in staged._staged:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)
        raise
    main = threading.current_thread() is threading.main_thread()
    if main:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        for tmp, path in staged._staged:
            os.replace(tmp, path)
    finally:
        if main:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)


def run_interruptible(main, what: str, resume: str) -> None:
    """Run an entry point's ``main``; Ctrl-C ends it with one line instead of a traceback.

    Every output is written atomically (above), so an interrupted run leaves
    each file complete or absent; the line says what stopped and how to go on.
    Exit status 130, as a shell reports a SIGINT.
    """
    import sys

    try:
        main()
    except KeyboardInterrupt:
        print(f"\ninterrupted: {what}; finished outputs are kept, nothing is half-written. To resume: {resume}",
              file=sys.stderr, flush=True)
        raise SystemExit(130) from None
