"""Event location of the event-driven stepper: the first of the guards crossing zero in a step, guard zeros by a
safeguarded Newton method, the consistency of a successor mode, and folds of the equilibrium branch by the
augmented system.

:class:`EventsMixin` is a part of :class:`~ocp_crawl.sim.event.HybridStepper`; it uses the
stepper's ``_solve``, ``guards``, ``point_guards``, ``tie_note``, ``noise``, ``opt``, ``sym``, ``torque`` and ``p``.
"""
from __future__ import annotations

import math

import numpy as np

from ocp_crawl.model.statics import AUX
from ocp_crawl.sim.event_kinks import KINK_GAP
from ocp_crawl.sim.event_state import _Failure, _Point, _Segment, event_kind, hermite_point, mode_q
from ocp_crawl.sim.result import Mode, mode_change_kind
from ocp_crawl.status import Status

#: phase steps [cycles] after an event at which the guards of a successor mode are tested (``_consistent``)
TRIAL_STEPS = (1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4)
#: an input whose rate is below this fraction of its largest rate over the cycle holds still (``_input_still``)
HOLD_RTOL = 1e-6

EPS = float(np.finfo(float).eps)
#: round-off level of the scaled guards that depend on the angles (and d') only, whatever k/(M g L)
ANGLE_NOISE = 1e-13


def guard_noise(name: str, noise: float) -> float:
    """Round-off level of the scaled guard ``name`` for the consistency test of a successor mode.

    ``noise``: the stepper's round-off level of f_t/(M g) [-], which grows with k/(M g L) (stiff joints
    fix the angles to O(M g L/k), so f_t absorbs the round-off of the joint balance).  Only the
    stick-stick friction guards ``slip_*`` contain f_t; the others (normal forces, d, joint heights,
    d', the friction limits of the slip modes) are functions of the angles and their rates, which stay
    accurate to round-off in the stiff limit: their level is ANGLE_NOISE, so that a guard of 1e-6 (a
    reversal of d' just before a stiff event) is not taken for noise when k/(M g L) = 1e8.
    """
    return noise if name.startswith("slip_") else ANGLE_NOISE


class EventsMixin:
    """Event location, mode consistency and fold location of :class:`~ocp_crawl.sim.event.HybridStepper`."""

    def _first_crossing(self, pt: _Point, new: _Point, seg: _Segment, crossed: list[str]):
        """((t, point), guard) of the first zero in the step [pt, new] of the guards ``crossed``: they are
        located in the order of their secant estimates, and a guard still positive at the earliest zero found
        so far is not located (it crosses later; a guard that dips and returns inside the step ends the step
        in its dip beforehand, see ``_crossings``)."""
        g0, g1 = self.point_guards(seg.mode, pt), self.point_guards(seg.mode, new)

        def estimate(k: str) -> float:
            a, b = g0[k], g1[k]
            return pt.t + (new.t - pt.t) * a / (a - b) if a > 0 > b else pt.t

        best = None
        for k in sorted(crossed, key=estimate):
            if best is not None and self.point_guards(seg.mode, best[0][1])[k] > guard_noise(k, self.noise):
                continue
            found = (self._locate(pt, new, seg.q, seg.mode, k, start=pt is seg.points[0]), k)
            if best is None or self._earlier(found, best, crossed):
                best = found
        return best

    def _earlier(self, found, best, crossed: list[str]) -> bool:
        """Whether the located zero ``found`` comes before ``best``; zeros within the location tolerance are
        simultaneous (e.g. at a kink of a sampled or pulse input, where the slip stops as another friction
        limit is reached) and then the guard first in ``crossed`` (the guards' table order) comes first."""
        t_f, t_b = found[0][0], best[0][0]
        tol = self.opt.event_xtol + 4 * EPS * abs(t_b)
        if abs(t_f - t_b) <= tol:
            return crossed.index(found[1]) < crossed.index(best[1])
        return t_f < t_b

    def _locate(self, p0: _Point, p1: _Point, q: np.ndarray, mode: Mode, name: str,
                start: bool = False) -> tuple[float, _Point]:
        """Phase and solved state where guard ``name`` crosses zero in [p0.t, p1.t] (:meth:`_root`).
        ``start``: p0 starts the mode's segment, where the guard that fired the transition is zero.  A guard at zero
        to round-off at p0 that is not a segment's start (a kink of the input) and negative after it, without rising
        first, crosses at p0 itself: the successor is then decided at p0 (:meth:`_successor`)."""

        # the ends are known (a re-solve there could differ in the last bits and break the bracket)
        cache: dict[float, _Point] = {p0.t: p0, p1.t: p1}

        def point_at(t: float) -> _Point:
            pt = cache.get(t)
            if pt is None:
                pt = self._solve(t, hermite_point(p0, p1, t), q, step=True)
                if pt is None:
                    raise _Failure(Status.NO_CONVERGENCE, t, mode, f"mode solve failed while locating event {name}")
                cache[t] = pt
            return pt

        g0, g1 = self.point_guards(mode, p0)[name], self.point_guards(mode, p1)[name]
        if g1 == 0.0:
            return p1.t, p1
        ta, tb, ga = p0.t, p1.t, g0
        if g0 <= 0 or (start and g0 <= 100 * self.noise):
            # the guard starts at zero (it fired the transition into this mode, or touches zero
            # there): [p0, p1] holds that zero and the crossing, so bracket the crossing between the
            # first sample where the guard is clearly positive and the next one where it is negative
            hh = p1.t - p0.t
            ta, below = None, False
            for frac in (1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 0.05, *np.linspace(0, 1, 10)[1:-1], 1.0):
                s = p0.t + frac * hh
                v = g1 if frac == 1.0 else self.point_guards(mode, point_at(s))[name]
                if v > 10 * self.noise:
                    ta, ga = s, v
                elif v < 0 and ta is not None:
                    tb, g1 = s, v
                    break
                below = below or (ta is None and v < -10 * self.noise)
            if ta is None and below and not start:
                # zero at p0 to round-off and negative after it: the guard crosses at p0 (a kink of the input where
                # its rate turned negative, e.g. the friction limits tie exactly at a sample of a sampled input)
                return p0.t, p0
            if ta is None and not below and p1.left and not self.tie_note(p0):
                # zero to round-off all the way to the kink that ends the step (a mode that holds at its limit up to a
                # kink, see _before_kink): the event is at the kink, where the rates after it decide (_pass_kink)
                return p1.t, p1
            if ta is None:
                raise _Failure(Status.NO_CONSISTENT_MODE, p0.t, mode,
                               f"guard {name} does not leave zero after the transition into {mode.label}"
                               f"{self.tie_note(p0)}")
        return self._root(point_at, mode, q, name, (ta, ga), (tb, g1))

    def _root(self, point_at, mode: Mode, q: np.ndarray, name: str, a: tuple[float, float],
              b: tuple[float, float]) -> tuple[float, _Point]:
        """Zero of the guard ``name`` of the solved branch between a = (phase, value > 0) and b = (phase, value
        < 0): safeguarded Newton (``rtsafe``) with the exact rate of the guard along the branch
        (:meth:`guard_rates`), from the secant point; a bisection step whenever the Newton step leaves the
        bracket or does not halve the step before last.  Returns the last solved (t, point) when the bracket
        is below tol = ``event_xtol`` + 4 eps |t| (brentq's tolerance) or the next Newton step below tol/10, so
        t is within tol of the zero (in the quadratic phase the step is about the square of the previous one).  About 3 solves per
        event against 7 for Brent's method.  ``point_at(t)`` solves the mode at t."""
        (ta, fa), (tb, fb) = a, b
        t = ta + (tb - ta) * fa / (fa - fb)
        if not ta < t < tb:
            t = 0.5 * (ta + tb)
        dx_old = dx = tb - ta
        for _ in range(200):
            pt = point_at(t)
            f = self.point_guards(mode, pt)[name]
            if f == 0.0:
                return t, pt
            if f > 0:
                ta = t
            else:
                tb = t
            tol = self.opt.event_xtol + 4 * EPS * abs(t)
            if tb - ta <= tol:
                return t, pt
            if pt.rates is None:
                pt.rates = self.guard_rates(mode, pt, q)
            df = pt.rates[name]
            step = f / df if df != 0.0 and math.isfinite(df) else math.nan
            if abs(step) <= 0.1 * tol:  # t is within about |step| of the zero (also when t - step rounds to t)
                return t, pt
            if ta < t - step < tb and abs(2 * f) <= abs(dx_old * df):
                dx_old, dx = dx, step
                t = t - step
            else:
                dx_old, dx = dx, 0.5 * (tb - ta)
                t = ta + dx
        raise _Failure(Status.NO_CONVERGENCE, t, mode, f"event {name} not located to {self.opt.event_xtol:g}")

    def _consistent(self, mode: Mode, pt: _Point, d0: float) -> _Point | None:
        """Return the start point of ``mode`` at pt if the mode is consistent going forward, else None.

        Guards that are clearly positive at the event stay positive over a short step.  Guards
        that vanish at the event (the one that fired, seen from the new mode) may grow only
        quadratically (slip -> stick at d' = 0 is tangential), so the trial step is enlarged
        until their sign is resolved above round-off (:meth:`_trial_steps`).
        """
        start, pending = self._trial_steps(mode, pt, d0)
        if start is None or not pending:
            return start
        # guards that stay at zero while the input holds still: a quasistatic (rate-independent) state does not move
        # while its input does not, so the mode holds at the limit until the hold ends, where the kink of the input
        # decides what follows; not at the friction tie, where the mode after the hold is ambiguous (tie_note)
        return start if self._input_still(pt.t) and not self.tie_note(pt) else None

    def _decide(self, pt: _Point) -> list[tuple[Mode, _Point]]:
        """The contact modes that continue from the state pt (solved with the input's rate after its phase) without
        a jump and with all their guards positive over the trial steps (those at zero growing), as (mode, its
        start): the rule at a tie of the friction limits and at the end of a hold (docs/guide/simulators.md,
        "Friction ties").

        Stick-stick and the one-foot slips are tried first; slip-slip only if none of them continues (at a tie held
        by a mirror-symmetric motion the one-foot slips keep the tie, so their switch guard stays at zero and they
        are not taken: the two feet then share the slip, the symmetric solution).  More than one mode found means
        the statics do not decide the motion (see :meth:`_apply_decision`)."""
        found: list[tuple[Mode, _Point]] = []
        for m in Mode:
            if m.foot == 3 and found:
                break
            start, pending = self._trial_steps(m, pt, pt.a[AUX["d"]])
            if start is not None and not pending and self._jump(pt, start)[0] <= self.opt.jump_tol:
                found.append((m, start))
        return found

    def _tie_successor(self, mode: Mode, kind: str, ev_pt: _Point) -> tuple[Mode, _Point, str] | None:
        """The successor of the event ``kind`` of ``mode`` at ev_pt, where the friction limits tie, by the rule of
        :meth:`_decide` rather than the transition table: (mode, its start, event kind) if one mode continues, None if
        none does (the table's tests then apply, which know holds and kinks inside the trial steps); SET_VALUED if
        several do."""
        found = self._decide(ev_pt)
        if len(found) > 1:
            raise _Failure(Status.SET_VALUED, ev_pt.t, mode, f"after event {kind} the modes that continue from the "
                           f"state are {', '.join(m.label for m, _ in found)}{self.tie_note(ev_pt)}")
        if not found:
            return None
        chosen, trial = found[0]
        return chosen, trial, mode_change_kind(mode, chosen) if chosen != mode else f"graze_{event_kind(kind)}"

    def _trial_steps(self, mode: Mode, pt: _Point, d0: float, kink: float | None = None) -> tuple[_Point | None, set]:
        """(start of ``mode`` at pt, its guards still at zero to round-off after the trial steps TRIAL_STEPS); (None,
        set()) if a guard is negative at pt or turns negative in the steps.  ``kink``: the next kink of the input, where
        the steps end (solved there with the rate before it): the guards still at zero there are decided by the kink."""
        q = mode_q(mode, d0)
        start = self._solve(pt.t, pt.xl, q, step=True)  # (step: with its stability numbers, for the event check)
        if start is None:
            return None, set()
        g0 = self.point_guards(mode, start)
        noise = self._noise_table.get(mode)
        if noise is None:  # (the round-off levels of the mode's guards, once per stepper and mode)
            noise = self._noise_table[mode] = {k: guard_noise(k, self.noise) for k in g0}
        if any(v < -100 * noise[k] for k, v in g0.items()):
            return None, set()
        pending = {k for k, v in g0.items() if v < 100 * noise[k]}
        for delta in TRIAL_STEPS:
            at_kink = kink is not None and pt.t + delta >= kink - KINK_GAP
            if at_kink:
                delta = kink - pt.t
            nxt = self._solve(pt.t + delta, [x + delta * xd for x, xd in zip(start.xl, start.xdl)], q, left=at_kink)
            if nxt is None:
                return None, set()
            g = self.point_guards(mode, nxt)
            for k in list(pending):
                if g[k] < -10 * noise[k]:
                    return None, set()
                if g[k] > 10 * noise[k]:
                    pending.discard(k)
            if not pending or at_kink:
                break
        return start, pending

    def _before_kink(self, target: Mode, pt: _Point, d0: float, found: list) -> list[tuple[Mode, _Point]]:
        """The successors ``found`` [(mode, its start)] of an event at pt by ``_consistent``, whose trial steps may cross
        the next kink of the input, checked on the piece before that kink (``_trial_steps`` up to it): ``found`` if it
        is one mode not refused there, or if no kink is inside the trial steps; else the table's ``target`` if it is
        not refused there, or the one other mode that is not; else ``found``.  A mode whose guards are still at zero
        at the kink holds up to it (the kink then decides, ``_pass_kink``), unless the friction limits tie there
        (``tie_note``: which foot slips after the kink is ambiguous).

        An event a little before a kink (e.g. a slip that stops 2e-8 cycles before the knot of a sampled input where
        an optimiser placed it) starts a mode whose guards may grow only quadratically (the stick-stick friction guard
        after a slip stops), still at zero to round-off at the kink; after it the new rates may turn them negative
        (the slip resumes).  Trial steps across the kink see those rates: they refuse that mode, and may accept one
        that the rates before the kink refuse (the slip that stops, by the rates after the kink), whose guard is then
        negative from the event on."""
        kink = self.next_kink(pt.t)
        if not kink - pt.t < TRIAL_STEPS[-1]:
            return found
        if len(found) == 1 and self._trial_steps(found[0][0], pt, d0, kink)[0] is not None:
            return found
        piece = []
        for m in (target, *(m for m in Mode if m != target)):
            start, pending = self._trial_steps(m, pt, d0, kink)
            if start is not None and not (pending and self.tie_note(pt)):
                if m == target:
                    return [(m, start)]
                piece.append((m, start))
        return piece if len(piece) == 1 else found

    def _input_still(self, t: float) -> bool:
        """Whether the input holds still just after phase t [cycles]: its rate below HOLD_RTOL times its largest
        rate over the cycle (a hold of a piecewise-linear input, to the round-off of its samples)."""
        if getattr(self, "_rate_scale", None) is None:
            grid = np.arange(1024) / 1024
            self._rate_scale = float(np.max(np.abs(np.asarray(self.torque.derivative(grid), float))))
        rate = np.asarray(self.torque.derivative(t + 1e-9), float)
        return bool(np.max(np.abs(rate)) <= HOLD_RTOL * self._rate_scale)

    def _locate_fold(self, pt: _Point, q: np.ndarray, t_limit: float) -> tuple[float, np.ndarray, float] | None:
        """Newton on the augmented fold system from pt; returns (t_fold, x_fold, sigma_min/sigma_max)."""
        _, J = self.sym.system(pt.x, self.torque(pt.t), q, self.p)
        J = np.asarray(J)
        _, _, vt = np.linalg.svd(J)
        v0 = vt[-1]
        z = np.concatenate([pt.x, [0.0], v0])
        t0 = pt.t
        for _outer in range(8):
            tau0, dtau0 = self.torque(t0), self.torque.derivative(t0)
            for _ in range(40):
                H, dH = self.sym.fold(z, v0, tau0, dtau0, q, self.p)
                H = np.asarray(H).ravel()
                dH = np.asarray(dH)
                try:
                    dz = np.linalg.solve(dH, -H)
                except np.linalg.LinAlgError:
                    return None
                z = z + dz
                if np.max(np.abs(dz)) < 1e-14 and np.max(np.abs(H)) < 1e-12:
                    break
            else:
                return None
            t0 = t0 + z[3]
            done = abs(z[3]) < 1e-14
            z[3] = 0.0
            if done:
                break
        if not (pt.t - 1e-9 <= t0 <= t_limit + 1e-9):
            return None
        _, J = self.sym.system(z[:3], self.torque(t0), q, self.p)
        s = np.linalg.svd(np.asarray(J), compute_uv=False)
        return t0, z[:3], s[-1] / s[0]

