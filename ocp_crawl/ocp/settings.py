"""Settings of the periodic-gait optimal control problem: the objectives and their options.

Every OCP default is defined here once, as an :class:`OCPSettings` field; the problem schema
(``[ocp]`` section of a problem file) reads its defaults from these fields, key by key of the same name.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

from ocp_crawl.checks import is_real, real
from ocp_crawl.model.statics import Robot
from ocp_crawl.nlp.ipopt import check_ipopt_options

Objective = Literal["max_speed", "min_cot", "robust_speed"]
OBJECTIVES = ("max_speed", "min_cot", "robust_speed")
PARAMETRIZATIONS = ("free", "fourier")
#: values of :attr:`OCPSettings.rate_limit` besides a number [N m per cycle]
RATE_LIMITS = ("harmonic", "none", "max_rate")
#: values of :attr:`OCPSettings.curvature_limit` besides a number [N m per cycle^2]
CURVATURE_LIMITS = ("harmonic", "none")

#: bounds of the settings that size the work (a solve within minutes; see the README's "Bounds"): the nodes
#: of the transcription, the Fourier order, the psi values and amplitudes of the harmonic sweep
NODES_BOUNDS = (8, 1000)
FOURIER_ORDER_BOUNDS = (1, 25)
HARMONIC_PSI_BOUNDS = (4, 180)
HARMONIC_A_BOUNDS = (1, 20)

#: default curvature limit in units of the peak curvature of the envelope's harmonic gait
CURVATURE_FACTOR = 4.0


@dataclass(frozen=True)
class OCPSettings:
    """Settings of the periodic-gait optimal control problem (the ``[ocp]`` keys of a problem file)."""

    objective: Objective = "max_speed"
    nodes: int = 100
    """steps per cycle N, in NODES_BOUNDS"""
    direction: int = -1
    """sign of S to pursue: -1 towards foot 1 (the direction of psi > 0 gaits), +1 towards foot 2"""
    gamma_deg: float = 90.0
    """centre of the reference-angle envelope [deg] (a problem file gives it as ``[gait] gamma_deg``)"""
    A_max_deg: float = 30.0
    """half-width of the reference-angle envelope [deg]"""
    parametrization: str = "free"
    """'free' torque at every node (default, sparse), or 'fourier' series of order fourier_order
    (band-limited, but its dense coefficient columns make IPOPT iterations much slower)"""
    fourier_order: int = 4
    rate_limit: float | str | None = "harmonic"
    """largest |d tau/d t| [N m per cycle]; "harmonic" (default): the peak rate 2 pi k A_max of the
    envelope's harmonic gait, so that the optimum cannot gain by packing several strokes into one
    cycle (a higher actuation frequency); "max_rate": the value of max_rate; "none" or None: no limit"""
    max_rate: float | None = None
    """largest |d tau/d t| [N m per cycle] when rate_limit = "max_rate" """
    curvature_limit: float | str | None = "harmonic"
    """largest |d^2 tau/d t^2| [N m per cycle^2]; "harmonic" (default): CURVATURE_FACTOR times the
    peak (2 pi)^2 k A_max of the envelope's harmonic gait.  Without a limit free profiles chatter:
    micro-strokes every few steps, each carrying an O(1/N) transition error of the transcription
    that the optimiser exploits and that does not vanish as N grows (the strokes multiply).  With
    the factor 1 the full-amplitude sine is about the only admissible stroke, hence 4 (room for a
    second harmonic at full amplitude).  "none" or None: no limit"""
    tie_margin: float = 0.0005
    """a foot may slip only while its friction limit is below the other foot's by tie_margin M g:
    at a tie the incremental Coulomb law leaves free which foot slips, which an optimiser would
    exploit and the continuous system does not allow (it slips both feet symmetrically)"""
    regularization: float = 1e-5
    """weight of N * sum_k |tau_k - tau_{k-1}|^2/(M g L)^2 in the objective"""
    S_min: float = 0.0
    """min_cot: smallest direction * S [m]"""
    mu_ratio_eps: float = 0.1
    """robust_speed: friction scenarios mu1/mu2 in {1 - eps, 1, 1 + eps} (just 1 when eps = 0), in [0, 1)"""
    mu_ratios: tuple | None = None
    """robust_speed: the scenarios mu1/mu2 (mu1 = mu sqrt(r), mu2 = mu / sqrt(r)) given explicitly;
    None (default): from mu_ratio_eps"""
    robust: str = "mean"
    """robust_speed: maximise the 'mean' or the 'worst' direction * S over the scenarios"""
    sigma0: tuple = (1e-2, 1e-6)
    """first relaxation parameters of the homotopies run from the harmonic initial guess (the
    problem is nonconvex and the relaxation path decides the local optimum: a loose start explores,
    a tight start stays near the guess); the best accepted result is kept"""
    sigma_min: float = 1e-10
    sigma_factor: float = 0.1
    comp_tol: float = 1e-6
    """largest accepted complementarity residual max_j |min(s_j/L, c_j/(M g))|"""
    periodic_tol: float = 1e-8
    harmonic_psi: int = 36
    """psi values of the harmonic sweep (initial guess and comparison), over (-180, 180] deg"""
    harmonic_A: int = 4
    """amplitudes of the harmonic sweep, up to A_max"""
    ipopt: dict = field(default_factory=dict)
    """IPOPT options passed through (copied per instance); override :data:`~ocp_crawl.nlp.ipopt.OCP_IPOPT`"""
    verbose: bool = False

    def __post_init__(self) -> None:
        self._check_choices()
        self._check_numbers()
        self._check_limits()
        object.__setattr__(self, "ipopt", check_ipopt_options("OCPSettings.ipopt", self.ipopt))

    def _set(self, name: str, value) -> None:
        object.__setattr__(self, name, value)

    def _check_choices(self) -> None:
        for name, choices in (("objective", OBJECTIVES), ("parametrization", PARAMETRIZATIONS)):
            if getattr(self, name) not in choices:
                raise ValueError(f"OCPSettings.{name} must be one of {choices}, got {getattr(self, name)!r}")
        if self.direction not in (-1, 1):
            raise ValueError(f"OCPSettings.direction must be -1 or +1, got {self.direction!r}")
        if self.robust not in ("mean", "worst"):
            raise ValueError(f"OCPSettings.robust must be 'mean' or 'worst', got {self.robust!r}")

    def _check_numbers(self) -> None:
        for name, (low, high) in (("nodes", NODES_BOUNDS), ("fourier_order", FOURIER_ORDER_BOUNDS),
                                  ("harmonic_psi", HARMONIC_PSI_BOUNDS), ("harmonic_A", HARMONIC_A_BOUNDS)):
            self._set(name, real(f"OCPSettings.{name}", getattr(self, name), integer=True, low=low, high=high))
        for name in ("gamma_deg", "A_max_deg", "sigma_min", "sigma_factor", "comp_tol", "periodic_tol"):
            self._set(name, real(f"OCPSettings.{name}", getattr(self, name), positive=True))
        for name in ("regularization", "S_min", "tie_margin", "mu_ratio_eps"):
            self._set(name, real(f"OCPSettings.{name}", getattr(self, name), nonneg=True))
        if not 0 < self.A_max_deg < 90:
            raise ValueError(f"OCPSettings.A_max_deg must be in (0, 90), got {self.A_max_deg}")
        if not (0 < self.gamma_deg - self.A_max_deg and self.gamma_deg + self.A_max_deg < 180):
            raise ValueError("OCPSettings: the envelope gamma +- A_max must lie in (0, 180) deg")
        s0 = (self.sigma0,) if is_real(self.sigma0) else tuple(self.sigma0)
        if not s0 or any(not is_real(v) or not 0 < v < 1 for v in s0):
            raise ValueError(f"OCPSettings.sigma0 must be numbers in (0, 1), got {self.sigma0!r}")
        self._set("sigma0", tuple(float(v) for v in s0))
        if not self.sigma_factor < 1 or not all(self.sigma_min < v for v in self.sigma0):
            raise ValueError("OCPSettings: need sigma_factor < 1 and sigma_min < sigma0")
        if not self.mu_ratio_eps < 1:
            raise ValueError(f"OCPSettings.mu_ratio_eps must be in [0, 1), got {self.mu_ratio_eps!r}")
        if self.mu_ratios is not None:
            ratios = tuple(float(r) for r in self.mu_ratios)
            if not ratios or any(not (math.isfinite(r) and r > 0) for r in ratios):
                raise ValueError(f"OCPSettings.mu_ratios must be positive numbers, got {self.mu_ratios!r}")
            self._set("mu_ratios", ratios)

    def _check_limits(self) -> None:
        """rate_limit and curvature_limit: "harmonic", None ("none"), or a number > 0 (rate: "max_rate")."""
        if self.max_rate is not None:
            self._set("max_rate", real("OCPSettings.max_rate", self.max_rate, positive=True))
        if self.rate_limit == "max_rate" and self.max_rate is None:
            raise ValueError('OCPSettings.rate_limit = "max_rate" needs OCPSettings.max_rate')
        for name, words in (("rate_limit", RATE_LIMITS), ("curvature_limit", CURVATURE_LIMITS)):
            value = getattr(self, name)
            if value == "none":
                self._set(name, None)
            elif isinstance(value, str) and value not in words:
                raise ValueError(f"OCPSettings.{name} must be one of {words} or a number, got {value!r}")
            elif value is not None and not isinstance(value, str):
                self._set(name, real(f"OCPSettings.{name}", value, positive=True))

    def scenarios(self, robot: Robot) -> list[Robot]:
        """The robots of the friction scenarios (robust_speed; else just ``robot``)."""
        if self.objective != "robust_speed":
            return [robot]
        mu = math.sqrt(robot.mu1 * robot.mu2)
        return [robot.replace(mu1=mu * math.sqrt(r), mu2=mu / math.sqrt(r)) for r in self.friction_ratios]

    @property
    def friction_ratios(self) -> tuple[float, ...]:
        """The scenarios mu1/mu2 of robust_speed: mu_ratios, else {1 - eps, 1, 1 + eps} (eps = mu_ratio_eps > 0)
        or (1,)."""
        if self.mu_ratios is not None:
            return self.mu_ratios
        eps = self.mu_ratio_eps
        return (1 - eps, 1.0, 1 + eps) if eps > 0 else (1.0,)

    def rate_bound(self, robot: Robot) -> float | None:
        """Largest |d tau / d t| [N m per cycle] or None."""
        if self.rate_limit == "harmonic":
            return 2 * math.pi * robot.k * math.radians(self.A_max_deg)
        return self.max_rate if self.rate_limit == "max_rate" else self.rate_limit

    def curvature_bound(self, robot: Robot) -> float | None:
        """Largest |d^2 tau / d t^2| [N m per cycle^2] or None."""
        if self.curvature_limit == "harmonic":
            return CURVATURE_FACTOR * (2 * math.pi) ** 2 * robot.k * math.radians(self.A_max_deg)
        return self.curvature_limit

    def torque_bounds(self, robot: Robot) -> tuple[float, float]:
        """Torque range [N m] that keeps phi_ref = pi + tau/k inside the envelope."""
        g, a = math.radians(self.gamma_deg), math.radians(self.A_max_deg)
        return robot.k * (g - a - math.pi), robot.k * (g + a - math.pi)
