"""Fig. 3: film reaction against rotor velocity at several eccentricities.

    python experiments/fig3_velocity.py        # writes reports/figures/fig3_velocity{.png,.csv,_radial.csv,_tangential.csv}
"""
from pathlib import Path

import hydra
from omegaconf import DictConfig

from fluidfilm import io
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
from fluidfilm.studies.plots import plot_velocity_response, velocity_response, velocity_response_wide
from fluidfilm.workflow.config_check import check_config


@hydra.main(config_path="../conf", config_name="fig3", version_base="1.3")
def main(cfg: DictConfig) -> None:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    bearing = bearing_from_cfg(cfg.bearing)
    model = reference_from_cfg(bearing, cfg.reference)
    frame = velocity_response(model, list(cfg.eccentricities), cfg.v_max, cfg.n_v, cfg.angle_deg)
    out = Path(cfg.out_dir)
    io.write_csv(out / "fig3_velocity.csv", frame)
    for direction in ("radial", "tangential"):  # one line per eccentricity in `dvc plots`
        io.write_csv(out / f"fig3_velocity_{direction}.csv", velocity_response_wide(frame, direction))
    io.save_figure(plot_velocity_response(frame), out / "fig3_velocity.png", dpi=130)
    print(f"{model}: {len(frame)} rows -> {out / 'fig3_velocity.csv'}")


if __name__ == "__main__":
    io.run_interruptible(main, "the Fig. 3 velocity study", "run the same command again")
