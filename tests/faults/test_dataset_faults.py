"""Items 1, 5, 12: the dataset under bad overrides, damaged and truncated parts, config changes."""
from __future__ import annotations

import json

import pandas as pd
import pytest

from fluidfilm import paper_bearing
from fluidfilm.data import DatasetIntegrityError, DatasetSpec, generate_dataset, random_test_set, verify_dataset
from fluidfilm.data import generate as gen
from fluidfilm.surrogate.training import read_dataset

from .conftest import REFERENCE, quick_cfg, run_entry, snapshot


def _make(out, spec=None, reference=REFERENCE):
    return generate_dataset(paper_bearing(), reference, spec or DatasetSpec.from_cfg(quick_cfg()), out,
                            scheduler="inline", progress=False)


def _frame(path):
    return pd.read_parquet(path).sort_values(["X1", "X2", "V1", "V2"], kind="stable").reset_index(drop=True)


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A finished quick dataset and test set, made once; tests copy it before damaging anything."""
    root = tmp_path_factory.mktemp("finished")
    _make(root / "dataset")
    random_test_set(paper_bearing(), REFERENCE, DatasetSpec.from_cfg(quick_cfg()), root / "testset")
    return root


@pytest.fixture
def copy_of(finished, tmp_path):
    import shutil

    shutil.copytree(finished / "dataset", tmp_path / "dataset")
    shutil.copytree(finished / "testset", tmp_path / "testset")
    return tmp_path


# --------------------------------------------------------------------------- item 1
@pytest.mark.parametrize("override, key", [
    ("reference.eps_threshold=abc", "reference.eps_threshold"),
    ("reference.coarse=[30]", "reference.coarse"),
    ("dataset.positions_per_chunk=0", "dataset.positions_per_chunk"),
])
def test_bad_override_leaves_a_finished_dataset_untouched_and_names_the_key(copy_of, override, key):
    before = snapshot(copy_of)
    proc = run_entry("make_dataset", "dataset=quick", "dask.scheduler=inline", "progress=false",
                     f"out_dir={copy_of / 'dataset'}", f"test_dir={copy_of / 'testset'}", override)
    assert proc.returncode != 0
    assert key in proc.stderr + proc.stdout
    assert snapshot(copy_of) == before  # not one byte of the finished work changed
    verify_dataset(copy_of / "dataset")


def test_new_config_is_built_aside_and_the_old_dataset_survives_an_interruption(copy_of, monkeypatch):
    out = copy_of / "dataset"
    before = snapshot(out)
    cfg = quick_cfg()
    cfg["velocity_sections"][0]["v_max"] = 0.1
    spec_b = DatasetSpec.from_cfg(cfg)
    real, calls = gen.compute_chunk, []

    def dies_on_the_third_chunk(job):
        calls.append(job["index"])
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(job)

    monkeypatch.setattr(gen, "compute_chunk", dies_on_the_third_chunk)
    with pytest.raises(KeyboardInterrupt):
        _make(out, spec_b)
    assert snapshot(out) == before  # the finished dataset is still there, whole
    monkeypatch.setattr(gen, "compute_chunk", real)
    meta = _make(out, spec_b)  # resumes the aside build (2 chunks kept), then swaps it in
    assert meta["chunks_computed_this_run"] == meta["n_chunks"] - 2
    assert not list(copy_of.glob(".dataset.*"))
    whole = _make(copy_of / "whole", spec_b)
    pd.testing.assert_frame_equal(_frame(out), _frame(copy_of / "whole"), check_exact=True)
    assert meta["config_hash"] == whole["config_hash"] != json.loads(before["_metadata.json"])["config_hash"]


def test_ctrl_c_while_a_part_file_is_set_up_leaves_no_temporary(tmp_path, monkeypatch):
    """The interrupt lands after the temporary file exists but before it is handed to the writer
    (here: in the permission fix-up), the window that once left ``.part-*.parquet`` behind."""
    from fluidfilm import io

    def interrupted(*args):
        raise KeyboardInterrupt

    monkeypatch.setattr(io.os, "chmod", interrupted)
    with pytest.raises(KeyboardInterrupt):
        with io.atomic_path(tmp_path / "part-00000.parquet"):
            pass
    assert list(tmp_path.iterdir()) == []


def test_temporary_that_escapes_the_writer_is_swept_when_the_run_is_interrupted(tmp_path, monkeypatch):
    """An interrupt between ``atomic_path`` yielding and the ``with`` body starting cannot be caught by
    the writer; the dataset run removes its directory's temporaries before it re-raises, and resumes."""
    out = tmp_path / "dataset"
    real, calls = gen._write_part, []

    def leaks_then_dies_on_the_third_part(path, cols):
        calls.append(path.name)
        if len(calls) == 3:
            (path.parent / f".{path.name}.abc123.parquet").write_bytes(b"half")  # what the window leaves
            raise KeyboardInterrupt
        return real(path, cols)

    monkeypatch.setattr(gen, "_write_part", leaks_then_dies_on_the_third_part)
    with pytest.raises(KeyboardInterrupt):
        _make(out)
    assert not list(out.glob(".part-*")) and not (out / "_metadata.json").exists()
    assert len(list(out.glob("part-*.parquet"))) == 2
    monkeypatch.setattr(gen, "_write_part", real)
    meta = _make(out)
    assert meta["chunks_computed_this_run"] == meta["n_chunks"] - 2
    verify_dataset(out)


# --------------------------------------------------------------------------- item 5
def _flip_byte(path, where=0.5):
    data = bytearray(path.read_bytes())
    data[int(len(data) * where)] ^= 0x01
    path.write_bytes(bytes(data))


@pytest.mark.parametrize("damage", ["flip", "truncate"])
def test_damaged_part_is_detected_on_load_and_recomputed_on_resume(copy_of, damage, capsys):
    out = copy_of / "dataset"
    reference = _frame(out)
    part = sorted(out.glob("part-*.parquet"))[2]
    if damage == "flip":
        _flip_byte(part)  # still parses as Parquet in most places: only a checksum sees it
    else:
        part.write_bytes(part.read_bytes()[: part.stat().st_size // 2])
    with pytest.raises(DatasetIntegrityError, match=part.name):
        verify_dataset(out)
    with pytest.raises(DatasetIntegrityError, match=part.name):
        read_dataset(out)  # what training reads
    capsys.readouterr()
    meta = _make(out)
    said = capsys.readouterr().out
    assert part.name in said and "recomputed" in said
    assert meta["damaged_parts_recomputed"] == [part.name]
    assert meta["chunks_computed_this_run"] == 1
    # the time reported is this run's, not the first run's
    assert meta["seconds_this_run"] == pytest.approx(meta["generation_seconds_last_run"])
    assert meta["generation_seconds_total"] >= meta["seconds_this_run"]
    verify_dataset(out)
    pd.testing.assert_frame_equal(_frame(out), reference, check_exact=True)


def test_damaged_test_set_is_named_on_load(copy_of):
    from fluidfilm.surrogate.fit import held_out_errors

    part = next((copy_of / "testset").glob("part-*.parquet"))
    _flip_byte(part, 0.3)
    with pytest.raises(DatasetIntegrityError, match=part.name):
        held_out_errors(None, copy_of / "testset")


def test_resume_with_nothing_to_do_reports_zero_work(copy_of):
    meta = _make(copy_of / "dataset")
    assert meta["chunks_computed_this_run"] == 0 and meta["damaged_parts_recomputed"] == []
    assert meta["seconds_this_run"] < meta["generation_seconds_total"]


def test_part_without_recorded_checksum_is_not_trusted(copy_of):
    """A crash between writing a part and recording its checksum: the part is recomputed."""
    out = copy_of / "dataset"
    state = json.loads((out / "_state.json").read_text())
    name = sorted(state["parts"])[0]
    del state["parts"][name]
    (out / "_state.json").write_text(json.dumps(state))
    (out / "_metadata.json").unlink()
    meta = _make(out)
    assert meta["damaged_parts_recomputed"] == [name]
    verify_dataset(out)


# --------------------------------------------------------------------------- item 12
def test_no_state_is_repeated_in_the_dataset(finished, quick_spec):
    """At eps = 0 every angle is the same state: it must appear once, not once per angle."""
    df = pd.read_parquet(finished / "dataset")
    assert not df.duplicated(["X1", "X2", "V1", "V2"]).any()
    centre = df[df.eps == 0.0]
    assert len(centre) == len(quick_spec.velocity_pairs(quick_spec.velocity_section_index(0.0)))
    # every other ring keeps all its angles
    sec = quick_spec.position_sections[0]
    ring = df[(df.eps == sec.eccentricities()[1])]
    assert ring.groupby(["X1", "X2"]).ngroups == sec.n_angle
