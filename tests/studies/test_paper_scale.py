"""The paper_scale study's measures against independent truth.

- a model equal to the reference has no static force error along the locus and no equilibrium offset;
- a model whose film is twice as stiff (forces doubled) settles where the reference carries half the
  load: its equilibrium offset is the distance between the reference's equilibria under W and W / 2,
  and its static force error at the reference's equilibrium is the load itself;
- the verdicts count the paper's seven verdicts a reading reproduces;
- the flat keys carry the size, the structure and the ablation variant.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidfilm import ReynoldsSolver, paper_bearing
from fluidfilm.characteristics.static import equilibrium
from fluidfilm.studies.paper_scale import (equilibrium_offset, locus_errors, points, size_label, summary_keys,
                                          verdicts)


class _Doubled:
    """The reference's forces times two (a stiffer film)."""

    def __init__(self, model):
        self.model = model
        self.bearing = model.bearing

    def forces(self, X, V):
        return 2.0 * np.asarray(self.model.forces(X, V))


@pytest.fixture(scope="module")
def reference():
    return ReynoldsSolver(paper_bearing(), 24, 12)


def test_the_reference_against_itself_has_no_static_error_and_no_offset(reference):
    loc = locus_errors(reference, reference, np.array([10.0, 25.0, 60.0]), np.array([0.0, 1.0]))
    assert [p["error_abs_N"] for p in loc["points"]] == [0.0, 0.0, 0.0]
    assert all(np.diff([p["eps"] for p in loc["points"]]) > 0)  # heavier loads sit further out
    off = equilibrium_offset(reference, reference, (0.0, 25.0))
    assert off["offset_pct_c"] == pytest.approx(0.0, abs=1e-6) and off["static_force_error_N"] == [0.0, 0.0]


def test_a_twice_stiffer_film_settles_where_the_reference_carries_half_the_load(reference):
    W = (0.0, 25.0)
    off = equilibrium_offset(_Doubled(reference), reference, W)
    full, half = equilibrium(reference, W), equilibrium(reference, (0.0, 12.5))
    c = reference.bearing.clearance
    expected = 100 * math.hypot(full["X1"] - half["X1"], full["X2"] - half["X2"]) / c
    assert off["offset_pct_c"] == pytest.approx(expected, rel=1e-4)
    assert off["eps_model"] == pytest.approx(half["eps"], rel=1e-6)
    # at the reference's equilibrium the doubled film pushes back with one extra load: |error| = |W|
    assert math.hypot(*off["static_force_error_N"]) == pytest.approx(25.0, rel=1e-6)
    loc = locus_errors(_Doubled(reference), reference, np.array([10.0, 40.0]), np.array([0.0, 1.0]))
    assert loc["error_share_of_load_max"] == pytest.approx(1.0, rel=1e-6)


def test_verdicts_count_the_papers_verdicts_each_reading_reproduces():
    rows = [{"case": k, "satisfactory": k in "ab", "satisfactory_paper_reading": k in "abcdefg"} for k in "abcdefg"]
    v = verdicts(rows, "split")  # the paper: a-e satisfactory, f and g not
    assert v["satisfactory_cases_position"] == "ab" and v["satisfactory_cases_paper_reading"] == "abcdefg"
    assert v["paper_verdicts_reproduced_position"] == 4  # a, b right; c, d, e wrong; f, g right
    assert v["paper_verdicts_reproduced_paper_reading"] == 5  # a-e right, f and g wrong
    assert verdicts(rows, "single")["paper_verdicts_reproduced_position"] == 4  # e only: a, b wrong, e wrong


def test_flat_keys_name_size_structure_and_variant():
    def rec(label, structure, n):
        return {"label": label, "structure": structure, "point": {"n_samples": n}, "satisfactory_cases_position": "ab",
                "satisfactory_cases_paper_reading": "abc", "equilibrium_offset_pct_c": 27.0, "orbit_rms_pct_max": 30.0,
                "train_time_s": 100.0, "locus": {"error_share_of_load_max": 4.0}, "converged": True}
    keys = summary_keys([rec("curve split 40000", "split", 40000), rec("ablation whirl_frame", "split", 40000),
                         rec("full scale single", "single", None), rec("full scale split", "split", None) | {
                             "train_time_s": 75.0}])
    assert keys["satisfactory_cases_split_40000"] == 2 and keys["equilibrium_offset_pct_c_split_40000"] == 27.0
    assert keys["satisfactory_cases_split_40000_paper_reading"] == 3
    assert keys["equilibrium_offset_pct_c_ablation_whirl_frame"] == 27.0
    assert keys["satisfactory_cases_single_full_scale"] == 2
    assert keys["train_time_reduction_pct_full_scale_lm"] == pytest.approx(25.0)
    assert keys["converged_split_40000"] == 1.0 and keys["converged_single_full_scale"] == 1.0
    # a full-scale network stopped by its time budget: no reduction (it would compare the budgets)
    capped = summary_keys([rec("full scale single", "single", None),
                           rec("full scale split", "split", None) | {"train_time_s": 300.0, "converged": False}])
    assert capped["train_time_converged_full_scale_lm"] is False and capped["converged_split_full_scale"] == 0.0
    assert "train_time_reduction_pct_full_scale_lm" not in capped


def test_the_full_scale_points_train_on_every_sample_and_print_as_all():
    cfg = {"sizes": [], "structures": ["single"], "boundaries": [0.5, 0.7], "ablation": {"enabled": False},
           "full_scale": {"single": {"enabled": True, "structure": "single", "network_protocol": None},
                          "split": {"enabled": False, "structure": "split"}}}
    (p,) = points(cfg)
    assert p["label"] == "full scale single" and p["n_samples"] is None
    assert size_label(p["n_samples"]) == "all" and size_label(160000) == "160,000"


def test_a_size_budget_caps_every_network_of_that_size_only():
    cfg = {"sizes": [40000, 640000], "structures": ["single", "split"], "boundaries": [0.5, 0.7],
           "size_budget_s": {"640000": 300}, "ablation": {"enabled": False}, "full_scale": {}}
    by_label = {p["label"]: p for p in points(cfg)}
    assert by_label["curve split 40000"]["network_protocol"] is None
    assert by_label["curve single 640000"]["network_protocol"] == {0: {"max_time_s": 300.0}}
    assert by_label["curve split 640000"]["network_protocol"] == {r: {"max_time_s": 300.0} for r in range(3)}
    # the checkpoints are shared with the unbudgeted point (point_key without the network protocol)
    unbudgeted = dict(by_label["curve split 640000"], network_protocol=None)
    assert unbudgeted == dict(points(cfg | {"size_budget_s": {}})[3])


def test_resolution_is_the_maps_half_range_at_the_equilibrium(reference):
    """A minmax-mapped network's unit at rest is its half-range of force; times the validation RMS error."""
    from fluidfilm.studies.paper_scale import resolution
    from fluidfilm.surrogate.scaling import Scaling

    class _Mapped:
        boundaries = np.array([0.5])
        scalings = [Scaling("minmax", 1.0, 1.0, 1.0, 0.0, np.zeros(4), np.ones(4), np.zeros(2), np.array([10.0, 20.0])),
                    Scaling("minmax", 1.0, 1.0, 1.0, 0.0, np.zeros(4), np.ones(4), np.zeros(2), np.array([300.0, 400.0]))]

    # the rotor's 25 N puts the paper bearing's journal above eps 0.5: the second network, 500 N per unit
    eq = equilibrium(reference, (0.0, 25.0))
    r = resolution(_Mapped(), reference, (0.0, 25.0), [{"val_mse": 1.0}, {"val_mse": 1e-4}])
    assert r["network"] == int(eq["eps"] >= 0.5)
    unit = [300.0, 400.0] if r["network"] == 1 else [10.0, 20.0]
    assert r["newton_per_mapped_unit"] == unit
    assert r["expected_static_error_N"] == pytest.approx(math.hypot(*unit) * (0.01 if r["network"] == 1 else 1.0))
