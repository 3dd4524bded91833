"""The harmonic family of the OCP's envelope and bandwidth: its parameters, gaits and simulations.

A member is the reference gait phi_ref,i = gamma_i + A_i sin(2 pi t/T +- psi/2) driven as the torque
tau_i = k (phi_ref,i - pi) (:class:`~ocp_crawl.model.inputs.Harmonic`, :class:`ReferenceTorque`).  It belongs
to the family of an :class:`~ocp_crawl.ocp.settings.OCPSettings` when both joints stay inside the envelope,
|gamma_i - gamma| + A_i <= A_max, A_i >= 0, and its reference rates 2 pi A_i / T stay within the bandwidth R
(``max_rate_deg_s``), i.e. T >= ``settings.min_period(A1, A2)`` = 2 pi max(A1, A2) / R.  A member is admissible
only when which foot slips does not depend on the friction coefficients within +-friction_tol/2 (its
slip-weighted friction margin, :mod:`ocp_crawl.ocp.slip_margin`, is at least ``settings.friction_tol``): this
excludes the near-mirror-symmetric gaits psi -> 0 that hold the friction tie.

Why the period is always the shortest one: a quasistatic gait is time-scale invariant, so S, W+ and CoT+
of a harmonic gait do not depend on T.  The mean speed direction * S / T is then largest at the smallest
allowed T, CoT+ is the same at every T, and a speed requirement direction * S / T >= speed_min is easiest
to meet at the smallest T.  Every objective of the OCP is therefore optimal at T = min_period(A1, A2), and
the family's search runs over (gamma1, gamma2, A1, A2, psi) only.

The search works in box coordinates z = (w1, w2, u1, u2, p) in [-1, 1] x [-1, 1] x [0, 1] x [0, 1] x [-1, 1]
that map one to one onto the envelope: A_i = u_i A_max, gamma_i = gamma + w_i (A_max - A_i), psi = 180 p.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ocp_crawl.model.inputs import Harmonic, ReferenceTorque
from ocp_crawl.model.statics import Model, Robot
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.slip_margin import admissible_text, result_margins
from ocp_crawl.sim.event import simulate_torque

#: bounds of the box coordinates z = (w1, w2, u1, u2, p) (see the module docstring)
BOX = ((-1.0, 1.0), (-1.0, 1.0), (0.0, 1.0), (0.0, 1.0), (-1.0, 1.0))
#: smallest amplitude max(A1, A2) [deg] of a member (a zero amplitude has no period and no gait)
A_MIN_DEG = 1e-6


@dataclass(frozen=True)
class HarmonicParams:
    """One harmonic gait of the family: angles in degrees (see :class:`~ocp_crawl.model.inputs.Harmonic`)."""

    gamma1_deg: float
    gamma2_deg: float
    A1_deg: float
    A2_deg: float
    psi_deg: float
    """phase lead of joint 1 over joint 2 [deg], in (-180, 180]"""

    def gait(self) -> Harmonic:
        """The reference angles [rad] of the gait."""
        return Harmonic.from_degrees(psi_deg=self.psi_deg, gamma1_deg=self.gamma1_deg, gamma2_deg=self.gamma2_deg,
                                     A1_deg=self.A1_deg, A2_deg=self.A2_deg)

    def torque(self, k: float) -> ReferenceTorque:
        """The torque input tau = k (phi_ref - pi) [N m] of the gait for the joint stiffness ``k`` [N m/rad]
        (a 1-periodic signal of the phase; its period in seconds is :meth:`period`)."""
        return ReferenceTorque(self.gait(), k)

    def period(self, settings: OCPSettings) -> float:
        """The gait's period T [s]: the shortest one the bandwidth allows, ``settings.min_period(A1, A2)``."""
        return settings.min_period(self.A1_deg, self.A2_deg)

    def in_envelope(self, settings: OCPSettings, rtol: float = 1e-9) -> bool:
        """True if both joints stay within gamma +- A_max (relative tolerance ``rtol`` of A_max) with A_i >= 0."""
        tol = rtol * settings.A_max_deg
        return all(a >= 0 and abs(g - settings.gamma_deg) + a <= settings.A_max_deg + tol
                   for g, a in ((self.gamma1_deg, self.A1_deg), (self.gamma2_deg, self.A2_deg)))

    @classmethod
    def from_box(cls, settings: OCPSettings, z) -> "HarmonicParams":
        """The member at box coordinates ``z`` = (w1, w2, u1, u2, p) (clipped into :data:`BOX`)."""
        w1, w2, u1, u2, p = (min(max(float(v), lo), hi) for v, (lo, hi) in zip(z, BOX))
        a_max, g = settings.A_max_deg, settings.gamma_deg
        a1, a2 = u1 * a_max, u2 * a_max
        psi = 180.0 * p
        return cls(g + w1 * (a_max - a1), g + w2 * (a_max - a2), a1, a2, 180.0 if psi == -180.0 else psi)

    def to_box(self, settings: OCPSettings) -> np.ndarray:
        """The box coordinates of this member (inverse of :meth:`from_box`)."""
        a_max, g = settings.A_max_deg, settings.gamma_deg

        def w(gamma, a):
            return 0.0 if a >= a_max else (gamma - g) / (a_max - a)
        return np.array([w(self.gamma1_deg, self.A1_deg), w(self.gamma2_deg, self.A2_deg),
                         self.A1_deg / a_max, self.A2_deg / a_max, self.psi_deg / 180.0])

    def as_dict(self) -> dict:
        """The five parameters [deg] by name."""
        return {"gamma1_deg": self.gamma1_deg, "gamma2_deg": self.gamma2_deg, "A1_deg": self.A1_deg,
                "A2_deg": self.A2_deg, "psi_deg": self.psi_deg}


@dataclass(frozen=True)
class Evaluation:
    """The simulations of one member (one per friction scenario) at its period T [s].

    ``S`` [m], ``W_plus`` [J], ``CoT_plus`` [-] per scenario (NaN where a simulation failed or the member is
    not admissible); ``success`` when every scenario simulated successfully with a slip-weighted friction
    margin of at least ``friction_tol``; ``message`` the first failure's message."""

    params: HarmonicParams
    T: float
    S: tuple
    W_plus: tuple
    CoT_plus: tuple
    success: bool
    message: str = ""
    margin: tuple = ()
    """per scenario: the slip-weighted friction margin [-] (:mod:`ocp_crawl.ocp.slip_margin`); a member below
    ``settings.friction_tol`` is not admissible (``success`` False)"""


class HarmonicFamily:
    """The harmonic gaits of the envelope and bandwidth of ``settings`` for ``robot`` (SI units) under the
    gravity convention ``gravity``, simulated with the event-driven stepper in every friction scenario of
    ``settings.scenarios(robot)``.  Evaluations are cached by parameters; ``evaluations`` counts the
    simulated members."""

    def __init__(self, robot: Robot, gravity: str, settings: OCPSettings) -> None:
        self.robot = robot
        self.settings = settings
        self.models = [Model(r, gravity=gravity) for r in settings.scenarios(robot)]
        self.evaluations = 0
        self._cache: dict[tuple, Evaluation] = {}

    def evaluate(self, params: HarmonicParams) -> Evaluation:
        """Simulate the member ``params`` in every scenario at its shortest period (cached).

        Returns an :class:`Evaluation`; a member of (almost) zero amplitude or a failed simulation (a
        fold, a lift-off, a non-periodic gait, bad input to the stepper) is an unsuccessful evaluation."""
        key = self._key(params)
        if key in self._cache:
            return self._cache[key]
        T = params.period(self.settings)
        nan = (math.nan,) * len(self.models)
        if max(params.A1_deg, params.A2_deg) < A_MIN_DEG:
            out = Evaluation(params, T, nan, nan, nan, False, "zero amplitude: no gait")
        else:
            self.evaluations += 1
            out = self._simulate(params, T, nan)
        self._cache[key] = out
        return out

    @staticmethod
    def _key(params: HarmonicParams) -> tuple:
        return tuple(round(v, 12) for v in params.as_dict().values())

    def absorb(self, evaluations) -> None:
        """Add evaluations made elsewhere (by a worker process's family of the same robot, gravity and settings)
        to the cache, in their order; each one not cached yet counts as a simulated member unless of zero
        amplitude (as in :meth:`evaluate`)."""
        for ev in evaluations:
            key = self._key(ev.params)
            if key not in self._cache:
                self._cache[key] = ev
                self.evaluations += max(ev.params.A1_deg, ev.params.A2_deg) >= A_MIN_DEG

    def _simulate(self, params: HarmonicParams, T: float, nan: tuple) -> Evaluation:
        sims = []
        for m in self.models:
            try:
                r = simulate_torque(m, params.torque(m.robot.k))
            except (ValueError, IndexError) as exc:
                # ValueError: the stepper rejects the input; IndexError: a stepper bug on some psi = 180 gaits
                # (e.g. gamma 91.65/90.44, A 27.93/29.30 deg: its steady-cycle metrics find no segment)
                return Evaluation(params, T, nan, nan, nan, False, f"{type(exc).__name__}: {exc}")
            if not r.success:
                return Evaluation(params, T, nan, nan, nan, False, r.message)
            sims.append(r)
        margins = tuple(result_margins(r, m.robot)[0] for r, m in zip(sims, self.models))
        eps = self.settings.friction_tol
        low = next((x for x in margins if not x >= eps), None)
        if low is not None:  # not admissible: which foot slips depends on friction known only to +-eps/2
            return Evaluation(params, T, nan, nan, nan, False, admissible_text(low, eps), margins)
        return Evaluation(params, T, tuple(r.S for r in sims), tuple(r.W_plus for r in sims),
                          tuple(r.CoT_plus for r in sims), True, margin=margins)

    def evaluated(self) -> list[Evaluation]:
        """Every evaluation so far (successful or not), in the order of their first request."""
        return list(self._cache.values())
