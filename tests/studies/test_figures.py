"""Figures a reader trusts at a glance, checked on small synthetic tables: log-axis tick labels that do
not overprint, axes that span the reference's values with a broken model's outliers marked and named
(not rescaling the plot), mathtext units, and a caption for every figure the pipeline draws."""
from __future__ import annotations

import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402
import yaml  # noqa: E402

from fluidfilm.studies import characteristics_study as study  # noqa: E402
from fluidfilm.studies import plots  # noqa: E402
from fluidfilm.reporting.captions import CAPTIONS  # noqa: E402
from fluidfilm.studies.figure_style import limit_with_outliers, readable_log_ticks  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def _labels(axis):
    """The tick labels matplotlib draws on ``axis`` (inside the view), with their extents, after a draw."""
    fig = axis.get_figure()
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    lo, hi = sorted(axis.get_view_interval())
    out = []
    for tick in axis.get_major_ticks() + axis.get_minor_ticks():
        label = tick.label1
        if label.get_visible() and label.get_text() and lo <= tick.get_loc() <= hi:
            out.append((label.get_text(), label.get_window_extent(renderer)))
    return out


def _assert_no_overlap(axis):
    labels = sorted(_labels(axis), key=lambda t: (t[1].x0, t[1].y0))
    assert len(labels) >= 2, f"fewer than 2 tick labels: {[t for t, _ in labels]}"
    for (ta, a), (tb, b) in zip(labels, labels[1:]):
        assert not a.overlaps(b), f"tick labels {ta!r} and {tb!r} overprint"


def _stability_table(outlier: float = 233.0) -> pd.DataFrame:
    """Reference, a converged reference and a 'broken' surrogate with one whirl ratio of ``outlier``
    and one critical mass 1000x the reference's, over less than two decades of S (where matplotlib
    labels minor ticks)."""
    s = np.geomspace(0.018, 0.8, 9)
    whirl = 0.5 * (1 - np.exp(-s / 0.05))
    mass = 6 + 0.5 / s
    rows = []
    for name, w, m in (("reference", whirl, mass), ("reference_converged", whirl * 1.01, mass * 1.02),
                       ("broken", np.where(np.arange(9) == 4, outlier, whirl * 0.9), np.where(np.arange(9) == 2, 1e3 * mass, mass))):
        rows.append(pd.DataFrame({"model": name, "sommerfeld": s, "whirl_ratio": w, "critical_mass_bar": m, "eps": s}))
    return pd.concat(rows, ignore_index=True)


def test_log_ticks_on_a_short_axis_are_plain_numbers_that_do_not_overprint():
    fig, ax = plt.subplots(figsize=(3, 3))
    ax.semilogx([0.2, 0.9], [0, 1])  # under a decade: matplotlib labels the minor ticks, and they overprint
    with pytest.raises(AssertionError, match="overprint"):
        _assert_no_overlap(ax.xaxis)
    readable_log_ticks(ax, "x")
    _assert_no_overlap(ax.xaxis)
    assert {"0.2", "0.5"} <= {t for t, _ in _labels(ax.xaxis)}
    ax.set_xlim(0.015, 0.9)  # under two decades: 1-2-5 steps
    readable_log_ticks(ax, "x")
    _assert_no_overlap(ax.xaxis)
    assert {"0.02", "0.05", "0.1", "0.2", "0.5"} <= {t for t, _ in _labels(ax.xaxis)}
    plt.close(fig)


def test_log_ticks_on_a_long_axis_are_decades():
    fig, ax = plt.subplots(figsize=(4, 3))
    ax.loglog([1e-3, 1e5], [1, 10])
    readable_log_ticks(ax, "x")
    texts = [t for t, _ in _labels(ax.xaxis)]
    assert all(re.fullmatch(r"\$\\mathdefault\{10\^\{[−-]?\d+\}\}\$", t) for t in texts), texts
    _assert_no_overlap(ax.xaxis)
    plt.close(fig)


def test_stability_map_keeps_the_whirl_ratio_axis_physical_and_names_the_outlier():
    fig = study.plot_stability_map(_stability_table(), {"k": 130.0},
                                   [{"factor": 0.95, "sommerfeld": 0.2, "mass_bar": 5.5, "ratio": 1e-6}])
    mass_ax, whirl_ax = fig.axes[:2]
    lo, hi = whirl_ax.get_ylim()
    assert (lo, hi) == (0.0, 1.0) and hi < 233.0  # the outlier does not scale the plot
    notes = [t.get_text() for t in whirl_ax.texts]
    assert any("broken" in n and "233" in n for n in notes), notes
    # the critical mass axis spans the reference, the 1000x point is marked, not drawn to scale
    m_lo, m_hi = mass_ax.get_ylim()
    assert m_hi < 1e3 * 6 and m_lo < 5.5 < m_hi
    assert any("broken" in t.get_text() and "above" in t.get_text() for t in mass_ax.texts)
    for ax in (mass_ax, whirl_ax):
        _assert_no_overlap(ax.xaxis)
    _assert_no_overlap(mass_ax.yaxis)
    assert r"\bar{m}" in mass_ax.get_ylabel() and "$" in mass_ax.get_ylabel()
    assert "omega^2" not in mass_ax.get_ylabel().replace(r"\omega^2", "")
    plt.close(fig)


def test_limit_with_outliers_marks_each_edge_once_per_series():
    fig, ax = plt.subplots()
    x = np.arange(5.0)
    ax.plot(x, [0.1, 50.0, 0.2, -7.0, -9.0])
    notes = limit_with_outliers(ax, 0.0, 1.0, [(x, [0.1, 50.0, 0.2, -7.0, -9.0], "net", "C0")])
    assert ax.get_ylim() == (0.0, 1.0)
    assert [(n["edge"], n["n"], n["value"]) for n in notes] == [("top", 1, 50.0), ("bottom", 2, -9.0)]
    assert {n["text"] for n in notes} == {t.get_text() for t in ax.texts}
    plt.close(fig)


def test_coefficients_panels_span_the_reference_and_mark_a_broken_surrogate():
    eps = np.linspace(0.1, 0.9, 9)
    base = {k: 1.0 + eps * (i + 1) for i, k in enumerate(study.coef.NAMES)}
    rows = [pd.DataFrame({"model": "reference", "eps": eps, **base})]
    rows.append(pd.DataFrame({"model": "broken", "eps": eps, **{k: v * np.where(eps > 0.5, 1e3, 1.0) for k, v in base.items()}}))
    fig = study.plot_coefficients(pd.concat(rows, ignore_index=True))
    for ax, k in zip(fig.axes, study.coef.NAMES):
        assert ax.get_ylim()[1] < 100 * base[k].max(), k
        assert any("broken" in t.get_text() for t in ax.texts), k
        assert ax.get_title().startswith("$"), ax.get_title()
    plt.close(fig)


def test_grading_study_log_axes_do_not_overprint():
    table = pd.DataFrame({"job": [f"grading.n={n}" for n in (6, 12, 24)], "n_samples": [9e4, 3e5, 2.6e6],
                          "generation_s": [10.7, 11.4, 16.8], "held_out_rel_err_median": [0.1, 0.02, 0.005],
                          "held_out_rel_err_p99": [40, 10, 3], "orbit_states_rel_err_median": [0.2, 0.05, 0.004],
                          "orbit_states_rel_err_p99": [0.4, 0.1, 0.02], "n_satisfactory": [0, 2, 7]})
    fig = plots.plot_grading_study(table, "grading")
    for ax in fig.axes[:2]:
        _assert_no_overlap(ax.xaxis)
    plt.close(fig)


def test_ablation_on_one_dataset_gets_one_row_per_job_and_no_label_overprints():
    """Every ablation job has the same dataset size: on a size axis their labels would stack on one point."""
    jobs = [f"scaling={s},split={p}" for s in ("physics_whirl", "standard", "physics_polar") for p in ("none", "five_blend")]
    n = len(jobs)
    table = pd.DataFrame({"job": jobs, "n_samples": [690625] * n, "generation_s": [11.0] * n,
                          "held_out_rel_err_median": np.linspace(0.01, 5, n), "held_out_rel_err_p99": np.linspace(1, 150, n),
                          "orbit_states_rel_err_median": np.linspace(0.01, 20, n),
                          "orbit_states_rel_err_p99": np.linspace(0.04, 180, n), "n_satisfactory": [7, 7, 0, 0, 0, 0]})
    fig = plots.plot_grading_study(table, "ablation")
    (ax,) = fig.axes
    assert [t.get_text() for t in ax.get_yticklabels()] == [f"{j} ({k}/7)" for j, k in zip(jobs, table.n_satisfactory)]
    _assert_no_overlap(ax.yaxis)
    _assert_no_overlap(ax.xaxis)
    plt.close(fig)


def _pipeline_figures() -> set[str]:
    """Every PNG the pipeline writes (dvc.yaml: the stages' outs and the plots list), as a path under reports/."""
    spec = yaml.safe_load((ROOT / "dvc.yaml").read_text())
    entries = [e for stage in spec["stages"].values() for e in stage.get("outs", [])] + spec.get("plots", [])
    out = set()
    for entry in entries:
        path = str(next(iter(entry)) if isinstance(entry, dict) else entry)
        if path.endswith(".png"):
            out.add(path.removeprefix("reports/"))
    return out


def test_every_pipeline_figure_has_a_caption_and_no_caption_is_stale():
    figures = _pipeline_figures()
    assert figures, "dvc.yaml lists no figure"
    assert figures == set(CAPTIONS), (sorted(figures - set(CAPTIONS)), sorted(set(CAPTIONS) - figures))
    for name, caption in CAPTIONS.items():
        assert len(caption) > 40 and caption.endswith("."), name


@pytest.mark.parametrize("label", ["m c omega^2 / W", "eps", "[um]"])
def test_no_code_style_units_left_in_the_plot_labels(label):
    text = "\n".join(p.read_text() for p in (ROOT / "src/fluidfilm/studies").glob("*.py"))
    calls = re.findall(r"set_[xy]?label\(([^)]*)\)|set_title\(([^)]*)\)", text)
    joined = " ".join(a + b for a, b in calls)
    assert label not in joined.replace(r"\varepsilon", "")


def test_every_plotting_function_draws_its_labels_on_small_synthetic_inputs(tmp_path):
    """Each figure is drawn to the end (a mathtext error in a label only shows when it is rendered)."""
    from types import SimpleNamespace

    eps = np.linspace(0.1, 0.95, 6)
    grid = pd.DataFrame({"eps": eps, **{f"F_{n}": 100 * (1 + k) / (1 - eps) for k, n in enumerate(("a", "ref"))},
                         "err_a_pct": 5 * eps})
    v = np.linspace(-0.1, 0.1, 5)
    velocity = pd.concat([pd.DataFrame({"eps": e, "direction": d, "v": v, "F1": 50 * v + e, "F2": 80 * v})
                          for e in (0.3, 0.6) for d in ("radial", "tangential")])
    phi = np.linspace(0, 6, 50)
    traj = SimpleNamespace(x=1e-4 * np.c_[0.3 * np.cos(phi), 0.3 * np.sin(phi)], t=phi, ok=True, status="ok")
    locus = pd.DataFrame({"X1": 1e-4 * eps * 0.5, "X2": 1e-4 * eps * 0.8, "sommerfeld": 1 / eps, "eps": eps,
                          "attitude_deg": 60 * (1 - eps)})
    hist = [{"t": t, "clearance": 1e-4, "amplitude": 2e-5 * t, "sleeve": 1e-3} for t in (0.0, 0.5, 1.0)]
    runs = {"none": {"history": hist, "x": traj.x, "t": traj.t, "max_amplitude_m": 2e-5}}
    figures = [plots.plot_grid_comparison(grid, ["a"], {}, "ref"), plots.plot_velocity_response(velocity),
               plots.plot_orbits({"a": ("case", {"reference": traj})}, 1e-4, 2.0, "orbits"),
               plots.plot_equilibrium_locus(locus, 1e-4)]
    for fig in figures:
        fig.savefig(tmp_path / "f.png")
        plt.close(fig)
    written = plots.fig5_panels(runs, 1e-4, tmp_path, ramp=(0.0, 1e-4))
    assert [p.name for p in written] == ["fig5_b_none.png", "fig5_amplitude.png"]
    static = pd.DataFrame({"cavitation": "gumbel", "feed": "none", "sommerfeld": 1 / eps, "eps": eps,
                           "attitude_deg": 60 * (1 - eps), "power_W": 2 + eps, "side_flow_m3s": 1e-5 * eps})
    fig = study.plot_static(static)
    fig.savefig(tmp_path / "s.png")
    _assert_no_overlap(fig.axes[0].xaxis)
    plt.close(fig)
