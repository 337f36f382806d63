"""Input and output scaling of the force networks, fitted on training data and saved with the model.

Two kinds:

- ``standard``: inputs (X1, X2, V1, V2) and outputs (F1, F2) standardised
  with the training data's mean and standard deviation;
- ``physics``: inputs in clearance units (X/c, V/(c omega)) and forces
  divided by the film-force scale mu omega R L (R/c)^2 and multiplied by
  (1 - eps^2)^p before standardising.  The forces span orders of magnitude
  across eps (squeeze damping grows like (1 - eps^2)^-1.5); the factor
  flattens that growth so one network's error is spread evenly over eps.
- ``physics_v``: as ``physics``, and the force also divided by
  (1 + |V|/(c omega)).  Squeeze forces grow with |V| and at |V| >> c omega
  dwarf the static (wedge) force; without this factor the network's error
  budget goes to them and the static load - what decides where the journal
  settles - gets a poor relative accuracy.

Pure numpy, so that inference needs no torch.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

SCALINGS = ("standard", "physics", "physics_v")
KIND_CODES = {"standard": 0.0, "physics": 1.0, "physics_v": 2.0}


@dataclass
class Scaling:
    kind: str
    clearance: float
    omega: float
    force_scale: float
    power: float
    in_mean: np.ndarray
    in_std: np.ndarray
    out_mean: np.ndarray
    out_std: np.ndarray

    # ------------------------------------------------------------------ fit
    @classmethod
    def fit(cls, kind: str, X: np.ndarray, V: np.ndarray, F: np.ndarray, clearance: float, omega: float,
            force_scale: float, power: float = 1.5) -> "Scaling":
        if kind not in SCALINGS:
            raise ValueError(f"unknown scaling {kind!r}; choose one of {SCALINGS}")
        s = cls(kind, float(clearance), float(omega), float(force_scale), float(power),
                np.zeros(4), np.ones(4), np.zeros(2), np.ones(2))
        z = s._raw_inputs(X, V)
        y = s._raw_targets(X, V, F)
        s.in_mean, s.in_std = z.mean(axis=0), z.std(axis=0) + 1e-12
        s.out_mean, s.out_std = y.mean(axis=0), y.std(axis=0) + 1e-12
        return s

    # ------------------------------------------------------------------ transforms
    def _eps2(self, X):
        return (X[..., 0] ** 2 + X[..., 1] ** 2) / self.clearance**2

    def gain(self, X, V) -> np.ndarray:
        """Force per unit of raw network target at each state (1 for standard scaling)."""
        if self.kind == "standard":
            return np.ones(np.shape(X)[:-1])
        g = self.force_scale / (1.0 - self._eps2(X)) ** self.power
        if self.kind == "physics_v":
            g = g * (1.0 + np.hypot(V[..., 0], V[..., 1]) / (self.clearance * self.omega))
        return g

    def _raw_inputs(self, X, V):
        if self.kind != "standard":
            return np.concatenate([X / self.clearance, V / (self.clearance * self.omega)], axis=-1)
        return np.concatenate([X, V], axis=-1)

    def _raw_targets(self, X, V, F):
        return F / self.gain(X, V)[..., None]

    def inputs(self, X, V) -> np.ndarray:
        return (self._raw_inputs(X, V) - self.in_mean) / self.in_std

    def targets(self, X, V, F) -> np.ndarray:
        return (self._raw_targets(X, V, F) - self.out_mean) / self.out_std

    def forces(self, X, V, y) -> np.ndarray:
        """Inverse of ``targets``: network outputs -> forces [N]."""
        return (y * self.out_std + self.out_mean) * self.gain(X, V)[..., None]

    # ------------------------------------------------------------------ io
    def to_dict(self) -> dict:
        d = asdict(self)
        for k in ("in_mean", "in_std", "out_mean", "out_std"):
            d[k] = np.asarray(d[k]).tolist()
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "Scaling":
        d = dict(d)
        for k in ("in_mean", "in_std", "out_mean", "out_std"):
            d[k] = np.asarray(d[k], dtype=float)
        return cls(**d)

    def kernel_row(self) -> np.ndarray:
        """Flat parameters for the compiled kernel: kind, c, omega, force_scale, power, means, stds."""
        return np.concatenate([[KIND_CODES[self.kind], self.clearance, self.omega,
                                self.force_scale, self.power], self.in_mean, self.in_std, self.out_mean,
                               self.out_std])
