"""Physical checks of the event-driven stepper: stability of every equilibrium it follows and
continuity of the state across events.

* **Stability** (:mod:`ocp_crawl.model.stability`): the margin of the current mode's equilibrium must be
  positive at the released start (else the run is ``no_start``: the robot cannot stand there), at the
  start of every mode after an event and at every accepted continuation step (else ``unstable``, with
  the phase and the mode).  Along a stick-stick branch the reduced stiffness changes sign only where
  the mode Jacobian is singular (``det J = -kappa |grad d|^2/(M g L^3)``), which the stepper already
  detects as a fold; along a slip branch ``det K`` likewise, but ``tr K`` can change sign anywhere,
  hence the check at every step (one compiled call, about 2 us).
* **Jumps**: across an event the state (phi1, phi2 [rad], f_t/(M g), d/L) of the successor mode's start
  must equal the state at the event of the mode before, within ``HybridOptions.jump_tol`` (f_t's change
  divided by 1 + k/(M g L), the growth of its round-off with the stiffness ratio), when the input
  is continuous there; otherwise the mode change needs a dynamic snap-through, which the quasistatic
  model cannot follow (``snap_through``, with the phase, the modes before and after and the jump).  An
  input with a discontinuity at the event's phase is exempt: the state may jump where the input does.

At an event the jump is checked before the successor's stability.  A jump is the observable outcome of a
loss of equilibrium at a friction limit: in the issue-11 robot the stick-stick branch is stable when it
reaches foot 2's limit (no fold: kappa > 0), its slip continuation is a saddle (det K < 0, hence
inconsistent), and the only consistent mode lies 8 deg away (and is unstable too).  ``snap_through`` with
the jump's size says what the robot does; ``fold`` is kept for a singular Jacobian of the tracked branch.

:class:`ChecksMixin` is a part of :class:`~ocp_crawl.sim.event.HybridStepper`; it uses the stepper's
``model``, ``p``, ``L``, ``Mg``, ``opt`` and ``torque``.
"""
from __future__ import annotations

import numpy as np

from ocp_crawl.model.statics import AUX
from ocp_crawl.model.stability import STABILITY_NAMES, fast_stability
from ocp_crawl.sim.event_state import _Failure, _Point, mode_q
from ocp_crawl.sim.result import Mode
from ocp_crawl.status import Status

_D = AUX["d"]


def describe_margin(s, mode: Mode) -> str:
    """The stability numbers ``s = (margin, kappa, trK, detK)`` (nondimensional, by M g L) in words."""
    if mode == Mode.STICK:
        return f"reduced stiffness kappa/(M g L) = {s[1]:.4g} <= 0"
    return f"slip stiffness tr K/(M g L) = {s[2]:.4g}, det K/(M g L)^2 = {s[3]:.4g} (stable iff both > 0)"


class ChecksMixin:
    """Stability and jump checks of :class:`~ocp_crawl.sim.event.HybridStepper`."""

    def _stability(self, x: np.ndarray, q: np.ndarray) -> np.ndarray:
        """(margin, kappa, trK, detK) of the equilibrium x of the mode q (see :mod:`ocp_crawl.model.stability`)."""
        return fast_stability()(x, q, self.p)[0]

    def _require_stable(self, pt: _Point, mode: Mode, q: np.ndarray, where: str) -> None:
        """Raise ``_Failure(UNSTABLE)`` unless the equilibrium pt of ``mode`` has a positive margin."""
        if pt.extra is not None and pt.q is q:
            if pt.extra[0] > 0:  # (the margin computed with the solve)
                return
            s = pt.extra[:4]
        else:
            s = self._stability(pt.x, q)
        if not s[0] > 0:  # also NaN
            raise _Failure(Status.UNSTABLE, pt.t, mode, f"{where}: the {mode.label} equilibrium is unstable "
                           f"({describe_margin(s, mode)})", {"stability": dict(zip(STABILITY_NAMES, map(float, s)))})

    def stable_start(self, t0: float, candidates) -> _Point:
        """The first of the released equilibria ``candidates`` (solved points at t0, in the order tried) whose
        stick-stick equilibrium (both feet held by friction, f_t = 0 inside the cone) is stable.

        Raises ValueError (the run is then ``no_start``) naming the margin of the first one when none is.
        """
        first = None
        for pt in candidates:
            s = self._stability(pt.x, mode_q(Mode.STICK, pt.aux[AUX["d"]]))
            if s[0] > 0:
                return pt
            first = s if first is None else first
        if first is None:
            raise ValueError("no equilibrium found for the starting configuration (t = 0, f_t = 0)")
        raise ValueError(f"the released robot can only settle on an unstable equilibrium at t = {t0:g} "
                         f"({describe_margin(first, Mode.STICK)}: a maximum of the potential on the "
                         "constraint, which the real robot leaves at once)")

    def _input_jumps(self, t: float) -> bool:
        """Whether the input has a discontinuity at phase t [cycles] (a step of more than round-off)."""
        eps = 1e-9
        tau = np.asarray(self.torque(np.array([t - eps, t + eps])), float).reshape(2, 2)
        rate = np.max(np.abs(np.asarray(self.torque.derivative(t), float)))
        scale = np.max(np.abs(tau)) + self.model.robot.MgL
        return bool(np.max(np.abs(tau[:, 1] - tau[:, 0])) > 100 * eps * rate + 1e-9 * scale)

    def _jump(self, ev_pt: _Point, start: _Point) -> tuple[float, float]:
        """Size of the change of the state from ev_pt to start (the largest of |d phi1|, |d phi2| [rad],
        |d f_t|/(M g)/(1 + k/(M g L)) and |d d|/L, see :meth:`_check_jump`), and |d d|/L."""
        a, b = start.xl, ev_pt.xl
        dd = abs(start.a[_D] - ev_pt.a[_D]) / self.L
        ft_scale = 1.0 + self.model.robot.k / self.model.robot.MgL
        return max(abs(a[0] - b[0]), abs(a[1] - b[1]), abs(a[2] - b[2]) / ft_scale, dd), dd  # (finite: the solves')

    def _check_jump(self, ev_pt: _Point, start: _Point, before: Mode, after: Mode, kind: str) -> None:
        """Raise ``_Failure(SNAP_THROUGH)`` if the successor's start differs from the event state by more than
        ``jump_tol`` in phi1, phi2 [rad], f_t/(M g)/(1 + k/(M g L)) or d/L while the input is continuous at the
        event.  f_t's change is divided by 1 + k/(M g L): its round-off grows with the stiffness ratio (as the
        guards' noise, about 2e-15 (1 + k/(M g L)) measured up to k/(M g L) = 1e5) while phi and d stay at round-off."""
        size, dd = self._jump(ev_pt, start)
        if size <= self.opt.jump_tol or self._input_jumps(ev_pt.t):
            return
        dx = np.abs(start.x - ev_pt.x)
        deg = np.degrees(dx[:2])
        raise _Failure(Status.SNAP_THROUGH, ev_pt.t, before,
                       f"{kind.replace('_', ' ')} from {before.label} to {after.label} needs a jump of the state "
                       f"(|d phi| = {deg[0]:.4g}, {deg[1]:.4g} deg, |d f_t|/(M g) = {dx[2]:.4g}, |d d|/L = {dd:.4g} "
                       f"> jump_tol {self.opt.jump_tol:g})",
                       {"jump": {"phi": dx[:2].tolist(), "f_t_over_Mg": float(dx[2]), "d_over_L": dd,
                                 "mode_before": before.label, "mode_after": after.label}})
