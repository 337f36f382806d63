"""Wrong types and unknown keys are refused before any work, naming the key (fluidfilm.workflow.config_check)."""
from __future__ import annotations

import pytest

from .conftest import run_entry


@pytest.mark.parametrize("override, key", [
    ("trainer.max_epochs=ten", "trainer.max_epochs"),
    ("+model.widht=10", "widht"),
    ("trainer.batch_size=1.5", "trainer.batch_size"),
    ("+lr_typo=0.1", "lr_typo"),
])
def test_wrong_type_or_unknown_key_is_refused_before_any_work(tmp_path, override, key):
    proc = run_entry("train_surrogate", override, f"dataset_dir={tmp_path / 'absent'}", "tracking.enabled=false",
                     f"out_dir={tmp_path / 'models'}", f"checkpoint_dir={tmp_path / 'ckpt'}", timeout=300)
    assert proc.returncode != 0
    said = proc.stderr + proc.stdout
    assert key in said
    # refused while composing the config, not deep inside: the missing dataset was never reached
    assert "absent" not in said and "_metadata.json" not in said
    assert not (tmp_path / "models").exists()
