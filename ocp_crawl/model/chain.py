"""A planar chain of n >= 3 rigid links with torsion-spring joints and a Coulomb foot at each end.

:class:`Chain` generalises :class:`~ocp_crawl.model.robot.Robot` (the symmetric three-link
crawler) to any number of links with their own lengths, masses and centres of mass, joints with
their own stiffness and rest angle, and feet with their own friction coefficients.  Its statics
are in :mod:`ocp_crawl.model.chain_statics` (symbolic) and :mod:`ocp_crawl.model.chain_model`
(numeric front end).

Conventions (those of :mod:`ocp_crawl.model.statics`, for any n):

* Links are numbered 1..n from foot 1 (left) to foot 2 (right); joint j joins links j and j + 1.
* ``phi_j`` is the interior joint angle below the chain, ``pi`` = straight; the spring of joint j
  is relaxed at ``phi_j = pi + rest_j``: ``rest_j`` is the rest bend from straight (0 = straight,
  negative = bent upwards, as the upright "Pi" shape at ``phi = pi/2``).
* The centre of mass of link i lies at the fraction ``com_i`` of its length from its foot-1 end.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Sequence

from ocp_crawl.checks import real
from ocp_crawl.model.robot import MAGNITUDE, MU_BOUNDS, Robot

#: largest ratio of the longest to the shortest link (the bound of Robot.beta: a link shorter than
#: 1 % of another makes the geometry degenerate)
LENGTH_RATIO_MAX = 100.0
#: relative slack of the length-ratio bound (a Robot at beta = 100 has l * beta / l = 100 + 1 ulp)
_RATIO_SLACK = 1e-9
#: fewest links of a chain with two feet on the ground and a free shape
MIN_LINKS = 3


def _floats(name: str, values: Sequence[float], size: int | None = None, **bounds) -> tuple:
    """``values`` as a tuple of checked floats (each named ``name[i]``, 0-based), of length ``size``
    when given; ValueError naming ``name`` otherwise, TypeError for a non-sequence."""
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__"):
        raise TypeError(f"{name} must be a sequence of real numbers, got {values!r}")
    if size is not None and len(values) != size:
        raise ValueError(f"{name} must have {size} entries, got {len(values)}")
    return tuple(real(f"{name}[{i}]", v, **bounds) for i, v in enumerate(values))


@dataclass(frozen=True)
class Chain:
    """Physical parameters of an n-link crawler (SI units), frozen and validated.

    Parameters
    ----------
    lengths : sequence of float
        Link lengths [m], n >= 3 entries, each in [1e-12, 1e12]; the longest at most
        :data:`LENGTH_RATIO_MAX` times the shortest.
    masses : sequence of float
        Link masses [kg], n entries, each in [0, 1e12]; their sum (the total mass) in
        [1e-12, 1e12].
    stiffness : sequence of float
        Torsion-spring stiffness of each joint [N m/rad], n - 1 entries in [1e-12, 1e12].
    mu : sequence of float
        Coulomb friction coefficients of foot 1 (left) and foot 2 (right) [-], in [1e-4, 1e4].
    com : sequence of float, optional
        Centre of mass of each link as a fraction of its length from its foot-1 end [-], n entries
        in [0, 1]; empty or None: 0.5 each (uniform links).
    rest : sequence of float, optional
        Rest bend of each joint's spring from straight [rad], n - 1 entries in (-pi, pi): the spring
        is relaxed at ``phi_j = pi + rest_j``; empty or None: 0 each (straight).
    g : float
        Gravitational acceleration [m/s^2], in [1e-12, 1e12].

    A value of the wrong count, out of range or not finite raises ValueError naming the field
    (``lengths[2]``, ``mu``, ...); ``chain.replace(g=1.62)`` gives a modified copy.
    """

    lengths: tuple[float, ...]
    """link lengths [m], from foot 1 to foot 2"""
    masses: tuple[float, ...]
    """link masses [kg]"""
    stiffness: tuple[float, ...]
    """joint stiffnesses [N m/rad], joint j between links j and j + 1"""
    mu: tuple[float, float]
    """friction coefficients of foot 1 and foot 2 [-]"""
    com: tuple[float, ...] = field(default=())
    """centre-of-mass fractions along each link from its foot-1 end [-] (empty: 0.5 each)"""
    rest: tuple[float, ...] = field(default=())
    """rest bends of the joint springs from straight [rad] (empty: 0 each)"""
    g: float = 9.81
    """gravitational acceleration [m/s^2]"""

    def __post_init__(self) -> None:
        lengths = _floats("lengths", self.lengths, low=MAGNITUDE[0], high=MAGNITUDE[1])
        n = len(lengths)
        if n < MIN_LINKS:
            raise ValueError(f"lengths must have at least {MIN_LINKS} entries (links), got {n}")
        if max(lengths) > LENGTH_RATIO_MAX * (1 + _RATIO_SLACK) * min(lengths):
            raise ValueError(f"lengths: the longest link ({max(lengths):.6g} m) is more than "
                             f"{LENGTH_RATIO_MAX:g} times the shortest ({min(lengths):.6g} m)")
        masses = _floats("masses", self.masses, n, nonneg=True, high=MAGNITUDE[1])
        real("total mass sum(masses)", math.fsum(masses), low=MAGNITUDE[0], high=MAGNITUDE[1])
        com = ((0.5,) * n if self.com is None or len(self.com) == 0
               else _floats("com", self.com, n, low=0.0, high=1.0))
        stiffness = _floats("stiffness", self.stiffness, n - 1, low=MAGNITUDE[0],
                            high=MAGNITUDE[1])
        rest = ((0.0,) * (n - 1) if self.rest is None or len(self.rest) == 0
                else _floats("rest", self.rest, n - 1))
        for j, r in enumerate(rest):
            if not -math.pi < r < math.pi:
                raise ValueError(f"rest[{j}] must lie in (-pi, pi) rad, got {r!r}")
        mu = _floats("mu", self.mu, 2, low=MU_BOUNDS[0], high=MU_BOUNDS[1])
        g = real("g", self.g, low=MAGNITUDE[0], high=MAGNITUDE[1])
        for name, value in (("lengths", lengths), ("masses", masses), ("com", com),
                            ("stiffness", stiffness), ("rest", rest), ("mu", mu), ("g", g)):
            object.__setattr__(self, name, value)

    # ------------------------------------------------------------------ sizes and totals
    @property
    def mu1(self) -> float:
        """Friction coefficient of foot 1 [-] (as :attr:`Robot.mu1`)."""
        return self.mu[0]

    @property
    def mu2(self) -> float:
        """Friction coefficient of foot 2 [-]."""
        return self.mu[1]

    @property
    def n(self) -> int:
        """number of links"""
        return len(self.lengths)

    @property
    def n_joints(self) -> int:
        """number of joints (n - 1)"""
        return len(self.lengths) - 1

    @property
    def M(self) -> float:
        """total mass [kg]"""
        return math.fsum(self.masses)

    @property
    def L(self) -> float:
        """total (straight) length [m]"""
        return math.fsum(self.lengths)

    @property
    def MgL(self) -> float:
        """gravitational torque scale M g L [N m]"""
        return self.M * self.g * self.L

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_robot(cls, robot: Robot) -> "Chain":
        """The symmetric three-link chain of a :class:`Robot`.

        Legs of length ``l = L/(2 + beta)`` and mass ``m = M/(2 + beta)``, a body of ``beta l`` and
        ``beta m``, all uniform (``com = 0.5``); both joints of stiffness ``k``, relaxed straight;
        friction ``(mu1, mu2)`` and the robot's ``g``.
        """
        if not isinstance(robot, Robot):
            raise TypeError(f"robot must be a Robot, got {type(robot).__name__}")
        l, m, b = robot.l, robot.m, robot.beta
        return cls(lengths=(l, b * l, l), masses=(m, b * m, m), stiffness=(robot.k, robot.k),
                   mu=(robot.mu1, robot.mu2), com=(0.5, 0.5, 0.5), rest=(0.0, 0.0), g=robot.g)

    def replace(self, **changes) -> "Chain":
        """A copy with the given fields changed (validated again)."""
        return replace(self, **changes)

    def reversed(self) -> "Chain":
        """The same chain read from the other end: foot 2 becomes foot 1.

        Links, joints and feet in reverse order; each centre-of-mass fraction ``c`` becomes
        ``1 - c``; rest bends keep their sign (the interior angle below the chain is the same angle
        read from either end).  A configuration ``phi`` of this chain is ``phi[::-1]`` of the
        reversed one, with the same feet distance and the foot forces exchanged.
        """
        return Chain(lengths=self.lengths[::-1], masses=self.masses[::-1],
                     stiffness=self.stiffness[::-1], mu=(self.mu[1], self.mu[0]),
                     com=tuple(1.0 - c for c in self.com[::-1]), rest=self.rest[::-1], g=self.g)

    def merged(self, j: int) -> "Chain":
        """The chain with joint ``j`` (0-based, between links j and j + 1) made rigid, straight.

        The two links become one of their summed length and mass, with their common centre of
        mass.  Needs ``rest[j] == 0`` (a rigid joint at a bend is not a straight link) and at least
        four links (a chain keeps three).
        """
        j = int(real("j", j, integer=True, low=0, high=self.n_joints - 1))
        if self.n <= MIN_LINKS:
            raise ValueError(f"merged: a chain of {self.n} links cannot lose a joint "
                             f"(at least {MIN_LINKS} links)")
        if self.rest[j] != 0.0:
            raise ValueError(f"merged: rest[{j}] = {self.rest[j]!r} rad; only a straight joint "
                             "(rest 0) merges into one straight link")
        la, lb = self.lengths[j], self.lengths[j + 1]
        ma, mb = self.masses[j], self.masses[j + 1]
        length, mass = la + lb, ma + mb
        pos = (ma * self.com[j] * la + mb * (la + self.com[j + 1] * lb)) / mass if mass > 0 \
            else 0.5 * length
        return Chain(lengths=self.lengths[:j] + (length,) + self.lengths[j + 2:],
                     masses=self.masses[:j] + (mass,) + self.masses[j + 2:],
                     stiffness=self.stiffness[:j] + self.stiffness[j + 1:], mu=self.mu,
                     com=self.com[:j] + (pos / length,) + self.com[j + 2:],
                     rest=self.rest[:j] + self.rest[j + 1:], g=self.g)

    def scaled(self, length: float = 1.0, mass: float = 1.0) -> "Chain":
        """The chain with lengths times ``length``, masses times ``mass`` and stiffnesses times
        ``length * mass`` [-, -]: the same equilibrium angles, forces times ``mass`` and torques
        and energies times ``length * mass``."""
        a = real("length", length, positive=True)
        b = real("mass", mass, positive=True)
        return self.replace(lengths=tuple(a * v for v in self.lengths),
                            masses=tuple(b * v for v in self.masses),
                            stiffness=tuple(a * b * v for v in self.stiffness))
