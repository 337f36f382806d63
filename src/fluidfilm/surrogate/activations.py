"""The hidden-layer activations, each declared once: the registry ``REGISTRY`` that every evaluation reads.

An activation is one ``Activation`` entry:

- ``code``: the integer the generic numba kernels dispatch on (saved models name the activation, not
  the code);
- ``exact64``: its compiled float64 form exact to rounding, for the generic one-state kernel
  (``surrogate.kernels.generic.surrogate_force``: tanh through one ``exp``, SiLU and the sigmoid through
  ``exp``);
- ``unit64`` / ``unit32``: its compiled forms from arithmetic alone, which vectorise, for the fast
  kernels (the generated one-state and batched kernels and the generic batched kernel): ``tanh64``
  (within 1.5e-15 relative of ``math.tanh``), ``tanh32`` (Eigen's, within 4e-7), SiLU and the sigmoid
  through them; generated kernels call them by name (``unit_name``), imported from this module;
- ``derivatives``: its value and first and second derivatives (f, f', f'') on NumPy arrays (for tanh
  and ``pade_tanh`` torch tensors too): the exact Jacobian (``surrogate.kernels.jacobian``) takes (f, f'), the
  universal fit's Levenberg-Marquardt steps all three (``surrogate.training.universal_fit.units``);
- ``torch``: where its torch module lives (``"module:Class"``, imported when asked for:
  ``torch_module``), and ``torch_training`` the faster equivalent the Lightning networks train with
  where there is one (tanh: ``surrogate.training.Tanh``);
- ``trainable`` / ``universal``: whether the Lightning networks (``surrogate.training.ForceMLP``) and
  the universal fit (``surrogate.training.universal_fit``) offer it.

Adding an activation: its compiled forms and derivatives here, one ``Activation`` entry in
``REGISTRY``, one branch in each of the three dispatchers (``exact64``, ``unit64``, ``unit32``:
numba dispatches on the code at run time), and its tests (``tests/surrogate/test_activations.py`` checks every
entry's forms against each other and that every code dispatches to its own forms).

``pade_tanh`` is tanh's [5/4] Pade approximant (a convergent of Lambert's continued fraction) taken as an
activation in its own right:

    f(x) = x (945 + 105 x^2 + x^4) / (945 + 420 x^2 + 15 x^4)

It is smooth and increasing on the whole line (f'(x) > 0 everywhere; f' has its least value about 0.0046 near
|x| = 3.9), within 4e-4 of tanh for |x| < 3, and grows like x / 15 beyond, where tanh saturates.  Networks
trained with it (the universal bearing's: ``surrogate.training.universal_fit``) are evaluated without approximation error (round-off only) by
6 vector operations and one division per 8 units (``pade_tanh64``), where a tanh exact to
round-off costs 19 and one (``tanh64``).

Examples
--------
>>> import numpy as np
>>> f, df, d2f = pade_tanh(np.array([0.0, 1.0, 3.0]))
>>> np.round(f, 4).tolist(), np.round(df, 4).tolist()
([0.0, 0.7616, 0.9955], [1.0, 0.42, 0.0107])
>>> [a.name for a in REGISTRY.values()]
['tanh', 'relu', 'silu', 'sigmoid', 'pade_tanh']
"""
from __future__ import annotations

import importlib
import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from numba import njit

__all__ = ["pade_tanh", "HIDDEN_ACTIVATIONS", "TRAINABLE_ACTIVATIONS", "Activation", "REGISTRY", "ACTIVATIONS",
           "tanh64", "tanh32", "silu64", "silu32", "sigmoid64", "sigmoid32", "pade_tanh64", "pade_tanh32", "relu64",
           "relu32", "exact64", "unit64", "unit32", "unit_name", "unit_names", "TANH64_CLAMP"]


# ---------------------------------------------------------------------------------------------- derivatives

def pade_tanh(A):
    """The ``pade_tanh`` activation's values and first and second derivatives (f, f', f'') at ``A``."""
    x2 = A * A
    n, d = 945.0 + x2 * (105.0 + x2), 945.0 + x2 * (420.0 + 15.0 * x2)
    f = A * n / d
    # f = P / d with P = A n: f' = (P' - f d') / d, f'' = (P'' - 2 f' d' - f d'') / d
    dP, d2P = n + 2.0 * x2 * (105.0 + 2.0 * x2), A * (630.0 + 20.0 * x2)
    dd, d2d = A * (840.0 + 60.0 * x2), 840.0 + 180.0 * x2
    df = (dP - f * dd) / d
    return f, df, (d2P - 2.0 * df * dd - f * d2d) / d


def _tanh_derivatives(A):
    """tanh's (f, f', f'') on a NumPy array or a torch tensor (``Tensor.tanh``)."""
    H = A.tanh() if hasattr(A, "tanh") else np.tanh(A)
    D = 1.0 - H * H
    return H, D, -2.0 * H * D


def _relu_derivatives(A):
    a = np.asarray(A)
    return np.maximum(a, 0.0), (a > 0.0).astype(float), np.zeros_like(a, dtype=float)


def _silu_derivatives(A):
    s = 1.0 / (1.0 + np.exp(-A))
    return A * s, s * (1.0 + A * (1.0 - s)), s * (1.0 - s) * (2.0 + A * (1.0 - 2.0 * s))


def _sigmoid_derivatives(A):
    y = 1.0 / (1.0 + np.exp(-A))
    d = y * (1.0 - y)
    return y, d, d * (1.0 - 2.0 * y)


# ---------------------------------------------------------------------------------------------- exact float64

@njit(cache=True, inline="always")
def _tanh_exact(x):
    # tanh through one exp (libm's tanh is about twice as slow); exact to rounding
    t = math.exp(-2.0 * abs(x))
    y = (1.0 - t) / (1.0 + t)
    return y if x >= 0.0 else -y


@njit(cache=True, inline="always")
def _relu_exact(x):
    return max(x, 0.0)


@njit(cache=True, inline="always")
def _silu_exact(x):
    return x / (1.0 + math.exp(-x))


@njit(cache=True, inline="always")
def _sigmoid_exact(x):
    return 1.0 / (1.0 + math.exp(-x))


@njit(cache=True, inline="always")
def _pade_tanh_exact(x):
    x2 = x * x
    return x * (945.0 + x2 * (105.0 + x2)) / (945.0 + x2 * (420.0 + 15.0 * x2))


# ---------------------------------------------------------------------------------------------- fast units

# tanh(u) ~ u P(u^2) / Q(u^2), the [9/8] Pade approximant (a convergent of Lambert's continued fraction), at u =
# x/4 with the 1/4 folded into the coefficients and p and q both scaled by 4 so that p = x (1 + ...): powers of
# two, so every product rounds as the unscaled form's would, and a tiny x (subnormal too) comes back exactly
# (scaling x by 1/4 first lost its last bits). Then both doublings in one step: with c = p q and s = p^2 + q^2,
# tanh(2u) = 2c/s and tanh(4u) = 4cs/(4c^2 + s^2) = cs/(c^2 + (s/2)^2); one division at the end, and each
# doubling contracts a relative error in p or q by (1 - t^2)/(1 + t^2). Clamped at |x| = 19.5, where tanh rounds
# to 1. 19 vector operations and a division per 8 units, against 23 for the [7/6] approximant at x/8 doubled
# three times that it replaced (the doublings were half of its cost). Accuracy: the largest relative error
# against mpmath is a little lower (``benchmarks/bench_tanh64.py`` measures both); near saturation (|x| above
# ~8) the fused step's last roundings all land on the result, so there it is a little higher than the old form's
# (4.0e-16 against 3.3e-16 at most, mpmath, 8 <= |x| <= 19.5), and |tanh64| can round one ulp above 1 there (the
# old form did too; tested to be never more). Measured and not kept: fewer doublings chosen per network from its
# largest |pre-activation| (an [11/10] approximant with one doubling below 4.875): 99 against 73 ns per force,
# the max-reduction and the branch sit on the one-state path's critical path.
_P1, _P3, _P5, _P7, _P9 = (1.0, 4729725.0 / 34459425.0 / 4.0 ** 2, 135135.0 / 34459425.0 / 4.0 ** 4,
                           990.0 / 34459425.0 / 4.0 ** 6, 1.0 / 34459425.0 / 4.0 ** 8)
_Q0, _Q2, _Q4, _Q6, _Q8 = (4.0, 16216200.0 / 34459425.0 / 4.0, 945945.0 / 34459425.0 / 4.0 ** 3,
                           13860.0 / 34459425.0 / 4.0 ** 5, 45.0 / 34459425.0 / 4.0 ** 7)
TANH64_CLAMP = 19.5


@njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def tanh64(x):
    """tanh in float64 from arithmetic only (vectorises); within 1.5e-15 relative of ``math.tanh`` (libm's own
    error included; tests/surrogate/test_surrogate_kernels.py), exactly odd, exactly x for tiny x."""
    x = min(max(x, -TANH64_CLAMP), TANH64_CLAMP)
    x2 = x * x
    p = x * (_P1 + x2 * (_P3 + x2 * (_P5 + x2 * (_P7 + x2 * _P9))))
    q = _Q0 + x2 * (_Q2 + x2 * (_Q4 + x2 * (_Q6 + x2 * _Q8)))
    c = p * q
    s = p * p + q * q
    h = 0.5 * s
    return (c * s) / (c * c + h * h)


# Eigen's float32 tanh (TensorFlow/Eigen ``generic_fast_tanh_float``): a 13/6 rational function on
# |x| <= 7.9053, the value +-1 beyond (tanh rounds to 1 in float32 there)
_EA = np.array([4.89352455891786e-03, 6.37261928875436e-04, 1.48572235717979e-05, 5.12229709037114e-08,
                -8.60467152213735e-11, 2.00018790482477e-13, -2.76076847742355e-16], dtype=np.float32)
_EB = np.array([4.89352518554385e-03, 2.26843463243900e-03, 1.18534705686654e-04, 1.19825839466702e-06],
               dtype=np.float32)
_A1, _A3, _A5, _A7, _A9, _A11, _A13 = (np.float32(a) for a in _EA)
_B0, _B2, _B4, _B6 = (np.float32(b) for b in _EB)
_CLAMP32 = np.float32(7.90531110763549805)


@njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def tanh32(x):
    """Eigen's rational tanh in float32 (vectorises); within 4e-7 relative of ``math.tanh``."""
    x = min(max(x, -_CLAMP32), _CLAMP32)
    x2 = x * x
    p = x2 * _A13 + _A11
    p = x2 * p + _A9
    p = x2 * p + _A7
    p = x2 * p + _A5
    p = x2 * p + _A3
    p = x2 * p + _A1
    q = x2 * _B6 + _B4
    q = x2 * q + _B2
    q = x2 * q + _B0
    # x (p / q), not Eigen's (x p) / q with its cut "x below 4e-4": x p underflows for subnormal x, while
    # p / q -> A1 / B0 = 1 - 1.3e-7 keeps x to float32 precision without a compare and select per unit
    # (three vector operations of the ~20 per unit: ~10 % of the float32 network's time on this machine)
    return x * (p / q)


# SiLU and the logistic sigmoid through tanh: sigma(x) = (1 + tanh(x / 2)) / 2, so that they vectorise like
# tanh (math.exp does not: no SVML here; the active bearing's 4-64-64-2 SiLU network spent ~60 % of its
# one-state force in 128 scalar exp calls).  tanh64 keeps them within round-off of x / (1 + exp(-x)): where
# 1 + tanh cancels (x below about -20) the error is absolute, ~2e-16 of sigma (times x for SiLU), far below one unit of
# the next layer's sum.  tanh32's clamp at |x / 2| = 7.9 puts sigma's error below 1.2e-7 absolute.


@njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def sigmoid64(x):
    """The logistic sigmoid in float64 from ``tanh64`` (vectorises)."""
    return 0.5 + 0.5 * tanh64(0.5 * x)


@njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def silu64(x):
    """SiLU, x sigma(x), in float64 from ``tanh64`` (vectorises)."""
    return x * sigmoid64(x)


@njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def sigmoid32(x):
    """The logistic sigmoid in float32 from ``tanh32`` (vectorises)."""
    return np.float32(0.5) + np.float32(0.5) * tanh32(np.float32(0.5) * x)


@njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def silu32(x):
    """SiLU in float32 from ``tanh32`` (vectorises)."""
    return x * sigmoid32(x)


# pade_tanh: no approximation error: the network is this function, not an approximation of one (round-off only)
@njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def pade_tanh64(x):
    """The ``pade_tanh`` activation in float64 (vectorises)."""
    x2 = x * x
    return x * (945.0 + x2 * (105.0 + x2)) / (945.0 + x2 * (420.0 + 15.0 * x2))


@njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def pade_tanh32(x):
    """The ``pade_tanh`` activation in float32 (vectorises)."""
    x2 = x * x
    return x * (np.float32(945.0) + x2 * (np.float32(105.0) + x2)) / (
        np.float32(945.0) + x2 * (np.float32(420.0) + np.float32(15.0) * x2))


@njit(cache=True, inline="always", error_model="numpy")
def relu64(x):
    """max(x, 0) (a float64 zero: for a float32 ``x`` the result is float64, as the kernels always had it)."""
    return max(x, 0.0)


#: ReLU is exact in either precision: one form
relu32 = relu64


# ---------------------------------------------------------------------------------------------- the registry

@dataclass(frozen=True)
class Activation:
    """One hidden-layer activation and every form of it (module doc)."""

    name: str
    code: int
    exact64: Any
    unit64: Any
    unit32: Any
    derivatives: Callable
    torch: str
    torch_training: str | None = None
    trainable: bool = True
    universal: bool = False

    def torch_module(self, training: bool = False):
        """The torch module class (``training``: the Lightning networks' faster form where there is one)."""
        module, _, name = ((self.torch_training if training and self.torch_training else self.torch)
                           .partition(":"))
        return getattr(importlib.import_module(module), name)


#: name (as in configs and model.json) -> its ``Activation``; the codes are the order here
REGISTRY: dict[str, Activation] = {a.name: a for a in (
    Activation("tanh", 0, _tanh_exact, tanh64, tanh32, _tanh_derivatives, "torch.nn:Tanh",
               "fluidfilm.surrogate.training.lightning:Tanh", universal=True),
    Activation("relu", 1, _relu_exact, relu64, relu32, _relu_derivatives, "torch.nn:ReLU"),
    Activation("silu", 2, _silu_exact, silu64, silu32, _silu_derivatives, "torch.nn:SiLU"),
    Activation("sigmoid", 3, _sigmoid_exact, sigmoid64, sigmoid32, _sigmoid_derivatives, "torch.nn:Sigmoid"),
    Activation("pade_tanh", 4, _pade_tanh_exact, pade_tanh64, pade_tanh32, pade_tanh,
               "fluidfilm.surrogate.training.universal_fit:PadeTanh", trainable=False, universal=True),
)}
#: activation name -> kernel code
ACTIVATIONS = {a.name: a.code for a in REGISTRY.values()}
#: hidden-layer activations the universal networks can be trained with (``conf/universal.yaml``: train.activation)
HIDDEN_ACTIVATIONS = tuple(a.name for a in REGISTRY.values() if a.universal)
#: hidden-layer activations of the Lightning networks (``conf``: model.activation)
TRAINABLE_ACTIVATIONS = tuple(a.name for a in REGISTRY.values() if a.trainable)

_TANH, _RELU, _SILU, _SIGMOID, _PADE_TANH = (REGISTRY[n].code for n in ("tanh", "relu", "silu", "sigmoid",
                                                                        "pade_tanh"))


# numba dispatches on the code at run time: one branch per entry (tests/surrogate/test_activations.py checks each code
# reaches its own form)
@njit(cache=True, inline="always")
def exact64(code, x):
    """The ``exact64`` form of the activation ``code`` at x."""
    if code == _TANH:
        return _tanh_exact(x)
    if code == _RELU:
        return _relu_exact(x)
    if code == _SILU:
        return _silu_exact(x)
    if code == _SIGMOID:
        return _sigmoid_exact(x)
    return _pade_tanh_exact(x)


@njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def unit64(code, x):
    """The ``unit64`` form of the activation ``code`` at x."""
    if code == _TANH:
        return tanh64(x)
    if code == _RELU:
        return relu64(x)
    if code == _SILU:
        return silu64(x)
    if code == _SIGMOID:
        return sigmoid64(x)
    return pade_tanh64(x)


@njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def unit32(code, x):
    """The ``unit32`` form of the activation ``code`` at x."""
    if code == _TANH:
        return tanh32(x)
    if code == _RELU:
        return relu32(x)
    if code == _SILU:
        return silu32(x)
    if code == _SIGMOID:
        return sigmoid32(x)
    return pade_tanh32(x)


def unit_name(name: str, f32: bool = False) -> str:
    """The name a generated kernel calls the activation's compiled unit by (``tanh64``, ``relu32``, ...)."""
    return f"{REGISTRY[name].name}{32 if f32 else 64}"


def unit_names() -> dict[str, Any]:
    """Every compiled unit by the name generated kernels call it (``unit_name``): their namespace."""
    return {unit_name(a.name, f32): (a.unit32 if f32 else a.unit64) for a in REGISTRY.values()
            for f32 in (False, True)}
