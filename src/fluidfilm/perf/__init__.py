"""Timing: the one timer (``benchmarking.median_seconds``), force evaluations per second (``speed``),
trajectories per second (``throughput``), what a second thread can add on this machine (``cores``), and
the benchmark files the README's speed tables come from.

Only the timer is imported here: ``speed`` and ``throughput`` pull in the rotor integrator, which a stage
that only times something should not depend on (``from fluidfilm.perf.speed import time_per_force_eval``).
"""
from fluidfilm.perf.benchmarking import machine, median_seconds, render, write_benchmark

__all__ = ["median_seconds", "machine", "write_benchmark", "render"]
