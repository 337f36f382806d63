"""The graded force dataset: layout (``spec``), generation (``generate``), loading (``load``).

Surrogates depend on this package and on the columns it writes, never on
the solver's internals.
"""
from .generate import COLUMNS, DatasetIntegrityError, generate_dataset, random_test_set, verify_dataset
from .spec import DatasetConfigError, DatasetSpec, config_hash

__all__ = ["COLUMNS", "DatasetIntegrityError", "verify_dataset", "DatasetSpec", "DatasetConfigError", "config_hash", "generate_dataset", "random_test_set"]
