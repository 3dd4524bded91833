"""The three-link crawler's physical parameters (:class:`Robot`) and their bounds.

The bounds are the model's own: the API's :class:`Robot` and the ``[robot]`` keys of a problem file
refuse the same values (:mod:`ocp_crawl.problem.schema` states them with their reasons).
"""
from __future__ import annotations

from dataclasses import dataclass

from ocp_crawl.checks import real

#: magnitude bounds of M [kg], L [m], k [N m/rad], g [m/s^2]: products and ratios of four such
#: numbers (M g L, k/(M g L), their squares) stay far inside the floating-point range (1e-308 ..
#: 1e308)
MAGNITUDE = (1e-12, 1e12)
#: friction coefficients: mu = 0 is outside the quasistatic model, friction forces below 1e-4 M g
#: sink into the solvers' force tolerances
MU_BOUNDS = (1e-4, 1e4)
#: body-to-leg length ratio: a link shorter than 1 % of another makes the geometry degenerate
BETA_BOUNDS = (0.01, 100.0)


@dataclass(frozen=True)
class Robot:
    """Physical parameters of the three-link crawler (SI units), frozen and validated.

    Parameters
    ----------
    M : float
        Total mass [kg], in [1e-12, 1e12] (:data:`MAGNITUDE`, as L, k and g).
    L : float
        Total length [m]; legs of length l = L / (2 + beta), body beta l.
    beta : float
        Body-to-leg length ratio [-], in [0.01, 100] (:data:`BETA_BOUNDS`).
    k : float
        Torsion spring stiffness of each joint [N m/rad].
    mu1, mu2 : float
        Coulomb friction coefficients of foot 1 (left) and foot 2 (right) [-], in [1e-4, 1e4]
        (:data:`MU_BOUNDS`).
    g : float
        Gravitational acceleration [m/s^2].

    The defaults are the paper's Table I robot (:meth:`paper`).  A non-finite or out-of-range value
    raises ValueError naming the field; ``robot.replace(k=0.2)`` gives a modified copy.
    """

    M: float = 0.052
    """total mass [kg]"""
    L: float = 0.120
    """total length [m]"""
    beta: float = 2.0
    """body-to-leg length ratio [-]; legs have length l = L/(2+beta)"""
    k: float = 0.1677
    """torsion spring stiffness of each joint [N m/rad]"""
    mu1: float = 0.389
    """Coulomb friction coefficient at foot 1 (left) [-]"""
    mu2: float = 0.389
    """Coulomb friction coefficient at foot 2 (right) [-]"""
    g: float = 9.81
    """gravitational acceleration [m/s^2]"""

    def __post_init__(self) -> None:
        for name in ("M", "L", "beta", "k", "mu1", "mu2", "g"):
            low, high = (MU_BOUNDS if name in ("mu1", "mu2") else BETA_BOUNDS if name == "beta"
                         else MAGNITUDE)
            object.__setattr__(self, name, real(name, getattr(self, name), low=low, high=high))

    @classmethod
    def paper(cls, **overrides: float) -> "Robot":
        """The robot of the paper's Table I (M = 52 g, L = 120 mm, k = 0.1677 N m/rad, mu =
        0.389)."""
        return cls(**overrides)

    @property
    def l(self) -> float:
        """leg length [m]"""
        return self.L / (2.0 + self.beta)

    @property
    def m(self) -> float:
        """leg mass [kg]"""
        return self.M / (2.0 + self.beta)

    @property
    def MgL(self) -> float:
        """gravitational torque scale M g L [N m]"""
        return self.M * self.g * self.L

    def with_stiffness_ratio(self, ratio: float) -> "Robot":
        """Copy with k = ratio * M g L."""
        return self.replace(k=ratio * self.MgL)

    def replace(self, **changes: float) -> "Robot":
        from dataclasses import replace

        return replace(self, **changes)
