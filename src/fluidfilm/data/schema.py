"""The dataset's schema, writing and reading: what a surrogate may know about the data.

A dataset (and a held-out test set) is a directory of Parquet part files
``part-NNNNN.parquet`` plus ``_metadata.json`` (written last: its presence
means the set is complete).  Every row is one state and the reference
model's force there:

=========  =======  ======  ===============================================
column     dtype    unit    meaning
=========  =======  ======  ===============================================
S          float64  m       sleeve displacement (active bearings only; first)
X1, X2     float64  m       journal position
V1, V2     float64  m/s     journal velocity
F1, F2     float64  N       film force on the journal
eps        float64  -       eccentricity ratio |X| / c (c at the row's sleeve position)
section    int8     -       position section of the dataset layout
n_theta    int16    -       grid the reference model used for the row
n_z        int16    -
=========  =======  ======  ===============================================

Surrogates read data through ``load_dataset`` / ``load_test_set`` and the
bearing through ``dataset_bearing``: they depend on this module, never on
the solver that wrote the data.
"""
from __future__ import annotations


import json
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from fluidfilm import io
from fluidfilm.io import file_sha256
from fluidfilm.core.bearing import ConicalBearing, JournalBearing, bearing_from_dict

#: columns of every row, in file order (``S`` comes first where present)
COLUMNS = ("X1", "X2", "V1", "V2", "F1", "F2", "eps", "section", "n_theta", "n_z")
#: columns present only for an active bearing; a surrogate takes them as extra network inputs
EXTRA_INPUTS = ("S",)
#: what a surrogate trains on (plus any extra inputs present)
TRAINING_COLUMNS = ("X1", "X2", "V1", "V2", "F1", "F2", "eps")
_INT_DTYPES = {"section": np.int8, "n_theta": np.int16, "n_z": np.int16}


def table(cols: dict) -> pa.Table:
    """A Parquet table in the schema's column order and dtypes from a dict of arrays."""
    extra = {k: cols[k] for k in EXTRA_INPUTS if k in cols}
    return pa.table({**extra, **{k: np.asarray(cols[k], dtype=_INT_DTYPES.get(k, np.float64)) if k in _INT_DTYPES
                                 else cols[k] for k in COLUMNS}})


def write_part(path: Path, cols: dict) -> str:
    """Write one part file atomically (temporary file + rename); return the SHA-256 of the bytes written
    (the manifest's checksum)."""
    with io.atomic_path(path, suffix=".parquet") as tmp:
        pq.write_table(table(cols), tmp, compression="zstd")
        digest = file_sha256(tmp)
    return digest


class DatasetIntegrityError(ValueError):
    """A dataset on disk is incomplete or damaged; the message names the file.

    Examples
    --------
    >>> from fluidfilm.data import DatasetIntegrityError, verify_dataset
    >>> try:
    ...     verify_dataset("no/such/dataset")
    ... except DatasetIntegrityError as err:
    ...     print(err)
    no/such/dataset is not a complete dataset (no _metadata.json); generate it first
    """


def verify_dataset(path) -> dict:
    """Check every part of a complete dataset against the checksums in its manifest; return the metadata.

    Raises ``DatasetIntegrityError`` naming the first missing or damaged file,
    so nothing is ever trained on forces that are not the ones computed.

    Parameters
    ----------
    path : path-like
        The dataset's (or test set's) folder.

    Returns
    -------
    dict
        The metadata.

    Raises
    ------
    DatasetIntegrityError
        Naming the folder or file: no ``_metadata.json``, no checksums listed, a part missing or
        damaged (its SHA-256 differs), or part files not in the manifest.

    Examples
    --------
    >>> import shutil, tempfile
    >>> from fluidfilm.data import example_dataset, verify_dataset
    >>> folder = example_dataset(tempfile.mkdtemp())
    >>> list(verify_dataset(folder)["parts"])
    ['part-00000.parquet']
    >>> shutil.rmtree(folder)
    """
    path = Path(path)
    meta_file = path / "_metadata.json"
    if not meta_file.exists():
        raise DatasetIntegrityError(f"{path} is not a complete dataset (no _metadata.json); generate it first")
    meta = json.loads(meta_file.read_text())
    parts = meta.get("parts")
    if parts is None:
        raise DatasetIntegrityError(f"{meta_file} lists no part checksums (made by an older version); "
                                    "generate the dataset again")
    for name, digest in sorted(parts.items()):
        f = path / name
        if not f.exists():
            raise DatasetIntegrityError(f"{f} is missing (listed in {meta_file})")
        if file_sha256(f) != digest:
            raise DatasetIntegrityError(f"{f} is damaged: its SHA-256 differs from the one recorded in "
                                        f"{meta_file}; run make_dataset again to recompute it")
    extra = sorted(p.name for p in path.glob("part-*.parquet") if p.name not in parts)
    if extra:
        raise DatasetIntegrityError(f"{path} holds part files not in its manifest: {extra[:3]}")
    return meta


def part_name(index: int) -> str:
    return f"part-{index:05d}.parquet"


def read_metadata(path) -> dict:
    """``_metadata.json`` of a complete dataset or test set; a clear error for an incomplete one.

    Parameters
    ----------
    path : path-like
        The dataset's folder.

    Returns
    -------
    dict
        Bearing, reference grid policy, spec, columns, part checksums, sizes and timings.

    Raises
    ------
    ValueError
        Naming the folder, when it holds no ``_metadata.json`` (generation not finished).

    Examples
    --------
    >>> import shutil, tempfile
    >>> from fluidfilm.data import example_dataset, read_metadata
    >>> folder = example_dataset(tempfile.mkdtemp())
    >>> read_metadata(folder)["n_samples"]
    128
    >>> shutil.rmtree(folder)
    """
    path = Path(path)
    meta_file = path / "_metadata.json"
    if not meta_file.exists():
        raise ValueError(f"{path} is not a complete dataset (no _metadata.json); generate it first")
    return json.loads(meta_file.read_text())


def load_dataset(path, columns=TRAINING_COLUMNS) -> tuple[pd.DataFrame, dict]:
    """The dataset's rows (``columns``; the sleeve column S comes along if present) and its metadata.

    Every part is checked against its recorded checksum first (``verify_dataset``).

    Parameters
    ----------
    path : path-like
        The dataset's folder.
    columns : sequence of str, default ("X1", "X2", "V1", "V2", "F1", "F2", "eps")
        Columns to read: positions [m], velocities [m/s], forces [N] in the (X1, X2) frame (+X2
        along gravity), and eps.

    Returns
    -------
    rows : pandas.DataFrame
    meta : dict
        The metadata (``read_metadata``).

    Raises
    ------
    ValueError
        For an incomplete dataset; ``DatasetIntegrityError`` naming a missing or damaged file.

    Examples
    --------
    >>> import shutil, tempfile
    >>> from fluidfilm.data import example_dataset, load_dataset
    >>> folder = example_dataset(tempfile.mkdtemp())
    >>> rows, meta = load_dataset(folder)
    >>> rows.shape, list(rows.columns)
    ((128, 7), ['X1', 'X2', 'V1', 'V2', 'F1', 'F2', 'eps'])
    >>> shutil.rmtree(folder)
    """
    meta = read_metadata(path)
    verify_dataset(path)  # checksums recorded at generation; names a damaged file
    extra = [c for c in EXTRA_INPUTS if c in meta.get("columns", ()) and c not in columns]
    return pd.read_parquet(Path(path), columns=list(columns) + extra), meta


def load_test_set(path) -> pd.DataFrame:
    """Every row of a held-out test set (checked against its manifest's checksums first).

    Parameters
    ----------
    path : path-like
        The test set's folder (``random_test_set``).

    Returns
    -------
    pandas.DataFrame
        All columns (``COLUMNS``), one row per state.

    Raises
    ------
    DatasetIntegrityError
        Naming a missing or damaged file, or an incomplete test set.

    Examples
    --------
    >>> import shutil, tempfile
    >>> from fluidfilm.data import example_dataset, load_test_set
    >>> folder = example_dataset(tempfile.mkdtemp(), test_set=True)
    >>> load_test_set(folder).shape
    (10, 10)
    >>> shutil.rmtree(folder)
    """
    verify_dataset(path)
    return pd.read_parquet(Path(path))


def dataset_bearing(meta: dict) -> JournalBearing | ConicalBearing:
    """The bearing a dataset was generated for (from its metadata).

    Parameters
    ----------
    meta : dict
        The dataset's metadata (``read_metadata``).

    Returns
    -------
    JournalBearing or ConicalBearing

    Examples
    --------
    >>> from fluidfilm import paper_bearing
    >>> from fluidfilm.data import dataset_bearing
    >>> dataset_bearing({"bearing": paper_bearing().to_dict()}) == paper_bearing()
    True
    """
    return bearing_from_dict(meta["bearing"])


def relative_force_errors(predicted: np.ndarray, truth: np.ndarray, floor_N: float) -> np.ndarray:
    """|F_model - F| / max(|F|, floor) per state, forces (..., 2) -> (...): the held-out measure of the whole
    workspace (the floor keeps states with almost no film force from dominating)."""
    d = predicted - truth
    return np.hypot(d[..., 0], d[..., 1]) / np.maximum(np.hypot(truth[..., 0], truth[..., 1]), floor_N)


def training_domain(meta: dict) -> list[list[float]]:
    """[eps_low, eps_high, v_max] of each velocity section of the dataset's layout.

    The rows of the surrogates' ``ValidityDomain.bands`` (v_max in m/s).

    Parameters
    ----------
    meta : dict
        Metadata with the layout under ``spec`` (as ``read_metadata`` gives it).

    Returns
    -------
    list of [float, float, float]
        One row per velocity section, in the layout's order.

    Examples
    --------
    >>> from fluidfilm.data import training_domain
    >>> training_domain({"spec": {"velocity_sections": [{"eps_low": 0.0, "eps_high": 0.5, "v_max": 0.2}]}})
    [[0.0, 0.5, 0.2]]
    """
    return [[s["eps_low"], s["eps_high"], s["v_max"]] for s in meta["spec"]["velocity_sections"]]
