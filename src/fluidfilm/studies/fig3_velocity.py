"""Fig. 3: film reaction against rotor velocity at several eccentricities (``experiments/fig3_velocity.py``)."""
from __future__ import annotations

import math
from pathlib import Path

from fluidfilm import io
from fluidfilm.studies.plots import plot_velocity_response, velocity_response, velocity_response_wide
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
from fluidfilm.workflow.config_check import ConfigError

NAMES = ("fig3_velocity.csv", "fig3_velocity_radial.csv", "fig3_velocity_tangential.csv", "fig3_velocity.png")
OUTPUTS = {"out_dir": list(NAMES)}


def check(cfg) -> None:
    """The sweep's own keys, named when wrong (before any solve)."""
    eps = list(cfg.eccentricities)
    if not eps:
        raise ConfigError("eccentricities=[] : give at least one eccentricity, e.g. eccentricities=[0.5]")
    bad = [e for e in eps if not (isinstance(e, (int, float)) and 0 <= e < 1)]
    if bad:
        raise ConfigError(f"eccentricities={eps}: each must lie in [0, 1), got {bad}")
    if isinstance(cfg.n_v, bool) or int(cfg.n_v) < 2:
        raise ConfigError(f"n_v={cfg.n_v}: the velocity sweep needs at least 2 points")
    if not (math.isfinite(cfg.v_max) and cfg.v_max > 0):
        raise ConfigError(f"v_max={cfg.v_max}: the largest speed must be a positive number of m/s")


def run(cfg) -> None:
    check(cfg)
    model = reference_from_cfg(bearing_from_cfg(cfg.bearing), cfg.reference)
    frame = velocity_response(model, list(cfg.eccentricities), cfg.v_max, cfg.n_v, cfg.angle_deg)
    # forces rounded below the solver's spread across machines: the same bytes from any machine
    # (docs/workflow.md, "Stage outputs across machines")
    frame = io.round_to_scale(frame, ["F1", "F2"])
    out = Path(cfg.out_dir)
    with io.output_set() as outputs:  # the four files as one set: an interrupted run leaves the old set
        outputs.write_csv(out / "fig3_velocity.csv", frame)
        for direction in ("radial", "tangential"):  # one line per eccentricity in `dvc plots`
            outputs.write_csv(out / f"fig3_velocity_{direction}.csv", velocity_response_wide(frame, direction))
        outputs.save_figure(plot_velocity_response(frame), out / "fig3_velocity.png", dpi=130)
    print(f"{model}: {len(frame)} rows -> {out / 'fig3_velocity.csv'}")
