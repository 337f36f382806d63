"""The force-model contract: what the rotor integrator, the controllers and the studies may ask of a model.

A force model gives the film force of one bearing on the journal, F(X, V), in N, for journal
positions X [m] and velocities V [m/s] in the conventions' frame.  Every model in the library -
``ReynoldsSolver``, ``GradedReynoldsModel``, ``ConicalReynoldsSolver``, ``SurrogateForceModel``,
``LinearBearing`` - implements ``ForceModel``; the active (conical) bearing's models implement
``AdjustableForceModel`` as well.  A type checker proves it (``fluidfilm._conformance``, run by
``make lint``); nothing in the library probes a model with ``getattr``/``hasattr``.

The members:

- ``forces(X, V)``: one state ((2,), (2,)) or any batch ((..., 2), (..., 2)) -> (..., 2) N;
- ``force_kernel``: ``(fn, params)``, a numba-compiled ``fn(params, x1, x2, v1, v2) -> (F1, F2)``
  that compiled callers (``rotor.simulate``) call in their own loop, with ``params`` whatever the
  kernel needs (read-only for the caller);
- ``name``: a display name (warnings, reports);
- ``bearing``: the bearing the model describes (geometry, lubricant, speed);
- ``clearance``: the radial clearance [m] at the current setting: the radius a journal
  position must stay inside (for an adjustable bearing it moves with the sleeve);
- ``validity``: the domain the model answers for (``ValidityDomain``); the reference solvers
  answer for the whole clearance, a surrogate for its training data's range;
- ``reset_domain_counter()`` / ``domain_report()``: count evaluations outside ``validity``
  from now on / say how many there were (``None`` when none, or when the model is valid everywhere).

Optional: ``BatchForceModel`` (a kernel of many states at once, which ``simulate_batch`` calls once
per RK4 stage for the whole batch), ``BatchSettable`` (a per-trajectory control setting),
``PrecisionKernelModel`` (a one-state kernel with float32 networks) and ``SpeedScalableModel`` (the force
at any shaft speed: run-ups).

Adding a model: see docs/adding_a_model.md.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from fluidfilm.core.bearing import ConicalBearing, JournalBearing

#: ``fn(params, x1, x2, v1, v2) -> (F1, F2)``, compiled with numba
ForceKernel = Callable[..., tuple[float, float]]
#: ``fn(bparams, x (m, 2), v (m, 2), out (m, 2)) -> None``, compiled with numba: forces [N] into ``out``
BatchForceKernel = Callable[..., None]
#: ``fn(params, omega, x1, x2, v1, v2) -> (F1, F2)``, compiled with numba: the film force at shaft speed omega [rad/s]
SpeedForceKernel = Callable[..., tuple[float, float]]
Bearing = JournalBearing | ConicalBearing


@dataclass(frozen=True)
class ValidityDomain:
    """Where a model's forces are trusted.

    The eccentricity ratio (relative to the current clearance) at most ``eps_max``, and, where
    ``bands`` are given as rows ``(eps_low, eps_high, v_max)``, every velocity component within
    that band's ``v_max`` [m/s] (the last band also covers eps above its ``eps_high``).

    Parameters
    ----------
    eps_max : float, default 1.0
        Largest trusted eccentricity ratio |X|/c.
    bands : tuple of (float, float, float), default ()
        Rows ``(eps_low, eps_high, v_max)``: the velocity bound [m/s] per eccentricity band.

    Examples
    --------
    >>> from fluidfilm.core import ValidityDomain
    >>> d = ValidityDomain(eps_max=0.9, bands=((0.0, 0.5, 0.01), (0.5, 0.9, 0.02)))
    >>> d.contains([[0.0, 50e-6], [0.0, 50e-6], [0.0, 110e-6]],
    ...            [[0.0, 0.005], [0.0, 0.05], [0.0, 0.0]], clearance=120e-6).tolist()
    [True, False, False]
    """

    eps_max: float = 1.0
    bands: tuple[tuple[float, float, float], ...] = ()

    def contains(self, X: ArrayLike, V: ArrayLike, clearance: float) -> np.ndarray:
        """Boolean mask over the leading dimensions of X [m], V [m/s] (..., 2): inside the domain, with
        eccentricities relative to ``clearance`` [m]."""
        x = np.asarray(X, dtype=float)
        v = np.asarray(V, dtype=float)
        eps = np.hypot(x[..., 0], x[..., 1]) / clearance
        inside = eps <= self.eps_max
        vabs = np.abs(v).max(axis=-1)
        for k, (lo, hi, v_max) in enumerate(self.bands):
            band = (eps >= lo) & ((eps < hi) | (k == len(self.bands) - 1))
            inside &= ~(band & (vabs > v_max))
        return inside


#: the domain of a physics-based model: any state inside the clearance
WHOLE_FILM = ValidityDomain()


@runtime_checkable
class ForceModel(Protocol):
    """The film force of one bearing: see the module docstring for each member.

    A structural protocol (``isinstance`` checks the members at run time, mypy statically): a class
    need not inherit from it.  ``forces(X, V)`` takes positions X [m] and velocities V [m/s] in the
    (X1, X2) frame, +X2 along gravity, and returns the film force on the journal [N].

    Examples
    --------
    >>> from fluidfilm import LinearBearing, ReynoldsSolver, paper_bearing
    >>> from fluidfilm.core import ForceModel
    >>> isinstance(ReynoldsSolver(paper_bearing(), 16, 8), ForceModel)
    True
    >>> isinstance(object(), ForceModel)
    False
    """

    @property
    def name(self) -> str: ...

    @property
    def bearing(self) -> Bearing: ...

    @property
    def clearance(self) -> float: ...

    @property
    def force_kernel(self) -> tuple[ForceKernel, Any]: ...

    @property
    def validity(self) -> ValidityDomain: ...

    def forces(self, X: ArrayLike, V: ArrayLike) -> np.ndarray: ...

    def reset_domain_counter(self) -> None: ...

    def domain_report(self) -> str | None: ...

    @property
    def n_outside_domain(self) -> int: ...


@runtime_checkable
class AdjustableForceModel(ForceModel, Protocol):
    """A force model of an active bearing whose sleeve (the control input) can be moved.

``adjustable`` is False where the class serves fixed bearings too and this instance models one
(``as_adjustable`` checks both).

    ``set_sleeve(s)`` moves the sleeve to ``s`` [m] (inside the bearing's travel, else a
    ``ValueError``); ``clearance`` and the forces follow at once.

    Examples
    --------
    >>> from fluidfilm import ConicalBearing, ConicalReynoldsSolver, ReynoldsSolver, paper_bearing
    >>> from fluidfilm.core import AdjustableForceModel
    >>> cone = ConicalBearing(length=0.05, diameter_small=0.04, diameter_large=0.05, clearance=100e-6,
    ...                       speed_rpm=3000, viscosity=6.53e-4, sleeve_min=-0.5e-3, sleeve_max=0.5e-3)
    >>> isinstance(ConicalReynoldsSolver(cone, 16, 8), AdjustableForceModel)
    True
    >>> isinstance(ReynoldsSolver(paper_bearing(), 16, 8), AdjustableForceModel)
    False
    """

    @property
    def adjustable(self) -> bool: ...

    @property
    def sleeve(self) -> float: ...

    def set_sleeve(self, sleeve: float) -> None: ...


@runtime_checkable
class BatchSettable(Protocol):
    """A force model whose kernel reads a mutable control setting that ``simulate_batch`` can vary per
    trajectory (a surrogate of the active bearing: [1/c_r^2, sleeve]).

    ``setting_array`` is the kernel's own setting (written in place during a batch and restored after);
    ``setting_for(sleeve)`` the row for one sleeve position.

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> from fluidfilm.core import BatchSettable
    >>> isinstance(ReynoldsSolver(paper_bearing(), 16, 8), BatchSettable)   # the solver re-solves instead
    False
    """

    @property
    def setting_array(self) -> np.ndarray: ...

    def setting_for(self, sleeve: float) -> np.ndarray: ...


@runtime_checkable
class BatchForceModel(Protocol):
    """A force model with a compiled kernel of many states at once (``simulate_batch`` calls it once per
    RK4 stage for all running trajectories).

    ``batch_force_kernel(precision, private)`` -> ``(fn, bparams)``: ``fn(bparams, x, v, out)`` writes the
    forces [N] of the states x (m, 2) [m], v (m, 2) [m/s] (C-contiguous float64) into ``out`` (m, 2), each
    row what ``force_kernel`` gives for that state (to round-off; exactly, for the reference models).
    ``precision`` "float64" or "float32": the arithmetic of a surrogate's networks (a reference model
    computes in float64 either way).  ``private=True``: parameters with their own counters (domain,
    ensemble flags) and nothing else mutable shared, so that calls on different private parameters may
    run in concurrent threads; ``merge_counts(bparams)`` adds a private set's counts to the model's own.
    ``batch_force_kernel`` returns None where this instance has no batched kernel (an ensemble whose
    members have none); ``simulate_batch`` then steps each trajectory with ``force_kernel``.

    Examples
    --------
    >>> from fluidfilm import GradedReynoldsModel, LinearBearing, ReynoldsSolver, paper_bearing
    >>> from fluidfilm.core import BatchForceModel
    >>> b = paper_bearing()
    >>> [isinstance(m, BatchForceModel) for m in (ReynoldsSolver(b, 16, 8), LinearBearing(b, 1e6, 1e3))]
    [True, True]
    """

    def batch_force_kernel(self, precision: str = "float64",
                           private: bool = False) -> tuple[BatchForceKernel, Any] | None: ...

    def merge_counts(self, bparams: Any) -> None: ...


@runtime_checkable
class PrecisionKernelModel(Protocol):
    """A force model whose one-state kernel can run its networks in float32 (``simulate(precision=...)``).

    ``force_kernel_at(precision)`` -> ``(fn, params)`` with ``force_kernel``'s signature: "float64" is
    ``force_kernel`` itself, "float32" the networks in single precision (forces within 1e-5 of
    float64 relative to the larger of |F| and the states' RMS force; the frame, gains and blend stay float64), sharing the parameters, setting and counter.  A
    model without it (a reference solver, an ensemble) computes in float64 whatever the precision asked.

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> from fluidfilm.core import PrecisionKernelModel
    >>> from fluidfilm.perf.speed import best_shaped_surrogate
    >>> b = paper_bearing()
    >>> [isinstance(m, PrecisionKernelModel) for m in (ReynoldsSolver(b, 16, 8), best_shaped_surrogate(b))]
    [False, True]
    """

    def force_kernel_at(self, precision: str = "float64") -> tuple[ForceKernel, Any]: ...


@runtime_checkable
class SpeedScalableModel(Protocol):
    """A force model that gives the film force at any shaft speed, not only its bearing's: what a run-up needs
    (``rotor.simulate`` with a ``speed`` schedule).

    ``speed_kernel()`` -> ``(fn, params)``: ``fn(params, omega, x1, x2, v1, v2)`` is the force [N] at shaft
    speed omega [rad/s] (at the bearing's own speed, what ``force_kernel`` gives); None where this instance
    cannot (a surrogate whose frame does not make the speed scaling exact).  For a plain film without supply
    pressure the Reynolds equation is linear in (omega, V), so F(X, V; omega) = s F(X, V/s; omega_ref) with
    s = omega/omega_ref, for every cavitation rule (the cavitated set is unchanged by a positive factor).

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> from fluidfilm.core import SpeedScalableModel
    >>> solver = ReynoldsSolver(paper_bearing(), 16, 8)
    >>> isinstance(solver, SpeedScalableModel), solver.speed_kernel() is not None
    (True, True)
    """

    def speed_kernel(self) -> tuple[SpeedForceKernel, Any] | None: ...


@runtime_checkable
class TransientFilmModel(Protocol):
    """A film with memory: the force depends on the film content carried from step to step (mass-conserving
    cavitation, ``reynolds.elrod_adams.ElrodAdamsSolver``).  ``simulate`` integrates such a model with the
    content as state (``rotor.film_memory``); ``forces``/``force_kernel`` give the force with the content at its
    steady value (equilibria, K and C).

    ``transient_kernels()`` -> ``(stage, commit, flows, params)``, compiled: ``stage(params, K_omega, x1, x2, v1,
    v2, dt, tol, th_n, content, p, th) -> (F1, F2, sweeps, status)``, ``commit(params, K_omega, x1_old, x2_old,
    x1, x2, dt, th_n, content, p, th) -> (sweeps, status)`` and ``flows(params, omega, e1, e2, p, th) -> (side
    flow, friction power, F1, F2)`` (the film's force of the field); ``steady_field(x, omega)`` -> (p, content) at rest.

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> from fluidfilm.core import TransientFilmModel
    >>> from fluidfilm.reynolds.elrod_adams import ElrodAdamsSolver
    >>> isinstance(ElrodAdamsSolver(paper_bearing(), 16, 8), TransientFilmModel)
    True
    >>> isinstance(ReynoldsSolver(paper_bearing(), 16, 8), TransientFilmModel)
    False
    """

    def transient_kernels(self) -> tuple[Callable[..., Any], Callable[..., Any], Callable[..., Any], Any]: ...

    def steady_field(self, x: ArrayLike, omega: float | None = None) -> tuple[np.ndarray, np.ndarray]: ...


def one_state_kernel(model: ForceModel, precision: str = "float64") -> tuple[ForceKernel, Any, str]:
    """``(fn, params, ran)``: the model's one-state kernel with its networks in ``precision`` where it has
    float32 networks (``PrecisionKernelModel``), else its float64 ``force_kernel``; ``ran`` is the precision
    that runs (a ValueError naming any other ``precision``)."""
    if check_precision(precision) == "float32" and isinstance(model, PrecisionKernelModel):
        fn, params = model.force_kernel_at("float32")
        return fn, params, "float32"
    fn, params = model.force_kernel
    return fn, params, "float64"


def check_precision(precision: str) -> str:
    """``precision`` if it is "float64" or "float32", else a ValueError naming it."""
    if precision not in ("float64", "float32"):
        raise ValueError(f"precision must be 'float64' or 'float32', got {precision!r}")
    return precision


class FilmGrid(Protocol):
    """What the film-region integrals need of a solver's grid (``reynolds.mesh.FilmMesh`` has it; named
    here as a protocol so that this module, which the surrogates import, does not import the solver)."""

    @property
    def w_z(self) -> np.ndarray: ...   # Simpson weights over the axial nodes [m]


@runtime_checkable
class LinearPressureModel(Protocol):
    """A grid model whose pressure field before cavitation can be asked for (``ReynoldsSolver``,
    ``ConicalReynoldsSolver``): what the film-region derivative of the stiffness and damping
    coefficients needs (``characteristics.coefficients_gumbel_field``, used when ``cavitation`` is
    ``"gumbel"``).

    ``linear_pressure(x, v)`` for one state ((2,), (2,)) -> (n_theta, n_z) Pa on ``mesh``; ``theta``
    the grid's angles; ``cavitation`` the label of the cavitation rule ("gumbel", "none", ...).

    Examples
    --------
    >>> from fluidfilm import LinearBearing, ReynoldsSolver, paper_bearing
    >>> from fluidfilm.core import LinearPressureModel
    >>> solver = ReynoldsSolver(paper_bearing(), 16, 8)
    >>> isinstance(solver, LinearPressureModel), solver.linear_pressure([0.0, 60e-6], [0.0, 0.0]).shape
    (True, (16, 8))
    """

    @property
    def bearing(self) -> Bearing: ...

    @property
    def cavitation(self) -> str: ...

    @property
    def mesh(self) -> FilmGrid: ...

    @property
    def theta(self) -> np.ndarray: ...

    def linear_pressure(self, x: ArrayLike, v: ArrayLike) -> np.ndarray: ...


class ReferenceModel:
    """Defaults for a physics-based model: valid in the whole film, nothing to count.

    Subclasses set ``_bearing`` (and ``_c`` when the clearance can move).  A mixin with no
    constructor of its own.

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> from fluidfilm.core import WHOLE_FILM, ReferenceModel
    >>> solver = ReynoldsSolver(paper_bearing(), 16, 8)
    >>> isinstance(solver, ReferenceModel), solver.validity is WHOLE_FILM, solver.domain_report()
    (True, True, None)
    """

    _bearing: Any

    @property
    def name(self) -> str:
        return type(self).__name__

    @property
    def bearing(self) -> Any:
        return self._bearing

    @property
    def clearance(self) -> float:
        """Radial clearance at the current setting [m]."""
        return float(self._bearing.clearance)

    @property
    def validity(self) -> ValidityDomain:
        return WHOLE_FILM

    def reset_domain_counter(self) -> None:
        """Nothing is counted: a physics-based model is valid wherever the film exists."""

    def domain_report(self) -> str | None:
        return None

    @property
    def n_outside_domain(self) -> int:
        """Evaluations outside the validity domain since the last reset: none for a physics-based model."""
        return 0

    def merge_counts(self, bparams: Any) -> None:
        """Nothing is counted (``BatchForceModel``)."""


def as_adjustable(model: ForceModel) -> AdjustableForceModel:
    """``model`` as an adjustable-bearing model, or a ``ValueError`` naming it.

    A model class may serve both kinds of bearing (a surrogate with or without the sleeve input, the
    graded reference model of a journal or a conical bearing); ``adjustable`` says which it is.

    Parameters
    ----------
    model : ForceModel
        Any force model.

    Returns
    -------
    AdjustableForceModel
        ``model`` itself.

    Raises
    ------
    ValueError
        Naming the model's class, when it has no sleeve input.

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> from fluidfilm.core import as_adjustable
    >>> as_adjustable(ReynoldsSolver(paper_bearing(), 16, 8))
    Traceback (most recent call last):
    ...
    ValueError: ReynoldsSolver has no sleeve input: an active (adjustable) bearing model is needed
    """
    if isinstance(model, AdjustableForceModel) and model.adjustable:
        return model
    raise ValueError(f"{type(model).__name__} has no sleeve input: an active (adjustable) bearing model is needed")
