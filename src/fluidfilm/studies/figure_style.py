"""What every figure of the pipeline shares: readable log ticks, and axes limited to the meaningful range with
the points outside it marked at the edge.

The caption each figure has on the results page lives in ``reporting.captions.CAPTIONS``, below the studies,
so that the results-page renderer reads it without importing a study.
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np


def readable_log_ticks(ax, axis: str = "x") -> None:
    """Label a log axis at most at a handful of ticks that cannot overprint: decades (10⁻², 10⁻¹, ...)
    when the axis spans two or more of them, else 1-2-5 steps written as plain numbers; minor ticks
    are never labelled (matplotlib labels them on short log axes, where they overprint).
    Call after the data are drawn (the labels follow the axis' limits)."""
    from matplotlib.ticker import FuncFormatter, LogFormatterSciNotation, LogLocator, NullFormatter

    a = ax.xaxis if axis == "x" else ax.yaxis
    lo, hi = sorted(a.get_view_interval())
    if lo <= 0:
        return
    decades = math.log10(hi / lo)
    if decades >= 2.0:
        step = max(1, math.ceil(decades / 6))  # at most ~6 labelled decades
        a.set_major_locator(LogLocator(base=10.0 ** step))
        a.set_major_formatter(LogFormatterSciNotation())
    else:
        a.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        a.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}" if 1e-4 <= v < 1e6 else f"{v:.0e}"))
    a.set_minor_locator(LogLocator(base=10.0, subs=tuple(np.arange(2, 10)), numticks=12))
    a.set_minor_formatter(NullFormatter())


def limit_with_outliers(ax, lo: float, hi: float, series: Sequence[tuple], fmt: str = "{:.3g}") -> list[dict]:
    """Limit the y axis to [lo, hi] and mark each series' points beyond it at the edge they cross.

    ``series``: (x, y, label, color) per drawn series.  Every point outside gets a triangle on the axis
    edge (pointing out); each series and edge gets one note inside the axes, in the corner of that edge,
    naming the series, how many points lie beyond and the extreme value.  Returns those notes' records
    ({"label", "edge", "n", "value", "text"}), in the order drawn.
    """
    ax.set_ylim(lo, hi)
    records: list[dict] = []
    for x, y, label, color in series:
        x, y = np.asarray(x, float), np.asarray(y, float)
        for edge, beyond, marker in (("top", y > hi, "^"), ("bottom", y < lo, "v")):
            beyond &= np.isfinite(y)
            if not beyond.any():
                continue
            ax.plot(x[beyond], np.full(beyond.sum(), hi if edge == "top" else lo), marker, color=color, ms=7,
                    clip_on=False, zorder=5, ls="none")
            worst = float(y[beyond].max() if edge == "top" else y[beyond].min())
            n = int(beyond.sum())
            text = (f"{marker} {label}: {n} point{'s' * (n > 1)} {'above' if edge == 'top' else 'below'}, "
                    f"{'max' if edge == 'top' else 'min'} {fmt.format(worst)}")
            k = sum(r["edge"] == edge for r in records)  # stack the notes of one edge
            ax.text(0.02, 0.97 - 0.075 * k if edge == "top" else 0.03 + 0.075 * k, text, transform=ax.transAxes,
                    ha="left", va="top" if edge == "top" else "bottom", fontsize=7, color=color, zorder=6,
                    bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.85))
            records.append({"label": label, "edge": edge, "n": n, "value": worst, "text": text})
    if ax.get_yscale() == "log":
        readable_log_ticks(ax, "y")
    return records


def reference_range(values, pad: float = 0.15, log: bool = False, include: Sequence[float] = ()) -> tuple[float, float]:
    """The y range of the trusted curves (``values``, e.g. the reference model's), widened by ``pad`` of
    its span (of its decades when ``log``) on both sides, and stretched to hold ``include``."""
    v = np.asarray(list(np.ravel(values)) + list(include), float)
    v = v[np.isfinite(v) & (v > 0 if log else True)]
    if v.size == 0:
        raise ValueError("reference_range: no finite values to take the range from")
    if log:
        a, b = math.log10(v.min()), math.log10(v.max())
        span = max(b - a, 0.3)
        return 10 ** (a - pad * span), 10 ** (b + pad * span)
    a, b = float(v.min()), float(v.max())
    span = max(b - a, 1e-12 + 0.1 * max(abs(a), abs(b)))
    return a - pad * span, b + pad * span


def square_window(ax, points: np.ndarray, min_half: float, y_down: bool = False) -> None:
    """A square window round every point of ``points`` (n x 2), centred on their box (not their mean, so that a
    lopsided orbit is not cut), at least ``2 min_half`` across; ``y_down`` puts the y axis's larger values at
    the bottom (gravity down the page)."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    mid, half = 0.5 * (lo + hi), max(min_half, 0.55 * float((hi - lo).max()))
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(*((mid[1] + half, mid[1] - half) if y_down else (mid[1] - half, mid[1] + half)))
