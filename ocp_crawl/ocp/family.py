"""The simple waveform families of the OCP's envelope and bandwidth: their parameters, gaits and
simulations.

A member is the reference gait phi_ref,i = gamma_i + A_i u(t +- s) of one *shape* u (a 1-periodic
unit wave in [-1, 1]), joint 1 leading joint 2 by the phase psi, driven as the torque tau_i = k
(phi_ref,i - pi) (:class:`~ocp_crawl.model.inputs.ReferenceTorque`).  The shapes (:data:`SHAPES`):

* ``harmonic``: u = sin(2 pi t) (:class:`~ocp_crawl.model.inputs.Harmonic`), largest slope 2 pi per
  cycle;
* ``triangle``: straight ramps up and down, each half a cycle (the reference rate saturated all
  cycle), largest slope 4 per cycle;
* ``pulse``: a trapezoid of soft actuators (:class:`~ocp_crawl.model.pulse.Pulse`): edges of
  ``rise`` cycles (in [RISE_MIN, 0.5]), the high level held for ``duty`` of the rest of the cycle,
  the low level for the remainder; largest slope 2/rise per cycle.  rise = 0.5 is the triangle.

A member belongs to the family of an :class:`~ocp_crawl.ocp.settings.OCPSettings` when both joints
stay inside the envelope, |gamma_i - gamma| + A_i <= A_max, A_i >= 0, and its reference rates stay
within the bandwidth R (``max_rate_deg_s``): slope * A_i / T <= R, i.e. T >=
:meth:`WaveParams.period`.  A member is simulated in every friction scenario of the settings and
scored as the OCP's objective scores them (the worst or the mean over a friction set): over a set
of friction ratios a near-mirror-symmetric member psi -> 0, whose slip a friction tie decides,
stops in some scenario and loses (docs/guide/optimal_gaits.md, "Friction uncertainty").

Why the period is always the shortest one: a quasistatic gait is time-scale invariant, so S, W+ and
CoT+ of a member do not depend on T.  The mean speed direction * S / T is then largest at the
smallest allowed T, CoT+ is the same at every T, and a speed requirement direction * S / T >=
speed_min is easiest to meet at the smallest T.  Every named objective of the OCP is therefore
optimal at the shortest period, and a family's search runs over its shape parameters only.  Bounds
on the period or an upper bound on the speed (``[[ocp.constraint]]``) slow a member down to the
shortest period they allow (:func:`allowed_period`); a user objective is evaluated at that period
too.

The search works in box coordinates z = (w1, w2, u, q, p[, r, d]) in [-1, 1] x [-1, 1] x [0, 1] x
[-1, 1] x [-1, 1] (x [0, 1] x [0, 1] for pulses) that map onto the envelope: the larger amplitude is
u A_max, the other (1 - |q|) u A_max (joint 2's when q > 0, joint 1's when q < 0), gamma_i = gamma +
w_i (A_max - A_i), psi = 180 p, rise = RISE_MIN + r (0.5 - RISE_MIN), duty = d.  The period depends
on u alone, so the objective has no kink where the amplitudes cross (with one coordinate per
amplitude, the shortest period's max(A1, A2) made one, and the local search stalled on it).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from ocp_crawl.model.inputs import Harmonic, PeriodicSignal, ReferenceTorque
from ocp_crawl.model.pulse import Pulse
from ocp_crawl.model.statics import GravityConvention, Model, Robot
from ocp_crawl.ocp.quantities import PROFILE_QUANTITIES, profile_of_signal
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.sim.event import simulate_torque

#: the waveform families, in the order of reports (the harmonic one is the OCP's first start)
SHAPES = ("harmonic", "triangle", "pulse")
#: bounds of the box coordinates z = (w1, w2, u, q, p) shared by every shape (see the module
#: docstring)
BOX = ((-1.0, 1.0), (-1.0, 1.0), (0.0, 1.0), (-1.0, 1.0), (-1.0, 1.0))
#: the pulse's two more coordinates (r, d): its rise and duty
PULSE_BOX = ((0.0, 1.0), (0.0, 1.0))
#: smallest amplitude max(A1, A2) [deg] of a member (a zero amplitude has no period and no gait)
A_MIN_DEG = 1e-6
#: shortest edge of a pulse member [cycles]: steeper edges only lengthen the shortest period (2 A /
#: (rise R))
RISE_MIN = 0.05


def shape_box(shape: str) -> tuple:
    """The box of the coordinates of a shape's members (:data:`BOX`, and :data:`PULSE_BOX` for
    pulses)."""
    if shape not in SHAPES:
        raise ValueError(f"waveform family must be one of {SHAPES}, got {shape!r}")
    return BOX + PULSE_BOX if shape == "pulse" else BOX


@dataclass(frozen=True)
class WaveParams:
    """One member of a waveform family: angles in degrees, the shape and, for pulses, rise and
    duty."""

    gamma1_deg: float
    gamma2_deg: float
    A1_deg: float
    A2_deg: float
    psi_deg: float
    """phase lead of joint 1 over joint 2 [deg], in (-180, 180]"""
    shape: str = "harmonic"
    """one of :data:`SHAPES`"""
    rise: float = 0.5
    """duration of each edge [cycles] (triangle: 0.5; pulse: in [RISE_MIN, 0.5]; unused by
    harmonics)"""
    duty: float = 0.0
    """share of the cycle outside the edges (1 - 2 rise) held at the high level (pulse) [-]"""

    def simulated(self) -> bool:
        """Whether the member is a gait to simulate: an amplitude max(A1, A2) of at least
        :data:`A_MIN_DEG` (a zero amplitude has no period and no gait)."""
        return max(self.A1_deg, self.A2_deg) >= A_MIN_DEG

    def gait(self) -> PeriodicSignal:
        """The reference angles [rad] of the gait (1-periodic in the phase)."""
        if self.shape == "harmonic":
            return Harmonic.from_degrees(psi_deg=self.psi_deg, gamma1_deg=self.gamma1_deg,
                                         gamma2_deg=self.gamma2_deg, A1_deg=self.A1_deg,
                                         A2_deg=self.A2_deg)
        rise = 0.5 if self.shape == "triangle" else self.rise
        g1, g2, a1, a2, psi = (math.radians(v) for v in (self.gamma1_deg, self.gamma2_deg,
                                                          self.A1_deg, self.A2_deg, self.psi_deg))
        return Pulse(g1, g2, a1, a2, psi, rise=rise,
                     hold=self.duty * (1.0 - 2.0 * rise) if rise < 0.5 else 0.0)

    def torque(self, k: float) -> ReferenceTorque:
        """The torque input tau = k (phi_ref - pi) [N m] of the gait for the joint stiffness ``k``
        [N m/rad] (a 1-periodic signal of the phase; its period in seconds is :meth:`period`)."""
        return ReferenceTorque(self.gait(), k)

    @property
    def slope(self) -> float:
        """The unit wave's largest slope |du/dt| [1/cycle]: 2 pi, 4 (triangle) or 2/rise (pulse)."""
        if self.shape == "harmonic":
            return 2.0 * math.pi
        return 4.0 if self.shape == "triangle" else 2.0 / self.rise

    def period(self, settings: OCPSettings) -> float:
        """The gait's period T [s]: the shortest one the bandwidth allows, slope max(A1, A2) / R
        (``settings.min_period(A1, A2)`` for a harmonic member)."""
        return self.slope * max(self.A1_deg, self.A2_deg) / settings.max_rate_deg_s

    def in_envelope(self, settings: OCPSettings, rtol: float = 1e-9) -> bool:
        """True if both joints stay within gamma +- A_max (relative tolerance ``rtol`` of A_max)
        with A_i >= 0."""
        tol = rtol * settings.A_max_deg
        return all(a >= 0 and abs(g - settings.gamma_deg) + a <= settings.A_max_deg + tol
                   for g, a in ((self.gamma1_deg, self.A1_deg), (self.gamma2_deg, self.A2_deg)))

    @classmethod
    def from_box(cls, settings: OCPSettings, z, shape: str = "harmonic") -> "WaveParams":
        """The member of ``shape`` at box coordinates ``z`` (clipped into :func:`shape_box`)."""
        box = shape_box(shape)
        c = [min(max(float(v), lo), hi) for v, (lo, hi) in zip(z, box)]
        w1, w2, u, q, p = c[:5]
        a_max, g = settings.A_max_deg, settings.gamma_deg
        a = u * a_max
        a1, a2 = (a, (1.0 - q) * a) if q >= 0 else ((1.0 + q) * a, a)
        psi = 180.0 * p
        extra = {}
        if shape == "pulse":
            extra = {"rise": RISE_MIN + c[5] * (0.5 - RISE_MIN), "duty": c[6]}
        return cls(g + w1 * (a_max - a1), g + w2 * (a_max - a2), a1, a2,
                   180.0 if psi == -180.0 else psi, shape, **extra)

    def to_box(self, settings: OCPSettings) -> np.ndarray:
        """The box coordinates of this member (inverse of :meth:`from_box`)."""
        a_max, g = settings.A_max_deg, settings.gamma_deg

        def w(gamma, a):
            return 0.0 if a >= a_max else (gamma - g) / (a_max - a)
        a = max(self.A1_deg, self.A2_deg)
        q = 0.0 if a == 0 else (1.0 - self.A2_deg / a if self.A1_deg >= self.A2_deg
                                else self.A1_deg / a - 1.0)
        z = [w(self.gamma1_deg, self.A1_deg), w(self.gamma2_deg, self.A2_deg), a / a_max, q,
             self.psi_deg / 180.0]
        if self.shape == "pulse":
            z += [(self.rise - RISE_MIN) / (0.5 - RISE_MIN), self.duty]
        return np.array(z)

    def as_dict(self) -> dict:
        """The parameters by name: angles [deg], the shape, and rise [cycles] and duty [-] of
        pulses."""
        out = {"gamma1_deg": self.gamma1_deg, "gamma2_deg": self.gamma2_deg, "A1_deg": self.A1_deg,
               "A2_deg": self.A2_deg, "psi_deg": self.psi_deg, "shape": self.shape}
        if self.shape == "pulse":
            out.update(rise=self.rise, duty=self.duty)
        return out


@dataclass(frozen=True)
class Evaluation:
    """The simulations of one member (one per friction scenario) at its period T [s].

    ``S`` [m], ``W_plus`` [J], ``CoT_plus`` [-] per scenario (NaN where a simulation failed or the
    member is not admissible); ``success`` when every scenario simulated successfully;
    ``message`` the first failure's message."""

    params: Any
    """the member: a :class:`WaveParams` (a chain's
    :class:`~ocp_crawl.ocp.chain_search.ChainWave`)"""
    T: float
    S: tuple
    W_plus: tuple
    CoT_plus: tuple
    success: bool
    message: str = ""
    profile: tuple = (math.nan, math.nan)
    """the torque profile's peak |tau| [N m] and mean squared torque [N^2 m^2]
    (:func:`~ocp_crawl.ocp.quantities.profile_of_signal`), computed only where a constraint bounds
    them"""


def allowed_period(settings: OCPSettings, T: float, S) -> float:
    """The shortest period [s], at least ``T`` (the bandwidth's), that the constraints allow a
    member of displacements ``S`` [m] per scenario: at least a ``period`` constraint's min and slow
    enough for a ``speed`` constraint's max (direction S_j / T <= v_max in every scenario, or on
    their mean)."""
    d = settings.direction
    for c in settings.requirements:
        if c.quantity == "period" and c.min is not None:
            T = max(T, c.min)
        elif c.quantity == "speed" and c.max is not None and c.max > 0:
            reach = [d * s for s in S] if c.over == "every" else [d * sum(S) / len(S)]
            T = max(T, max(reach) / c.max)
    return T


class WaveFamily:
    """The members of one shape in the envelope and bandwidth of ``settings`` for ``robot`` (SI
    units) under the gravity convention ``gravity``, simulated with the event-driven stepper in
    every friction scenario of ``settings.scenarios(robot)``.  Evaluations are cached by parameters;
    ``evaluations`` counts the simulated members."""

    def __init__(self, robot: Robot, gravity: GravityConvention, settings: OCPSettings,
                 shape: str = "harmonic") -> None:
        shape_box(shape)
        self.robot = robot
        self.settings = settings
        self.shape = shape
        self.models = [Model(cast(Robot, r), gravity=gravity) for r in settings.scenarios(robot)]
        self.evaluations = 0
        self._cache: dict[tuple, Evaluation] = {}

    def member(self, z) -> WaveParams:
        """The member of this family's shape at box coordinates ``z``."""
        return WaveParams.from_box(self.settings, z, self.shape)

    def evaluate(self, params: WaveParams) -> Evaluation:
        """Simulate the member ``params`` in every scenario at its shortest period (cached).

        Returns an :class:`Evaluation`; a member of (almost) zero amplitude or a failed simulation
        (a fold, a lift-off, a non-periodic gait, bad input to the stepper) is an unsuccessful
        evaluation."""
        key = self.key(params)
        if key in self._cache:
            return self._cache[key]
        T = params.period(self.settings)
        nan = (math.nan,) * len(self.models)
        if not params.simulated():
            out = Evaluation(params, T, nan, nan, nan, False, "zero amplitude: no gait")
        else:
            self.evaluations += 1
            out = self._simulate(params, T, nan)
        self._cache[key] = out
        return out

    @staticmethod
    def key(params: WaveParams) -> tuple:
        """The cache key of a member: its parameters, floats rounded to 12 decimals."""
        return tuple(round(v, 12) if isinstance(v, float) else v for v in params.as_dict().values())

    def absorb(self, evaluations) -> None:
        """Add evaluations made elsewhere (by a worker process's family of the same robot, gravity,
        settings and shape) to the cache, in their order; each one not cached yet counts as a
        simulated member unless of zero amplitude (as in :meth:`evaluate`)."""
        for ev in evaluations:
            key = self.key(ev.params)
            if key not in self._cache:
                self._cache[key] = ev
                self.evaluations += ev.params.simulated()

    def _simulate(self, params: WaveParams, T: float, nan: tuple) -> Evaluation:
        sims = []
        for m in self.models:
            try:
                r = simulate_torque(m, params.torque(m.robot.k))
            except (ValueError, IndexError) as exc:
                # ValueError: the stepper rejects the input; IndexError: its steady-cycle metrics
                # find no segment on some psi = 180 gaits (e.g. gamma 91.65/90.44, A 27.93/29.30
                # deg)
                return Evaluation(params, T, nan, nan, nan, False, f"{type(exc).__name__}: {exc}")
            if not r.success:
                return Evaluation(params, T, nan, nan, nan, False, r.message)
            sims.append(r)
        S = tuple(r.S for r in sims)
        T = allowed_period(self.settings, T, S)
        profile = (math.nan, math.nan)
        if (self.settings.user_objective is not None
                or any(c.quantity in PROFILE_QUANTITIES for c in self.settings.requirements)):
            profile = profile_of_signal(params.torque(self.robot.k))
        return Evaluation(params, T, S, tuple(r.W_plus for r in sims),
                          tuple(r.CoT_plus for r in sims), True, profile=profile)

    def evaluated(self) -> list[Evaluation]:
        """Every evaluation so far (successful or not), in the order of their first request."""
        return list(self._cache.values())
