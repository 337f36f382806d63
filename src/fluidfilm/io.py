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


def write_csv(path, frame) -> None:
    """Write a pandas DataFrame as CSV atomically."""
    with atomic_path(path) as tmp:
        frame.to_csv(tmp, index=False)


def save_figure(fig, path, **kwargs) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=Path(path).suffix.lstrip(".") or "png", **kwargs)


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
