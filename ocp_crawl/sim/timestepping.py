"""Time-stepping simulation of the torque-driven crawler: one MPCC step (:mod:`ocp_crawl.sim.mpcc`)
per grid phase.

The cycle is divided into N equal steps, t_n = n / N (phase in cycles).  Step n takes the state at
t_{n-1} and the torque at t_n and solves the incremental contact problem with IPOPT, warm-started
from step n-1.  Steps are switch-exact (``switch_exact``, default): when a step's solution ends in
another contact mode than it started in, the event is located inside the step as the root of a guard
of the starting mode in the step fraction (:mod:`ocp_crawl.sim.step_split`: the step NLP solved in
that mode, with the friction margins and the slip rate as guards) and the step is split there, so
that every event (slip onset, slip-to-stick, change of the slipping foot, direction reversal) is a
step boundary and a sample of the result (up to ``MAX_SPLITS`` events per step; a slip-to-stick that
the previous step passed with a positive net slip is traced back into it and that step redone).  The
foot positions, and so S, then carry no discretisation error.  The run starts like the event-driven
stepper (a released start at t = 0: equilibrium with f_t = 0, stick-stick) and continues cycle by
cycle until the state at the end of a cycle repeats (or for a given number of cycles); the last
cycle is reported in a :class:`~ocp_crawl.sim.result.CrawlResult` with the same fields as the
event-driven result.

Metrics on the samples of the reported cycle (the step phases and the located events):

* S = x1(t0 + 1) - x1(t0) [m];
* W+ by the midpoint rule on each step: sum_n sum_i max(0, tau_i(t_{n-1/2}) (phi_i,n - phi_i,n-1))
  [J] (second order on smooth stretches, where the right-end rule tau_i(t_n) would be first order);
* energy: input work sum_n tau(t_{n-1/2}) . (phi_n - phi_{n-1}), potential change, friction
  dissipation sum_n -(f_t1 dx1 + f_t2 dx2) with the forces averaged over the ends of step n
  (trapezoid rule), so that the balance residual (input work - potential change - dissipation,
  relative to the gross work sum |tau_i dphi_i| as in the event-driven stepper) is O(1/N^2).

Failures stop the run with a status: a step that IPOPT cannot solve (after retries) gives
``SOLVER_FAILURE``, or ``LIFT_OFF`` if the mode-enumeration oracle finds that every equilibrium of
the step has a normal force <= 0; the message names the step, its phase and the return status with
its meaning from :data:`~ocp_crawl.nlp.ipopt.IPOPT_RETURN_STATUS`, and the result keeps the steps of
the failing cycle solved before it.  A torque input that is not finite at a step gives
``SOLVER_FAILURE`` too, and no released equilibrium at t = 0 gives ``NO_START`` (as the event-driven
stepper).  A solution with a normal force <= 0 gives ``LIFT_OFF``, d <= 0 ``FEET_CROSSED``, a joint
at or below the ground ``JOINT_ON_GROUND``, also where such a guard reaches zero between two
steps' ends (:mod:`ocp_crawl.sim.step_dips`, the run ends at its first zero); a sign change of the
Jacobian determinant of the active mode's equations within one mode, or a jump of phi larger than
``max_dphi`` in one step, gives ``FOLD`` (the tracked equilibrium branch was lost).  Every solved
step's equilibrium must be stable in its contact mode (:mod:`ocp_crawl.model.stability`, the
criterion of the event-driven stepper), else ``UNSTABLE``; the released start must be stable, else
``NO_START``; a steady cycle whose energy balance residual exceeds ``energy_tol_n2 / N^2`` is
``ENERGY_IMBALANCE``.  S's discretisation error is estimated by re-running the steady cycle with
2 N + 1 steps (:mod:`ocp_crawl.sim.discretisation`); above ``s_error_tol (|S| + 1e-3 L)`` it is
``COARSE_STEPS``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ocp_crawl.checks import real
from ocp_crawl.model.inputs import PeriodicSignal, as_signal
from ocp_crawl.model.statics import Model
from ocp_crawl.model.stability import fast_stability
from ocp_crawl.sim.discretisation import error_gate, estimate_S_error
from ocp_crawl.sim.assemble import no_start_result, output_phases
from ocp_crawl.sim.event import HybridStepper
from ocp_crawl.sim.event_checks import describe_margin
from ocp_crawl.sim.event_state import mode_q
from ocp_crawl.nlp.ipopt import ipopt_status
from ocp_crawl.sim.mpcc import MPCCOptions, MPCCStep
from ocp_crawl.sim.step import StepResult, StepState, step_params, step_result_from_w
from ocp_crawl.sim.step_input import StepInput
from ocp_crawl.sim.step_split import TieHeld, locate_event, solve_to_end
from ocp_crawl.sim.options import STEPS_BOUNDS, CycleOptions, count
from ocp_crawl.sim.result import CrawlResult, Event, Mode, mode_change_kind
from ocp_crawl.status import Status
from ocp_crawl.sim.oracle import ENUM_MODES, mode_system, selector, solve_step_enumerate
from ocp_crawl.sim.step_dips import three_link_dip
from ocp_crawl.sim.timestepping_output import SteppingRun, build_result


@dataclass(frozen=True)
class TimeSteppingOptions(CycleOptions):
    """Options of the time-stepping simulator and the cycle options of
    :class:`~ocp_crawl.sim.options.CycleOptions` (``max_cycles`` applies without ``cycles``)."""

    mpcc: MPCCOptions = field(default_factory=MPCCOptions)
    """options of the step solver"""
    max_dphi: float = 0.35
    """largest change of a joint angle in one step [rad]; a larger jump: the branch was lost"""
    steps: int = 200
    """steps per cycle (read by :func:`ocp_crawl.sim.simulate`; ``simulate_mpcc``: an argument)"""
    switch_exact: bool = True
    """split a step whose contact mode changes at the event located inside it
    (:mod:`ocp_crawl.sim.step_split`), so that every event falls on a step boundary; False: the
    plain incremental step (the whole step in its end mode: an O(1/N) error in S per change of the
    slipping foot)"""
    energy_tol_n2: float = 10.0
    """a successful cycle's |energy balance residual| (relative to the gross work) must be <=
    energy_tol_n2 / N^2 (N steps per cycle), else ``energy_imbalance``.  The midpoint work and
    trapezoid dissipation rules leave an O(1/N^2) residual (N^2 |residual| = 0.04 on the paper's
    gait, <= 10 over the random problems of the property test), while a missing term or a
    snap-through between steps leaves an O(1) one"""
    s_error_tol: float = 1e-3
    """bound on the estimate of S's discretisation error, relative: s_error_tol (|S| + 1e-3 L)
    [-]; the estimate re-runs the steady cycle with 2 N + 1 steps
    (:mod:`ocp_crawl.sim.discretisation`), above it the result is ``coarse_steps``; 0: no estimate
    (and no check run)"""

    def __post_init__(self) -> None:
        if not isinstance(self.mpcc, MPCCOptions):
            raise TypeError("TimeSteppingOptions.mpcc must be MPCCOptions, "
                            f"got {type(self.mpcc).__name__}")
        super().__post_init__()
        self._set("max_dphi", real("TimeSteppingOptions.max_dphi", self.max_dphi, positive=True))
        self._set("steps", count("TimeSteppingOptions.steps", self.steps, *STEPS_BOUNDS))
        if not isinstance(self.switch_exact, bool):
            raise TypeError("TimeSteppingOptions.switch_exact must be a bool, "
                            f"got {self.switch_exact!r}")
        self._set("energy_tol_n2", real("TimeSteppingOptions.energy_tol_n2", self.energy_tol_n2,
                                        positive=True))
        self._set("s_error_tol", real("TimeSteppingOptions.s_error_tol", self.s_error_tol,
                                      nonneg=True))


#: most events located inside one step (further changes of mode in the step are taken at its end)
MAX_SPLITS = 3


class _Stop(Exception):
    def __init__(self, status: Status, diagnosis: str, detail: str, t: float, mode: Mode):
        detail = f"{detail}; {diagnosis}" if diagnosis else detail
        super().__init__(detail)
        self.status, self.detail, self.t, self.mode = status, detail, t, mode


class TimeStepper:
    """MPCC time-stepping of a torque-driven gait with N steps per cycle.  Build once, call
    :meth:`run`."""

    def __init__(self, model: Model, torque, steps: int = 200,
                 options: TimeSteppingOptions | MPCCOptions | None = None):
        if not isinstance(model, Model):
            raise TypeError(f"model must be a Model, got {type(model).__name__}")
        if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) \
                or not STEPS_BOUNDS[0] <= steps <= STEPS_BOUNDS[1]:
            raise ValueError(f"steps must be an integer in [{STEPS_BOUNDS[0]}, "
                             f"{STEPS_BOUNDS[1]}] (steps per cycle), got {steps!r}")
        if options is None:
            options = TimeSteppingOptions()
        elif isinstance(options, MPCCOptions):
            options = TimeSteppingOptions(mpcc=options)
        elif not isinstance(options, TimeSteppingOptions):
            raise TypeError("options must be TimeSteppingOptions or MPCCOptions, "
                            f"got {type(options).__name__}")
        self.model = model
        self.torque: PeriodicSignal = as_signal(torque)
        self.input = StepInput(self.torque)
        self.steps = int(steps)
        self.opt = options
        self.step = MPCCStep(model, options.mpcc)
        self._jac = mode_system()
        r = model.robot
        self.Mg = r.M * r.g

    def _det(self, res: StepResult, state: StepState, tau: np.ndarray) -> float:
        """Determinant of the Jacobian of the active mode's equations at the step solution."""
        # slip-slip (equal limits) is solved by the equations of either foot: use foot 1's
        mode = res.mode if res.mode in ENUM_MODES else Mode.slip(1, res.mode.sigma)
        z = np.array([res.phi[0], res.phi[1], res.f_t / self.Mg])
        J = np.asarray(self._jac(z, step_params(self.model, state, tau), selector(mode))[1])
        return float(np.linalg.det(J))

    def _diagnose(self, state: StepState, tau: np.ndarray, mode: Mode) -> tuple[Status, str]:
        """Status of a step IPOPT could not solve, from the mode-enumeration oracle: lift-off when
        every mode solution has a normal force <= 0, a fold when no mode is consistent and the
        current mode's equations have no solution near the last state, else a solver failure."""
        orc = solve_step_enumerate(self.model, state, tau)
        check = f"mode-enumeration check: {orc.message}"
        if orc.extra.get("lift_off"):
            return Status.LIFT_OFF, check
        if not orc.success:
            current = mode if mode in ENUM_MODES else Mode.slip(1, mode.sigma)
            cand = next(c for c in orc.extra["candidates"] if c["mode"] == current.label)
            if not cand["converged"] \
                    or np.max(np.abs(np.asarray(cand["phi"]) - state.phi)) > self.opt.max_dphi:
                return Status.FOLD, (f"{check}; the {mode.label} equilibrium branch ends within "
                                     "the step (fold)")
        return Status.SOLVER_FAILURE, check

    def run(self, cycles: int | None = None, t_eval=None) -> CrawlResult:
        """Simulate from the released start; ``cycles``: exact number of cycles, or None to run
        until periodic (at most ``max_cycles``).  ``t_eval``: phases in [0, 1] of the reported cycle
        for the output arrays (linear interpolation between steps); by default the step phases."""
        if cycles is not None and (isinstance(cycles, bool)
                                   or not isinstance(cycles, (int, np.integer)) or cycles < 1):
            raise ValueError(f"cycles must be a positive integer or None, got {cycles!r}")
        te = output_phases(t_eval)
        try:
            start = HybridStepper(self.model, self.torque).initial_state(0.0)
        except ValueError as exc:
            # as the event-driven stepper: no released equilibrium at t = 0 is a status, not an
            # exception
            return no_start_result(self.model, str(exc),
                                   extra={"steps_per_cycle": self.steps, "ipopt_calls": 0})
        kin0 = self.model.kinematics(start.x[:2])
        state = StepState(start.x[:2], 0.0, float(kin0["d"]), 0.0)
        run = SteppingRun(state, [(0.0, state.phi, float(kin0["theta"]), float(kin0["d"]),
                                   state.x1, state.x2, 0.0, float(kin0["fn1"]), float(kin0["fn2"]),
                                   int(Mode.STICK))])
        status, detail, fail_t, fail_mode = Status.SUCCESS, "", None, None
        calls0 = self.step.ncalls
        try:
            self._run_cycles(run, None if cycles is None else int(cycles))
        except _Stop as stop:
            status, detail, fail_t, fail_mode = stop.status, stop.detail, stop.t, stop.mode.label
        stats = {"steps_per_cycle": self.steps, "ipopt_calls": self.step.ncalls - calls0,
                 "retried_steps": run.retries,
                 "step_time_median": float(np.median(run.times)) if run.times else float("nan"),
                 "step_time_total": float(np.sum(run.times)), "max_comp_residual": run.comp_max,
                 "max_eq_residual": run.eq_max, "polished_steps": run.polished,
                 "W_plus_rule": "midpoint", "periodicity_deviation": run.periodic_dev,
                 "split_steps": sum(e.guard_name != "mode_change_between_steps"
                                    for e in run.events),
                 "split_ipopt_calls": run.split_calls, "unsplit_mode_changes": run.unsplit}
        check = None
        if status == Status.SUCCESS and self.opt.s_error_tol > 0:
            check = estimate_S_error(self, run, _Stop)
            stats.update(check)
        res = build_result(self, run, status, detail, fail_t, fail_mode, te, stats)
        return error_gate(res, check, self.model.robot.L, self.opt.s_error_tol)

    def _run_cycles(self, run: SteppingRun, n_target: int | None) -> None:
        """Steps until ``n_target`` cycles are done, or (None) until the state at a cycle's end
        repeats."""
        N = self.steps
        while True:
            try:
                res = self._step(run)
            except _Stop as stop:   # (a contact lost earlier in the cycle, or in the step, first)
                self._dip(run, [r for r in run.rows if r[0] >= run.ncycles - 1e-12],
                          (stop.t, run.mode), stop.detail)
                raise
            if run.n % N:
                continue
            # (a contact guard may dip below zero and back inside a step, unseen at the steps' ends)
            self._dip(run, [r for r in run.rows if r[0] >= run.ncycles - 1e-12])
            run.ncycles += 1
            ends = run.cycle_ends
            ends.append((res.phi.copy(), res.f_t / self.Mg, res.mode))
            if len(ends) >= 2:
                (pa, fa, _), (pb, fb, _) = ends[-2], ends[-1]
                run.periodic_dev = max(float(np.max(np.abs(pa - pb))), abs(fa - fb))
            if n_target is not None:
                if run.ncycles >= n_target:
                    return
                continue
            verdict = self.opt.cycle_verdict(run.ncycles, run.periodic_dev,
                                             len(ends) >= 2 and ends[-1][2] == ends[-2][2])
            if verdict:
                return
            if verdict is False:
                raise _Stop(Status.NOT_PERIODIC, "", f"not periodic after {run.ncycles} cycles "
                            f"(last change {run.periodic_dev:.3g})", run.n / N, run.mode)

    def _step(self, run: SteppingRun) -> StepResult:
        """Solve step n + 1 from the run's state, check the solution and record it."""
        run.n += 1
        N = self.steps
        return self._advance(run, (run.n - 1) / N, run.n / N, rewind=True)

    def _advance(self, run: SteppingRun, ta: float, tb: float, rewind: bool) -> StepResult:
        """Advance the run from its state at phase ``ta`` to ``tb``: one MPCC step, or with
        ``switch_exact``, when the step's mode changes, sub-steps split at the events located inside
        it (:mod:`ocp_crawl.sim.step_split`, at most ``MAX_SPLITS``); ``rewind``: an event the
        previous step passed without a change of mode (slip-to-stick) may be traced back into it,
        and the previous step redone from there."""
        tau = self._tau(tb, run)
        for k in range(MAX_SPLITS + 1):
            state, mode = run.state, run.mode
            res = self._solve(run, state, tau, tb)
            if res.mode != mode and self.input.held(ta, tb):
                # nothing moves while the input holds still: the mode holds with it (a slip at
                # zero rate), as in the event-driven stepper, and is decided where the hold ends
                res = replace(res, mode=mode)
            elif res.mode.foot == 3 and mode.foot != 3 and self.opt.switch_exact:
                res = self._single_to_end(run, state, mode, ta, tb, tau) or res
            if res.mode == mode or not self.opt.switch_exact or k == MAX_SPLITS:
                break
            t_prev = run.rows[-2][0] if rewind and len(run.rows) >= 2 and run.rows[-1][0] == ta \
                and round(ta * self.steps) % self.steps != 0 else None
            lo = -1.0 if t_prev is not None else 0.0
            split, why = locate_event(self.step, state, mode,
                                      lambda th: self._tau(ta + th * (tb - ta), run),
                                      None if run.prev is None else run.prev.w, lo=lo,
                                      kinks=self.input.kinks_in(ta, tb, lo), end_mode=res.mode)
            run.split_calls += self.step.ncalls - run.calls_mark
            te = ta + (0.0 if split is None else split.theta) * (tb - ta)  # theta < 0: t_prev set
            if split is not None and split.theta < 0 and not te > (t_prev or 0.0) + 1e-12:
                split, why = None, f"the event at t = {te:.9f} precedes the previous step's start"
            if split is None:
                run.unsplit.append(f"t = {tb:.6f}: {why}")
                break
            if split.theta == 0:
                # the event is the step's start, already a sample: only the mode changes there
                self._mode_change(run, split, te)
                continue
            if split.theta < 0:
                # the event is in the previous step: drop its end and redo it from the event
                run.rows.pop()
                row = run.rows[-1]
                run.state = StepState(row[1], row[4], row[5], row[6])
            self._event_point(run, split, state, te)
            if split.theta < 0:
                self._advance(run, te, ta, rewind=False)
            else:
                ta = te
            rewind = False
        self._record(run, res, state, tau, tb)
        run.prev = res
        return res

    def _single_to_end(self, run: SteppingRun, state: StepState, mode: Mode, ta: float, tb: float,
                       tau: np.ndarray) -> StepResult | None:
        """The step in its starting ``mode`` if that mode holds to its end (else None) when it ends
        with both feet slipping, a tie one foot's slip reaches; a tie over the step: set-valued."""
        calls, x0 = self.step.ncalls, None if run.prev is None else run.prev.w
        try:
            sol = solve_to_end(self.step, state, mode,
                               lambda th: self._tau(ta + th * (tb - ta), run), x0,
                               self.input.kinks_in(ta, tb))
        except TieHeld as tie:
            raise _Stop(Status.SET_VALUED, "", f"step at t = {tb:.6f}: {tie}", tb, mode) from None
        finally:
            run.split_calls += self.step.ncalls - calls
        if sol is None:
            return None
        return replace(step_result_from_w(self.model, state, sol.x, tau, success=True,
                                          status=sol.status, message="the step in its starting "
                                          "mode", iterations=sol.iterations, solve_time=0.0,
                                          w=sol.x), mode=mode)

    def _event_point(self, run: SteppingRun, split, state: StepState, te: float) -> None:
        """Record the located event at phase ``te``: the sub-step to it in the old mode (its
        positions from ``state``, the start of the searched step) and the change to the guard's
        mode."""
        mode = run.mode
        tau = self._tau(te, run)
        res = replace(step_result_from_w(self.model, state, split.solve.x, tau, success=True,
                                         status=split.solve.status, message="event point",
                                         iterations=split.solve.iterations, solve_time=0.0),
                      mode=mode)
        self._record(run, res, run.state, tau, te)
        self._mode_change(run, split, te)

    @staticmethod
    def _mode_change(run: SteppingRun, split, te: float) -> None:
        """Record the located event at phase ``te`` and continue in the guard's mode."""
        mode = run.mode
        run.events.append(Event(te, mode_change_kind(mode, split.mode_after), mode.label,
                                split.mode_after.label, split.value, split.guard))
        run.mode, run.det_ref = split.mode_after, None

    def _where(self, run: SteppingRun, t1: float) -> str:
        cyc, ph = int(math.floor(t1 - 1e-12)) + 1, t1 - math.floor(t1 - 1e-12)
        return f"step {run.n} (t = {t1:.6f} cycles: cycle {cyc}, phase {ph:.6f})"

    def _tau(self, t: float, run: SteppingRun) -> np.ndarray:
        """The torque [N m] at phase t; _Stop with SOLVER_FAILURE when it is not finite."""
        tau = np.asarray(self.torque(t), float).reshape(2)
        if not np.all(np.isfinite(tau)):
            raise _Stop(Status.SOLVER_FAILURE, "", f"{self._where(run, t)}: the torque input is "
                        f"not finite (tau = {tau.tolist()} N m at t = {t:.9g}); no IPOPT call was "
                        "made", t, run.mode)
        return tau

    def _solve(self, run: SteppingRun, state: StepState, tau: np.ndarray, t1: float) -> StepResult:
        """The MPCC step from ``state`` to the torque ``tau`` at t1; _Stop with a diagnosis when it
        fails."""
        res = self.step.solve(state, tau, warm_start=run.prev)
        run.calls_mark = self.step.ncalls
        run.times.append(res.solve_time)
        if not res.success:
            source = "IPOPT " if ipopt_status(res.status).source == "ipopt" else ""
            raise _Stop(*self._diagnose(state, tau, run.mode),
                        f"{self._where(run, t1)} failed with {source}"
                        f"return status {res.status} [{res.message}]", t1, run.mode)
        run.retries += res.attempts > 1
        run.comp_max = max(run.comp_max, res.comp_residual)
        run.eq_max = max(run.eq_max, res.eq_residual)
        run.polished += bool(res.extra.get("polished"))
        return res

    def _record(self, run: SteppingRun, res: StepResult, state: StepState, tau: np.ndarray,
                t1: float) -> None:
        """Check a solved (sub)step from ``state`` ending at phase t1 and record it; a change of
        mode not located before (:meth:`_advance`) is recorded as an event at t1."""
        mode, where = run.mode, self._where(run, t1)
        kin = self._check_contact(res, state, where, t1, mode)
        det = self._det(res, state, tau)
        if res.mode != mode:
            # not located: the change happened within the step (t1 - 1/N, t1]; no guard value
            run.events.append(Event(t1, mode_change_kind(mode, res.mode), mode.label,
                                    res.mode.label, float("nan"), "mode_change_between_steps"))
            run.det_ref = None
        if run.det_ref is not None and np.sign(det) != run.det_ref:
            raise _Stop(Status.FOLD, "", f"{where}: the Jacobian of the {res.mode.label} equations "
                        "changes sign (fold of the equilibrium branch)", t1, res.mode)
        run.det_ref = np.sign(det) or run.det_ref
        self._check_stable(res, where, t1)
        run.mode = res.mode
        run.rows.append((t1, res.phi, float(kin["theta"]), res.d, res.x1, res.x2, res.f_t, res.f_n1,
                         res.f_n2, int(res.mode)))
        run.state = res.next_state()

    def _dip(self, run: SteppingRun, rows: list, end: tuple | None = None, then: str = "") -> None:
        """_Stop at the first zero of a contact guard inside the steps ``rows`` (and the step
        from the last of them to ``end`` = (phase, mode), the step the run stopped in), if any;
        ``then``: what ended the run after it."""
        located = {e.t for e in run.events if e.guard_name != "mode_change_between_steps"}
        dip = three_link_dip(self, rows, located, end)
        if dip is not None:
            raise _Stop(dip[1], "", dip[3] + (f"; then {then}" if then else ""), dip[0], dip[2])

    def _check_stable(self, res: StepResult, where: str, t1: float) -> None:
        """_Stop with UNSTABLE unless the step's equilibrium has a positive stability margin in its
        mode (the same criterion as the event-driven stepper, :mod:`ocp_crawl.model.stability`)."""
        s = fast_stability()(np.array([res.phi[0], res.phi[1], res.f_t / self.Mg]),
                             mode_q(res.mode), self.model.p)[0]
        if not s[0] > 0:
            raise _Stop(Status.UNSTABLE, "", f"{where}: the {res.mode.label} equilibrium is "
                        f"unstable ({describe_margin(s, res.mode)})", t1, res.mode)

    def _check_contact(self, res: StepResult, state: StepState, where: str, t1: float,
                       mode: Mode) -> dict:
        """The kinematics of a step's solution; _Stop if a foot lifts off, the feet cross, a joint
        reaches the ground or phi jumps by more than ``max_dphi`` (the branch was lost)."""
        if min(res.f_n1, res.f_n2) <= 0:
            raise _Stop(Status.LIFT_OFF, "", f"{where}: normal forces {res.f_n1:.4g}, "
                        f"{res.f_n2:.4g} N", t1, mode)
        if res.d <= 0:
            raise _Stop(Status.FEET_CROSSED, "", f"{where}: d = {res.d:.4g} m", t1, mode)
        kin = self.model.kinematics(res.phi)
        for i in (1, 2):
            if f"zj{i}" in kin and not kin[f"zj{i}"] > 0:
                raise _Stop(Status.JOINT_ON_GROUND, "",
                            f"{where}: joint {i} height {kin[f'zj{i}']:.4g} m", t1, mode)
        jump = float(np.max(np.abs(res.phi - state.phi)))
        if jump > self.opt.max_dphi:
            # an input that itself moves by more than half of max_dphi in the step (a sharp edge of
            # a pulse or a square wave) says that the step is too coarse, not that the equilibrium
            # branch folds
            inside = np.linspace(t1 - 1.0 / self.steps, t1, 9)
            # (the largest rate over the step times the step: an edge inside the step counts)
            edge = float(np.max(np.abs(np.asarray(self.torque.derivative(inside), float)))) \
                / self.model.robot.k / self.steps
            if edge > 0.5 * self.opt.max_dphi:
                raise _Stop(Status.NO_CONVERGENCE, "", f"{where}: phi jumps by {jump:.3g} rad "
                            f"while the input moves by {edge:.3g} rad (tau/k) in the step: the "
                            "step is coarser than the input's edges; raise [simulation] steps "
                            f"(now {self.steps}) or use the event solver", t1, mode)
            raise _Stop(Status.FOLD, "", f"{where}: phi jumps by {jump:.3g} rad > max_dphi "
                        "(branch lost)", t1, mode)
        return kin


def simulate_mpcc(model: Model, torque, steps: int = 200, cycles: int | None = None,
                  options: TimeSteppingOptions | MPCCOptions | None = None,
                  t_eval=None) -> CrawlResult:
    """MPCC time-stepping simulation of a torque-driven gait with ``steps`` steps per cycle (see
    module docstring).

    Every step is an IPOPT solve of the incremental Coulomb problem with complementarity constraints
    (relaxation homotopy); the result converges to the event-driven one as ``steps`` grows.

    Parameters
    ----------
    model : Model
        The robot and the gravity convention.
    torque : PeriodicSignal or callable
        1-periodic joint torques (tau1, tau2) [N m] of the phase t [cycles].
    steps : int
        Time steps per cycle (in [4, 10000]; each is an IPOPT solve of about 2 ms).
    cycles : int, optional
        Number of cycles to run, or None to run until periodic (at most ``options.max_cycles``).
    options : TimeSteppingOptions or MPCCOptions, optional
        Solver and cycle options (None: the defaults).
    t_eval : array_like of float, optional
        Output phases in [0, 1] of the steady cycle [cycles].

    Returns
    -------
    CrawlResult
        S [m], W+ [J], CoT+ [-], the trajectories at the step phases, and the status.
    """
    return TimeStepper(model, torque, steps, options).run(cycles=cycles, t_eval=t_eval)
