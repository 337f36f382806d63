"""Trajectories per second of the reference and the best surrogate, one by one and batched, side by side.

    python experiments/batch_speed.py
Writes reports/batch_speed.json: for each N in ``batch_sizes`` the trajectories per second of each
model run one at a time (``simulate``) and as one batch (``simulate_batch``), and the ratios;
``trajectories_per_s_batch_speedup`` is the surrogate's batched rate over the reference's batched
rate at the largest N, ``trajectories_per_s_single_speedup`` the same for one trajectory run alone.
"""
import hydra
from omegaconf import DictConfig, OmegaConf

from fluidfilm import io, load_surrogate
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
from fluidfilm.perf.throughput import trajectories_per_second
from fluidfilm.workflow.config_check import check_config


@hydra.main(config_path="../conf", config_name="batch_speed", version_base="1.3")
def main(cfg: DictConfig) -> dict:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    models = {"reference": reference_from_cfg(bearing_from_cfg(cfg.bearing), cfg.reference),
              "surrogate": load_surrogate(cfg.surrogate_dir)}
    rows = []
    for n in cfg.batch_sizes:
        reps = int(cfg.repeats_small) if n == 1 else 1
        for name, model in models.items():
            row = {"model": name, "n": int(n)}
            if name == "surrogate" or n <= cfg.reference_one_by_one_max_n:
                r = trajectories_per_second(model, n, cfg.t_end, cfg.dt, batched=False, repeats=reps)
                row["one_by_one_per_s"] = r["trajectories_per_s"]
            r = trajectories_per_second(model, n, cfg.t_end, cfg.dt, batched=True, repeats=reps)
            row["batched_per_s"] = r["trajectories_per_s"]
            row["n_ok"] = r["n_ok"]
            rows.append(row)
            print(f"{name:>10} N={n:5d}: one by one {row.get('one_by_one_per_s', float('nan')):10.1f}/s, "
                  f"batched {row['batched_per_s']:10.1f}/s ({row['n_ok']}/{n} ok)")
    by = {(r["model"], r["n"]): r for r in rows}
    n_max, n_min = max(cfg.batch_sizes), min(cfg.batch_sizes)
    ref1 = by[("reference", n_min)]["one_by_one_per_s"]
    ratios = {str(n): {"batched": by[("surrogate", n)]["batched_per_s"] / by[("reference", n)]["batched_per_s"],
                       "surrogate_batched_vs_reference_alone": by[("surrogate", n)]["batched_per_s"] / ref1,
                       "batching_gain_surrogate": by[("surrogate", n)]["batched_per_s"]
                       / by[("surrogate", n)]["one_by_one_per_s"]}
              for n in cfg.batch_sizes}
    out = {"rows": rows, "ratios": ratios, "config": OmegaConf.to_container(cfg, resolve=True),
           "trajectories_per_s_batch_speedup": ratios[str(n_max)]["batched"],
           "trajectories_per_s_single_speedup": by[("surrogate", n_min)]["one_by_one_per_s"] / ref1}
    io.write_json(cfg.out_json, out)
    print(f"surrogate / reference at N={n_max} (both batched): {out['trajectories_per_s_batch_speedup']:.1f}x; "
          f"one trajectory alone: {out['trajectories_per_s_single_speedup']:.1f}x")
    return out


if __name__ == "__main__":
    io.run_interruptible(main, "the batched-trajectory speed study", "run the same command again")
