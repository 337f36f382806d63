"""The training-time study's statistics (src/fluidfilm/studies/train_time.py) against independent truth."""
import math

import numpy as np
import pytest

from fluidfilm.studies.train_time import mean_ci, reduction_ci, seeds_needed


def test_the_same_times_on_every_seed_give_1_minus_the_ratio_with_no_spread():
    red, lo, hi, hw = reduction_ci([10.0] * 6, [7.4] * 6)
    assert red == pytest.approx(26.0) and lo == pytest.approx(26.0) and hi == pytest.approx(26.0) and hw == 0.0


def test_the_reduction_is_that_of_the_mean_times_not_the_mean_of_ratios():
    single, split = [10.0, 40.0], [20.0, 20.0]          # per seed -100 % and +50 %: mean of ratios -25 %
    red, *_ = reduction_ci(single, split, n_resamples=200)
    assert red == pytest.approx(100 * (1 - 20.0 / 25.0))  # 20 % from the mean times


def test_bootstrap_interval_matches_the_delta_method_on_many_seeds():
    rng = np.random.default_rng(1)
    n = 400
    single = rng.lognormal(np.log(40.0), 0.35, n)
    split = rng.lognormal(np.log(30.0), 0.35, n)
    red, lo, hi, hw = reduction_ci(single, split, n_resamples=4000)
    # delta method for R = mean(split)/mean(single): var R ~ R^2 (cv_p^2 + cv_s^2) / n (independent)
    r = split.mean() / single.mean()
    se = 100 * r * math.sqrt((split.std(ddof=1) / split.mean()) ** 2 + (single.std(ddof=1) / single.mean()) ** 2) / math.sqrt(n)
    assert hw == pytest.approx(1.96 * se, rel=0.15)
    assert lo < red < hi
    # and the truth (1 - 30/40 in the medians of equal-shape lognormals: 25 %) lies inside
    assert lo < 25.0 < hi


def test_the_interval_covers_the_truth_about_95_percent_of_the_time():
    rng = np.random.default_rng(7)
    truth = 25.0  # equal-shape lognormals: the ratio of means equals the ratio of medians
    hits = 0
    trials = 120
    for _ in range(trials):
        single = rng.lognormal(np.log(40.0), 0.3, 30)
        split = rng.lognormal(np.log(30.0), 0.3, 30)
        _, lo, hi, _ = reduction_ci(single, split, n_resamples=1000, seed=int(rng.integers(1 << 30)))
        hits += lo <= truth <= hi
    assert 0.85 <= hits / trials <= 1.0


def test_mean_ci_of_a_constant_is_the_constant_and_unknown_with_one_value():
    assert mean_ci([3.0, 3.0, 3.0]) == (3.0, 3.0, 0.0)
    lo, hi, hw = mean_ci([1.0])
    assert math.isnan(lo) and math.isnan(hi) and hw == math.inf


def test_seeds_needed_follows_the_square_root_law():
    assert seeds_needed(14, 36.6, 10.0) == math.ceil(14 * 3.66 ** 2)
    assert seeds_needed(14, 5.0, 10.0) == 14          # already narrow enough
    assert seeds_needed(1, math.inf, 10.0) is None


@pytest.mark.parametrize("single, split, match", [
    ([10.0, -1.0], [5.0, 5.0], "positive and finite"),
    ([10.0, math.nan], [5.0, 5.0], "positive and finite"),
    ([10.0, 2.0, 3.0], [5.0, 5.0], "one single and one split time per seed"),
])
def test_bad_times_are_refused_naming_them(single, split, match):
    with pytest.raises(ValueError, match=match):
        reduction_ci(single, split)


def test_an_interrupted_study_resumes_at_the_next_seed_with_the_finished_seeds_unchanged(quick_data, tmp_path):
    """Seeds finished before an interruption come back from the cache as they were; only new seeds train;
    another subsample size (or protocol, code, data) is another cache key and trains afresh."""
    from pathlib import Path

    import yaml

    from fluidfilm.studies.train_time import study
    from fluidfilm.surrogate.training import read_dataset

    frame, meta = read_dataset(quick_data[0])
    protocol = yaml.safe_load((Path(__file__).parents[2] / "conf" / "protocol" / "paper.yaml").read_text())
    protocol["max_epochs"] = 15
    args = dict(frame=frame, meta=meta, protocol=protocol, boundaries=[0.5, 0.7], n_samples=900, target_hw=0.0,
                n_jobs=1, n_resamples=100, budget_s=math.inf, cache_dir=tmp_path)
    first = study(seeds_min=2, seeds_max=2, **args)          # "interrupted" after two seeds
    again = study(seeds_min=2, seeds_max=3, **args)
    assert first["resumed_seeds"] == 0 and again["resumed_seeds"] == 2
    assert [r["seed"] for r in again["runs"]] == [0, 1, 2]
    assert again["runs"][:2] == first["runs"]                 # times and errors as measured the first time
    assert len(list(tmp_path.glob("*/seed_*.json"))) == 3
    other = study(seeds_min=1, seeds_max=1, **(args | {"n_samples": 1200}))
    assert other["resumed_seeds"] == 0 and len(list(tmp_path.glob("*/seed_*.json"))) == 4
