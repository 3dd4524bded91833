"""Switch-exact stepping of an n-link chain: a step whose contact mode changes is split at the event
located inside it (the chain counterpart of :mod:`ocp_crawl.sim.step_split`).

A step from phase ta to tb in the mode of its start is solved for the torques at
ta + theta (tb - ta), theta in [0, 1], by :meth:`~ocp_crawl.sim.chain_mpcc.ChainStep.mode_solution`.
Its guards are positive while the mode holds: in stick-stick the four friction margins; in a slip
of pair j the other three margins and the slip rate ds_j/dtheta (central differences of the mode
solutions, scaled by L).  When the enumerated step ends in another mode, the first zero in theta
of a guard negative at theta = 1 is located by Brent's method, the step is cut there (an event
point in the old mode) and the rest of the step is solved from it, at most ``MAX_SPLITS`` times;
so is a step that ends in its slip mode with the slip's rate below zero at its end (a slip that
stops inside the step while its net slip over the step is still positive: the step's contact
checks then read the mode after it).  A guard already negative at the next step's start belongs
to an event the previous step passed in its mode otherwise: it is located at theta < 0 on the
same mode solutions, and the previous step is redone from its start to the event and from the
event on in the new mode.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import brentq

from ocp_crawl.sim.chain_mpcc import CONSISTENCY_TOL, ENUM_MODES, ChainStep, ChainStepResult
from ocp_crawl.model.step_equations import other_foot
from ocp_crawl.sim.result import Mode
from ocp_crawl.sim.step_split import GUARD_TOL
from ocp_crawl.status import Status

#: most events located inside one step
MAX_SPLITS = 3
#: phase fraction of the central differences of the slip rate [-]
RATE_EPS = 1e-6
#: Brent tolerance of the event's step fraction [-]
THETA_TOL = 1e-13


def _guards(step: ChainStep, mode: Mode, row: tuple, tau_of, theta: float,
            end: bool = False) -> dict | None:
    """The guards of ``mode`` on the step from ``row`` at the step fraction theta (``end``: the
    slip rate differenced before theta only, at the step's end, which may be a kink of the
    input); None when a mode solve fails."""
    phi_k, ft = row[1], row[4]
    k = ENUM_MODES.index(mode)
    cand = step.mode_solution(mode, phi_k, tau_of(theta), ft)
    if cand is None:
        return None
    g = {f"c{i}": float(cand["c"][i]) for i in range(4) if i != k - 1}
    if k:
        # (one-sided at the step's start, from either side: a traced-back theta < 0 is inside the
        # previous step, and the input may have a kink at the start)
        if end:
            lo, hi = theta - RATE_EPS, theta
        elif theta >= 0:
            lo, hi = max(theta - RATE_EPS, 0.0), theta + RATE_EPS
        else:
            lo, hi = theta - RATE_EPS, min(theta + RATE_EPS, 0.0)
        rate = _slip_rate(step, mode, row, tau_of, lo, hi)
        if rate is None:
            return None
        g["rate"] = rate
    return g


def _slip_rate(step: ChainStep, mode: Mode, row: tuple, tau_of, lo: float,
               hi: float) -> float | None:
    """The slip ``mode``'s rate ds/dtheta on the step from ``row``, differenced between the step
    fractions lo and hi; None when a mode solve fails."""
    k = ENUM_MODES.index(mode)
    a = step.mode_solution(mode, row[1], tau_of(lo), row[4])
    b = step.mode_solution(mode, row[1], tau_of(hi), row[4])
    if a is None or b is None:
        return None
    return float((b["slip"][k - 1] - a["slip"][k - 1]) / (hi - lo))


def _locate(step: ChainStep, mode: Mode, row: tuple, tau_of, back: float = 0.0) -> float | None:
    """The step fraction of the first event of ``mode`` in (0, 1], or None (no guard negative at
    theta = 1, or a failed solve).  With ``back`` < 0, a guard already negative at the step's
    start is traced back to its zero in [back, 0) (an event the previous step passed in its mode,
    as a slip-to-stick whose slip over that step was still positive in net)."""
    g1 = _guards(step, mode, row, tau_of, 1.0)
    if g1 is None:
        return None
    found = []
    for name in (k for k, v in g1.items() if v < 0):
        def g(theta, name=name):
            gv = _guards(step, mode, row, tau_of, theta)
            return np.nan if gv is None else gv[name]
        lo = 1e-9
        g_lo = g(lo)
        try:
            if g_lo > 0:
                found.append(brentq(g, lo, 1.0, xtol=THETA_TOL))
            elif back < 0 and g(-lo) < 0 and g(back) > 0:
                found.append(brentq(g, back, -lo, xtol=THETA_TOL))
            else:
                found.append(0.0)
        except ValueError:
            continue
    return min(found) if found else None


def _slip_stopped(step: ChainStep, mode: Mode, row: tuple, tau_of) -> bool:
    """Whether the slip ``mode`` of a step that ends in it stopped inside the step: its rate at
    the step's end below zero (the net slip over the step still positive).  Its end is then an
    event inside this step, located and split as a change of mode (the step's own contact checks
    then read the mode that holds after it)."""
    if not ENUM_MODES.index(mode):
        return False
    rate = _slip_rate(step, mode, row, tau_of, 1.0 - RATE_EPS, 1.0)
    return rate is not None and rate < -GUARD_TOL


def _row(t: float, res: ChainStepResult, mode: Mode | None = None) -> tuple:
    return (t, res.phi, res.x1, res.x2, res.f_t, res.f_n1, res.f_n2, res.d,
            res.mode if mode is None else mode)


def _event_row(step: ChainStep, mode: Mode, row: tuple, tau: np.ndarray, t: float) -> tuple:
    """The event point at phase t in the old ``mode`` from ``row``."""
    cand = step.mode_solution(mode, row[1], tau, row[4])
    assert cand is not None  # (the event's phase was located on this mode's solutions)
    z, s = cand["z"], np.asarray(cand["slip"]) * step.L
    x1, x2 = row[2] + s[0] - s[1], row[3] + s[2] - s[3]
    kin = step.model.kinematics(z[:step.m])
    return (t, z[:step.m].copy(), x1, x2, float(z[step.m] * step.Mg), float(kin["fn1"]),
            float(kin["fn2"]), float(kin["d"]), mode)


def _solve_step(step: ChainStep, row: tuple, tau_of, switch_exact: bool) -> ChainStepResult:
    """The step from ``row`` to the torques ``tau_of(1)``: its consistent solution closest to the
    start (:meth:`ChainStep.solve`), or, for switch-exact steps, the solution in the mode the step
    starts in when that mode holds to the step's end (its margins and a slip's rate there
    nonnegative): where the feet's friction limits tie at the step's end, or the input holds still,
    several modes close the step, and the mode that holds goes on, as in the event-driven
    stepper."""
    mode = row[8]
    res = step.solve(row[1], row[2], row[3], tau_of(1.0), row[4])
    if not switch_exact or not res.success or res.mode == mode or mode not in ENUM_MODES:
        return res
    kept = step.solve(row[1], row[2], row[3], tau_of(1.0), row[4], prefer=mode)
    if kept.mode != mode:
        return res
    g = _guards(step, mode, row, tau_of, 1.0, end=True)
    if g is None or min(g.values()) < -CONSISTENCY_TOL:
        return res
    if res.mode.foot in (1, 2) and mode.foot in (1, 2) and res.mode.foot != mode.foot:
        # the other foot's slip closes the step too: at a tie of the feet's limits at the step's
        # end the slip goes on; a tie held over the whole step (read in its middle) leaves which
        # foot slips (or both) undecided, which the chain's steps do not model (one foot slips at
        # a time); a margin below zero there: the mode broke inside the step
        mid = _guards(step, mode, row, tau_of, 0.5)
        other = min(mid[f"c{i}"] for i in other_foot(ENUM_MODES.index(mode) - 1)) \
            if mid is not None else -1.0
        if other < -GUARD_TOL:
            return res
        if other <= GUARD_TOL:
            return replace(kept, success=False, message="the feet's friction limits tie over the "
                           "whole step: either foot's slip (or both) closes it, and the chain's "
                           "steps move one foot at a time",
                           extra={**kept.extra, "status": Status.SET_VALUED})
    return kept


def advance(step: ChainStep, torque, row: tuple, ta: float, tb: float,
            switch_exact: bool = True, prev: tuple | None = None
            ) -> tuple[list, ChainStepResult, bool, list]:
    """Rows (t, phi, x1, x2, f_t, f_n1, f_n2, d, mode) from ``row`` at phase ``ta`` [cycles] to
    ``tb``: the located event points and the step's end, the last step's result, whether ``row``
    is dropped, and the phases of the located events.  An event point carries the mode after the
    event; one at ``ta`` itself repeats ``row``'s phase in that mode.  ``prev``: the row where the
    step that ended in ``row`` started, in the same mode; an event of that mode found before
    ``ta`` is then placed in that step, which is redone from ``prev`` (the rows returned replace
    ``row``)."""
    out: list[tuple] = []
    located: list[float] = []
    dropped = False
    for split in range(MAX_SPLITS + 1):
        mode = row[8]
        a = ta

        def tau_of(theta, a=a):
            return np.asarray(torque(a + theta * (tb - a)), float).reshape(step.m)

        res = _solve_step(step, row, tau_of, switch_exact)
        if (not res.success or not switch_exact or split == MAX_SPLITS or mode not in ENUM_MODES
                or (res.mode == mode and not _slip_stopped(step, mode, row, tau_of))):
            break

        back = (prev[0] - ta) / (tb - ta) if prev is not None and not out and prev[8] == mode \
            else 0.0
        theta = _locate(step, mode, row, tau_of, back)
        if theta is None:
            break
        te = ta + theta * (tb - ta)
        if theta < 0:
            # the event is in the previous step: redo it from its start to the event, in its
            # mode, and from the event to ta in the mode after it
            assert prev is not None
            event = _event_row(step, mode, prev, tau_of(theta), te)
            after = step.solve(event[1], event[2], event[3], tau_of(min(theta + 1e-9, 0.0)),
                               event[4])
            if not after.success or after.mode == mode:
                break
            event = event[:8] + (after.mode,)
            rest, _, _, found = advance(step, torque, event, te, ta, switch_exact)
            out, dropped, row = [event, *rest], True, rest[-1]
            located += [te, *found]
            continue
        if theta > 0:
            row = _event_row(step, mode, row, tau_of(theta), te)
            out.append(row)
        nxt = step.solve(row[1], row[2], row[3], tau_of(min(theta + 1e-9, 1.0)), row[4])
        new_mode = nxt.mode if nxt.success else None
        if new_mode in (None, mode):
            # a guard of the mode crossed zero at the event, so the mode ends there; so short a
            # step after it cannot tell the modes apart (a slip that starts with zero rate, or
            # that a kink at the step's start stops): the step's own end mode follows it
            new_mode = res.mode
        if new_mode is None or new_mode == mode:
            break
        # the event row continues in the mode taken just after the event
        row = row[:8] + (new_mode,)
        if out and out[-1][0] == te:
            out[-1] = row
        else:
            out.append(row)
        located.append(te)
        ta = te
    if not res.success:   # the mode the failed solve started in (a split may have changed it)
        res = replace(res, extra={**res.extra, "start_mode": row[8]})
    out.append(_row(tb, res))
    return out, res, dropped, located
