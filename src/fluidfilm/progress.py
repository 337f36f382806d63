"""Progress lines that work without a terminal (DVC stages, CI logs, SLURM output files).

A progress *bar* redraws one line with carriage returns: in a log file that is either nothing for
minutes or thousands of fragments.  These helpers print whole lines instead — what was done, the
elapsed time and an estimate of the rest — at most every ``every_s`` seconds, plus the last one.
"""
from __future__ import annotations

import sys
import time


def _fmt(seconds: float) -> str:
    seconds = max(0.0, seconds)
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


class ProgressLog:
    """``update()`` once per finished unit (part, case, epoch); prints throttled lines with an ETA.

    >>> p = ProgressLog(4, "dataset parts", every_s=0.0, stream=None)
    >>> for _ in range(4): p.update()
    >>> p.done
    4
    """

    def __init__(self, total: int, what: str, every_s: float = 10.0, enabled: bool = True, stream=sys.stdout):
        if total < 0:
            raise ValueError(f"total must be >= 0, got {total}")
        self.total, self.what, self.every_s = int(total), what, float(every_s)
        self.enabled = enabled and stream is not None
        self.stream = stream
        self.done = 0
        self.t0 = time.perf_counter()
        self._last = -float("inf")

    def line(self, extra: str = "") -> str:
        elapsed = time.perf_counter() - self.t0
        pct = 100.0 * self.done / self.total if self.total else 100.0
        text = f"{self.what}: {self.done}/{self.total} ({pct:.0f} %), {_fmt(elapsed)} elapsed"
        if 0 < self.done < self.total:
            text += f", about {_fmt(elapsed / self.done * (self.total - self.done))} left"
        return text + (f" - {extra}" if extra else "")

    def update(self, n: int = 1, extra: str = "") -> None:
        self.done += n
        now = time.perf_counter()
        if self.enabled and (now - self._last >= self.every_s or self.done >= self.total):
            self._last = now
            print(self.line(extra), file=self.stream, flush=True)


def epoch_log_callback(max_epochs: int, what: str = "training", every_s: float = 5.0):
    """A Lightning callback printing one line per validated epoch (throttled) with the validation error and an ETA.

    Built lazily so that importing this module does not import Lightning.
    """
    import lightning as L

    class EpochLog(L.pytorch.callbacks.Callback):
        def __init__(self):
            self.progress = ProgressLog(max_epochs, f"{what} epochs", every_s=every_s)

        def on_validation_epoch_end(self, trainer, pl_module):
            if trainer.sanity_checking:
                return
            metrics = {k: float(v) for k, v in trainer.callback_metrics.items() if k.startswith(("val_", "train_"))}
            shown = ", ".join(f"{k} {v:.4g}" for k, v in sorted(metrics.items()))
            self.progress.done = trainer.current_epoch  # update() adds the finished epoch
            self.progress.update(extra=shown)

        def on_train_end(self, trainer, pl_module):
            if self.progress.done < self.progress.total:
                print(f"{self.progress.what}: stopped after {trainer.current_epoch} epochs "
                      f"({_fmt(time.perf_counter() - self.progress.t0)})", flush=True)

    return EpochLog()


# Third-party messages that say nothing to this workspace's user: advertising, deprecations inside a
# library's own internals, and notes about settings we chose on purpose.  Matched by message, so a
# real warning from the same library still shows.
_NOISE = (
    r"💡 Tip:",
    r"`isinstance\(treespec, LeafSpec\)` is deprecated",
    r"Your `IterableDataset` has `__len__` defined",
    r"The number of training batches \(\d+\) is smaller than the logging interval",
    r"GPU available: |TPU available: |HPU available: |You are using a CUDA device",
    r"`Trainer.fit` stopped: `max_epochs=\d+` reached",
    r"`weights_only` was not set, defaulting to `False`",
    r"Time limit reached\. Elapsed time is",
)


def quiet_third_party() -> None:
    """Drop the messages in ``_NOISE`` from Lightning's loggers and Python warnings (idempotent)."""
    import logging
    import re
    import warnings

    pattern = re.compile("|".join(_NOISE))

    class _Drop(logging.Filter):
        def filter(self, record: logging.LogRecord) -> bool:
            return not pattern.search(record.getMessage())

    for name in ("lightning.pytorch.utilities.rank_zero", "lightning.fabric.utilities.rank_zero",
                 "lightning.pytorch.accelerators.cuda", "lightning.pytorch",
                 "lightning.pytorch.trainer.connectors.checkpoint_connector", "lightning.pytorch.callbacks.timer"):
        logger = logging.getLogger(name)
        if not any(isinstance(f, _Drop) for f in logger.filters):
            logger.addFilter(_Drop())
    for message in _NOISE:
        warnings.filterwarnings("ignore", message=f".*{message}")
