"""Switch-exact time-stepping: locate a contact event inside a step and split the step there.

A step of the MPCC time-stepping (:mod:`ocp_crawl.sim.timestepping`) from t_a to t_b is exact as
long as one contact mode holds over it (quasistatics: the step equations are then the mode's
equations at t_b).  A step whose MPCC solution ends in another mode than it started contains an
event.  Single events of the slip onset kind lose nothing (the end state is the same), but a change
of the slipping foot gives the whole slip of the step to the foot slipping at its end, an O(h) error
in the foot positions per switch, and slip-to-stick an O(h^2) one.  Here the event is found as the
root of the step equations as a function of the step fraction theta, so that it falls on a step
boundary:

* the step is solved *in the mode it started in*
  (:meth:`~ocp_crawl.sim.mpcc.MPCCStep.solve_in_mode`, one IPOPT call on the step's own NLP with the
  pairs' branches imposed by bounds) at the torque of t_a + theta (t_b - t_a);
* the guards of that mode are read from the solution: the friction margin c_k (scaled by M g) of
  every pair that does not slip (slip onset, change of the slipping foot: the other foot's limit is
  reached), and the slip rate ds_j/dtheta of the slipping pair (slip-to-stick or direction reversal:
  the rate changes sign), by a difference of the mode's slip increment that stays on one piece of
  the input: the input's kinks (the knots where its rate jumps) and the step's end bound it, so
  that the rate at the step's end is the rate the step ends with (a central
  difference across a kink at the step's end would average the rates of both sides and place a
  slip-to-stick at the kink half a difference step early);
* every guard that is negative at theta = 1 is brought to its root in (0, 1) by Brent's method
  (:func:`scipy.optimize.brentq`), and the earliest root is the event; a guard already negative
  just after the step's start is traced back into the previous step when it was positive there
  (``lo``), and otherwise, where the input has a kink at the step's start, changed sign at the
  kink: the event is the step's start.

This search uses only the step NLP (no event function or locator of the event-driven stepper), so
the time-stepping stays an independent check of :mod:`ocp_crawl.sim.event`.  For the gait OCP the
same split reads as a step with two sub-steps of free lengths theta h and (1 - theta) h whose common
boundary carries the guard equation (c_k = 0 there), i.e. a finite element with switch detection.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from ocp_crawl.model.step_equations import NPAIR, PAIR_NAMES, other_foot
from ocp_crawl.nlp.homotopy import Solve
from ocp_crawl.sim.mpcc import MPCCStep
from ocp_crawl.sim.result import Mode
from ocp_crawl.sim.step import SLIP_PAIR_MODES, StepState

#: spacing of the differences of the slip rate [step fraction] (at most a third of the piece of the
#: input they are read on)
RATE_DELTA = 1e-3
#: roots closer than this to the step's start [step fraction] are the start itself (the event is on
#: the boundary)
MIN_FRACTION = 1e-9
#: a guard counts as violated at the step's end when below -GUARD_TOL (scaled margin or slip rate)
GUARD_TOL = 1e-10
#: Brent's tolerance on the step fraction
XTOL = 1e-12


@dataclass(frozen=True)
class Split:
    """A located event: step fraction, the solution in the old mode there, the guard that
    crossed."""

    theta: float
    """fraction of the step at the event, in (lo, 1) (negative: in the previous step; 0: at the
    step's start)"""
    solve: Solve
    """the step to the event solved in the mode it started in (its point w is the state at the
    event)"""
    guard: str
    """name of the guard: '<pair> margin' or '<pair> slip rate'"""
    value: float
    """the guard's value at the event (about 0; for an event at a kink of the input at the step's
    start, its value just after the kink)"""
    mode_after: Mode
    """the mode the guard leads to: slip of the pair whose margin reached zero, stick when the slip
    rate did"""
    calls: int
    """IPOPT calls of the search"""


def slip_pair(mode: Mode) -> int | None:
    """Index of the slipping pair of a single-foot slip mode, None for stick-stick (ValueError for
    both feet)."""
    if mode == Mode.STICK:
        return None
    if mode in SLIP_PAIR_MODES:
        return SLIP_PAIR_MODES.index(mode)
    raise ValueError(f"no single slipping pair in mode {mode.label}")


class _Guards:
    """Guards of one mode along the step fraction, each mode solve cached."""

    def __init__(self, step: MPCCStep, state: StepState, mode: Mode,
                 tau_at: Callable[[float], np.ndarray], x0: np.ndarray | None,
                 kinks: Sequence[float] = ()):
        self.step, self.state, self.tau_at = step, state, tau_at
        self.pair = slip_pair(mode)
        self.x0 = x0
        self.kinks = sorted(set(kinks) | {1.0})   # the input beyond the step's end is not its own
        self.cache: dict[float, Solve] = {}
        self.failed = False

    def solve(self, theta: float) -> Solve:
        if theta not in self.cache:
            near = min(self.cache, key=lambda t: abs(t - theta)) if self.cache else None
            x0 = self.x0 if near is None else self.cache[near].x
            sol = self.step.solve_in_mode(self.state, self.tau_at(theta), self.pair, x0)
            if not (sol.accepted and sol.eq <= self.step.options.eq_tol
                    and np.all(np.isfinite(sol.x))):
                self.failed = True
                raise _SearchFailed(f"mode solve at theta = {theta:.6g}: IPOPT {sol.status}, "
                                    f"residual {sol.eq:.3g}")
            self.cache[theta] = sol
        return self.cache[theta]

    def names(self) -> list[str]:
        out = [f"{PAIR_NAMES[k]} margin" for k in range(NPAIR) if k != self.pair]
        return out + ([] if self.pair is None else [f"{PAIR_NAMES[self.pair]} slip rate"])

    def piece(self, theta: float, left: bool = False) -> tuple[float, float]:
        """The piece (a, b) of the input between kinks on which the guards at ``theta`` are read:
        a kink at ``theta`` starts its piece (``left``: ends it), and the step's end always ends
        one."""
        left = left or theta >= 1.0
        a = max((k for k in self.kinks if (k < theta if left else k <= theta)), default=-math.inf)
        b = min((k for k in self.kinks if (k >= theta if left else k > theta)), default=math.inf)
        return a, b

    def slip_rate(self, theta: float, left: bool = False) -> float:
        """d s_j / d theta of the slipping pair on the piece of ``theta``: a central difference
        inside the piece, a one-sided one of the same order (three points) at its ends."""
        a, b = self.piece(theta, left)
        d = min(RATE_DELTA, (b - a) / 3)
        j = 4 + self.pair

        def s(t: float) -> float:
            return float(self.solve(t).x[j])
        if a <= theta - d and theta + d <= b:
            return (s(theta + d) - s(theta - d)) / (2 * d)
        if theta + d > b:
            return (3 * s(theta) - 4 * s(theta - d) + s(theta - 2 * d)) / (2 * d)
        return (-3 * s(theta) + 4 * s(theta + d) - s(theta + 2 * d)) / (2 * d)

    def violated(self) -> list[str]:
        """The guards of the mode violated at the step's end."""
        return [n for n in self.names() if self.value(n, 1.0) < -GUARD_TOL]

    def turns_at_kink(self, name: str, v0: float) -> bool:
        """Whether the guard ``name``, ``v0`` just after the step's start, turned negative at a
        kink of the input there: a slip rate not negative just before it, or a margin at zero
        (continuous: only its rate jumps at a kink)."""
        if 0.0 not in self.kinks:
            return False
        if name.endswith("slip rate"):
            return self.slip_rate(0.0, left=True) >= -GUARD_TOL
        return abs(v0) <= GUARD_TOL

    def value(self, name: str, theta: float) -> float:
        if name.endswith("slip rate"):
            return self.slip_rate(theta)
        return float(self.solve(theta).c[PAIR_NAMES.index(name.split()[0])])


class _SearchFailed(Exception):
    pass


class TieHeld(Exception):
    """The feet's friction limits tie over a whole step (:func:`solve_to_end`)."""


def solve_to_end(step: MPCCStep, state: StepState, mode: Mode,
                 tau_at: Callable[[float], np.ndarray], x0: np.ndarray | None = None,
                 kinks: Sequence[float] = ()) -> Solve | None:
    """The step solved in ``mode`` (stick-stick or a single-foot slip) to its end, when no guard of
    ``mode`` is violated there (the mode holds over the whole step); None otherwise or when the
    mode solve fails, or the slip of a slip mode reversed.  Arguments as :func:`locate_event`'s.

    Raises TieHeld when the other foot of a slip mode is at its friction limit (to GUARD_TOL) in the
    middle of the step too: the feet's limits tie over the step, and which foot slips (or how the
    feet share the slip) is left undecided by the statics; the step's end alone is a tie that the
    slip reaches.  (One phase is read: a tie over part of a step away from its middle is not seen.)
    """
    g = _Guards(step, state, mode, tau_at, x0, kinks)
    try:
        if g.violated():
            return None
        sol = g.solve(1.0)
        # the slip's sign is free in the mode solve: a slip that reversed is not this mode's
        if g.pair is not None and sol.x[4 + g.pair] < 0:
            return None
        mid = (0.0 if g.pair is None else
               min(g.value(f"{PAIR_NAMES[k]} margin", 0.5) for k in other_foot(g.pair)))
    except _SearchFailed:
        return None
    if mid < -GUARD_TOL:   # (the mode broke inside the step: not this mode's)
        return None
    if g.pair is not None and mid <= GUARD_TOL:
        raise TieHeld("the feet's friction limits tie over the whole step: either foot's slip, or "
                      "both shared, closes it (the statics leave the motion undecided)")
    return sol


def locate_event(step: MPCCStep, state: StepState, mode: Mode,
                 tau_at: Callable[[float], np.ndarray], x0: np.ndarray | None = None,
                 lo: float = 0.0, kinks: Sequence[float] = (),
                 end_mode: Mode | None = None) -> tuple[Split | None, str]:
    """The first event of ``mode`` inside a step (see the module docstring).

    Parameters
    ----------
    step : the step solver of the model
    state : the state at the start of the step (in ``mode``)
    mode : the contact mode at the start of the step (stick-stick or a single-foot slip)
    tau_at : torque [N m] (shape (2,)) at the step fraction theta (0 = start, 1 = end of the step)
    x0 : a scaled step point to start the first mode solve from (e.g. the previous step's solution)
    lo : lowest step fraction searched, in [-1, 0]: with lo < 0 a guard that is already negative at
        the step's start is traced back to a root in [lo, 0] (an event the previous step passed
        without a change of mode, as slip-to-stick: the slip increment of that step is still
        positive); the caller then redoes the previous step from the event
    kinks : the step fractions where the input's rate jumps (from a little below ``lo`` to 1): the
        slip rate is read on one side of them, and a guard that turns negative at a kink at the
        step's start places the event there
    end_mode : the mode the whole step's solution ends in: of several guards turning at once at
        the step's start, the one leading to it gives the event

    Returns
    -------
    (split or None, reason): None when no guard of ``mode`` is violated at the step's end (the
    change of mode seen by the MPCC is not an event of ``mode``, e.g. a tie), or when a mode solve
    fails; ``reason`` then says which.  A root within ``MIN_FRACTION`` of the step's start is
    returned as theta = 0.
    """
    try:
        slip_pair(mode)
    except ValueError as exc:
        return None, str(exc)
    g = _Guards(step, state, mode, tau_at, x0, kinks)
    calls0 = step.ncalls
    try:
        crossed = g.violated()
        if not crossed:
            return None, "no guard of the starting mode is violated at the end of the step"
        from scipy.optimize import brentq  # scipy only where used (start-up time)

        roots = []
        for name in crossed:
            v0 = g.value(name, 0.0)
            if v0 > 0:
                a, b = 0.0, 1.0
            elif g.turns_at_kink(name, v0):
                roots.append((0.0, name))
                continue
            elif lo < 0 and v0 < 0 and g.value(name, lo) > GUARD_TOL:
                # (a guard at zero there, as a slip rate while the input holds, is no crossing)
                a, b = lo, 0.0
            else:
                continue
            roots.append((brentq(lambda th, n=name: g.value(n, th), a, b, xtol=XTOL), name))
    except _SearchFailed as exc:
        return None, str(exc)
    if not roots:
        return None, "the violated guards are not positive at the start of the step"
    theta, name = min(roots)
    if abs(theta) < MIN_FRACTION:
        # the event is the step's start (e.g. a slip that stops exactly at a step phase)
        theta = 0.0
    if theta == 0.0:
        # several guards turning at the step's start (at a kink of the input) are a tie: the mode
        # the step's own solution ends in decides it when it is one of theirs
        tied = [n for t, n in roots if abs(t) < MIN_FRACTION]
        name = next((n for n in tied if _mode_after(n) == end_mode), name)
    try:
        value = g.value(name, theta)
        sol = g.solve(theta)
    except _SearchFailed as exc:
        return None, str(exc)
    return Split(theta, sol, name, value, _mode_after(name), step.ncalls - calls0), ""


def _mode_after(guard: str) -> Mode:
    """The mode a guard leads to: slip of the pair whose margin reached zero, stick when the slip
    rate did."""
    return (Mode.STICK if guard.endswith("slip rate")
            else SLIP_PAIR_MODES[PAIR_NAMES.index(guard.split()[0])])
