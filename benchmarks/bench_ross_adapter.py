"""fluidfilm inside ROSS 3.1 (``fluidfilm.interop.ross``): the adapter's checks and its time cost per Newmark step.

    make ross-adapter            (in the ROSS environment, .venv-ross; ``make ross-peer`` runs it too)
    .venv-ross/bin/python benchmarks/bench_ross_adapter.py [--quick]

The rotor: ``jeffcott_rotor()`` (steel shaft 0.5 m x 50 mm in four Timoshenko elements, a 20 kg disc in the
middle, ~28 kg in all) on two plain journal bearings (L = 25 mm, D = 50 mm, c = 50 um, 0.02 Pa s), each a
``ReynoldsSolver`` 30 x 30 (Gumbel) carrying half the weight.

1. Linear match: a linearised film (``LinearisedFilm``: the solver's K, C at its equilibrium) through the
   callback against ROSS's own ``BearingElement`` with the same K, C, after a 1 ms push on the disc. With
   ``linear_part="none"`` the callback carries the whole force (explicit, predicted to the step's end): the
   difference is the integrator's and falls with the step at second order; ``"implicit"`` is exact.
2. Small orbits: the nonlinear film (``linear_part="implicit"``) against the linear response, pushes of
   200, 20 and 2 N.
3. Whirl onset: ROSS's modal analysis fed the films' K, C at every speed (``stability_threshold``) against
   the growth rate of small orbits in nonlinear runs at 0.98, 0.99, 1.01 and 1.02 of it; the onset is where
   the fitted growth rate crosses zero.
4. Cost per Newmark step (ROSS's "simple" Newmark, ``linear_part="implicit"``): ROSS's own step without the
   callback; the callback with the reference solver (measured in the run); the callback with a
   surrogate-shaped model (an untrained 4-64-64-2 tanh ``SurrogateForceModel``: a network's cost, not its
   accuracy) and the linearised film, replayed on the run's states, each through the compiled callback
   (``FilmBearings.compiled``, where every node has a compiled kernel) and through the Python loop over the
   nodes, side by side.

Writes reports/benchmarks/ross_adapter.json (keys ``ross_adapter_linear_match_rel_err``,
``ross_adapter_threshold_rel_err``) and reports/figures/ross_orbits.png (the 200 N orbit beside ROSS's linear
one) unless --quick.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from fluidfilm import JournalBearing, ReynoldsSolver
from fluidfilm.characteristics import static
from fluidfilm.interop import ross as fr
from bench_ross_peer import write_report  # the same report layout (this folder is on sys.path)

BEARING = dict(length=0.025, diameter=0.05, clearance=50e-6, viscosity=0.02)
GRID = (30, 30)


def solver(rpm: float) -> ReynoldsSolver:
    return ReynoldsSolver(JournalBearing(speed_rpm=rpm, **BEARING), *GRID)


def setup():
    rotor = fr.jeffcott_rotor()
    w = float(rotor.m) * 9.80665 / 2.0
    return rotor, {0: (0.0, -w), 4: (0.0, -w)}


def push(rotor, t, amplitude: float, duration: float = 1e-3):
    """A push of ``amplitude`` N along x on the disc node for ``duration`` s."""
    F = np.zeros((t.size, rotor.ndof))
    F[t < duration, rotor.number_dof * 2] = amplitude
    return F


def rel_diff(a, b) -> float:
    return float(np.abs(np.asarray(a) - np.asarray(b)).max() / np.abs(np.asarray(b)).max())


def linear_match(rotor, loads, rpm: float, steps, t_end: float) -> dict:
    s = solver(rpm)
    w = loads[0]
    lin = fr.LinearisedFilm(s, static.equilibrium(s, (w[0], -w[1]))["X"])
    models = {0: lin, 4: lin}
    out = {"dt": [], "none": [], "implicit": []}
    for dt in steps:
        t = np.arange(int(round(t_end / dt)) + 1) * dt
        F = push(rotor, t, 200.0)
        film = fr.FilmBearings(rotor, models, loads, linear_part="implicit")
        ref = np.asarray(film.rotor.run_time_response(s.bearing.omega, F, t, method="newmark").yout)
        ref = {n: ref[:, film.dofs[n]] for n in film.nodes}
        imp = fr.run_time_response(film, s.bearing.omega, t, F)
        none = fr.run_time_response(fr.FilmBearings(rotor, models, loads, linear_part="none"), s.bearing.omega, t, F)
        out["dt"].append(dt)
        out["implicit"].append(max(rel_diff(imp["orbits_ross"][n], ref[n]) for n in film.nodes))
        out["none"].append(max(rel_diff(none["orbits_ross"][n], ref[n]) for n in film.nodes))
        print(f"linear match dt={dt:g}: whole force in the callback {out['none'][-1]:.3g}, "
              f"implicit split {out['implicit'][-1]:.3g}", flush=True)
    out["order"] = float(np.log(out["none"][-2] / out["none"][-1]) / np.log(steps[-2] / steps[-1]))
    return out


def orbit_figure(path: Path, t, origin, nonlinear, linear, push_n: float, rpm: float) -> None:
    """The journal orbit at bearing node 0: fluidfilm's film in ROSS beside ROSS's linear bearing element."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    c_um = BEARING["clearance"] * 1e6
    fig, axes = plt.subplots(1, 2, figsize=(9, 4))
    for q, style, label in ((nonlinear, "-", "fluidfilm ReynoldsSolver in ROSS (nonlinear)"),
                            (linear, "--", "ROSS BearingElement, fluidfilm's K, C (linear)")):
        x = (origin + q) * 1e6
        axes[0].plot(x[:, 0], x[:, 1], style, lw=1, label=label)
        axes[1].plot(t * 1e3, np.linalg.norm(x, axis=1) / c_um, style, lw=1, label=label)
    axes[0].plot(*(origin * 1e6), "k+", ms=10, label="static equilibrium")
    axes[0].set(xlabel="X1 [um]", ylabel="X2 [um] (along gravity, drawn downwards)", title="journal orbit, node 0")
    axes[0].invert_yaxis()
    axes[0].set_aspect("equal", adjustable="datalim")
    axes[1].set(xlabel="t [ms]", ylabel="eccentricity ratio", title=f"{push_n:g} N push on the disc, {rpm:g} rpm")
    axes[0].legend(fontsize=7, loc="best")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp.png")
    fig.savefig(tmp, dpi=110)
    tmp.replace(path)
    plt.close(fig)
    print(f"-> {path}")


def small_orbits(rotor, loads, rpm: float, amplitudes, dt: float, t_end: float, figure: Path | None = None) -> dict:
    s = solver(rpm)
    film = fr.FilmBearings(rotor, {0: s, 4: s}, loads, linear_part="implicit")
    t = np.arange(int(round(t_end / dt)) + 1) * dt
    out = {"push_N": [], "amplitude_over_c": [], "rel_diff": []}
    for a in amplitudes:
        F = push(rotor, t, a)
        lin = np.asarray(film.rotor.run_time_response(s.bearing.omega, F, t, method="newmark").yout)[:, film.dofs[0]]
        non = fr.run_time_response(film, s.bearing.omega, t, F)["orbits_ross"][0]
        if a == amplitudes[0] and figure is not None:
            orbit_figure(figure, t, film.origin[0], fr.to_ross(non), fr.to_ross(lin), a, rpm)
        out["push_N"].append(a)
        out["amplitude_over_c"].append(float(np.abs(lin).max() / BEARING["clearance"]))
        out["rel_diff"].append(rel_diff(non, lin))
        print(f"small orbit push {a} N (amplitude {out['amplitude_over_c'][-1]:.2g} c): nonlinear vs linear "
              f"{out['rel_diff'][-1]:.3g}", flush=True)
    return out


def whirl_onset(rotor, loads, bracket_rpm, factors, dt: float, t_end: float, t_from: float) -> dict:
    th = fr.stability_threshold(rotor, lambda rpm: {0: solver(rpm), 4: solver(rpm)}, loads, bracket_rpm)
    period = 2 * np.pi / th["whirl_frequency"]
    print(f"ROSS stability analysis on fluidfilm's K, C: threshold {th['speed_rpm']:.1f} rpm, whirl "
          f"{th['whirl_frequency']:.1f} rad/s", flush=True)
    rows = []
    for f in factors:
        rpm = f * th["speed_rpm"]
        s = solver(rpm)
        film = fr.FilmBearings(rotor, {0: s, 4: s}, loads, linear_part="implicit")
        t = np.arange(int(round(t_end / dt)) + 1) * dt
        res = fr.run_time_response(film, s.bearing.omega, t, push(rotor, t, 2.0))
        sigma = fr.growth_rate(t, res["orbits_ross"][0], period, t_from)
        lin = fr.min_log_dec(rotor, {0: s, 4: s}, loads)
        rows.append({"factor": f, "speed_rpm": rpm, "growth_rate": sigma, "growth_rate_modal": lin["growth_rate"],
                     "amplitude_over_c": float(np.abs(res["orbits_ross"][0]).max() / BEARING["clearance"])})
        print(f"  {f:.3f} x threshold: growth rate {sigma:+.4f} 1/s (modal {lin['growth_rate']:+.4f})", flush=True)
    sp = np.array([r["speed_rpm"] for r in rows])
    sg = np.array([r["growth_rate"] for r in rows])
    slope, icpt = np.polyfit(sp, sg, 1)
    onset = float(-icpt / slope)
    return {"threshold_rpm": th["speed_rpm"], "whirl_frequency": th["whirl_frequency"], "onset_rpm": onset,
            "rel_err": abs(onset / th["speed_rpm"] - 1.0), "runs": rows, "dt": dt, "t_end": t_end, "t_from": t_from}


def surrogate_shaped(bearing) -> object:
    """An untrained 4-64-64-2 tanh network with fitted scalings: a surrogate's cost per force, not its accuracy."""
    from fluidfilm import SurrogateForceModel
    from fluidfilm.perf.speed import sample_states
    from fluidfilm.surrogate import Scaling

    x, v = sample_states(bearing.clearance, n=400, v_max=0.01)
    sc = Scaling.fit("standard", x, v, ReynoldsSolver(bearing, 16, 8).forces(x, v), bearing.clearance,
                     bearing.omega, bearing.force_scale)
    rng = np.random.default_rng(0)
    sizes = [4, 64, 64, 2]
    layers = [(rng.normal(size=(o, i)) / np.sqrt(i), np.zeros(o)) for i, o in zip(sizes[:-1], sizes[1:])]
    return SurrogateForceModel(bearing, [layers], [sc], "tanh", name="surrogate-shaped 4-64-64-2")


def step_cost(rotor, loads, rpm: float, dt: float, t_end: float) -> dict:
    s = solver(rpm)
    t = np.arange(int(round(t_end / dt)) + 1) * dt
    F = push(rotor, t, 20.0)
    film = fr.FilmBearings(rotor, {0: s, 4: s}, loads, linear_part="implicit")
    steps = t.size - 1
    # ROSS alone (the same rotor and bearing elements, no callback), then with the reference film, interleaved
    ross_alone, with_ref = [], []
    for _ in range(3):
        t0 = time.perf_counter()
        film.rotor.run_time_response(s.bearing.omega, F, t, method="newmark")
        ross_alone.append((time.perf_counter() - t0) / steps)
        res = fr.run_time_response(film, s.bearing.omega, t, F)
        with_ref.append((res["seconds"] / steps, res["film_seconds"] / res["film_calls"]))
    alone = float(np.median(ross_alone))
    step_ref = float(np.median([a for a, _ in with_ref]))
    call_ref = float(np.median([b for _, b in with_ref]))
    # replay the run's states through the callback with other models (the same calls a run would make)
    y = np.asarray(res["response"].yout)
    states = y[:: max(1, steps // 2000)]
    out = {"ross_step_s": alone, "step_with_reference_s": step_ref, "reference_call_s": call_ref,
           "reference_share": call_ref / step_ref, "steps": steps, "dt": dt,
           "reference_model": f"ReynoldsSolver {GRID[0]}x{GRID[1]} (Gumbel), two bearings per call"}
    others = {"surrogate": surrogate_shaped(s.bearing), "linearised": fr.LinearisedFilm(s, film.origin[0])}
    zeros = np.zeros(film.ndof)
    for name, m in {"reference": s, **others}.items():
        if name == "reference":
            f2 = film
        else:  # the same origin as the run (an untrained network balances no load: no equilibrium of its own)
            f2 = fr.FilmBearings(rotor, {0: m, 4: m}, None, linear_part="implicit")
            for n in f2.nodes:
                f2.origin[n] = film.origin[n]
                f2.f_origin[n] = np.asarray(m.forces(film.origin[n], np.zeros(2)), dtype=float)
            f2.refresh()
        f2.predict = True
        # the compiled callback (the default where every node has a compiled kernel) and the Python loop over
        # the nodes, interleaved in chunks of states, medians of the chunks' time per call
        compiled_too = all(p[6] is not None for p in f2._plan)
        paths = (True, False) if compiled_too else (False,)
        for compiled in paths:
            f2.compiled = compiled
            for q in states[:50]:
                f2(1, time_step=dt, disp_resp=q, velc_resp=zeros, accl_resp=zeros)
        per_path: dict[bool, list[float]] = {c: [] for c in paths}
        for chunk in np.array_split(states, 10):
            for compiled in paths:
                f2.compiled = compiled
                f2.reset_timing()
                for q in chunk:
                    f2(1, time_step=dt, disp_resp=q, velc_resp=zeros, accl_resp=zeros)
                per_path[compiled].append(f2.seconds / f2.calls)
        f2.compiled = True
        call = float(np.median(per_path[paths[0]]))
        out[f"{name}_replay_call_s"] = call
        out[f"{name}_share"] = call / (alone + call)
        if compiled_too:
            py = float(np.median(per_path[False]))
            out[f"{name}_python_call_s"] = py
            out[f"{name}_python_share"] = py / (alone + py)
        print(f"step cost: ROSS alone {1e6 * alone:.0f} us, callback {name} {1e6 * call:.1f} us "
              f"({100 * out[f'{name}_share']:.0f} % of the step)"
              + (f"; Python loop {1e6 * out[f'{name}_python_call_s']:.1f} us" if compiled_too else ""), flush=True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="shorter runs, no file")
    args = ap.parse_args()
    warnings.filterwarnings("ignore", category=UserWarning)
    import ross

    load0 = os.getloadavg()
    t_start = time.perf_counter()
    rotor, loads = setup()
    rpm0 = 6000.0
    q = args.quick
    lm = linear_match(rotor, loads, rpm0, [2e-6, 1e-6] if q else [2e-6, 1e-6, 5e-7], 0.005 if q else 0.01)
    so = small_orbits(rotor, loads, rpm0, [200.0, 20.0, 2.0], 2e-5, 0.02,
                      None if q else Path("reports/figures/ross_orbits.png"))
    wo = whirl_onset(rotor, loads, (6000.0, 10000.0), [0.98, 0.99, 1.01, 1.02], 1e-4, 0.6 if q else 1.0,
                     0.15)
    sc = step_cost(rotor, loads, rpm0, 2e-5, 0.02 if q else 0.04)
    load1 = os.getloadavg()
    wall = time.perf_counter() - t_start

    metrics = {"ross_adapter_linear_match_rel_err": lm["none"][-1], "ross_adapter_threshold_rel_err": wo["rel_err"],
               "ross_adapter_reference_step_share": sc["reference_share"],
               "ross_adapter_surrogate_step_share": sc["surrogate_share"],
               "ross_adapter_surrogate_step_share_python_loop": sc["surrogate_python_share"]}
    header = ["check", "result"]
    rows = [["linear film through the callback (whole force, explicit) vs ROSS's BearingElement, max rel. diff.",
             ", ".join(f"{v:.2g} at dt {d:g} s" for d, v in zip(lm["dt"], lm["none"]))
             + f" (order {lm['order']:.2f})"],
            ["same, linear part implicit (the default)", f"{max(lm['implicit']):.2g}"],
            ["nonlinear film vs linear, small orbits (implicit split)",
             ", ".join(f"{d:.2g} at {a:.1g} c" for a, d in zip(so["amplitude_over_c"], so["rel_diff"]))],
            ["whirl threshold, ROSS modal analysis on fluidfilm's K, C", f"{wo['threshold_rpm']:.1f} rpm"],
            ["whirl onset, nonlinear runs (growth rate through zero)",
             f"{wo['onset_rpm']:.1f} rpm ({100 * wo['rel_err']:.3f} % off)"],
            ["ROSS Newmark step alone (30 DOF rotor)", f"{1e6 * sc['ross_step_s']:.0f} us"],
            ["callback, reference solver 30x30, two bearings",
             f"{1e6 * sc['reference_call_s']:.0f} us per step ({100 * sc['reference_share']:.0f} % of the step)"],
            ["callback, reference solver 30x30, two bearings, replayed: compiled callback / Python loop",
             f"{1e6 * sc['reference_replay_call_s']:.0f} / {1e6 * sc['reference_python_call_s']:.0f} us per step"],
            ["callback, surrogate-shaped network, two bearings (compiled callback)",
             f"{1e6 * sc['surrogate_replay_call_s']:.1f} us per step ({100 * sc['surrogate_share']:.0f} % of the step)"],
            ["same, the Python loop over the nodes (the callback before the compiled path)",
             f"{1e6 * sc['surrogate_python_call_s']:.1f} us per step ({100 * sc['surrogate_python_share']:.0f} % of the "
             f"step)"],
            ["callback, linearised film (numpy forces(), no compiled kernel)",
             f"{1e6 * sc['linearised_replay_call_s']:.0f} us per step ({100 * sc['linearised_share']:.0f} % of the step)"]]
    notes = (f"ROSS {ross.__version__} (Python {sys.version.split()[0]}), fluidfilm.interop.ross; Jeffcott rotor "
             f"({float(rotor.m):.1f} kg) on two ReynoldsSolver {GRID[0]}x{GRID[1]} films (L 25 mm, D 50 mm, c 50 um, "
             f"0.02 Pa s) carrying half its weight each; linear match and small orbits at {rpm0:.0f} rpm, 1 ms push "
             f"on the disc. Whirl: runs of {wo['t_end']} s at dt {wo['dt']:g} s, growth rate fitted from "
             f"{wo['t_from']} s to peaks per whirl period. Step cost: median of 3 runs of {sc['steps']} steps "
             f"(ROSS alone and with the callback interleaved); the other models replay the run's states through "
             f"the callback, compiled (FilmBearings.compiled, the default where every node has a compiled kernel) "
             f"and as the Python loop over the nodes, interleaved in 10 chunks (medians). Shares = callback / (ROSS's step + callback). Load average {load0[0]:.1f} before, "
             f"{load1[0]:.1f} after ({os.cpu_count()} cores shared); wall time {wall:.0f} s.")
    for r in rows:
        print(" | ".join(r))
    if q:
        return
    write_report("ross_adapter", "fluidfilm force models inside ROSS 3.1 (fluidfilm.interop.ross): checks and "
                 "cost per Newmark step", header, rows, notes, metrics,
                 {"linear_match": lm, "small_orbits": so, "whirl_onset": wo, "step_cost": sc,
                  "loadavg_before": load0, "loadavg_after": load1})


if __name__ == "__main__":
    main()
