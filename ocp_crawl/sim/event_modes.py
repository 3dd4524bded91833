"""The contact mode after an event of the event-driven stepper: the consistency of a successor mode
over trial steps, the table's successor or the one mode that continues, and the rule at a tie of the
friction limits, at the end of a hold of the input and at a kink (docs/guide/simulators.md,
"Friction ties").

:class:`ModeChooser` decides on the solves of a :class:`~ocp_crawl.sim.event_solve.ModeSolver`, the
guards of a :class:`~ocp_crawl.sim.event_guards.Guards`, the jump test of a
:class:`~ocp_crawl.sim.event_checks.Checks` and the kinks of the input
(:class:`~ocp_crawl.sim.event_kinks.InputPieces`).
"""
from __future__ import annotations

import numpy as np

from ocp_crawl.model.statics import AUX
from ocp_crawl.sim.event_checks import Checks
from ocp_crawl.sim.event_context import StepperContext
from ocp_crawl.sim.event_guards import Guards
from ocp_crawl.sim.event_kinks import KINK_GAP, InputPieces
from ocp_crawl.sim.event_locate import guard_noise
from ocp_crawl.sim.event_solve import ModeSolver
from ocp_crawl.sim.event_state import _Failure, _Point, event_kind, mode_q
from ocp_crawl.sim.result import Mode, mode_change_kind
from ocp_crawl.status import Status

#: phase steps [cycles] after an event at which the guards of a successor mode are tested
#: (``consistent``)
TRIAL_STEPS = (1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4)
#: an input whose rate is below this fraction of its largest rate over the cycle holds still
#: (``input_still``)
HOLD_RTOL = 1e-6


class ModeChooser:
    """The mode that follows an event or a decision point, from the modes consistent at its
    state."""

    def __init__(self, ctx: StepperContext, solver: ModeSolver, guards: Guards, checks: Checks,
                 pieces: InputPieces):
        self._solver, self._guards, self._checks, self._pieces = solver, guards, checks, pieces
        self._noise, self._jump_tol, self._torque = ctx.noise, ctx.opt.jump_tol, ctx.torque
        self._noise_table: dict = {}
        """mode -> the round-off levels of its guards
        (:func:`~ocp_crawl.sim.event_locate.guard_noise`)"""
        self._rate_scale: float | None = None
        """the input's largest rate over the cycle (:meth:`input_still`; None until asked for)"""

    def successor(self, mode: Mode, target: Mode, kind: str, ev_pt: _Point,
                  t_ev: float) -> tuple[Mode, _Point, str]:
        """The mode after the event ``kind`` at ev_pt: the table's successor ``target`` if it is
        consistent, else the one other consistent mode (the current one for a grazing event), or of
        several the one that starts from the event's state without a jump
        (:meth:`~ocp_crawl.sim.event_checks.Checks.jump`); with a kink of the input inside the trial
        steps, the mode consistent on the piece before it if that one is not or none is
        (:meth:`before_kink`); where that leaves no mode or several at tied friction limits, the
        rule of :meth:`tie_successor`; (mode, its start, event kind)."""
        new_d0 = ev_pt.aux[AUX["d"]]
        trial = self.consistent(target, ev_pt, new_d0)
        found = [(target, trial)] if trial is not None else \
            [(m, tr) for m in Mode
             if m != target and (tr := self.consistent(m, ev_pt, new_d0)) is not None]
        if len(found) > 1 and not self._checks.input_jumps(t_ev):
            # (e.g. at a kink of the input) a mode that continues the state wins
            found = [f for f in found
                     if self._checks.jump(ev_pt, f[1])[0] <= self._jump_tol] or found
        found = self.before_kink(target, ev_pt, new_d0, found)
        if len(found) != 1 and self._guards.tie_note(ev_pt) and not self._checks.input_jumps(t_ev):
            tied = self.tie_successor(mode, kind, ev_pt)  # (at tied limits: the rule of decide)
            if tied:
                return tied
        if len(found) != 1:
            raise _Failure(Status.NO_CONSISTENT_MODE, t_ev, mode,
                           f"after event {kind}: {len(found)} consistent successor modes (table "
                           f"successor {target.label} is inconsistent)"
                           f"{self._guards.tie_note(ev_pt)}")
        chosen, trial = found[0]
        graze = chosen == mode != target
        return chosen, trial, f"graze_{event_kind(kind)}" if graze else event_kind(kind)

    def consistent(self, mode: Mode, pt: _Point, d0: float) -> _Point | None:
        """Return the start point of ``mode`` at pt if the mode is consistent going forward, else
        None.

        Guards that are clearly positive at the event stay positive over a short step.  Guards
        that vanish at the event (the one that fired, seen from the new mode) may grow only
        quadratically (slip -> stick at d' = 0 is tangential), so the trial step is enlarged
        until their sign is resolved above round-off (:meth:`trial_steps`).
        """
        start, pending = self.trial_steps(mode, pt, d0)
        if start is None or not pending:
            return start
        # guards that stay at zero while the input holds still: a quasistatic (rate-independent)
        # state does not move while its input does not, so the mode holds at the limit until the
        # hold ends, where the kink of the input decides what follows; not at the friction tie,
        # where the mode after the hold is ambiguous (tie_note)
        return start if self.input_still(pt.t) and not self._guards.tie_note(pt) else None

    def decide(self, pt: _Point) -> list[tuple[Mode, _Point]]:
        """The contact modes that continue from the state pt (solved with the input's rate after its
        phase) without a jump and with all their guards positive over the trial steps (those at zero
        growing), as (mode, its start): the rule at a tie of the friction limits and at the end of a
        hold (docs/guide/simulators.md, "Friction ties").

        Stick-stick and the one-foot slips are tried first; slip-slip only if none of them continues
        (at a tie held by a mirror-symmetric motion the one-foot slips keep the tie, so their switch
        guard stays at zero and they are not taken: the two feet then share the slip, the symmetric
        solution).  More than one mode found means the statics do not decide the motion (see
        :meth:`~ocp_crawl.sim.event_switch.ModeSwitch.apply_decision`)."""
        found: list[tuple[Mode, _Point]] = []
        for m in Mode:
            if m.foot == 3 and found:
                break
            start, pending = self.trial_steps(m, pt, pt.a[AUX["d"]])
            if start is not None and not pending and \
                    self._checks.jump(pt, start)[0] <= self._jump_tol:
                found.append((m, start))
        return found

    def tie_successor(self, mode: Mode, kind: str,
                      ev_pt: _Point) -> tuple[Mode, _Point, str] | None:
        """The successor of the event ``kind`` of ``mode`` at ev_pt, where the friction limits tie,
        by the rule of :meth:`decide` rather than the transition table: (mode, its start, event
        kind) if one mode continues, None if none does (the table's tests then apply, which know
        holds and kinks inside the trial steps); SET_VALUED if several do."""
        found = self.decide(ev_pt)
        if len(found) > 1:
            names = ", ".join(m.label for m, _ in found)
            raise _Failure(Status.SET_VALUED, ev_pt.t, mode, f"after event {kind} the modes that "
                           f"continue from the state are {names}{self._guards.tie_note(ev_pt)}")
        if not found:
            return None
        chosen, trial = found[0]
        return chosen, trial, \
            mode_change_kind(mode, chosen) if chosen != mode else f"graze_{event_kind(kind)}"

    def trial_steps(self, mode: Mode, pt: _Point, d0: float,
                    kink: float | None = None) -> tuple[_Point | None, set]:
        """(start of ``mode`` at pt, its guards still at zero to round-off after the trial steps
        TRIAL_STEPS); (None, set()) if a guard is negative at pt or turns negative in the steps.
        ``kink``: the next kink of the input, where the steps end (solved there with the rate before
        it): the guards still at zero there are decided by the kink."""
        q = mode_q(mode, d0)
        # (step: with its stability numbers, for the event check)
        start = self._solver.solve(pt.t, pt.xl, q, step=True)
        if start is None:
            return None, set()
        g0 = self._guards.at(mode, start)
        noise = self._noise_table.get(mode)
        if noise is None:  # (the round-off levels of the mode's guards, once per stepper and mode)
            noise = self._noise_table[mode] = {k: guard_noise(k, self._noise) for k in g0}
        if any(v < -100 * noise[k] for k, v in g0.items()):
            return None, set()
        pending = {k for k, v in g0.items() if v < 100 * noise[k]}
        for delta in TRIAL_STEPS:
            at_kink = kink is not None and pt.t + delta >= kink - KINK_GAP
            if at_kink:
                delta = kink - pt.t
            guess = [x + delta * xd for x, xd in zip(start.xl, start.xdl)]
            nxt = self._solver.solve(pt.t + delta, guess, q, left=at_kink)
            if nxt is None:
                return None, set()
            g = self._guards.at(mode, nxt)
            for k in list(pending):
                if g[k] < -10 * noise[k]:
                    return None, set()
                if g[k] > 10 * noise[k]:
                    pending.discard(k)
            if not pending or at_kink:
                break
        return start, pending

    def before_kink(self, target: Mode, pt: _Point, d0: float,
                    found: list) -> list[tuple[Mode, _Point]]:
        """The successors ``found`` [(mode, its start)] of an event at pt by ``consistent``, whose
        trial steps may cross the next kink of the input, checked on the piece before that kink
        (``trial_steps`` up to it): ``found`` if it is one mode not refused there, or if no kink is
        inside the trial steps; else the table's ``target`` if it is not refused there, or the one
        other mode that is not; else ``found``.  A mode whose guards are still at zero at the kink
        holds up to it (the kink then decides, ``ModeSwitch.pass_kink``), unless the friction limits
        tie there (``tie_note``: which foot slips after the kink is ambiguous).

        An event a little before a kink (e.g. a slip that stops 2e-8 cycles before the knot of a
        sampled input where an optimiser placed it) starts a mode whose guards may grow only
        quadratically (the stick-stick friction guard after a slip stops), still at zero to
        round-off at the kink; after it the new rates may turn them negative (the slip resumes).
        Trial steps across the kink see those rates: they refuse that mode, and may accept one that
        the rates before the kink refuse (the slip that stops, by the rates after the kink), whose
        guard is then negative from the event on."""
        kink = self._pieces.next_kink(pt.t)
        if not kink - pt.t < TRIAL_STEPS[-1]:
            return found
        if len(found) == 1 and self.trial_steps(found[0][0], pt, d0, kink)[0] is not None:
            return found
        piece = []
        for m in (target, *(m for m in Mode if m != target)):
            start, pending = self.trial_steps(m, pt, d0, kink)
            if start is not None and not (pending and self._guards.tie_note(pt)):
                if m == target:
                    return [(m, start)]
                piece.append((m, start))
        return piece if len(piece) == 1 else found

    def input_still(self, t: float) -> bool:
        """Whether the input holds still just after phase t [cycles]: its rate below HOLD_RTOL times
        its largest rate over the cycle (a hold of a piecewise-linear input, to the round-off of its
        samples)."""
        if self._rate_scale is None:
            grid = np.arange(1024) / 1024
            rates = np.asarray(self._torque.derivative(grid), float)
            self._rate_scale = float(np.max(np.abs(rates)))
        rate = np.asarray(self._torque.derivative(t + 1e-9), float)
        return bool(np.max(np.abs(rate)) <= HOLD_RTOL * self._rate_scale)
