"""Physical checks of the event-driven stepper: stability of every equilibrium it follows and
continuity of the state across events.

* **Stability** (:mod:`ocp_crawl.model.stability`): the margin of the current mode's equilibrium
  must be positive at the released start (else the run is ``no_start``: the robot cannot stand
  there), at the start of every mode after an event and at every accepted continuation step (else
  ``unstable``, with the phase and the mode).  Along a stick-stick branch the reduced stiffness
  changes sign only where the mode Jacobian is singular (``det J = -kappa |grad d|^2/(M g L^3)``),
  which the stepper already detects as a fold; along a slip branch ``det K`` likewise, but ``tr K``
  can change sign anywhere, hence the check at every step (one compiled call, about 2 us).
* **Jumps**: across an event the state (phi1, phi2 [rad], f_t/(M g), d/L) of the successor mode's
  start must equal the state at the event of the mode before, within ``HybridOptions.jump_tol``
  (f_t's change divided by 1 + k/(M g L), the growth of its round-off with the stiffness ratio),
  when the input is continuous there; otherwise the mode change needs a dynamic snap-through, which
  the quasistatic model cannot follow (``snap_through``, with the phase, the modes before and after
  and the jump).  An input with a discontinuity at the event's phase is exempt: the state may jump
  where the input does.

At an event the jump is checked before the successor's stability.  A jump is the observable outcome
of a loss of equilibrium at a friction limit: in the issue-11 robot the stick-stick branch is stable
when it reaches foot 2's limit (no fold: kappa > 0), its slip continuation is a saddle (det K < 0,
hence inconsistent), and the only consistent mode lies 8 deg away (and is unstable too).
``snap_through`` with the jump's size says what the robot does; ``fold`` is kept for a singular
Jacobian of the tracked branch.

:class:`Checks` makes both checks for the model, the input and the ``jump_tol`` of a stepper's
context.
"""
from __future__ import annotations

import numpy as np

from ocp_crawl.model.statics import AUX
from ocp_crawl.model.stability import STABILITY_NAMES, fast_stability
from ocp_crawl.sim.event_context import StepperContext
from ocp_crawl.sim.event_state import _Failure, _Point, mode_q
from ocp_crawl.sim.result import Mode
from ocp_crawl.status import Status

_D = AUX["d"]


def describe_margin(s, mode: Mode) -> str:
    """The stability numbers ``s = (margin, kappa, trK, detK)`` (nondimensional, by M g L) in
    words."""
    if mode == Mode.STICK:
        return f"reduced stiffness kappa/(M g L) = {s[1]:.4g} <= 0"
    return (f"slip stiffness tr K/(M g L) = {s[2]:.4g}, det K/(M g L)^2 = {s[3]:.4g} "
            "(stable iff both > 0)")


class Checks:
    """Stability and jump checks of the equilibria of the model of ``ctx`` under its input."""

    def __init__(self, ctx: StepperContext):
        self._p, self._L, self._torque, self.jump_tol = ctx.p, ctx.L, ctx.torque, ctx.opt.jump_tol
        self._k, self._MgL = ctx.model.robot.k, ctx.model.robot.MgL

    def stability(self, x: np.ndarray, q: np.ndarray) -> np.ndarray:
        """(margin, kappa, trK, detK) of the equilibrium x of the mode q (see
        :mod:`ocp_crawl.model.stability`)."""
        return fast_stability()(x, q, self._p)[0]

    def require_stable(self, pt: _Point, mode: Mode, q: np.ndarray, where: str) -> None:
        """Raise ``_Failure(UNSTABLE)`` unless the equilibrium pt of ``mode`` has a positive
        margin."""
        if pt.extra is not None and pt.q is q:
            if pt.extra[0] > 0:  # (the margin computed with the solve)
                return
            s = pt.extra[:4]
        else:
            s = self.stability(pt.x, q)
        if not s[0] > 0:  # also NaN
            raise _Failure(Status.UNSTABLE, pt.t, mode, f"{where}: the {mode.label} equilibrium is "
                           f"unstable ({describe_margin(s, mode)})",
                           {"stability": dict(zip(STABILITY_NAMES, map(float, s)))})

    def stable_start(self, t0: float, candidates) -> _Point:
        """The first of the released equilibria ``candidates`` (solved points at t0, in the order
        tried) whose stick-stick equilibrium (both feet held by friction, f_t = 0 inside the cone)
        is stable.

        Raises ValueError (the run is then ``no_start``) naming the margin of the first one when
        none is.
        """
        first = None
        for pt in candidates:
            s = self.stability(pt.x, mode_q(Mode.STICK, pt.aux[AUX["d"]]))
            if s[0] > 0:
                return pt
            first = s if first is None else first
        if first is None:
            raise ValueError("no equilibrium found for the starting configuration (t = 0, f_t = 0)")
        raise ValueError("the released robot can only settle on an unstable equilibrium at "
                         f"t = {t0:g} ({describe_margin(first, Mode.STICK)}: a maximum of the "
                         "potential on the constraint, which the real robot leaves at once)")

    def input_jumps(self, t: float) -> bool:
        """Whether the input has a discontinuity at phase t [cycles] (a step of more than
        round-off)."""
        eps = 1e-9
        tau = np.asarray(self._torque(np.array([t - eps, t + eps])), float).reshape(2, 2)
        rate = np.max(np.abs(np.asarray(self._torque.derivative(t), float)))
        scale = np.max(np.abs(tau)) + self._MgL
        return bool(np.max(np.abs(tau[:, 1] - tau[:, 0])) > 100 * eps * rate + 1e-9 * scale)

    def jump(self, ev_pt: _Point, start: _Point) -> tuple[float, float]:
        """Size of the change of the state from ev_pt to start (the largest of |d phi1|, |d phi2|
        [rad], |d f_t|/(M g)/(1 + k/(M g L)) and |d d|/L, see :meth:`check_jump`), and |d d|/L."""
        a, b = start.xl, ev_pt.xl
        dd = abs(start.a[_D] - ev_pt.a[_D]) / self._L
        ft_scale = 1.0 + self._k / self._MgL
        # (finite: the solves')
        return max(abs(a[0] - b[0]), abs(a[1] - b[1]), abs(a[2] - b[2]) / ft_scale, dd), dd

    def check_jump(self, ev_pt: _Point, start: _Point, before: Mode, after: Mode,
                   kind: str) -> None:
        """Raise ``_Failure(SNAP_THROUGH)`` if the successor's start differs from the event state by
        more than ``jump_tol`` in phi1, phi2 [rad], f_t/(M g)/(1 + k/(M g L)) or d/L while the input
        is continuous at the event.  f_t's change is divided by 1 + k/(M g L): its round-off grows
        with the stiffness ratio (as the guards' noise, about 2e-15 (1 + k/(M g L)) measured up to
        k/(M g L) = 1e5) while phi and d stay at round-off."""
        size, dd = self.jump(ev_pt, start)
        if size <= self.jump_tol or self.input_jumps(ev_pt.t):
            return
        dx = np.abs(start.x - ev_pt.x)
        deg = np.degrees(dx[:2])
        raise _Failure(Status.SNAP_THROUGH, ev_pt.t, before,
                       f"{kind.replace('_', ' ')} from {before.label} to {after.label} needs a "
                       f"jump of the state (|d phi| = {deg[0]:.4g}, {deg[1]:.4g} deg, "
                       f"|d f_t|/(M g) = {dx[2]:.4g}, |d d|/L = {dd:.4g} "
                       f"> jump_tol {self.jump_tol:g})",
                       {"jump": {"phi": dx[:2].tolist(), "f_t_over_Mg": float(dx[2]),
                                 "d_over_L": dd, "mode_before": before.label,
                                 "mode_after": after.label}})
