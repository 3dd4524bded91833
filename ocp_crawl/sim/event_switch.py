"""Changes of the contact mode of a run of the event-driven stepper: an event located in a step, a
kink of the input where a guard turns negative, and a hold of the input, which the run crosses in
one step.

:class:`ModeSwitch` records the event, checks the successor's start (jump, stability, events per
cycle) and starts its segment on the :class:`~ocp_crawl.sim.event_state._Run`; the successor comes
from a
:class:`~ocp_crawl.sim.event_modes.ModeChooser`.  The kinks and holds of the input are those of
:mod:`ocp_crawl.sim.event_kinks`.
"""
from __future__ import annotations

import numpy as np

from ocp_crawl.model.statics import AUX
from ocp_crawl.sim.event_checks import Checks
from ocp_crawl.sim.event_context import StepperContext
from ocp_crawl.sim.event_guards import Guards, transition
from ocp_crawl.sim.event_kinks import KINK_GAP, InputPieces
from ocp_crawl.sim.event_locate import guard_noise
from ocp_crawl.sim.event_modes import ModeChooser
from ocp_crawl.sim.event_solve import ModeSolver
from ocp_crawl.sim.event_state import _Failure, _Point, _Run, _Segment, event_kind, hermite_point
from ocp_crawl.sim.result import Event, Mode, mode_change_kind
from ocp_crawl.status import Status

_D, _DET = AUX["d"], AUX["det"]


class ModeSwitch:
    """Mode changes of a run: events, kinks and holds of the input, decisions by the rates."""

    def __init__(self, ctx: StepperContext, solver: ModeSolver, guards: Guards, checks: Checks,
                 modes: ModeChooser, pieces: InputPieces):
        self._solver, self._guards, self._checks = solver, guards, checks
        self._modes, self._pieces = modes, pieces
        self._noise, self._max_step = ctx.noise, ctx.max_step
        self._jump_tol, self._max_events = ctx.opt.jump_tol, ctx.opt.max_events_per_cycle

    def pass_kink(self, run: _Run, kind: str | None = None) -> None:
        """At a kink of the input (run.pt, solved with the rate before it): the same state with the
        rate after it continues the segment, unless a guard that was positive before the kink is
        negative after it (sigma d' of a slip that stops or reverses exactly there), or ``kind``
        names a guard found at zero there: then that event happens at the kink, and the successor
        mode is decided by the rates after it (:mod:`ocp_crawl.sim.event_kinks`)."""
        pt, seg = run.pt, run.seg
        right = self._solver.solve(pt.t, pt.xl, seg.q, step=True)
        if right is None:
            raise _Failure(Status.NO_CONVERGENCE, pt.t, seg.mode,
                           "mode solve failed at a kink of the input")
        run.pt = right
        # (at tied limits the rates after it decide)
        if self._guards.tie_note(right) and self._pieces.hold_at(pt.t) is None:
            self.apply_decision(run, right, "at a kink of the input where the friction limits tie")
            return
        g, g_left = self._guards.at(seg.mode, right), self._guards.at(seg.mode, pt)
        jumped = [kind] if kind else [k for k, v in g.items()
                                      if v < -100 * guard_noise(k, self._noise) and g_left[k] >= 0]
        if jumped:
            self.enter(run, right, jumped[0], pt.t)

    def enter(self, run: _Run, ev_pt: _Point, kind: str, t_ev: float) -> None:
        """Record the event ``kind`` at t_ev (state ev_pt, of the current segment's mode) and start
        the successor mode's segment, or end the run with the table's failure status."""
        seg = run.seg
        g_ev = self._guards.at(seg.mode, ev_pt)[kind]
        target = transition(seg.mode, kind)
        if isinstance(target, Status):
            run.events.append(Event(t_ev, event_kind(kind), seg.mode.label, "failure", g_ev, kind))
            raise _Failure(target, t_ev, seg.mode, f"{kind.replace('_', ' ')}")
        chosen, trial, kind_out = self._modes.successor(seg.mode, target, kind, ev_pt, t_ev)
        self.start_mode(run, ev_pt, chosen, trial,
                        Event(t_ev, kind_out, seg.mode.label, chosen.label, g_ev, kind))

    def start_mode(self, run: _Run, ev_pt: _Point, chosen: Mode, trial: _Point,
                   event: Event) -> None:
        """Record the ``event`` (into ``chosen``) and start the segment of the successor ``chosen``
        from ``trial``, its start at the event's state ev_pt, after the jump and stability
        checks."""
        seg = run.seg
        run.events.append(event)
        self._checks.check_jump(ev_pt, trial, seg.mode, chosen, event.kind)
        # (trial.q: mode_q(chosen, d at the event))
        self._checks.require_stable(trial, chosen, trial.q, f"after the event {event.kind}")
        run.events_in_cycle += 1
        if run.events_in_cycle > self._max_events:
            raise _Failure(Status.TOO_MANY_EVENTS, event.t, chosen,
                           f"more than {self._max_events} events in cycle {run.cycle + 1}")
        x1, x2 = seg.feet(ev_pt.a[_D])
        run.seg = _Segment(chosen, trial.q, x1, x2, [trial])
        run.segments.append(run.seg)
        run.pt = trial
        run.det_sign = np.sign(trial.aux[_DET]) or 1.0
        run.h = self._max_step

    def not_at_hold(self, seg, pt: _Point, new: _Point, crossed: list[str]) -> list[str]:
        """The guards ``crossed`` in the step [pt, new], less all of them when the step ends at a
        hold's start with each of them at zero to round-off there and not negative inside the step
        (solved at a quarter, half and three quarters of it): a guard that reaches zero as the input
        comes to rest (the slip of a half-cosine edge stops with its rate) is decided at the hold's
        end, by the rates after it."""
        if not crossed or abs(self._pieces.next_hold(new.t - 2 * KINK_GAP) - new.t) > KINK_GAP:
            return crossed
        g = self._guards.at(seg.mode, new)
        if any(g[k] < -100 * self._noise for k in crossed):
            return crossed
        for s in (0.25, 0.5, 0.75):
            t = pt.t + s * (new.t - pt.t)
            inside = self._solver.solve(t, hermite_point(pt, new, t), seg.q)
            if inside is None:
                return crossed
            g = self._guards.at(seg.mode, inside)
            if any(g[k] < -100 * self._noise for k in crossed):
                return crossed
        return []

    def cross_hold(self, run: _Run, t_end: float) -> bool:
        """If run.pt is at (or inside) a hold of the input, move it to the hold's end (or to t_end,
        the end of the cycle, if that comes first) with the state unchanged, and decide there the
        mode that follows (:meth:`leave_hold`); returns whether it did."""
        span = self._pieces.hold_at(run.pt.t)
        if span is None:
            return False
        seg, tb = run.seg, min(span[1], t_end)
        # the hold's ends at rest (zero rates: the dense output interpolates the constant state
        # between them), then the state at its end with the rates after it; a hold of zero length (a
        # rest of the input) is left once
        ends = [self._solver.solve(t, run.pt.xl, seg.q, step=True, held=True)
                for t in (run.pt.t, tb) if span[0] < span[1]]
        ends.append(self._solver.solve(tb, run.pt.xl, seg.q, step=True))
        self._pieces.leave_rest(span)
        if any(p is None or self._checks.jump(run.pt, p)[0] > self._jump_tol for p in ends):
            raise _Failure(Status.NO_CONVERGENCE, tb, seg.mode, "the mode's state changed across a "
                           "hold of the input (the solve did not return the state it started from)")
        run.nsteps += 1
        seg.points.extend(ends)
        run.pt = end = ends[-1]
        if tb == span[1]:
            self.leave_hold(run, end)
        return True

    def leave_hold(self, run: _Run, end: _Point) -> None:
        """At the end of a hold (state ``end``, with the rates after it): keep the current mode if
        its guards stay positive after the hold (those at zero grow), else :meth:`apply_decision` of
        the modes that continue."""
        start, pending = self._modes.trial_steps(run.seg.mode, end, end.a[_D])
        # (at a tie every mode is tried: set_valued if several)
        if start is None or pending or self._guards.tie_note(end):
            self.apply_decision(run, end, "at the end of a hold of the input")

    def apply_decision(self, run: _Run, pt: _Point, where: str) -> None:
        """Continue from pt in the one mode of
        :meth:`~ocp_crawl.sim.event_modes.ModeChooser.decide`: the current segment goes on if it is
        the current mode, else a new segment starts (its event's kind from the two modes).
        NO_CONSISTENT_MODE if no mode continues; SET_VALUED if several do (the statics leave the
        motion undecided: which foot slips, or whether they stick, then depends on what breaks the
        tie, e.g. mu1 != mu2)."""
        found, seg = self._modes.decide(pt), run.seg
        if len(found) != 1:
            names = ", ".join(m.label for m, _ in found) or "none"
            status = Status.SET_VALUED if found else Status.NO_CONSISTENT_MODE
            raise _Failure(status, pt.t, seg.mode, f"{where} the modes that continue from the "
                           f"state are {names}{self._guards.tie_note(pt)}")
        chosen, start = found[0]
        if chosen != seg.mode:
            event = Event(pt.t, mode_change_kind(seg.mode, chosen), seg.mode.label, chosen.label,
                          0.0, "decided")
            self.start_mode(run, pt, chosen, start, event)
