"""Torque-driven hybrid-quasistatic motion of an n-link chain (the event-driven stepper of
:mod:`ocp_crawl.sim.event` for any n >= 3).

The chain follows its equilibrium branch by continuation in the phase t [cycles]: in each contact
mode every point is a Newton solve of :meth:`~ocp_crawl.model.chain_model.ChainModel.solve` from
the tangent predictor of the previous point, with an adaptive step (a guard that dips below zero
and back inside a step is found by its Hermite interpolant; a step in which a contact's guard nears
zero is halved).  Guards (positive while the mode holds,
:meth:`~ocp_crawl.sim.chain_torque_parts.ChainSolver.guards`): in stick-stick both feet's
friction margins mu_i f_n,i -+ f_t; in a slip of foot s with sign(d') = sigma, sigma d' and the
other foot's margin mu_o f_n,o - mu_s f_n,s; in every mode the normal forces, d and the joint
heights.  A guard crossing zero in a step is located on the guard of the solved state by the
three-link stepper's safeguarded Newton method on its exact rate
(:func:`~ocp_crawl.sim.event_locate.guard_root`, to 1e-13 cycles); the mode after it is that of
the transition table (:func:`ocp_crawl.sim.event_guards.transition`) when it is consistent (its
guards positive and its equilibrium stable just after the event), else the only consistent
single-foot mode, else the run fails (``no_consistent_mode``).  A lost contact ends the run
(``lift_off``, ``joint_on_ground``, ``feet_crossed``), so does a fold of the branch (the Newton
solve fails as the step shrinks, or the sign of det J or of the stability margin changes:
``fold``).  A stuck foot stays; a slipping foot moves with d.  Only single-foot slips are
modelled (a gait whose friction limits tie identically, mu1 f_n1 = mu2 f_n2, ends with
``no_consistent_mode``).  Cycles run until the state and mode at the start of a cycle repeat (at
least two cycles); the last cycle is reported.

An input with kinks or holds (piecewise-linear tables, pulses, optimal-control profiles) is taken
piece by piece (:mod:`ocp_crawl.sim.chain_pieces`): steps end at its kinks, where the mode after a
guard that turns negative is decided by the rates after the kink; a hold is crossed in one step
and the mode after it decided by the rates after it; the cycle integrals are split at its knots.
"""
from __future__ import annotations

import math

import numpy as np

from ocp_crawl.checks import real
from ocp_crawl.model.chain_inputs import ChainReferenceTorque, as_joint_signal
from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.model.chain_stability import chain_stability_margins
from ocp_crawl.model.inputs import PeriodicSignal, ReferenceTorque
from ocp_crawl.sim.assemble import (balance_metrics, default_phases, energy_gate,
                                    failure_message, new_result, output_phases, sample_fields,
                                    success_message)
from ocp_crawl.sim.chain_torque_parts import (GUARD_NOISE, JUMP_TOL, SINGLE_MODES, ChainSolver,
                                              Point, Segment, Stop, locate, mode_vector,
                                              sample_segment, segment_integrals)
from ocp_crawl.sim.event_guards import transition
from ocp_crawl.sim.event_kinks import linear_pieces, step_limit
from ocp_crawl.sim.result import CrawlResult, Event, Mode, mode_change_kind
from ocp_crawl.status import Status


#: largest |energy balance residual| of a success, relative to the gross work (the cycle integrals
#: close to ~1e-12 on smooth inputs; the event stepper's default tolerance)
ENERGY_TOL = 1e-6


class NoStart(ValueError):
    """No stable released equilibrium at t = 0 (:meth:`ChainTorqueStepper.start`)."""


class ChainTorqueStepper:
    """The continuation of one run (see the module docstring); call :meth:`run`."""

    def __init__(self, model: ChainModel, torque: PeriodicSignal, *, max_step: float,
                 min_step: float, event_xtol: float, trial_step: float, quad_h: float):
        self.solver = ChainSolver(model, torque)
        self.model, self.torque = model, torque
        # the step resolves the input's harmonics as the three-link stepper's does (a short dip of
        # a friction margin between the knots of a spline is an event), unless it is linear
        # between its knots
        if not linear_pieces(torque, self.solver.pieces.knots):
            max_step = min(max_step, max(step_limit(torque), max_step / 64))
        self.max_step, self.min_step = max_step, min_step
        self.event_xtol, self.trial_step, self.quad_h = event_xtol, trial_step, quad_h
        self.segments: list[Segment] = []
        self.events: list[Event] = []
        self._rest_left: float | None = None
        """the hold of zero length (a rest of the input) the run has just left"""

    # ------------------------------------------------------------------ start
    def start(self) -> Point:
        """The released start (f_t = 0) at t = 0, stable in stick-stick; ValueError if none."""
        s, chain = self.solver, self.model.chain
        if isinstance(self.torque, (ChainReferenceTorque, ReferenceTorque)):
            ref = np.asarray(self.torque.reference(0.0), float)
        else:
            ref = math.pi + np.asarray(chain.rest) + s.tau(0.0)[0] / np.asarray(chain.stiffness)
        released = np.array([0.0, 0.0, 1.0, 0.0])
        for lam in (1.0, 0.5, 0.25, 0.0):
            phi = lam * ref + (1 - lam) * 0.6 * math.pi
            pt = s.solve(0.0, np.append(phi, 0.0), released)
            if pt is None or min(s.guards(Mode.STICK, pt).values()) <= 0:
                continue
            q = mode_vector(Mode.STICK, pt.aux["d"])
            if s.margin(pt.x, q) > 0:
                return s.solve(0.0, pt.x, q) or pt
        raise NoStart("no stable released equilibrium with both feet on the ground at t = 0")

    # ------------------------------------------------------------------ stepping
    def _step(self, seg: Segment, pt: Point, t_new: float, left: bool = False) -> Point | None:
        """The mode's solution at t_new from pt (at a kink with the rates before it when
        ``left``), or None (no convergence, a jump or a fold)."""
        s = self.solver
        new = s.solve(t_new, s.guess(pt, t_new), seg.q, left=left)
        if new is None:
            return None
        m = s.m
        if np.max(np.abs(new.x[:m] - pt.x[:m])) > 0.35:
            return None
        if np.sign(new.det()) != np.sign(pt.det()):
            return None
        return new

    def _place(self, seg: Segment, pt: Point) -> Point:
        """pt with the feet positions of the segment's mode (the stuck foot of its first point)."""
        first = seg.points[0]
        foot = seg.mode.foot
        pt.x1 = first.x2 - pt.aux["d"] if foot == 1 else first.x1
        pt.x2 = first.x1 + pt.aux["d"] if foot == 2 else first.x2
        return pt

    def _advance(self, seg: Segment, t_end: float, h: float) -> tuple[Segment, float]:
        """Continue from the segment's last point to t_end through the events, the input's kinks
        and holds (:mod:`ocp_crawl.sim.chain_pieces`); returns the segment at t_end and the step
        size."""
        s, pieces = self.solver, self.solver.pieces
        while seg.t1 < t_end - 1e-15:
            pt = seg.points[-1]
            span = pieces.hold_at(pt.t, self._rest_left)
            if span is not None:
                seg = self._cross_hold(seg, pt, span, t_end)
                continue
            brk = pieces.next_break(pt.t)
            stop = min(t_end, brk)
            hh = min(h, stop - pt.t)
            t_new = stop if stop - (pt.t + hh) < 1e-12 else pt.t + hh
            at_kink, at_break = pieces.is_kink(t_new), t_new == brk
            new = self._step(seg, pt, t_new, left=at_kink)
            if new is None:
                h = hh / 4
                if h < self.min_step:
                    raise Stop(Status.FOLD, pt.t, seg.mode, "the equilibrium branch of mode "
                               f"{seg.mode.label} ends (fold) at t = {pt.t:.10f}")
                continue
            g0, g1 = s.guards(seg.mode, pt), s.guards(seg.mode, new)
            # (a guard at zero to round-off at a kink or where a hold starts, such as the feet's
            # friction limits tying where a table's sample makes the shape symmetric, is decided
            # by the rates after it)
            floor = -GUARD_NOISE if at_kink or at_break else 0.0
            crossed = [k for k, v in g1.items() if v < floor]
            # (a guard that dips below zero and back inside the step, unseen by the signs at its
            # ends, is an event; so is one that does so before another crosses at the step's end)
            early, dipped, near = self._dip(seg, pt, new)
            if dipped and (not crossed or early.t < new.t):
                new, crossed = early, dipped
            elif near and not crossed and hh > 1e-5:   # (a contact nears zero: look closer)
                h = hh / 2
                continue
            if not crossed:
                seg.points.append(self._place(seg, new))
                h = min(self.max_step, 2 * hh) if hh >= 0.999 * h else h
                if at_kink and new.t == t_new:
                    seg = self._cross_kink(seg, new)
                continue
            self._check_stable(seg)
            seg = self._event(seg, pt, new, g0, crossed)
            h = min(h, self.max_step)
        return seg, h

    def _dip(self, seg: Segment, pt: Point, new: Point) -> tuple[Point, list[str], bool]:
        """The end of the step [pt, new] and its crossed guards: inside the step at the first dip of
        a guard's interpolant (:meth:`ChainSolver.dips`) where a guard is negative, else new and
        none; and whether a contact's guard nears zero in the step."""
        s = self.solver
        dips, near = s.dips(seg.mode, seg.q, pt, new)
        for t in dips:
            pm = s.solve(t, s.guess(pt, t), seg.q)
            if pm is None:
                continue
            crossed = [k for k, v in s.guards(seg.mode, pm).items() if v < 0]
            if crossed:
                return pm, crossed, near
        return new, [], near

    def _check_stable(self, seg: Segment) -> None:
        """A fold failure at the first point of the segment whose stability margin is <= 0."""
        X = np.array([p.x for p in seg.points]).T
        margins = chain_stability_margins(self.model, X, seg.q)
        bad = np.flatnonzero(~(margins > 0))
        if bad.size:
            t = seg.points[bad[0]].t
            raise Stop(Status.FOLD, t, seg.mode, f"stability margin of mode {seg.mode.label} "
                       f"{margins[bad[0]]:.3g} <= 0 at t = {t:.10f}")

    def _event(self, seg: Segment, pt: Point, new: Point, g0: dict, crossed: list) -> Segment:
        """Locate the first crossing in the step [pt, new], record the event and return the
        segment of the mode after it."""
        s, g1 = self.solver, self.solver.guards(seg.mode, new)
        best = None   # ((t, point), guard) of the earliest zero; the guards by their secant zeros
        for k in sorted(crossed, key=lambda k: (g0[k] / (g0[k] - g1[k]) if g0[k] > 0 else 0, k)):
            if best is not None and s.guards(seg.mode, best[0][1])[k] > GUARD_NOISE:
                continue   # (still positive at the earliest zero found: it crosses later)
            found = (locate(s, seg, pt, new, k, g0[k], self.trial_step, self.event_xtol), k)
            if best is None or (found[0][0], k) < (best[0][0], best[1]):
                best = found
        assert best is not None   # (crossed is not empty)
        (t_ev, ev), kind = best
        if ev is not pt:
            seg.points.append(self._place(seg, ev))
        return self._switch(seg, ev, kind)

    def _switch(self, seg: Segment, ev: Point, kind: str) -> Segment:
        """The segment of the mode after guard ``kind`` of the segment's mode reached zero at the
        point ``ev`` (the transition table's mode when it is consistent, else the only
        consistent single-foot mode), the event recorded."""
        s, t_ev = self.solver, ev.t
        g_ev = s.guards(seg.mode, ev)[kind]
        nxt = transition(seg.mode, kind)
        if isinstance(nxt, Status):
            self.events.append(Event(t_ev, kind, seg.mode.label, "failure", g_ev, kind))
            raise Stop(nxt, t_ev, seg.mode, f"guard {kind} reached zero at t = {t_ev:.10f}")
        chosen, start = nxt, s.consistent(nxt, ev, self.trial_step)
        if start is None:
            ok = [(m, p) for m in SINGLE_MODES if m is not seg.mode
                  for p in [s.consistent(m, ev, self.trial_step)] if p is not None]
            if len(ok) > 1:   # (a mode that continues the state wins)
                ok = [c for c in ok if s.jump(ev, c[1]) <= JUMP_TOL] or ok
            if len(ok) != 1:
                raise Stop(Status.NO_CONSISTENT_MODE, t_ev, seg.mode,
                           f"{len(ok)} consistent modes after {kind} at t = {t_ev:.10f}")
            chosen, start = ok[0]
        size = s.jump(ev, start)
        if size > JUMP_TOL:
            raise Stop(Status.SNAP_THROUGH, t_ev, seg.mode,
                       f"{kind} from {seg.mode.label} to {chosen.label} needs a jump of the state "
                       f"of {size:.3g} at t = {t_ev:.10f}")
        return self._start_mode(seg, ev, chosen, start, kind, g_ev)

    def _start_mode(self, seg: Segment, ev: Point, chosen: Mode, start: Point, kind: str,
                    g_ev: float) -> Segment:
        """A new segment of mode ``chosen`` from ``start`` (at ev, the feet where they are), the
        event recorded."""
        self.events.append(Event(ev.t, mode_change_kind(seg.mode, chosen), seg.mode.label,
                                 chosen.label, g_ev, kind))
        start.x1, start.x2 = ev.x1, ev.x2
        new_seg = Segment(chosen, mode_vector(chosen, ev.aux["d"]), ev.t, [start])
        self.segments.append(new_seg)
        return new_seg

    # ------------------------------------------------------------------ kinks and holds
    def _cross_kink(self, seg: Segment, left: Point) -> Segment:
        """At a kink of the input (the segment's last point, solved with the rates before it): the
        point again with the rates after it, which continues the segment when every guard stays
        positive, else an event at the kink (of the most negative guard)."""
        s = self.solver
        right = s.solve(left.t, left.x, seg.q)
        if right is None:
            raise Stop(Status.NO_CONVERGENCE, left.t, seg.mode, "mode solve failed at a kink "
                       f"of the input at t = {left.t:.10f}")
        right.x1, right.x2 = left.x1, left.x2
        g = s.guards(seg.mode, right)
        crossed = sorted((v, k) for k, v in g.items() if v < -GUARD_NOISE)
        if not crossed:
            seg.points[-1] = right
            return seg
        self._check_stable(seg)
        return self._switch(seg, right, crossed[0][1])

    def _cross_hold(self, seg: Segment, pt: Point, span: tuple[float, float],
                    t_end: float) -> Segment:
        """Across the hold ``span`` of the input from pt in one step, to its end or to t_end (the
        cycle's end) if sooner: a quasistatic state does not move while its input does not; at the
        hold's end, the mode after it (:meth:`_leave_hold`)."""
        s = self.solver
        stop = min(span[1], t_end)
        end = pt
        if stop > pt.t:
            solved = s.solve(stop, pt.x, seg.q)
            if solved is None:
                raise Stop(Status.NO_CONVERGENCE, stop, seg.mode, "mode solve failed at the "
                           f"end of a hold of the input at t = {stop:.10f}")
            end = self._place(seg, solved)
            seg.points.append(end)
        if span[0] == span[1]:
            self._rest_left = span[0]
        return self._leave_hold(seg, end) if stop == span[1] else seg

    def _leave_hold(self, seg: Segment, end: Point) -> Segment:
        """The mode after a hold: the segment's own when it is consistent with the rates after the
        hold, else the one single-foot mode that is and continues the state without a jump
        (NO_CONSISTENT_MODE for none, SET_VALUED for several: the statics leave the motion
        undecided)."""
        s = self.solver
        if s.consistent(seg.mode, end, self.trial_step) is not None:
            return seg
        ok = [(m, p) for m in SINGLE_MODES if m is not seg.mode
              for p in [s.consistent(m, end, self.trial_step)]
              if p is not None and s.jump(end, p) <= JUMP_TOL]
        if len(ok) != 1:
            status = Status.SET_VALUED if ok else Status.NO_CONSISTENT_MODE
            names = ", ".join(m.label for m, _ in ok) or "none"
            raise Stop(status, end.t, seg.mode, "at the end of a hold of the input the modes "
                       f"that continue from the state are {names}")
        return self._start_mode(seg, end, ok[0][0], ok[0][1], "decided", 0.0)

    # ------------------------------------------------------------------ cycles
    def run_cycles(self, cycles_max: int, periodic_tol: float) -> tuple[int, float]:
        """Run cycles until periodic; returns (steady cycles run, periodicity deviation)."""
        start = self.start()
        seg = Segment(Mode.STICK, mode_vector(Mode.STICK, start.aux["d"]), 0.0, [start])
        self.segments = [seg]
        h = self.max_step
        ends = [(start.x.copy(), seg.mode)]
        for cycle in range(1, cycles_max + 1):
            seg, h = self._advance(seg, float(cycle), h)
            self._check_stable(seg)
            end = seg.points[-1]
            ends.append((end.x.copy(), seg.mode))
            # (a new segment from the cycle's end, so that segments do not straddle cycles)
            seg = Segment(seg.mode, seg.q, end.t, [end])
            self.segments.append(seg)
            if cycle < 2:
                continue
            # (the state and mode at a cycle's start decide the cycle: when they repeat, so does
            # the cycle, its displacement included)
            (xa, ma), (xb, mb) = ends[-2], ends[-1]
            dev = float(np.max(np.abs(xb - xa)))
            if ma == mb and dev <= periodic_tol:
                return cycle, dev
        raise Stop(Status.NOT_PERIODIC, float(cycles_max), seg.mode,
                   f"not periodic after {cycles_max} cycles")

    # ------------------------------------------------------------------ the steady cycle
    def steady(self, t0: float) -> list[tuple[Segment, float, float]]:
        """The segments of the cycle [t0, t0 + 1] with their stretch in it (nonempty)."""
        out = []
        for i, seg in enumerate(self.segments):
            a = seg.t0
            b = seg.t1 if i + 1 == len(self.segments) else self.segments[i + 1].t0
            lo, hi = max(a, t0), min(b, t0 + 1.0)
            if hi > lo + 1e-15:
                out.append((seg, lo, hi))
        return out

    def integrals(self, t0: float) -> tuple[np.ndarray, float, float, float]:
        """W+ per joint (m,), input work, gross work and friction dissipation [J] of the cycle."""
        m = self.solver.m
        wp, work = np.zeros(m), np.zeros(m)
        diss = 0.0
        for seg, a, b in self.steady(t0):
            try:
                p, wj, ds = segment_integrals(self.solver, seg, a, b, self.quad_h)
            except RuntimeError as exc:   # (a Newton solve at a quadrature node)
                raise Stop(Status.NO_CONVERGENCE, a, seg.mode, f"the steady cycle's integrals: "
                           f"{exc}") from None
            wp, work, diss = wp + p, work + wj, diss + ds
        # (|p| = 2 max(p, 0) - p)
        return wp, float(np.sum(work)), float(np.sum(2 * wp - work)), diss

    def samples(self, t0: float, te: np.ndarray) -> tuple[dict, dict]:
        """The output fields at the phases t0 + te and the ``extra`` fields."""
        parts, modes = [], []
        steady = self.steady(t0)
        ts = t0 + te
        for k, (seg, a, b) in enumerate(steady):
            last = k + 1 == len(steady)
            sel = ts[(ts >= a) & ((ts <= b) if last else (ts < b))]
            if sel.size:
                try:
                    parts.append(sample_segment(self.solver, seg, sel))
                except RuntimeError as exc:   # (a Newton solve at an output phase)
                    raise Stop(Status.NO_CONVERGENCE, a, seg.mode, f"the output samples: {exc}"
                               ) from None
                modes.append(np.full(sel.size, int(seg.mode)))
        f = {k: np.concatenate([p[k] for p in parts], axis=-1) for k in parts[0]}
        mode = np.concatenate(modes)
        fields = sample_fields(ts, f["phi"], f["theta"], f["d"], f["x1"], f["x2"], f["f_t"],
                               f["f_n1"], f["f_n2"], f["tau"], mode)
        extra = {"links": self.model.chain.n, "alpha": f["alpha"],
                 "foot": np.array([Mode(c).foot for c in mode], int)}
        return fields, extra


def as_chain_torque(torques, model: ChainModel) -> PeriodicSignal:
    """The torque signal (m rows) of ``torques``."""
    if isinstance(torques, (ReferenceTorque, ChainReferenceTorque)):
        shape = np.shape(torques(0.0))
        if shape != (model.chain.n_joints,):
            raise ValueError(f"torques must have {model.chain.n_joints} rows, got {shape}")
        return torques
    return as_joint_signal(torques, model.chain.n_joints)


def simulate_chain_torque(chain_model: ChainModel, torques, *, cycles_max: int = 12,
                          t_eval=None, max_step: float = 1.0 / 16, min_step: float = 1e-11,
                          event_xtol: float = 1e-13, trial_step: float = 1e-8,
                          quad_h: float = 1.0 / 32, periodic_tol: float = 1e-10) -> CrawlResult:
    """Torque-driven quasistatic gait of an n-link chain (see the module docstring).

    Parameters
    ----------
    chain_model : ChainModel
        The chain and the gravity convention.
    torques : PeriodicSignal, callable or array_like
        1-periodic joint torques tau(t) [N m] with m = n - 1 rows of the phase t [cycles]: a signal
        (:class:`ChainReferenceTorque`, for three links also
        :class:`~ocp_crawl.model.inputs.ReferenceTorque`), a callable or samples (m, K).
    cycles_max : int
        Most cycles run before the status ``not_periodic``.
    t_eval : array_like of float, optional
        Output phases in [0, 1] of the steady cycle [cycles]; default 201 phases and the events.
    max_step, min_step : float
        Largest and smallest continuation step [cycles] (the largest as the three-link stepper's,
        :class:`~ocp_crawl.sim.event.HybridOptions`; a signal's harmonics may ask for less).
    event_xtol : float
        Tolerance of the event phases [cycles].
    trial_step : float
        Phase after an event at which the next mode's guards must be positive [cycles].
    quad_h : float
        Largest Gauss-Legendre panel of the cycle integrals [cycles].
    periodic_tol : float
        Largest change of the state at the cycle start [rad, -] between the last two cycles of a
        periodic gait.

    Returns
    -------
    CrawlResult
        ``S`` [m] (displacement per cycle along +x), ``W_plus`` [J] (sum over the joints of the
        integral of max(tau_j phi_j', 0), per joint ``W_plus_joint`` (m,)), CoT+, the energy
        balance, the events of the run and the samples on the output phases (phi, tau (m, N)).
        A failure is a status with ``failure_t`` and ``failure_mode``.
    """
    if not isinstance(chain_model, ChainModel):
        raise TypeError("simulate_chain_torque: chain_model must be a ChainModel, got "
                        f"{type(chain_model).__name__}")
    torque = as_chain_torque(torques, chain_model)
    if isinstance(cycles_max, bool) or not isinstance(cycles_max, (int, np.integer)) \
            or cycles_max < 1:
        raise ValueError(f"simulate_chain_torque: cycles_max must be an integer >= 1, got "
                         f"{cycles_max!r}")
    steps = {k: real(k, v, positive=True) for k, v in
             (("max_step", max_step), ("min_step", min_step), ("event_xtol", event_xtol),
              ("trial_step", trial_step), ("quad_h", quad_h), ("periodic_tol", periodic_tol))}
    te = output_phases(t_eval)
    periodic_tol = steps.pop("periodic_tol")
    st = ChainTorqueStepper(chain_model, torque, **steps)
    try:
        cycles, dev = st.run_cycles(int(cycles_max), periodic_tol)
        t0 = float(cycles - 1)
        wp, w_in, w_abs, diss = st.integrals(t0)
        ev_t = [e.t - t0 for e in st.events if t0 <= e.t <= t0 + 1]
        samples, extra = st.samples(t0, default_phases(ev_t) if te is None else te)
    except NoStart as exc:
        return new_result(chain_model, "torque", Status.NO_START,
                          failure_message(Status.NO_START, str(exc)), failure_t=0.0,
                          failure_mode="released start", nfev=st.solver.nfev)
    except Stop as stop:
        return new_result(chain_model, "torque", stop.status,
                          failure_message(stop.status, stop.detail), events=st.events,
                          failure_t=stop.t, failure_mode=stop.mode.label, nfev=st.solver.nfev)
    steady = st.steady(t0)
    p0, p1 = steady[0][0].points[0], steady[-1][0].points[-1]
    S = float(p1.x1 - p0.x1)
    dV = float(chain_model.potential(p1.x[:-1]) - chain_model.potential(p0.x[:-1]))
    extra["periodicity_deviation"] = dev
    res = new_result(chain_model, "torque", Status.SUCCESS, success_message(cycles, t0),
                     cycles=cycles, t0=t0, events=st.events, **samples,
                     **balance_metrics(chain_model.chain, S, wp, w_in, dV, diss, w_abs),
                     periodicity_residual=dev, nfev=st.solver.nfev, extra=extra)
    # (a quadrature across an unresolved kink of the input, or a missed event, breaks the balance)
    return energy_gate(res, ENERGY_TOL, "ENERGY_TOL, the balance of the chain's cycle integrals")
