"""The one timer of the workspace (fluidfilm.perf.benchmarking.median_seconds), on a scripted clock."""
from __future__ import annotations

import pytest

from fluidfilm.perf import benchmarking


def _scripted(monkeypatch, durations):
    """A clock that only ``fn`` advances: call k takes ``durations[k]`` seconds."""
    clock = {"t": 0.0, "calls": 0}
    monkeypatch.setattr(benchmarking.time, "perf_counter", lambda: clock["t"])

    def fn():
        clock["t"] += durations[clock["calls"]]
        clock["calls"] += 1
    return fn, clock


def test_median_of_repeats_after_one_untimed_warm_up(monkeypatch):
    # warm-up 100 s (a compile) is not counted; samples 1, 9, 2, 3, 50: the median is 3
    fn, clock = _scripted(monkeypatch, [100.0, 1.0, 9.0, 2.0, 3.0, 50.0])
    assert benchmarking.median_seconds(fn, repeats=5) == 3.0
    assert clock["calls"] == 6


def test_calls_per_sample_are_averaged_and_warm_up_can_be_left_out(monkeypatch):
    # two samples of three calls: (1+2+3)/3 = 2 and (4+4+7)/3 = 5; the median of two is their mean
    fn, clock = _scripted(monkeypatch, [1.0, 2.0, 3.0, 4.0, 4.0, 7.0])
    assert benchmarking.median_seconds(fn, repeats=2, calls=3, warmup=False) == pytest.approx(3.5)
    assert clock["calls"] == 6


@pytest.mark.parametrize("repeats, calls", [(0, 1), (3, 0)])
def test_bad_counts_are_refused(repeats, calls):
    with pytest.raises(ValueError, match="repeats and calls"):
        benchmarking.median_seconds(lambda: None, repeats, calls)


# ---------------------------------------------------------------------------- perf.cores: the core probe
@pytest.mark.parametrize("kw, text", [({"threads": 1}, "threads must be an integer >= 2, got 1"),
                                      ({"seconds": 0.0}, "seconds must be a positive finite number, got 0.0"),
                                      ({"seconds": float("nan")}, "got nan"),
                                      ({"repeats": 0}, "repeats must be a positive integer, got 0")])
def test_core_probe_refuses_bad_arguments_naming_them(kw, text):
    from fluidfilm.perf.cores import core_scaling
    with pytest.raises(ValueError, match=text):
        core_scaling(**kw)


def test_core_probe_vector_loop_is_packed_fma_and_the_scalings_are_bounded_by_the_threads():
    # the premise of the probe: its vector loop runs packed (ymm/zmm) single-precision arithmetic, so it
    # loads the vector units; and a scaling is a throughput ratio, positive and (noise aside) at most the
    # number of threads
    import re

    from fluidfilm.perf.cores import _vector_fma, core_scaling
    r = core_scaling(threads=2, seconds=0.02, repeats=1)
    asm = next(iter(_vector_fma.inspect_asm().values()))
    assert re.search(r"v(fmadd|fmul|add)[0-9a-z]*ps\s+%[yz]mm", asm), "the FMA probe did not vectorise"
    for kind in ("vector_fma", "scalar_chain"):
        assert 0.3 < r[kind] < 3.0, (kind, r[kind])
