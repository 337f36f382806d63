"""Shared fixtures: the quick dataset and test set, generated once per session."""
from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from fluidfilm import paper_bearing
from fluidfilm.data import DatasetSpec, generate_dataset, random_test_set

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = {"coarse": [30, 30], "dense": [55, 55], "eps_threshold": 0.9, "cavitation": "gumbel"}


@pytest.fixture(scope="session")
def quick_data(tmp_path_factory):
    """(dataset_dir, testset_dir) of the quick profile."""
    cfg = yaml.safe_load((ROOT / "conf" / "dataset" / "quick.yaml").read_text())
    spec = DatasetSpec.from_cfg(cfg)
    out = tmp_path_factory.mktemp("quick_data")
    generate_dataset(paper_bearing(), REFERENCE, spec, out / "dataset", scheduler="inline", progress=False)
    random_test_set(paper_bearing(), REFERENCE, spec, out / "testset")
    return out / "dataset", out / "testset"
