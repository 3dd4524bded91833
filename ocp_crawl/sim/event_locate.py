"""Event location of the event-driven stepper: the first of the guards crossing zero in a step,
guard zeros by a safeguarded Newton method, and folds of the equilibrium branch by the augmented
system.

:class:`EventLocator` locates them on the solves of a :class:`~ocp_crawl.sim.event_solve.ModeSolver`
and the guards of a :class:`~ocp_crawl.sim.event_guards.Guards`; which mode follows an event is
chosen by
:class:`~ocp_crawl.sim.event_modes.ModeChooser`.
"""
from __future__ import annotations

import math
from typing import Callable, TypeVar

import numpy as np

from ocp_crawl.sim.event_context import StepperContext
from ocp_crawl.sim.event_guards import Guards
from ocp_crawl.sim.event_solve import ModeSolver
from ocp_crawl.sim.event_state import _Failure, _Point, _Segment, hermite_point
from ocp_crawl.sim.result import Mode
from ocp_crawl.status import Status

EPS = float(np.finfo(float).eps)
#: a solved point of a branch (the three-link stepper's and the chain's)
PointT = TypeVar("PointT")
#: round-off level of the scaled guards that depend on the angles (and d') only, whatever k/(M g L)
ANGLE_NOISE = 1e-13


def guard_noise(name: str, noise: float) -> float:
    """Round-off level of the scaled guard ``name`` for the consistency test of a successor mode.

    ``noise``: the stepper's round-off level of f_t/(M g) [-], which grows with k/(M g L) (stiff
    joints fix the angles to O(M g L/k), so f_t absorbs the round-off of the joint balance).  Only
    the stick-stick friction guards ``slip_*`` contain f_t; the others (normal forces, d, joint
    heights, d', the friction limits of the slip modes) are functions of the angles and their rates,
    which stay accurate to round-off in the stiff limit: their level is ANGLE_NOISE, so that a guard
    of 1e-6 (a reversal of d' just before a stiff event) is not taken for noise when k/(M g L) =
    1e8.
    """
    return noise if name.startswith("slip_") else ANGLE_NOISE


class NotLocated(Exception):
    """A guard's zero not located in :func:`guard_root`'s steps; ``t`` the last phase tried."""

    def __init__(self, t: float):
        super().__init__(f"no zero located by t = {t!r}")
        self.t = t


def guard_root(point_at: Callable[[float], PointT], value: Callable[[PointT], float],
               rate: Callable[[PointT], float], a: tuple[float, float], b: tuple[float, float],
               xtol: float) -> tuple[float, PointT]:
    """Zero of a guard along a solved branch between a = (phase, value > 0) and b = (phase,
    value < 0): safeguarded Newton (``rtsafe``) with the guard's exact rate along the branch, from
    the secant point; a bisection step whenever the Newton step leaves the bracket or does not
    halve the step before last.  Returns the last solved (t, point) when the bracket is below tol =
    ``xtol`` + 4 eps |t| (brentq's tolerance) or the next Newton step below tol/10, so t is within
    tol of the zero (in the quadratic phase the step is about the square of the previous one);
    :class:`NotLocated` after 200 steps.  About 3 solves per event against 7 for Brent's method.

    ``point_at(t)`` solves the branch at phase t; ``value(point)`` and ``rate(point)`` are the
    guard [-] and its rate [1/cycle] there.
    """
    (ta, fa), (tb, fb) = a, b
    t = ta + (tb - ta) * fa / (fa - fb)
    if not ta < t < tb:
        t = 0.5 * (ta + tb)
    dx_old = dx = tb - ta
    for _ in range(200):
        pt = point_at(t)
        f = value(pt)
        if f == 0.0:
            return t, pt
        if f > 0:
            ta = t
        else:
            tb = t
        tol = xtol + 4 * EPS * abs(t)
        if tb - ta <= tol:
            return t, pt
        df = rate(pt)
        step = f / df if df != 0.0 and math.isfinite(df) else math.nan
        # (t is within about |step| of the zero, also when t - step rounds to t)
        if abs(step) <= 0.1 * tol:
            return t, pt
        if ta < t - step < tb and abs(2 * f) <= abs(dx_old * df):
            dx_old, dx = dx, step
            t = t - step
        else:
            dx_old, dx = dx, 0.5 * (tb - ta)
            t = ta + dx
    raise NotLocated(t)


class EventLocator:
    """Location of the events and folds of the branches solved by ``solver``, with the ``guards``;
    reads the context's input, symbolic fold system, round-off level and ``event_xtol``."""

    def __init__(self, ctx: StepperContext, solver: ModeSolver, guards: Guards):
        self._solver, self._guards = solver, guards
        self._noise, self._xtol = ctx.noise, ctx.opt.event_xtol
        self._sym, self._torque, self._p = ctx.sym, ctx.torque, ctx.p

    def first_crossing(self, pt: _Point, new: _Point, seg: _Segment, crossed: list[str]):
        """((t, point), guard) of the first zero in the step [pt, new] of the guards ``crossed``:
        they are located in the order of their secant estimates, and a guard still positive at the
        earliest zero found so far is not located (it crosses later; a guard that dips and returns
        inside the step ends the step in its dip beforehand, see ``HybridStepper._crossings``)."""
        g0, g1 = self._guards.at(seg.mode, pt), self._guards.at(seg.mode, new)

        def estimate(k: str) -> float:
            a, b = g0[k], g1[k]
            return pt.t + (new.t - pt.t) * a / (a - b) if a > 0 > b else pt.t

        best = None
        for k in sorted(crossed, key=estimate):
            if best is not None and \
                    self._guards.at(seg.mode, best[0][1])[k] > guard_noise(k, self._noise):
                continue
            found = (self.locate(pt, new, seg.q, seg.mode, k, start=pt is seg.points[0]), k)
            if best is None or self._earlier(found, best, crossed):
                best = found
        return best

    def _earlier(self, found, best, crossed: list[str]) -> bool:
        """Whether the located zero ``found`` comes before ``best``; zeros within the location
        tolerance are simultaneous (e.g. at a kink of a sampled or pulse input, where the slip stops
        as another friction limit is reached) and then the guard first in ``crossed`` (the guards'
        table order) comes first."""
        t_f, t_b = found[0][0], best[0][0]
        tol = self._xtol + 4 * EPS * abs(t_b)
        if abs(t_f - t_b) <= tol:
            return crossed.index(found[1]) < crossed.index(best[1])
        return t_f < t_b

    def locate(self, p0: _Point, p1: _Point, q: np.ndarray, mode: Mode, name: str,
                start: bool = False) -> tuple[float, _Point]:
        """Phase and solved state where guard ``name`` crosses zero in [p0.t, p1.t] (:meth:`_root`).
        ``start``: p0 starts the mode's segment, where the guard that fired the transition is zero.
        A guard at zero to round-off at p0 that is not a segment's start (a kink of the input) and
        negative after it, without rising first, crosses at p0 itself: the successor is then decided
        at p0 (:meth:`~ocp_crawl.sim.event_modes.ModeChooser.successor`)."""

        # the ends are known (a re-solve there could differ in the last bits and break the bracket)
        cache: dict[float, _Point] = {p0.t: p0, p1.t: p1}

        def point_at(t: float) -> _Point:
            pt = cache.get(t)
            if pt is None:
                pt = self._solver.solve(t, hermite_point(p0, p1, t), q, step=True)
                if pt is None:
                    raise _Failure(Status.NO_CONVERGENCE, t, mode,
                                   f"mode solve failed while locating event {name}")
                cache[t] = pt
            return pt

        g0, g1 = self._guards.at(mode, p0)[name], self._guards.at(mode, p1)[name]
        if g1 == 0.0:
            return p1.t, p1
        ta, tb, ga = p0.t, p1.t, g0
        if g0 <= 0 or (start and g0 <= 100 * self._noise):
            # the guard starts at zero (it fired the transition into this mode, or touches zero
            # there): [p0, p1] holds that zero and the crossing, so bracket the crossing between the
            # first sample where the guard is clearly positive and the next one where it is negative
            hh = p1.t - p0.t
            ta, below = None, False
            for frac in (1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 0.05, *np.linspace(0, 1, 10)[1:-1], 1.0):
                s = p0.t + frac * hh
                v = g1 if frac == 1.0 else self._guards.at(mode, point_at(s))[name]
                if v > 10 * self._noise:
                    ta, ga = s, v
                elif v < 0 and ta is not None:
                    tb, g1 = s, v
                    break
                below = below or (ta is None and v < -10 * self._noise)
            if ta is None and below and not start:
                # zero at p0 to round-off and negative after it: the guard crosses at p0 (a kink of
                # the input where its rate turned negative, e.g. the friction limits tie exactly at
                # a sample of a sampled input)
                return p0.t, p0
            if ta is None and not below and p1.left and not self._guards.tie_note(p0):
                # zero to round-off all the way to the kink that ends the step (a mode that holds at
                # its limit up to a kink, see ModeChooser.before_kink): the event is at the kink,
                # where the rates after it decide (ModeSwitch.pass_kink)
                return p1.t, p1
            if ta is None:
                raise _Failure(Status.NO_CONSISTENT_MODE, p0.t, mode,
                               f"guard {name} does not leave zero after the transition into "
                               f"{mode.label}{self._guards.tie_note(p0)}")
        return self._root(point_at, mode, q, name, (ta, ga), (tb, g1))

    def _root(self, point_at, mode: Mode, q: np.ndarray, name: str, a: tuple[float, float],
              b: tuple[float, float]) -> tuple[float, _Point]:
        """Zero of the guard ``name`` of the solved branch between a = (phase, value > 0) and b =
        (phase, value < 0) by :func:`guard_root`, with the exact rate of the guard along the
        branch (:meth:`~ocp_crawl.sim.event_guards.Guards.rates`).  ``point_at(t)`` solves the mode
        at t."""
        def rate(pt: _Point) -> float:
            if pt.rates is None:
                pt.rates = self._guards.rates(mode, pt, q)
            return pt.rates[name]

        try:
            return guard_root(point_at, lambda pt: self._guards.at(mode, pt)[name], rate, a, b,
                              self._xtol)
        except NotLocated as exc:
            raise _Failure(Status.NO_CONVERGENCE, exc.t, mode,
                           f"event {name} not located to {self._xtol:g}") from None

    def fold(self, pt: _Point, q: np.ndarray,
             t_limit: float) -> tuple[float, np.ndarray, float] | None:
        """Newton on the augmented fold system from pt; returns (t_fold, x_fold,
        sigma_min/sigma_max)."""
        _, J = self._sym.system(pt.x, self._torque(pt.t), q, self._p)
        J = np.asarray(J)
        _, _, vt = np.linalg.svd(J)
        v0 = vt[-1]
        z = np.concatenate([pt.x, [0.0], v0])
        t0 = pt.t
        for _outer in range(8):
            tau0, dtau0 = self._torque(t0), self._torque.derivative(t0)
            for _ in range(40):
                H, dH = self._sym.fold(z, v0, tau0, dtau0, q, self._p)
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
        _, J = self._sym.system(z[:3], self._torque(t0), q, self._p)
        s = np.linalg.svd(np.asarray(J), compute_uv=False)
        return t0, z[:3], s[-1] / s[0]

