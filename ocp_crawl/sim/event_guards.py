"""Guard functions of the event-driven stepper, their rates, the search for dips inside a step and
the transition table (see :mod:`ocp_crawl.sim.event` for the table of guards and modes).

:class:`Guards` evaluates the guards of a mode at solved points; :func:`transition` is the table.
"""
from __future__ import annotations

import math

import numpy as np

from ocp_crawl.model.statics import AUX
from ocp_crawl.sim.event_context import StepperContext
from ocp_crawl.sim.event_kinks import InputPieces
from ocp_crawl.sim.event_state import _Point
from ocp_crawl.sim.result import Mode
from ocp_crawl.status import Status

_FN1, _FN2, _D, _ZJ1, _ZJ2, _FT, _LIM1, _LIM2, _DDOT, _DFT, _DFN1, _DFN2, _DZJ1, _DZJ2 = (
    AUX[n] for n in ("fn1", "fn2", "d", "zj1", "zj2", "ft", "lim1", "lim2", "ddot", "dft", "dfn1",
                     "dfn2", "dzj1", "dzj2"))

#: largest |mu1 f_n1 - mu2 f_n2|/(M g) for which the slip-slip mode is kept
SYMMETRY_TOL = 1e-8

_S_GRID = np.linspace(0.0, 1.0, 33)[1:-1]
_S_BUMP = (_S_GRID * (1 - _S_GRID)) ** 2
#: a contact guard (a normal force, d, a joint's height) whose interpolant has an interior minimum
#: below NEAR_TOUCH times its lower end value comes near zero inside the step: the step is suspect
#: (the error estimate is a heuristic, and near such a touch it has missed dips of 1e-6 L)
NEAR_TOUCH = 0.05
_CONTACT_GUARDS = ("lift_off", "feet_crossed", "joint_")


def cubic_min(g0: float, g1: float, m0: float, m1: float) -> tuple[float, float]:
    """Lowest interior local minimum (s, value) on (0, 1) of the cubic with values g0, g1 and slopes
    m0, m1 (per unit s) at the ends; (nan, inf) if it has none."""
    a = 2 * (g0 - g1) + m0 + m1
    b = 3 * (g1 - g0) - 2 * m0 - m1
    best = (math.nan, math.inf)
    # critical points: 3 a s^2 + 2 b s + m0 = 0; a local minimum where 6 a s + 2 b > 0
    if abs(a) < 1e-300:
        roots = [-m0 / (2 * b)] if b > 0 else []
    else:
        disc = b * b - 3 * a * m0
        if disc < 0:
            return best
        sq = math.sqrt(disc)
        roots = [(-b - sq) / (3 * a), (-b + sq) / (3 * a)]
    for s in roots:
        if 0 < s < 1 and 6 * a * s + 2 * b > 0:
            v = ((a * s + b) * s + m0) * s + g0
            if v < best[1]:
                best = (s, v)
    return best


def interior(a: float, b: float, m0: float, m1: float, floor: float,
             contact: bool = False) -> tuple[str | None, float]:
    """What the cubic Hermite interpolant of a guard over a step (values a, b and slopes m0, m1 per
    unit step fraction at its ends) says of the step's inside: ("dip", s) its local minimum at s is
    below ``floor``; ("near", s) the guard is a ``contact`` guard and that minimum is below
    :data:`NEAR_TOUCH` min(a, b); ("suspect", s) the cubic less its error estimate
    E s^2 (1 - s)^2, E = 6 |b - a - (m0 + m1)/2| (the trapezoid defect, of order h^3 times the
    third derivative), is below ``floor`` at s; else (None, nan)."""
    err = 6.0 * abs(b - a - 0.5 * (m0 + m1))
    # the Hermite basis bounds the cubic below by min(a, b) - 4/27 (|m0| + |m1|)
    if (b if b < a else a) - 0.15 * (abs(m0) + abs(m1)) - err / 16 >= floor:  # (min(a, b))
        return None, math.nan
    s, v = cubic_min(a, b, m0, m1)
    if v < floor:
        return "dip", s
    if contact and v < NEAR_TOUCH * min(a, b):
        return "near", s
    if min(a, b, v) - err / 16 >= floor:
        # (the grid test below cannot fail: the cubic >= min(a, b, v) and err s^2 (1 - s)^2
        # <= err/16)
        return None, math.nan
    c3, c2 = 2 * (a - b) + m0 + m1, 3 * (b - a) - 2 * m0 - m1
    bound = ((c3 * _S_GRID + c2) * _S_GRID + m0) * _S_GRID + a - err * _S_BUMP
    i = int(np.argmin(bound))
    return ("suspect", float(_S_GRID[i])) if bound[i] < floor else (None, math.nan)


def _add_slip_guards(out: dict, lim1: float, lim2: float, ft: float, Mg: float) -> dict:
    """Add the stick-stick friction guards (lim_i - sigma f_t)/(M g) of both feet and signs to
    ``out`` (their rates, given the rates of lim_i and f_t); returns ``out``."""
    out["slip_1+"] = (lim1 - ft) / Mg
    out["slip_1-"] = (lim1 + ft) / Mg
    out["slip_2+"] = (lim2 - ft) / Mg
    out["slip_2-"] = (lim2 + ft) / Mg
    return out


class Guards:
    """The guards of the modes, their rates and their dips inside a step, for the model and input of
    ``ctx``; the curvature of the input is taken inside its ``pieces`` (between its kinks)."""

    def __init__(self, ctx: StepperContext, pieces: InputPieces):
        self.Mg, self.L, self.mu, self.noise = ctx.Mg, ctx.L, ctx.mu, ctx.noise
        self._p, self._torque, self._ddot2 = ctx.p, ctx.torque, ctx.ddot2
        self._pieces = pieces

    def values(self, mode: Mode, aux) -> dict[str, float]:
        """Guard functions of a mode (scaled, positive while the mode is valid); ``aux``: the
        compiled outputs of a solve (array, or the list
        :attr:`~ocp_crawl.sim.event_state._Point.a`)."""
        a = aux.tolist() if isinstance(aux, np.ndarray) else aux
        Mg, L = self.Mg, self.L
        g = {"lift_off_1": a[_FN1] / Mg, "lift_off_2": a[_FN2] / Mg, "feet_crossed": a[_D] / L,
             "joint_1_on_ground": a[_ZJ1] / L, "joint_2_on_ground": a[_ZJ2] / L}
        ft, lim1, lim2 = a[_FT], a[_LIM1], a[_LIM2]
        if mode is Mode.STICK:
            return _add_slip_guards(g, lim1, lim2, ft, Mg)
        g["stick"] = mode.sigma * a[_DDOT] / L
        foot = mode.foot
        if foot == 3:
            g["asymmetry"] = SYMMETRY_TOL - abs(lim1 - lim2) / Mg
        elif foot == 1:
            g["switch_to_2"] = (lim2 - lim1) / Mg
        else:
            g["switch_to_1"] = (lim1 - lim2) / Mg
        return g

    def at(self, mode: Mode, pt: _Point) -> dict[str, float]:
        """:meth:`values` of the mode at the solved point pt, computed once per point and mode."""
        cached = pt.guards
        if cached is None or cached[0] is not mode:
            cached = pt.guards = (mode, self.values(mode, pt.a))
        return cached[1]

    def rates(self, mode: Mode, pt: _Point, q: np.ndarray) -> dict[str, float]:
        """Time derivatives [1/cycle] of :meth:`values` along the mode's solution at pt (the same
        keys in the same order).

        The slip modes' ``stick`` guard sigma d'/L needs d'', which depends on the torque's second
        derivative; that is taken by central differences of the torque's derivative (inside the
        point's piece when the input has kinks,
        :meth:`~ocp_crawl.sim.event_kinks.InputPieces.curvature`).
        """
        a = pt.a
        Mg, L = self.Mg, self.L
        r = {"lift_off_1": a[_DFN1] / Mg, "lift_off_2": a[_DFN2] / Mg, "feet_crossed": a[_DDOT] / L,
             "joint_1_on_ground": a[_DZJ1] / L, "joint_2_on_ground": a[_DZJ2] / L}
        dft = a[_DFT]
        dlim1, dlim2 = self.mu[0] * a[_DFN1], self.mu[1] * a[_DFN2]
        if mode is Mode.STICK:
            return _add_slip_guards(r, dlim1, dlim2, dft, Mg)
        t, dt = pt.t, 1e-5
        if pt.extra is not None and pt.q is q:
            ab = pt.extra[4:].tolist()
        else:
            tau, dtau = (pt.tau, pt.dtau) if pt.tau is not None else \
                (self._torque(t), self._torque.derivative(t))
            ab = self._ddot2(pt.x, tau, dtau, q, self._p)[0].tolist()
        ddtau = self._pieces.curvature(t, pt.left, dt)  # (with kinks: inside the point's piece)
        r["stick"] = mode.sigma * (ab[0] + ab[1] * ddtau[0] + ab[2] * ddtau[1]) / L
        foot = mode.foot  # (the guards in the order of :meth:`values`)
        if foot == 3:
            r["asymmetry"] = -math.copysign(1.0, a[_LIM1] - a[_LIM2]) * (dlim1 - dlim2) / Mg
        elif foot == 1:
            r["switch_to_2"] = (dlim2 - dlim1) / Mg
        else:
            r["switch_to_1"] = (dlim1 - dlim2) / Mg
        return r

    def dips(self, mode: Mode, q: np.ndarray, p0: _Point, p1: _Point, g0: dict,
              g1: dict) -> tuple[list[tuple[str, float]], bool]:
        """Look inside the step [p0.t, p1.t] for zeros of the guards that a sign test at its ends
        misses (a guard dipping below zero and back: two events closer together than the step).

        Each guard is interpolated by the cubic Hermite polynomial of its values and exact rates at
        the ends.  Returns the guards whose interpolant dips below zero, with the phase of its
        minimum, and whether the step is suspect: the interpolant stays positive but not by more
        than an estimate of its error, E s^2 (1 - s)^2 with E = 6 |g1 - g0 - h (g0' + g1')/2|
        (the trapezoid defect, of order h^3 times the third derivative), or a contact guard's
        interpolant nears zero inside the step (:data:`NEAR_TOUCH`), so the caller halves the
        step.
        """
        h = p1.t - p0.t
        for pt in (p0, p1):
            if pt.rates is None:
                pt.rates = self.rates(mode, pt, q)
        floor = -100 * self.noise
        out = []
        suspect = False
        # (the guards and their rates have the same keys in the same order)
        for name, a, b, rate0, rate1 in zip(g0, g0.values(), g1.values(), p0.rates.values(),
                                            p1.rates.values()):
            kind, s = interior(a, b, h * rate0, h * rate1, floor, name.startswith(_CONTACT_GUARDS))
            if kind == "dip":
                out.append((name, p0.t + s * h))
            elif kind is not None:
                suspect = True
        return (sorted(out, key=lambda r: r[1]) if len(out) > 1 else out), suspect

    def tie_note(self, pt: _Point) -> str:
        """A note for a failure at pt: '' unless f_t is at both feet's friction limits, equal to
        SYMMETRY_TOL (the tie mu1 f_n1 = mu2 f_n2, e.g. a mirror-symmetric state of a symmetric
        robot), where the contact mode is physically ambiguous (which foot slips is not decided by
        the statics)."""
        a, Mg = pt.a, self.Mg
        lim1, lim2, ft = a[_LIM1], a[_LIM2], abs(a[_FT])
        if abs(lim1 - lim2) > SYMMETRY_TOL * Mg or abs(ft - lim1) > SYMMETRY_TOL * Mg:
            return ""
        return ("; both feet are at their friction limits and the limits tie "
                f"(|mu1 f_n1 - mu2 f_n2|/(M g) = {abs(lim1 - lim2) / Mg:.2g}): which foot slips is "
                "physically ambiguous")

def transition(mode: Mode, kind: str) -> Mode | Status:
    """The transition table: the mode after the guard ``kind`` of ``mode`` reaches zero, or the
    failure status it ends the run with."""
    if kind.startswith("lift_off"):
        return Status.LIFT_OFF
    if kind == "feet_crossed":
        return Status.FEET_CROSSED
    if kind.startswith("joint_"):
        return Status.JOINT_ON_GROUND
    if kind.startswith("slip_"):
        return Mode.slip(int(kind[5]), +1 if kind[6] == "+" else -1)
    if kind == "stick":
        return Mode.STICK
    if kind.startswith("switch_to_"):
        return Mode.slip(int(kind[-1]), mode.sigma)
    if kind == "asymmetry":
        return Mode.slip(1, mode.sigma)  # provisional: the consistency search picks the weaker foot
    raise AssertionError(kind)

