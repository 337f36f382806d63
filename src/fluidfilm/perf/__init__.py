"""Timing: the one timer (``benchmarking.median_seconds``), force evaluations per second (``speed``) and
trajectories per second (``throughput``), and the benchmark files the README's speed tables come from."""
from fluidfilm.perf.benchmarking import machine, median_seconds, render, write_benchmark
from fluidfilm.perf.speed import sample_states, time_per_force_eval
from fluidfilm.perf.throughput import monte_carlo_batch, trajectories_per_second

__all__ = ["median_seconds", "machine", "write_benchmark", "render", "sample_states", "time_per_force_eval",
           "monte_carlo_batch", "trajectories_per_second"]
