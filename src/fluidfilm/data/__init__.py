"""The graded force dataset: layout (``spec``), generation (``generate``), schema, writing and reading (``schema``).

Surrogates depend on this package and on the columns it writes (``load_dataset``,
``load_test_set``, ``dataset_bearing``), never on the solver's internals.
"""
from fluidfilm.data.schema import (COLUMNS, EXTRA_INPUTS, DatasetIntegrityError, dataset_bearing, load_dataset, load_test_set,
                     read_metadata, training_domain, verify_dataset)
from fluidfilm.data.spec import DatasetConfigError, DatasetSpec, config_hash, example_spec

__all__ = ["COLUMNS", "EXTRA_INPUTS", "DatasetSpec", "DatasetConfigError", "config_hash", "example_spec", "generate_dataset",
           "random_test_set", "example_dataset", "load_dataset", "load_test_set", "read_metadata", "dataset_bearing",
           "training_domain", "DatasetIntegrityError", "verify_dataset"]


def __getattr__(name: str):
    # the generator needs the reference solver; imported on first use so that reading data
    # (what a surrogate does) does not import the solver
    if name in ("generate_dataset", "random_test_set", "example_dataset"):
        from fluidfilm.data import generate

        return getattr(generate, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
