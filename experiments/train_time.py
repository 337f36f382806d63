"""Training time of the single vs the split network to the same target validation error, over seeds.

    python experiments/train_time.py            # reports/train_time.json
"""
import hydra
import pandas as pd
from omegaconf import DictConfig, OmegaConf

from fluidfilm import io, tracking
from fluidfilm.comparison import machine, summarise_training_times
from fluidfilm.surrogate.fit import fit_surrogate


@hydra.main(config_path="../conf", config_name="train_time", version_base="1.3")
def main(cfg: DictConfig) -> None:
    c = OmegaConf.to_container(cfg, resolve=True)
    studies = {}
    for study, sc in c["studies"].items():
        rows = []
        for seed in cfg.seeds:
            for name, boundaries in cfg.splits.items():
                _, rep = fit_surrogate(cfg.dataset_dir, c["model"], {"boundaries": list(boundaries)}, sc["scaling"],
                                       c["trainer"], sc["target_val_rel_rmse"], seed=seed, name=name,
                                       val_fraction=cfg.trainer.val_fraction, batch_size=cfg.trainer.batch_size)
                reached = rep["time_to_target_s"] is not None
                rows.append({"seed": seed, "model": name, "reached_target": reached,
                             "time_s": rep["time_to_target_s"] if reached else rep["train_time_s"],
                             "train_time_s": rep["train_time_s"],
                             "epochs": [n["epochs"] for n in rep["networks"]],
                             "val_rel_rmse": [n["val_rel_rmse"] for n in rep["networks"]],
                             "time_per_network_s": [n["time_to_target_s"] or n["train_time_s"]
                                                    for n in rep["networks"]]})
                print(study, rows[-1], flush=True)
        frame = pd.DataFrame(rows)
        summary = summarise_training_times(frame)
        summary.update(target_val_rel_rmse=sc["target_val_rel_rmse"], scaling=sc["scaling"]["kind"],
                       all_reached_target=bool(frame.reached_target.all()), runs=rows)
        studies[study] = summary
    head = studies[cfg.headline_study]
    out = {k: v for k, v in head.items() if k != "runs"} | {
        "headline_study": cfg.headline_study, "max_epochs": cfg.trainer.max_epochs, "machine": machine(),
        "runs": head["runs"], "studies": studies}
    io.write_json(cfg.out, out)
    with tracking.run(cfg.tracking, "train_time", c):
        for study, s in studies.items():
            tracking.log_metrics({f"{study}.{k}": float(v) for k, v in s.items()
                                    if isinstance(v, (int, float)) and not isinstance(v, bool)})
    print({k: v for k, v in out.items() if k not in ("runs", "studies")})


if __name__ == "__main__":
    main()
