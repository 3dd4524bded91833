"""Event-driven hybrid-quasistatic stepper for prescribed torques (paper Section II-B).

The robot is tracked along its equilibrium branch by continuation in the phase t (cycles).
In each contact mode the configuration solves three equations in x = (phi1, phi2, f_t/(M g)):
the joint balance F = 0 and one mode equation (stick-stick: d = d0; slip of foot i with
sign(d') = sigma: f_t = sigma mu_i f_n,i).  Every point is a Newton solve of the compiled
mode system (no integration drift); events are guard functions of the mode, detected by a
sign change between steps, located by a safeguarded Newton method on the guard of the solved state
(xtol 1e-13 in phase) and applied by a transition table:

=============  ==========================================  ======================
mode           guard (positive inside)                     on zero
=============  ==========================================  ======================
stick-stick    mu_i f_n,i - sigma f_t  (i = 1, 2; +-)        slip of foot i, sign(d') = sigma
slip i, sigma  sigma d'                                     stick-stick (d0 = d)
slip i, sigma  mu_j f_n,j - mu_i f_n,i                       slip of foot j, same sigma
any            f_n,1, f_n,2                                 lift-off (failure status)
any            d                                            feet crossing (failure status)
any            det J (sign of the mode's start)              fold (failure status)
=============  ==========================================  ======================

Where the input holds still (both rates zero on a piece), the state does not move: the hold is crossed in
one step and the mode after it decided by the rates after it; so is the mode at a kink or an event where the
two feet's friction limits tie (docs/guide/simulators.md, "Friction ties";
:meth:`~ocp_crawl.sim.event_locate.EventsMixin._decide`).
When mu1 f_n1 = mu2 f_n2 identically (mirror-symmetric motion, equal friction), no single-foot slip
is consistent; the stepper then uses the non-generic slip-slip mode, in which both feet are at
their friction limits and, the split of d' between the feet being statically indeterminate, each
foot takes half of it (the symmetric solution), which stands only if the one-sided friction limits
agree with it (:mod:`ocp_crawl.sim.event_ties`). It leaves slip-slip when the limits separate.

A fold is located exactly by the augmented system G(x, t) = 0, J v = 0, v0.v = 1.

At a kink of the input (a knot of piecewise-linear samples, where tau' jumps) a step ends; the state is
continuous there and the mode after it is decided by the rates after it (:mod:`ocp_crawl.sim.event_kinks`).

This module holds the options, the continuation and the cycle loop; the guards and the transition
table are in :mod:`ocp_crawl.sim.event_guards`, event and fold location in
:mod:`ocp_crawl.sim.event_locate`, dense output and the cycle integrals in
:mod:`ocp_crawl.sim.event_output`, the points and segments in :mod:`ocp_crawl.sim.event_state`, and the physical checks (stability of the
start, of every mode after an event and of every accepted step; continuity of the state across events;
see :mod:`ocp_crawl.sim.event_checks`) in their own module.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ocp_crawl.checks import real
from ocp_crawl.model.inputs import PeriodicSignal, ReferenceTorque, as_signal, merged_knots
from ocp_crawl.model.stability import fast_step
from ocp_crawl.model.statics import AUX, NAUX, Model, fast_ddot2, fast_newton, symbolic
from ocp_crawl.sim.assemble import no_start_result, output_phases
from ocp_crawl.sim.event_checks import ChecksMixin
from ocp_crawl.sim.event_guards import GuardsMixin
from ocp_crawl.sim.event_kinks import KINK_GAP, KinksMixin, linear_pieces, step_limit
from ocp_crawl.sim.event_locate import EventsMixin, guard_noise
from ocp_crawl.sim.event_output import OutputMixin
from ocp_crawl.sim.event_state import Q_RELEASED, _Failure, _LeftPoint, _Point, _Run, _Segment, event_kind, \
    hermite_point, mode_q, torque_pair
from ocp_crawl.sim.event_ties import check_shared_slip
from ocp_crawl.sim.options import MAX_EVENTS_BOUNDS, MAX_STEP_BOUNDS, CycleOptions, count
from ocp_crawl.sim.result import CrawlResult, Event, Mode
from ocp_crawl.status import Status

_RES, _DET, _D = AUX["res"], AUX["det"], AUX["d"]
#: positions in the flat output (x (3), aux (NAUX)[, extra]) of a compiled solve: the residual, the end of aux
_RES3, _EXTRA3 = 3 + _RES, 3 + NAUX


@dataclass(frozen=True)
class HybridOptions(CycleOptions):
    """Options of the event-driven stepper (and the cycle options of :class:`~ocp_crawl.sim.options.CycleOptions`)."""

    max_step: float = 1.0 / 16
    """largest continuation step in phase [cycles].  The step does not set the accuracy (every point is a
    Newton solve, events are located to ``event_xtol``, the cycle integrals use their own panels); it bounds
    the stretch in which a guard could dip below zero and back unseen, which the Hermite dip test covers
    with its error estimate (a suspect step is halved), and ``resolve_input`` shortens it for fast inputs.
    1/16 gives the paper gait's S, W+ and event phases of 1/64 to within 4e-15 with 37 instead of 133 steps"""
    min_step: float = 1e-11
    """smallest continuation step before giving up [cycles]"""
    event_xtol: float = 1e-13
    """tolerance of event location in phase [cycles]"""
    residual_tol: float = 1e-10
    """largest accepted scaled residual |G|_inf of a mode solve"""
    max_events_per_cycle: int = 200
    """events allowed in one cycle before the run ends with status ``too_many_events``"""
    resolve_input: bool = True
    """limit the step to 1/8 of the period of the input's fastest significant harmonic (see
    :func:`~ocp_crawl.sim.event_kinks.input_step`), so that fast (chattering) inputs are followed and no event
    pair hides inside a step; not for an input linear between its knots (piecewise-linear samples,
    trapezoid pulses: :func:`~ocp_crawl.sim.event_kinks.linear_pieces`), whose steps end at every knot"""
    trial_step: float = 1e-9
    """phase step used to test the consistency of a mode after a transition"""
    quad_h: float = 1.0 / 32
    """largest Gauss-Legendre panel for the per-cycle integrals [cycles]"""
    jump_tol: float = 1e-6
    """largest change of the state (phi1, phi2 [rad], f_t/(M g)/(1 + k/(M g L)), d/L) across an event with a
    continuous input; a larger one ends the run with status ``snap_through``.  The state is continuous
    across a true event up to round-off (measured <= 4e-12 over 3,100 events of 500 random problems),
    while a snap moves it by O(0.01-0.1) (>= 0.06 in the same sample)"""
    energy_tol: float = 1e-6
    """largest |energy balance residual| (relative to the gross work) of a successful steady cycle;
    a larger one is ``energy_imbalance``.  The cycle integrals are exact to the quadrature tolerance
    (residuals about 1e-13 on the paper's gaits), so a residual above 1e-6 means a missing term
    (an undetected jump, a wrong branch)"""

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in ("max_step", "min_step", "event_xtol", "residual_tol", "trial_step", "quad_h", "jump_tol",
                     "energy_tol"):
            self._set(name, real(f"HybridOptions.{name}", getattr(self, name), positive=True))
        self._set("max_step", real("HybridOptions.max_step", self.max_step, low=MAX_STEP_BOUNDS[0],
                                   high=MAX_STEP_BOUNDS[1]))
        self._set("max_events_per_cycle", count("HybridOptions.max_events_per_cycle", self.max_events_per_cycle,
                                                *MAX_EVENTS_BOUNDS))
        self._set("quad_h", real("HybridOptions.quad_h", self.quad_h, low=MAX_STEP_BOUNDS[0], high=MAX_STEP_BOUNDS[1]))
        if not isinstance(self.resolve_input, bool):
            raise ValueError(f"HybridOptions.resolve_input must be True or False, got {self.resolve_input!r}")


class HybridStepper(GuardsMixin, EventsMixin, OutputMixin, ChecksMixin, KinksMixin):
    """Event-driven simulation of the torque-driven crawler.  Build once, call :meth:`run`."""

    def __init__(self, model: Model, torque, options: HybridOptions | None = None):
        self.model = model
        self.torque: PeriodicSignal = as_signal(torque)
        self.torque_at = torque_pair(self.torque)
        self._torque_values = self.torque_at.values
        self.opt = options or HybridOptions()
        self.sym = symbolic()
        self.newton = fast_newton()
        self.ddot2 = fast_ddot2()
        self.step_fn = fast_step()
        self.p = model.p
        self.p_list = np.asarray(model.p, float).ravel().tolist()
        self.Mg = model.robot.M * model.robot.g
        self.L = model.robot.L
        self.nfev = 0
        self.nsteps = 0
        self._noise_table: dict = {}
        self._tails: dict = {}
        """id(q) -> (q, the solves' last inputs (q, p) as a list) of the mode parameters q of the run (see _solve)"""
        # round-off level of the scaled guards: the mode equations are scaled by M g L, so the
        # conditioning (and the noise in f_t) grows with k/(M g L)
        self.noise = 1e-13 * (1.0 + model.robot.k / model.robot.MgL)
        # accepted residual of a mode solve: residual_tol, or 10 noise when the stiffness makes the
        # round-off floor of the scaled joint balance (about 1e-16 k/(M g L)) reach it (stiff limit)
        self.res_tol = max(self.opt.residual_tol, 10 * self.noise)
        self.mu = (model.robot.mu1, model.robot.mu2)
        self.max_step = self.opt.max_step
        # phases where a sampled input's derivative may have a kink (its knots): quadrature panel edges
        signal = self.torque.reference if isinstance(self.torque, ReferenceTorque) else self.torque
        self.breakpoints = merged_knots(getattr(signal, "t_knots", np.zeros(0)))
        self._init_kinks()  # (those where the torque's rate jumps: the continuation stops there)
        self._init_holds()  # (where it holds still: crossed in one step, the mode decided at the end)
        if self.opt.resolve_input and not linear_pieces(self.torque, self.breakpoints):
            self.max_step = min(self.max_step, max(step_limit(self.torque), self.max_step / 64))

    # ------------------------------------------------------------------ primitive evaluations
    def _solve(self, t: float, x0: np.ndarray | list, q: np.ndarray, step: bool = False,
               left: bool = False, held: bool = False) -> _Point | None:
        """Newton solve of the mode q at phase t from x0 (an array or a list); None if it does not converge.
        ``step``: a continuation step, solved by :func:`~ocp_crawl.model.stability.fast_step` (the point then
        carries its stability numbers and d'' coefficients).  At a kink of the input the rates are those after
        it, or before it with ``left`` (:mod:`ocp_crawl.sim.event_kinks`); ``held``: with the rates of a hold (zero)."""
        tq = self._torque_values(float(t)) if not left else self.kink_values(t, True) or self._torque_values(float(t))
        if held:
            tq = tq[:2] + [0.0, 0.0]
        fn, tol = self.step_fn if step else self.newton, self.res_tol
        tail = self._tails.get(id(q))
        if tail is None or tail[0] is not q:  # (q, its inputs q and p as a list, kept in the compiled buffer)
            tail = self._tails[id(q)] = (q, q.tolist() + self.p_list)
        xl = x0 if type(x0) is list else x0.tolist()
        for _ in range(4):
            out = fn.flat(xl + tq, tail[1])  # x (3), aux (NAUX)[, extra]
            self.nfev += 1
            lst = out.tolist()
            xl, res = lst[:3], lst[_RES3]
            if not math.isfinite(xl[0] + xl[1] + xl[2]):  # (the compiled max norm of a NaN residual can read 0)
                return None
            if not res <= tol:  # also catches NaN
                if not math.isfinite(res) or res > 1e3:
                    return None
                continue
            return (_LeftPoint if left else _Point)(t, out[:3], out[3:_EXTRA3], tau=tq[:2], dtau=tq[2:], q=q,
                                                    extra=out[_EXTRA3:] if step else None, a=lst[3:_EXTRA3], xl=xl)
        return None

    def initial_state(self, t0: float = 0.0) -> _Point:
        """Released start: the first stable equilibrium with f_t = 0 at phase t0 of :meth:`released_states`.

        Raises ValueError if there is none, or if the first one found is not a valid contact state, or if
        each one found is unstable (its stick-stick reduced stiffness is <= 0, see
        :meth:`~ocp_crawl.sim.event_checks.ChecksMixin.stable_start`).
        """
        return self.stable_start(t0, self.released_states(t0))

    def released_states(self, t0: float = 0.0):
        """The released equilibria (f_t = 0) at phase t0, solved lazily from guesses in a fixed order (the
        input's reference angles, then blends towards 0.6 pi).  The first one found must be a valid contact
        state (ValueError otherwise); later ones (wanted only when the earlier ones are unstable) are
        skipped if they are not.  Yields points with ``x = (phi1, phi2 [rad], f_t/(M g) = 0)``."""
        ref = self.torque.reference(t0) if isinstance(self.torque, ReferenceTorque) else \
            math.pi + self.torque(t0) / self.model.robot.k
        guesses = [np.array([ref[0], ref[1], 0.0])]
        for lam in (0.5, 0.25, 0.0):
            guesses.append(np.array([lam * ref[0] + (1 - lam) * math.pi * 0.6, lam * ref[1] + (1 - lam) * math.pi * 0.6, 0.0]))
        first = True
        for x0 in guesses:
            pt = self._solve(t0, x0, Q_RELEASED)
            if pt is None:
                continue
            try:
                self.model.check_contact(pt.x[:2], where="starting configuration")
            except ValueError:
                if first:
                    raise
                continue
            first = False
            yield pt

    def run(self, t_eval=None) -> CrawlResult:
        """Simulate cycles from a released start until the gait is periodic; report the steady cycle.

        ``t_eval``: optional phases in [0, 1] (relative to the start of the steady cycle) for the
        output arrays; by default 201 equally spaced phases plus the event phases.  A failed run
        reports the accepted steps and events up to the failure.
        """
        te = output_phases(t_eval)
        self.nfev = 0
        self.nsteps = 0
        self._tails.clear()
        try:
            start = self.initial_state(0.0)
        except ValueError as exc:
            self._segments = []
            return no_start_result(self.model, str(exc), nfev=self.nfev, extra={"segments": 0})
        run = self._start_run(start)
        status, detail, fail_t, fail_mode, periodic_at = Status.SUCCESS, "", None, None, None
        try:
            periodic_at = self._run_cycles(run)
        except _Failure as f:
            status, detail, fail_t, fail_mode = f.status, f.detail, f.t, f.mode.label
            run.extra.update(f.extra)
        try:
            return self._build_result(run, status, detail, fail_t, fail_mode, periodic_at, te)
        except _Failure as f:
            # the output or the cycle integrals need a solve that fails: report it, with the steps so far
            run.extra.update(f.extra)
            return self._build_result(run, f.status, f"{f.detail} (output of the result)", f.t, f.mode.label,
                                      None, None)

    def _start_run(self, start: _Point) -> _Run:
        """The run's first segment: stick-stick from the released start, with the stick distance d0 [m] there."""
        d0 = start.aux[AUX["d"]]
        seg = _Segment(Mode.STICK, mode_q(Mode.STICK, d0), 0.0, d0)
        pt = self._solve(0.0, start.x, seg.q)
        seg.points.append(pt)
        return _Run(seg, pt, self.max_step, np.sign(pt.aux[AUX["det"]]) or 1.0, [seg])

    def _run_cycles(self, run: _Run) -> int:
        """Run cycles until the state at a cycle's end repeats; returns the number of cycles then."""
        states = [(run.pt, run.seg.mode)]
        while True:
            self._advance_cycle(run)
            run.cycle += 1
            run.events_in_cycle = 0
            states.append((run.pt, run.seg.mode))
            (pa, ma), (pb, mb) = states[-2], states[-1]
            dev = max(np.max(np.abs(pa.x[:2] - pb.x[:2])), abs(pa.x[2] - pb.x[2]))
            verdict = self.opt.cycle_verdict(run.cycle, dev, ma == mb)
            if verdict:
                run.extra["periodicity_deviation"] = float(dev)
                return run.cycle
            if verdict is False:
                raise _Failure(Status.NOT_PERIODIC, run.pt.t, run.seg.mode, f"not periodic after {run.cycle} cycles "
                               f"(last change {np.max(np.abs(pa.x - pb.x)):.3g})")

    def _advance_cycle(self, run: _Run) -> None:
        """Continue the equilibrium to the end of the current cycle, through its events."""
        t_end = float(run.cycle + 1)
        while run.pt.t < t_end - 1e-15:
            pt, seg, h = run.pt, run.seg, run.h
            t_new = min(pt.t + h, t_end)
            if self._hold_list:  # (a hold is crossed in one step, and a step ends where one starts)
                if self._cross_hold(run, t_end):
                    continue
                t_new = min(t_new, self.next_hold(pt.t))
            if t_end - t_new < 1e-12:
                t_new = t_end
            at_kink = False
            if self._kink_list:  # a step ends at the next kink of the input
                kink = self.next_kink(pt.t)
                at_kink = kink - t_new < 1e-12
                if at_kink:
                    t_new = kink
            hh = t_new - pt.t
            new = self._continuation_step(run, t_new, hh, at_kink)
            if new is None:
                continue
            self.nsteps += 1
            new, crossed, refine = self._crossings(seg, pt, new)
            if crossed and self._hold_list:
                crossed = self._not_at_hold(seg, pt, new, crossed)
            if refine and not crossed and hh > 1e-5:
                run.h = hh / 2
                continue
            if not crossed:
                self._require_stable(new, seg.mode, seg.q, "along the branch")
                run.pt = new
                seg.points.append(new)
                run.h = min(self.max_step, 2 * h) if hh >= h * 0.999 else h
                if at_kink:
                    self._pass_kink(run)
                continue
            self._take_event(run, new, crossed)

    def _continuation_step(self, run: _Run, t_new: float, hh: float, left: bool = False) -> _Point | None:
        """The mode's solution at t_new from the current point, or None after shrinking the step when
        the solve fails, jumps or crosses a fold (a fold close enough is located and ends the run).
        ``left``: t_new is a kink of the input, solved with the rate before it (the end of the step's piece)."""
        pt, seg = run.pt, run.seg
        px, xd = pt.xl, pt.xdl
        gx = [px[0] + hh * xd[0], px[1] + hh * xd[1], px[2] + hh * xd[2]]  # (as pt.x + hh pt.x')
        new = self._solve(t_new, gx, seg.q, step=True, left=left)
        ok = new is not None
        if ok:
            nx = new.xl
            jump = max(abs(nx[0] - gx[0]), abs(nx[1] - gx[1]))
            ok = jump <= 0.05 + 0.5 * max(abs(gx[0] - px[0]), abs(gx[1] - px[1])) and \
                max(abs(nx[0] - px[0]), abs(nx[1] - px[1])) < 0.35
        if ok:
            det = new.a[_DET]
            ok = (det > 0) - (det < 0) == run.det_sign  # else it crossed a fold onto another branch: locate it
        if ok:
            return new
        if hh < 1e-3:
            fold = self._locate_fold(pt, seg.q, t_new)
            if fold is not None and fold[0] <= t_new + 1e-12 and fold[2] < 1e-6:
                run.events.append(Event(fold[0], "fold", seg.mode.label, "failure", fold[2], "det"))
                raise _Failure(Status.FOLD, fold[0], seg.mode, f"fold of the {seg.mode.label} equilibrium branch",
                               {"fold_x": fold[1].tolist(), "fold_sigma_ratio": fold[2]})
        run.h = hh / 4
        if run.h < self.opt.min_step:
            raise _Failure(Status.NO_CONVERGENCE, pt.t, seg.mode,
                           f"continuation step fell below {self.opt.min_step:g} cycles")
        return None

    def _crossings(self, seg: _Segment, pt: _Point, new: _Point) -> tuple[_Point, list[str], bool]:
        """Guards that cross zero in the step [pt, new]: (end of the step, crossed guards, whether to refine).

        A guard dipping below zero and back inside the step (possibly before another guard's
        crossing), which the sign test at its ends misses, ends the step inside the dip.
        """
        g_old = self.point_guards(seg.mode, pt)
        g_new = self.point_guards(seg.mode, new)
        floor = -100 * self.noise
        crossed = [k for k, v in g_new.items() if v < 0 and g_old[k] > floor]
        dips, refine = self._dips(seg.mode, seg.q, pt, new, g_old, g_new)
        for name, t_min in dips:
            pm = self._solve(t_min, hermite_point(pt, new, t_min), seg.q)
            if pm is None:
                refine = True
                break
            g_min = self.point_guards(seg.mode, pm)
            in_dip = [k for k, v in g_min.items() if v < 0 and g_old[k] > floor]
            if in_dip:
                new, crossed = pm, in_dip  # the step now ends inside the dip
                break
            if g_min[name] > 100 * self.noise:
                refine = True  # the interpolant was not accurate enough there
        return new, crossed, refine

    def _take_event(self, run: _Run, new: _Point, crossed: list[str]) -> None:
        """Locate the first of the crossed guards, record the event and start the successor mode's segment."""
        pt, seg = run.pt, run.seg
        (t_ev, ev_pt), kind = self._first_crossing(pt, new, seg, crossed)
        if ev_pt is None:
            raise _Failure(Status.NO_CONVERGENCE, t_ev, seg.mode, "mode solve failed at an event")
        if new.left and new.t - t_ev <= KINK_GAP:
            # located at the kink that ends the step (to round-off): the event is at the kink, where the rates
            # after it decide the successor
            run.pt = new
            seg.points.append(new)
            self._pass_kink(run, kind)
            return
        if ev_pt.t > pt.t:
            seg.points.append(ev_pt)
        self._enter(run, ev_pt, kind, t_ev)

    def _pass_kink(self, run: _Run, kind: str | None = None) -> None:
        """At a kink of the input (run.pt, solved with the rate before it): the same state with the rate after it
        continues the segment, unless a guard that was positive before the kink is negative after it (sigma d'
        of a slip that stops or reverses exactly there), or ``kind`` names a guard found at zero there: then that
        event happens at the kink, and the successor mode is decided by the rates after it
        (:mod:`ocp_crawl.sim.event_kinks`)."""
        pt, seg = run.pt, run.seg
        right = self._solve(pt.t, pt.xl, seg.q, step=True)
        if right is None:
            raise _Failure(Status.NO_CONVERGENCE, pt.t, seg.mode, "mode solve failed at a kink of the input")
        run.pt = right
        if self.tie_note(right) and self.hold_at(pt.t) is None:  # (at tied limits the rates after it decide)
            self._apply_decision(run, right, "at a kink of the input where the friction limits tie")
            return
        g, g_left = self.point_guards(seg.mode, right), self.point_guards(seg.mode, pt)
        jumped = [kind] if kind else [k for k, v in g.items()
                                      if v < -100 * guard_noise(k, self.noise) and g_left[k] >= 0]
        if jumped:
            self._enter(run, right, jumped[0], pt.t)

    def _enter(self, run: _Run, ev_pt: _Point, kind: str, t_ev: float) -> None:
        """Record the event ``kind`` at t_ev (state ev_pt, of the current segment's mode) and start the successor
        mode's segment, or end the run with the table's failure status."""
        seg = run.seg
        g_ev = self.point_guards(seg.mode, ev_pt)[kind]
        target = self._transition(seg.mode, kind)
        if isinstance(target, Status):
            run.events.append(Event(t_ev, event_kind(kind), seg.mode.label, "failure", g_ev, kind))
            raise _Failure(target, t_ev, seg.mode, f"{kind.replace('_', ' ')}")
        chosen, trial, kind_out = self._successor(seg.mode, target, kind, ev_pt, t_ev)
        self._start_mode(run, ev_pt, t_ev, chosen, trial, kind_out, g_ev, kind)

    def _start_mode(self, run: _Run, ev_pt: _Point, t_ev: float, chosen: Mode, trial: _Point, kind_out: str,
                    g_ev: float, guard: str) -> None:
        """Record the event ``kind_out`` (located by ``guard``, of value g_ev) at t_ev and start the segment of the
        successor ``chosen`` from ``trial``, its start at the event's state ev_pt, after the jump and stability
        checks."""
        seg = run.seg
        run.events.append(Event(t_ev, kind_out, seg.mode.label, chosen.label, g_ev, guard))
        self._check_jump(ev_pt, trial, seg.mode, chosen, kind_out)
        # (trial.q: mode_q(chosen, d at the event))
        self._require_stable(trial, chosen, trial.q, f"after the event {kind_out}")
        run.events_in_cycle += 1
        if run.events_in_cycle > self.opt.max_events_per_cycle:
            raise _Failure(Status.TOO_MANY_EVENTS, t_ev, chosen,
                           f"more than {self.opt.max_events_per_cycle} events in cycle {run.cycle + 1}")
        x1, x2 = seg.feet(ev_pt.a[_D])
        run.seg = _Segment(chosen, trial.q, x1, x2, [trial])
        run.segments.append(run.seg)
        run.pt = trial
        run.det_sign = np.sign(trial.aux[AUX["det"]]) or 1.0
        run.h = self.max_step

    def _successor(self, mode: Mode, target: Mode, kind: str, ev_pt: _Point, t_ev: float) -> tuple[Mode, _Point, str]:
        """The mode after the event ``kind`` at ev_pt: the table's successor ``target`` if it is consistent,
        else the one other consistent mode (the current one for a grazing event), or of several the one that starts
        from the event's state without a jump (:meth:`_jump`); with a kink of the input inside the trial steps, the
        mode consistent on the piece before it if that one is not or none is (:meth:`_before_kink`); where that
        leaves no mode or several at tied friction limits, the rule of :meth:`_tie_successor`; (mode, its start,
        event kind)."""
        new_d0 = ev_pt.aux[AUX["d"]]
        trial = self._consistent(target, ev_pt, new_d0)
        found = [(target, trial)] if trial is not None else \
            [(m, tr) for m in Mode if m != target and (tr := self._consistent(m, ev_pt, new_d0)) is not None]
        if len(found) > 1 and not self._input_jumps(t_ev):  # (e.g. at a kink of the input) a mode that continues
            found = [f for f in found if self._jump(ev_pt, f[1])[0] <= self.opt.jump_tol] or found  # the state wins
        found = self._before_kink(target, ev_pt, new_d0, found)
        if len(found) != 1 and self.tie_note(ev_pt) and not self._input_jumps(t_ev):
            tied = self._tie_successor(mode, kind, ev_pt)  # (at tied limits: the rule of _decide)
            if tied:
                return tied
        if len(found) != 1:
            raise _Failure(Status.NO_CONSISTENT_MODE, t_ev, mode, f"after event {kind}: {len(found)} consistent "
                           f"successor modes (table successor {target.label} is inconsistent){self.tie_note(ev_pt)}")
        chosen, trial = found[0]
        return chosen, trial, f"graze_{event_kind(kind)}" if chosen == mode != target else event_kind(kind)


def simulate_torque(model: Model, torque, options: HybridOptions | None = None, t_eval=None) -> CrawlResult:
    """Event-driven hybrid-quasistatic simulation of a torque-driven gait (see module docstring).

    The same as ``simulate(model, torque, "event", options, t_eval)``.

    Parameters
    ----------
    model : Model
        The robot and the gravity convention.
    torque : PeriodicSignal or callable
        1-periodic joint torques tau(t) = (tau1, tau2) [N m] of the phase t [cycles], e.g.
        ``ReferenceTorque(Harmonic.from_degrees(90, 30, 45), robot.k)``.
    options : HybridOptions, optional
        Step size, event tolerance, cycle limits, ... (None: the defaults).
    t_eval : array_like of float, optional
        Output phases in [0, 1] of the steady cycle [cycles]; None: the solver's steps and events.

    Returns
    -------
    CrawlResult
        Runs cycles from a released start until the gait is periodic: S [m], W+ [J], CoT+ [-], the
        events of the steady cycle, trajectories; a failure (fold, lift-off, not periodic, ...) is a status.
        A gait in which the feet share a slip at a tie of equal friction limits stands only if the one-sided
        friction limits agree with it (:mod:`ocp_crawl.sim.event_ties`), else its status is ``set_valued``.
    """
    res = HybridStepper(model, torque, options).run(t_eval=t_eval)
    return check_shared_slip(res, model, lambda m: HybridStepper(m, torque, options).run())
