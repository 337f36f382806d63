"""Bit-for-bit evidence for refactors of the surrogate's evaluation (issue #50).

Evaluates every shipped and trained surrogate it finds (the universal networks of
``surrogate/universal_weights``, the saved models under ``models/**/model.json``) and the test models
of ``tests/golden_models.py`` (one per frame, scaling kind, structure and activation the kernels know),
plus one synthetic model per activation that no other model has in every frame it can run in, on
fixed random states through every evaluation path: the generic kernel (``forces``), the one-state
kernels (float64, float32), the batched kernels (generated and generic, float64 and float32), the
exact Jacobian, the torch networks' forward passes and the activations' torch and NumPy forms, and
short ``simulate`` / ``simulate_batch`` trajectories.

    python benchmarks/surrogate_bitwise.py save  OUT.npz   # before a change
    python benchmarks/surrogate_bitwise.py check OUT.npz   # after it: every array equal (np.array_equal)

``check`` prints one line per array that differs (and the largest difference) and exits 1 if any does.
"""
from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np

from fluidfilm.perf.benchmarking import save_or_check

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def _models():
    from golden_models import models as golden

    from fluidfilm import paper_bearing
    from fluidfilm.surrogate import Scaling, SurrogateForceModel, load_surrogate
    from fluidfilm.surrogate.universal import UNIVERSAL_RULES, universal_bearing

    out = {}
    for name, (model, sleeve) in golden().items():
        if name.startswith("surrogate"):
            out[name] = (model, sleeve)
    b = paper_bearing()
    for rule in UNIVERSAL_RULES:
        out[f"universal_{rule}"] = (universal_bearing(b, rule), None)
    for f in sorted(ROOT.glob("models/**/model.json")):
        out[f"saved_{f.parent.parent.parent.name}_{f.parent.name}"] = (load_surrogate(f.parent), None)
    # every activation in a cartesian, a polar and a whirl frame, split and blended
    rng = np.random.default_rng(50)
    c, om = b.clearance, b.omega

    def net(n_in, width=6, depth=2):
        sizes = [n_in] + [width] * depth + [2]
        return [(rng.normal(0, 1 / np.sqrt(a), (o, a)), rng.normal(0, 0.3, o)) for a, o in zip(sizes[:-1], sizes[1:])]

    def scaling(kind, frame):
        n = 4 if frame == "cartesian" else 3
        return Scaling(kind, c, om, 50.0, 1.5, rng.normal(0, 0.1, n), 1 + rng.random(n), rng.normal(0, 1, 2),
                       1 + rng.random(2), frame)

    for act in ("tanh", "relu", "silu", "sigmoid", "pade_tanh"):
        for frame, kind in (("cartesian", "physics_v"), ("polar", "physics"), ("whirl", "physics")):
            n_in = 4 if frame == "cartesian" else 3
            out[f"synthetic_{act}_{frame}"] = (SurrogateForceModel(
                b, [net(n_in), net(n_in)], [scaling(kind, frame), scaling(kind, frame)], act, boundaries=(0.5,),
                blend_width=0.1, domain=[[0.0, 0.6, 0.2], [0.6, 1.0, 0.1]], eps_max=0.9), None)
    return out


def _states(model, n=48, seed=11):
    rng = np.random.default_rng(seed)
    c = model.clearance
    eps = 0.05 + 0.85 * rng.random(n)
    ang = 2 * np.pi * rng.random(n)
    x = np.stack([eps * c * np.cos(ang), eps * c * np.sin(ang)], axis=1)
    v = rng.normal(0, 0.3 * c * model.bearing.omega, (n, 2))
    return x, v


def _torch_forward(model, x, v):
    """The torch networks (``training.ForceMLP``) on the model's scaled inputs, float32 as trained."""
    import torch

    from fluidfilm.surrogate.training import ForceMLP

    outs = []
    for net, sc in zip(model.networks, model.scalings):
        static, damping = (net, None) if model.structure == "plain" else net
        width, depth = static[0][0].shape[0], len(static) - 1
        if depth < 1:
            continue
        if model.activation not in ("tanh", "relu", "silu", "sigmoid") or damping is not None or sc.extras:
            continue  # ForceMLP's activations; its damping static net sees the positions only (the test model's all)
        m = ForceMLP(width=width, depth=depth, activation=model.activation, structure=model.structure,
                     n_inputs=len(sc.in_mean))
        seqs = [(m.net, static)] if damping is None else [(m.static, static), (m.damping, damping)]
        with torch.no_grad():
            for seq, layers in seqs:
                lin = [mod for mod in seq if isinstance(mod, torch.nn.Linear)]
                for mod, (W, b) in zip(lin, layers):
                    mod.weight.copy_(torch.as_tensor(W, dtype=torch.float32))
                    mod.bias.copy_(torch.as_tensor(b, dtype=torch.float32))
            z = torch.as_tensor(sc.inputs(x, v), dtype=torch.float32)
            outs.append(m(z).double().numpy())
    return np.concatenate(outs, axis=0) if outs else np.zeros((0, 2))


def _activations():
    import torch

    from fluidfilm.surrogate import activations, training, universal_fit

    rng = np.random.default_rng(3)
    a = np.concatenate([rng.normal(0, 3, 200), [0.0, -0.0, 1e-300, 25.0, -25.0]])
    out = {}
    for name in ("tanh", "pade_tanh"):
        for k, arr in enumerate(universal_fit.units(a, name)):
            out[f"act_units_np_{name}_{k}"] = np.asarray(arr)
        for k, arr in enumerate(universal_fit.units(torch.as_tensor(a), name)):
            out[f"act_units_torch_{name}_{k}"] = arr.numpy()
    for k, arr in enumerate(activations.pade_tanh(a)):
        out[f"act_pade_np_{k}"] = arr
    with torch.no_grad():
        out["act_PadeTanh_module"] = universal_fit.PadeTanh()(torch.as_tensor(a)).numpy()
        for name in ("tanh", "relu", "silu", "sigmoid"):
            mod = training._mlp(1, 1, 1, 1, name)[1]
            out[f"act_torch_{name}"] = mod(torch.as_tensor(a, dtype=torch.float32)[:, None]).numpy()[:, 0]
    return out


def _compiled_units():
    from fluidfilm.surrogate import kernels as k

    rng = np.random.default_rng(4)
    a = np.concatenate([rng.normal(0, 3, 200), [0.0, 1e-300, 25.0, -25.0]])
    out = {}
    for name in ("tanh64", "silu64", "sigmoid64", "pade_tanh64"):
        fn = getattr(k, name)
        out[f"unit_{name}"] = np.array([fn(float(t)) for t in a])
    for name in ("tanh32", "silu32", "sigmoid32", "pade_tanh32"):
        fn = getattr(k, name)
        out[f"unit_{name}"] = np.array([fn(np.float32(t)) for t in a], dtype=np.float32)
    return out


def evaluate() -> dict[str, np.ndarray]:
    from fluidfilm import Rotor, simulate
    from fluidfilm.rotor.batch import simulate_batch
    from fluidfilm.surrogate.jacobian import surrogate_jacobian
    from fluidfilm.surrogate.kernels import batch_params, forces_batch

    warnings.simplefilter("ignore")
    res: dict[str, np.ndarray] = {}
    res.update(_activations())
    res.update(_compiled_units())
    for name, (model, sleeve) in _models().items():
        if sleeve is not None:
            model.set_sleeve(sleeve)
        x, v = _states(model)
        model.reset_domain_counter()
        res[f"{name}/forces"] = model.forces(x, v)
        res[f"{name}/count_forces"] = np.array([model.n_outside_domain])
        for prec in ("float64", "float32"):
            fn, p = model.force_kernel_at(prec)
            res[f"{name}/one_state_{prec}"] = np.array([fn(p, *x[i], *v[i]) for i in range(len(x))])
            fnb, bp = model.batch_force_kernel(prec)
            out = np.empty_like(x)
            fnb(bp, x, v, out)
            res[f"{name}/batch_{prec}"] = out.copy()
            out = np.empty_like(x)
            forces_batch(batch_params(model, prec), x, v, out)
            res[f"{name}/generic_batch_{prec}"] = out.copy()
        res[f"{name}/count_all"] = np.array([model.n_outside_domain])
        if not model.scalings[0].extras:
            jac = [surrogate_jacobian(model, x[i], v[i]) for i in range(12)]
            res[f"{name}/jacobian_F"] = np.array([f for f, _ in jac])
            res[f"{name}/jacobian_J"] = np.array([j for _, j in jac])
        res[f"{name}/torch"] = _torch_forward(model, x, v)
        rotor = Rotor(mass=2.5, imbalance=1e-4)
        c = model.clearance
        for prec in ("float64", "float32"):
            traj = simulate(model, rotor, t_end=2e-4, dt=1e-5, x0=[0.0, 0.3 * c], v0=[0.0, 0.01], precision=prec)
            res[f"{name}/simulate_{prec}"] = np.concatenate([traj.x, traj.v], axis=1)
        if sleeve is None:
            x0 = np.array([[0.0, 0.3 * c], [0.2 * c, 0.1 * c], [-0.1 * c, 0.4 * c]])
            for prec in ("float64", "float32"):
                bt = simulate_batch(model, rotor, 2e-4, 1e-5, x0, np.zeros((3, 2)), precision=prec, threads=1)
                res[f"{name}/simulate_batch_{prec}"] = np.concatenate([bt.x, bt.v], axis=-1)
    return res


def main(argv: list[str]) -> int:
    return save_or_check(argv, __doc__, evaluate)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
