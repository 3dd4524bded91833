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

Where the input holds still (both rates zero on a piece), the state does not move: the hold is
crossed in one step and the mode after it decided by the rates after it; so is the mode at a kink or
an event where the two feet's friction limits tie (docs/guide/simulators.md, "Friction ties";
:meth:`~ocp_crawl.sim.event_modes.ModeChooser.decide`).
When mu1 f_n1 = mu2 f_n2 identically (mirror-symmetric motion, equal friction), no single-foot slip
is consistent; the stepper then uses the non-generic slip-slip mode, in which both feet are at
their friction limits and, the split of d' between the feet being statically indeterminate, each
foot takes half of it (the symmetric solution), which stands only if the one-sided friction limits
agree with it (:mod:`ocp_crawl.sim.event_ties`). It leaves slip-slip when the limits separate.

A fold is located exactly by the augmented system G(x, t) = 0, J v = 0, v0.v = 1.

At a kink of the input (a knot of piecewise-linear samples, where tau' jumps) a step ends; the state
is continuous there and the mode after it is decided by the rates after it
(:mod:`ocp_crawl.sim.event_kinks`).

The stepper is composed of parts that each get what they read at construction:

* :class:`~ocp_crawl.sim.event_context.StepperContext`: the model, the input, the options and the
  compiled functions, fixed for the stepper's life (what every part reads, none writes);
* :class:`~ocp_crawl.sim.event_kinks.InputPieces`: the kinks and holds of the input;
* :class:`~ocp_crawl.sim.event_solve.ModeSolver`: the Newton solves of a mode (counted);
* :class:`~ocp_crawl.sim.event_guards.Guards`: the guards, their rates and dips, and the transition
  table;
* :class:`~ocp_crawl.sim.event_checks.Checks`: stability and continuity of the state across events;
* :class:`~ocp_crawl.sim.event_locate.EventLocator`: events and folds located in a step;
* :class:`~ocp_crawl.sim.event_modes.ModeChooser`: the mode after an event or a decision point;
* :class:`~ocp_crawl.sim.event_switch.ModeSwitch`: the mode changes applied to the run (events,
  kinks, holds);
* :class:`~ocp_crawl.sim.event_output.ResultBuilder`: the result, with the dense output of
  :mod:`ocp_crawl.sim.event_dense` and the cycle integrals of :mod:`ocp_crawl.sim.event_quad`.

This module holds the options and the driver: the continuation step by step, through the cycles,
with the run's state in a :class:`~ocp_crawl.sim.event_state._Run`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ocp_crawl.checks import real
from ocp_crawl.model.inputs import ReferenceTorque
from ocp_crawl.model.statics import AUX, Model
from ocp_crawl.sim.assemble import no_start_result, output_phases
from ocp_crawl.sim.event_checks import Checks
from ocp_crawl.sim.event_context import StepperContext
from ocp_crawl.sim.event_dense import DenseOutput
from ocp_crawl.sim.event_guards import Guards
from ocp_crawl.sim.event_kinks import KINK_GAP, InputPieces
from ocp_crawl.sim.event_locate import EventLocator
from ocp_crawl.sim.event_modes import ModeChooser
from ocp_crawl.sim.event_output import ResultBuilder
from ocp_crawl.sim.event_quad import CycleQuadrature
from ocp_crawl.sim.event_solve import ModeSolver
from ocp_crawl.sim.event_state import Q_RELEASED, _Failure, _Outcome, _Point, _Run, _Segment, \
    hermite_point, mode_q
from ocp_crawl.sim.event_switch import ModeSwitch
from ocp_crawl.sim.event_ties import check_shared_slip
from ocp_crawl.sim.options import MAX_EVENTS_BOUNDS, MAX_STEP_BOUNDS, CycleOptions, count
from ocp_crawl.sim.result import CrawlResult, Event, Mode
from ocp_crawl.status import Status

_DET, _D = AUX["det"], AUX["d"]


@dataclass(frozen=True)
class HybridOptions(CycleOptions):
    """Options of the event-driven stepper (and the cycle options of
    :class:`~ocp_crawl.sim.options.CycleOptions`)."""

    max_step: float = 1.0 / 16
    """largest continuation step in phase [cycles].  The step does not set the accuracy (every point
    is a Newton solve, events are located to ``event_xtol``, the cycle integrals use their own
    panels); it bounds the stretch in which a guard could dip below zero and back unseen, which the
    Hermite dip test covers with its error estimate (a suspect step is halved), and
    ``resolve_input`` shortens it for fast inputs. 1/16 gives the paper gait's S, W+ and event
    phases of 1/64 to within 4e-15 with 37 instead of 133 steps"""
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
    :func:`~ocp_crawl.sim.event_kinks.input_step`), so that fast (chattering) inputs are followed
    and no event pair hides inside a step; not for an input linear between its knots
    (piecewise-linear samples, trapezoid pulses: :func:`~ocp_crawl.sim.event_kinks.linear_pieces`),
    whose steps end at every knot"""
    trial_step: float = 1e-9
    """phase step used to test the consistency of a mode after a transition"""
    quad_h: float = 1.0 / 32
    """largest Gauss-Legendre panel for the per-cycle integrals [cycles]"""
    jump_tol: float = 1e-6
    """largest change of the state (phi1, phi2 [rad], f_t/(M g)/(1 + k/(M g L)), d/L) across an
    event with a continuous input; a larger one ends the run with status ``snap_through``.  The
    state is continuous across a true event up to round-off (measured <= 4e-12 over 3,100 events of
    500 random problems), while a snap moves it by O(0.01-0.1) (>= 0.06 in the same sample)"""
    energy_tol: float = 1e-6
    """largest |energy balance residual| (relative to the gross work) of a successful steady cycle;
    a larger one is ``energy_imbalance``.  The cycle integrals are exact to the quadrature tolerance
    (residuals about 1e-13 on the paper's gaits), so a residual above 1e-6 means a missing term
    (an undetected jump, a wrong branch)"""

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in ("max_step", "min_step", "event_xtol", "residual_tol", "trial_step", "quad_h",
                     "jump_tol", "energy_tol"):
            self._set(name, real(f"HybridOptions.{name}", getattr(self, name), positive=True))
        self._set("max_step", real("HybridOptions.max_step", self.max_step, low=MAX_STEP_BOUNDS[0],
                                   high=MAX_STEP_BOUNDS[1]))
        self._set("max_events_per_cycle", count("HybridOptions.max_events_per_cycle",
                                                self.max_events_per_cycle, *MAX_EVENTS_BOUNDS))
        self._set("quad_h", real("HybridOptions.quad_h", self.quad_h, low=MAX_STEP_BOUNDS[0],
                                 high=MAX_STEP_BOUNDS[1]))
        if not isinstance(self.resolve_input, bool):
            raise ValueError("HybridOptions.resolve_input must be True or False, "
                             f"got {self.resolve_input!r}")


class HybridStepper:
    """Event-driven simulation of the torque-driven crawler.  Build once, call :meth:`run`.

    The parts (see the module docstring) are public attributes: ``ctx``, ``pieces``, ``solver``,
    ``guards``, ``checks``, ``locator``, ``modes``, ``switch`` and ``output``; ``segments`` are the
    constant-mode segments of the last run.
    """

    def __init__(self, model: Model, torque, options: HybridOptions | None = None):
        self.ctx = ctx = StepperContext.build(model, torque, options or HybridOptions())
        self.pieces = InputPieces(ctx.torque, ctx.torque_at, ctx.breakpoints)
        self.solver = ModeSolver(ctx, self.pieces)
        self.guards = Guards(ctx, self.pieces)
        self.checks = Checks(ctx)
        self.locator = EventLocator(ctx, self.solver, self.guards)
        self.modes = ModeChooser(ctx, self.solver, self.guards, self.checks, self.pieces)
        self.switch = ModeSwitch(ctx, self.solver, self.guards, self.checks, self.modes,
                                 self.pieces)
        dense = DenseOutput(ctx, self.solver)
        self.output = ResultBuilder(ctx, self.solver, dense, CycleQuadrature(ctx, dense))
        self.segments: list[_Segment] = []

    def initial_state(self, t0: float = 0.0) -> _Point:
        """Released start: the first stable equilibrium with f_t = 0 at phase t0 of
        :meth:`released_states`.

        Raises ValueError if there is none, or if the first one found is not a valid contact state,
        or if each one found is unstable (its stick-stick reduced stiffness is <= 0, see
        :meth:`~ocp_crawl.sim.event_checks.Checks.stable_start`).
        """
        return self.checks.stable_start(t0, self.released_states(t0))

    def released_states(self, t0: float = 0.0):
        """The released equilibria (f_t = 0) at phase t0, solved lazily from guesses in a fixed
        order (the input's reference angles, then blends towards 0.6 pi).  The first one found must
        be a valid contact state (ValueError otherwise); later ones (wanted only when the earlier
        ones are unstable) are skipped if they are not.  Yields points with ``x = (phi1, phi2 [rad],
        f_t/(M g) = 0)``."""
        torque, model = self.ctx.torque, self.ctx.model
        ref = torque.reference(t0) if isinstance(torque, ReferenceTorque) else \
            math.pi + torque(t0) / model.robot.k
        guesses = [np.array([ref[0], ref[1], 0.0])]
        for lam in (0.5, 0.25, 0.0):
            guesses.append(np.array([lam * ref[0] + (1 - lam) * math.pi * 0.6,
                                     lam * ref[1] + (1 - lam) * math.pi * 0.6, 0.0]))
        first = True
        for x0 in guesses:
            pt = self.solver.solve(t0, x0, Q_RELEASED)
            if pt is None:
                continue
            try:
                model.check_contact(pt.x[:2], where="starting configuration")
            except ValueError:
                if first:
                    raise
                continue
            first = False
            yield pt

    def run(self, t_eval=None) -> CrawlResult:
        """Simulate cycles from a released start until the gait is periodic; report the steady
        cycle.

        ``t_eval``: optional phases in [0, 1] (relative to the start of the steady cycle) for the
        output arrays; by default 201 equally spaced phases plus the event phases.  A failed run
        reports the accepted steps and events up to the failure.
        """
        te = output_phases(t_eval)
        self.solver.reset()
        try:
            run = self._start_run(self.initial_state(0.0))
        except ValueError as exc:
            self.segments = []
            return no_start_result(self.ctx.model, str(exc), nfev=self.solver.nfev,
                                   extra={"segments": 0})
        try:
            end = _Outcome(Status.SUCCESS, periodic_at=self._run_cycles(run))
        except _Failure as f:
            end = _Outcome(f.status, f.detail, f.t, f.mode.label)
            run.extra.update(f.extra)
        try:
            res = self.output.build(run, end, te)
        except _Failure as f:
            # the output or the cycle integrals need a solve that fails: report it, with the steps
            # so far
            run.extra.update(f.extra)
            failed = _Outcome(f.status, f"{f.detail} (output of the result)", f.t, f.mode.label)
            res = self.output.build(run, failed, None)
        self.segments = run.segments
        return res

    def cycle_energy(self, cycle: int) -> dict:
        """Energy balance [J] of cycle ``cycle`` (0-based) of the last run: input work, potential
        change, dissipation."""
        return self.output.cycle_energy(self.segments, cycle)

    def _start_run(self, start: _Point) -> _Run:
        """The run's first segment: stick-stick from the released start, with the stick distance d0
        [m] there."""
        d0 = start.aux[_D]
        seg = _Segment(Mode.STICK, mode_q(Mode.STICK, d0), 0.0, d0)
        pt = self.solver.solve(0.0, start.x, seg.q)
        if pt is None:  # a NO_START status, as a start that does not release
            raise ValueError("the released start does not solve in stick-stick at t = 0")
        seg.points.append(pt)
        return _Run(seg, pt, self.ctx.max_step, np.sign(pt.aux[_DET]) or 1.0, [seg])

    def _run_cycles(self, run: _Run) -> int:
        """Run cycles until the state at a cycle's end repeats; returns the number of cycles
        then."""
        states = [(run.pt, run.seg.mode)]
        while True:
            self._advance_cycle(run)
            run.cycle += 1
            run.events_in_cycle = 0
            states.append((run.pt, run.seg.mode))
            (pa, ma), (pb, mb) = states[-2], states[-1]
            dev = max(np.max(np.abs(pa.x[:2] - pb.x[:2])), abs(pa.x[2] - pb.x[2]))
            verdict = self.ctx.opt.cycle_verdict(run.cycle, dev, ma == mb)
            if verdict:
                run.extra["periodicity_deviation"] = float(dev)
                return run.cycle
            if verdict is False:
                raise _Failure(Status.NOT_PERIODIC, run.pt.t, run.seg.mode,
                               f"not periodic after {run.cycle} cycles "
                               f"(last change {np.max(np.abs(pa.x - pb.x)):.3g})")

    def _step_end(self, run: _Run, t_end: float) -> tuple[float, bool] | None:
        """The end of the next step from run.pt, before t_end (the end of the cycle), and whether it
        is at a kink of the input (where a step ends); None when a hold of the input was crossed
        instead (:meth:`~ocp_crawl.sim.event_switch.ModeSwitch.cross_hold`)."""
        pt, pieces = run.pt, self.pieces
        t_new = min(pt.t + run.h, t_end)
        if pieces.held:  # (a hold is crossed in one step, and a step ends where one starts)
            if self.switch.cross_hold(run, t_end):
                return None
            t_new = min(t_new, pieces.next_hold(pt.t))
        if t_end - t_new < 1e-12:
            t_new = t_end
        at_kink = False
        if pieces.kinked:  # a step ends at the next kink of the input
            kink = pieces.next_kink(pt.t)
            at_kink = kink - t_new < 1e-12
            if at_kink:
                t_new = kink
        return t_new, at_kink

    def _advance_cycle(self, run: _Run) -> None:
        """Continue the equilibrium to the end of the current cycle, through its events."""
        t_end = float(run.cycle + 1)
        while run.pt.t < t_end - 1e-15:
            pt, seg, h = run.pt, run.seg, run.h
            step = self._step_end(run, t_end)
            if step is None:
                continue
            t_new, at_kink = step
            hh = t_new - pt.t
            new = self._continuation_step(run, t_new, hh, at_kink)
            if new is None:
                continue
            run.nsteps += 1
            new, crossed, refine = self._crossings(seg, pt, new)
            if crossed and self.pieces.held:
                crossed = self.switch.not_at_hold(seg, pt, new, crossed)
            if refine and not crossed and hh > 1e-5:
                run.h = hh / 2
                continue
            if not crossed:
                self.checks.require_stable(new, seg.mode, seg.q, "along the branch")
                run.pt = new
                seg.points.append(new)
                run.h = min(self.ctx.max_step, 2 * h) if hh >= h * 0.999 else h
                if at_kink:
                    self.switch.pass_kink(run)
                continue
            self._take_event(run, new, crossed)

    def _continuation_step(self, run: _Run, t_new: float, hh: float,
                           left: bool = False) -> _Point | None:
        """The mode's solution at t_new from the current point, or None after shrinking the step
        when the solve fails, jumps or crosses a fold (a fold close enough is located and ends the
        run). ``left``: t_new is a kink of the input, solved with the rate before it (the end of the
        step's piece)."""
        pt, seg = run.pt, run.seg
        assert pt is not None  # a run has a point from its start on
        px, xd = pt.xl, pt.xdl
        gx = [px[0] + hh * xd[0], px[1] + hh * xd[1], px[2] + hh * xd[2]]  # (as pt.x + hh pt.x')
        new = self.solver.solve(t_new, gx, seg.q, step=True, left=left)
        ok = new is not None
        if new is not None:
            nx = new.xl
            jump = max(abs(nx[0] - gx[0]), abs(nx[1] - gx[1]))
            ok = jump <= 0.05 + 0.5 * max(abs(gx[0] - px[0]), abs(gx[1] - px[1])) and \
                max(abs(nx[0] - px[0]), abs(nx[1] - px[1])) < 0.35
        if ok and new is not None:
            det = new.a[_DET]
            # (else it crossed a fold onto another branch: locate it)
            ok = (det > 0) - (det < 0) == run.det_sign
        if ok:
            return new
        if hh < 1e-3:
            fold = self.locator.fold(pt, seg.q, t_new)
            if fold is not None and fold[0] <= t_new + 1e-12 and fold[2] < 1e-6:
                run.events.append(Event(fold[0], "fold", seg.mode.label, "failure", fold[2], "det"))
                raise _Failure(Status.FOLD, fold[0], seg.mode,
                               f"fold of the {seg.mode.label} equilibrium branch",
                               {"fold_x": fold[1].tolist(), "fold_sigma_ratio": fold[2]})
        run.h = hh / 4
        min_step = self.ctx.opt.min_step
        if run.h < min_step:
            raise _Failure(Status.NO_CONVERGENCE, pt.t, seg.mode,
                           f"continuation step fell below {min_step:g} cycles")
        return None

    def _crossings(self, seg: _Segment, pt: _Point, new: _Point) -> tuple[_Point, list[str], bool]:
        """Guards that cross zero in the step [pt, new]: (end of the step, crossed guards, whether
        to refine).

        A guard dipping below zero and back inside the step (possibly before another guard's
        crossing), which the sign test at its ends misses, ends the step inside the dip.
        """
        guards = self.guards
        g_old = guards.at(seg.mode, pt)
        g_new = guards.at(seg.mode, new)
        floor = -100 * self.ctx.noise
        crossed = [k for k, v in g_new.items() if v < 0 and g_old[k] > floor]
        dips, refine = guards.dips(seg.mode, seg.q, pt, new, g_old, g_new)
        for name, t_min in dips:
            pm = self.solver.solve(t_min, hermite_point(pt, new, t_min), seg.q)
            if pm is None:
                refine = True
                break
            g_min = guards.at(seg.mode, pm)
            in_dip = [k for k, v in g_min.items() if v < 0 and g_old[k] > floor]
            if in_dip:
                new, crossed = pm, in_dip  # the step now ends inside the dip
                break
            if g_min[name] > 100 * self.ctx.noise:
                refine = True  # the interpolant was not accurate enough there
        return new, crossed, refine

    def _take_event(self, run: _Run, new: _Point, crossed: list[str]) -> None:
        """Locate the first of the crossed guards, record the event and start the successor mode's
        segment."""
        pt, seg = run.pt, run.seg
        (t_ev, ev_pt), kind = self.locator.first_crossing(pt, new, seg, crossed)
        if ev_pt is None:
            raise _Failure(Status.NO_CONVERGENCE, t_ev, seg.mode, "mode solve failed at an event")
        if new.left and new.t - t_ev <= KINK_GAP:
            # located at the kink that ends the step (to round-off): the event is at the kink, where
            # the rates after it decide the successor
            run.pt = new
            seg.points.append(new)
            self.switch.pass_kink(run, kind)
            return
        if ev_pt.t > pt.t:
            seg.points.append(ev_pt)
        self.switch.enter(run, ev_pt, kind, t_ev)


def simulate_torque(model: Model, torque, options: HybridOptions | None = None,
                    t_eval=None) -> CrawlResult:
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
        events of the steady cycle, trajectories; a failure (fold, lift-off, not periodic, ...) is a
        status. A gait in which the feet share a slip at a tie of equal friction limits stands only
        if the one-sided friction limits agree with it (:mod:`ocp_crawl.sim.event_ties`), else its
        status is ``set_valued``.
    """
    res = HybridStepper(model, torque, options).run(t_eval=t_eval)
    return check_shared_slip(res, model, lambda m: HybridStepper(m, torque, options).run())
