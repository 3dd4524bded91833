"""Cross-check of the MPCC time-stepping simulator against the event-driven hybrid stepper.

Both simulators run the same model and torque input.  For every number of steps per cycle N the
time-stepping result is compared with the event-driven one on the step phases of the steady cycle
(the event-driven stepper is evaluated exactly there through ``t_eval``):

* S, W+ and CoT+ and their relative differences;
* the largest deviation of phi over the cycle at the step phases;
* the contact-mode sequence of each over the steady cycle, and for each event of the event-driven
  stepper the phase of the step where the time-stepping changes mode (its lag, in steps);
* the convergence of S: the errors |S_N - S_event| must decrease with N until they reach the solver's
  round-off floor, and the least-squares slope p of log|S_N - S_event| against log N (|error| ~ N^-p) over
  the errors above that floor.

What to expect.  Inside a mode the step equations are the mode's equations at t_n, so the
time-stepping is exact there; errors come from transitions.  With the default switch-exact steps
(:mod:`ocp_crawl.sim.step_split`) every contact event (slip onset, slip-to-stick, change of the slipping
foot, direction reversal) is located inside its step as the root of the starting mode's guard in the
step fraction and the step is split there, so S carries no discretisation error at all: what remains
is the solvers' tolerance accumulated over the steps (measured |dS|/|S| <= 2e-8 at N = 50..400 on
the shipped gaits, growing about like N), and the event phases agree to about 1e-6 steps.  The errors
that remain are those of the cycle metrics' quadrature on the step grid: W+ by the midpoint rule and
the energy balance are O(h^2) (h = 1/N; W+ about 6e-4 relative at N = 50, 6e-6 at N = 400 on the paper
gait).  Without switch-exact steps (``TimeSteppingOptions(switch_exact=False)``) a change of mode is
taken at the first step after the event (slip -> stick up to two steps late); the stick distance then
carries an O(h^2) error, and when the slipping foot changes during slip (unequal friction) the step
straddling the switch attributes its whole slip to one foot: an O(h) error in S whose size depends on
where the event falls inside the step (1.2 / 2.5 / 0.7 / 0.9 % at N = 50 / 100 / 200 / 400 on
problems/unequal_friction.toml); such runs need looser tolerances than the defaults.

``passed`` is True when every run succeeded, the relative S error is at most ``rel_S`` at every N >= 200
(at the finest N if all are smaller), the S errors decrease with N (or are below the round-off floor),
every other difference at the finest N is within :class:`CrossCheckTolerances`, the mode sequences agree
and every event is matched within the lag window, and the measured order over the errors above the
floor (when at least two are) is at least ``min_order``.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ocp_crawl.checks import finite_or_none, real
from ocp_crawl.io import units
from ocp_crawl.model.inputs import as_signal
from ocp_crawl.model.statics import Model
from ocp_crawl.sim.event import HybridOptions
from ocp_crawl.sim.mpcc import MPCCOptions
from ocp_crawl.sim.registry import simulate
from ocp_crawl.sim.result import CrawlResult, Mode
from ocp_crawl.sim.timestepping import TimeSteppingOptions

#: significant digits of CoT+ in the cross-check table (more than the 3 of a summary: it compares two solvers)
CROSSCHECK_DIGITS = 5


@dataclass(frozen=True)
class CrossCheckTolerances:
    """PASS/FAIL thresholds of the cross-check (all applied at the finest N)."""

    rel_S: float = 1e-4
    """largest relative difference of S at every N >= 200 (at the finest N if all are smaller) [-]"""
    rel_W_plus: float = 5e-3
    """largest relative difference of W+ [-]"""
    rel_CoT_plus: float = 1e-2
    """largest relative difference of CoT+ [-]"""
    max_phi_dev: float = 5e-3
    """largest deviation of phi over the steady cycle at the step phases [rad]"""
    min_order: float = 1.0
    """smallest accepted convergence order of S [-], fitted over the errors above ``rel_S_floor``"""
    rel_S_floor: float = 1e-7
    """S errors below rel_S_floor max(|S|, L) [m] are the solvers' round-off (the per-step IPOPT tolerance
    accumulated over the run; measured <= 2e-8 |S| at N = 400 on the shipped gaits, about 1e-8 L on gaits with
    little net motion): such errors need not decrease with N and carry no order"""
    event_lag_steps: tuple[float, float] = (-1e-3, 1e-3)
    """window of the lag (step phase - event phase) of a mode change, in steps (switch-exact steps put each
    event on a step boundary: measured |lag| <= 1e-6 steps)"""
    S_floor: float = 1e-6
    """|S| below this [m] counts as no motion: relative differences of S and CoT+ use this instead"""

    def __post_init__(self) -> None:
        for name in ("rel_S", "rel_W_plus", "rel_CoT_plus", "max_phi_dev", "S_floor", "min_order", "rel_S_floor"):
            object.__setattr__(self, name, real(f"CrossCheckTolerances.{name}", getattr(self, name),
                                                positive=name != "min_order"))
        lo, hi = (real("CrossCheckTolerances.event_lag_steps", v) for v in self.event_lag_steps)
        if not lo < hi:
            raise ValueError(f"CrossCheckTolerances.event_lag_steps must be (lo, hi) with lo < hi, "
                             f"got {self.event_lag_steps!r}")


def convergence_order(steps, errors) -> float:
    """Least-squares slope p of log(error) = c - p log(N); NaN with fewer than two positive errors."""
    n = np.asarray(steps, float)
    e = np.asarray(errors, float)
    ok = (e > 0) & np.isfinite(e)
    if np.count_nonzero(ok) < 2:
        return float("nan")
    slope = np.polyfit(np.log(n[ok]), np.log(e[ok]), 1)[0]
    return float(-slope)


def _rel(a: float, b: float, floor: float = 0.0) -> float:
    """|a - b| / max(|b|, floor)."""
    den = max(abs(b), floor)
    return abs(a - b) / den if den > 0 else (0.0 if a == b else math.inf)


def mode_sequence(res: CrawlResult) -> list[dict]:
    """Modes over the steady cycle: the mode at its start, then one entry per event (phase within the cycle)."""
    if len(res.mode) == 0:
        return []
    seq = [{"phase": 0.0, "mode": Mode(int(res.mode[0])).label, "kind": "start"}]
    for e in res.events:
        if res.t0 + 1e-12 < e.t <= res.t0 + 1 + 1e-12:
            seq.append({"phase": float(e.t - res.t0), "mode": e.mode_after, "kind": e.kind})
    return seq


def _cyclic(labels: list[str]) -> list[str]:
    """Cyclic sequence of distinct consecutive modes (the end of the cycle wraps to its start)."""
    out = []
    for m in labels:
        if not out or out[-1] != m:
            out.append(m)
    while len(out) > 1 and out[-1] == out[0]:
        out.pop()
    return out


def _same_cycle(a: list[str], b: list[str]) -> bool:
    if len(a) != len(b):
        return False
    return any(a == b[i:] + b[:i] for i in range(len(b))) if a else True


@dataclass(frozen=True)
class CrossCheckRow:
    """Comparison at one N (steps per cycle)."""

    steps: int
    success: bool
    message: str
    S: float
    W_plus: float
    CoT_plus: float
    rel_diff_S: float
    rel_diff_W_plus: float
    rel_diff_CoT_plus: float
    max_phi_dev: float
    modes: tuple
    event_lags: tuple
    """(kind, mode_after, event phase, step phase or None, lag in steps or None) per event-driven event"""
    modes_match: bool
    time: float
    """wall time of the time-stepping run [s]"""


@dataclass(frozen=True)
class CrossCheckResult:
    """Outcome of :func:`crosscheck`; ``summary()`` is JSON-able, ``table()`` readable."""

    event: CrawlResult
    rows: tuple
    order: float
    tolerances: CrossCheckTolerances
    checks: dict = field(default_factory=dict)
    """name -> (value, threshold, passed)"""
    passed: bool = False
    event_modes: tuple = ()

    @property
    def finest(self) -> CrossCheckRow:
        return self.rows[-1]

    def summary(self) -> dict:
        """JSON-safe summary (non-finite numbers are None)."""
        num = finite_or_none
        ev, fin = self.event, self.finest
        return {
            "passed": bool(self.passed),
            "steps": [r.steps for r in self.rows],
            "S_event": num(ev.S), "S_mpcc": num(fin.S), "rel_diff_S": num(fin.rel_diff_S),
            "W_plus_event": num(ev.W_plus), "W_plus_mpcc": num(fin.W_plus), "rel_diff_W_plus": num(fin.rel_diff_W_plus),
            "CoT_plus_event": num(ev.CoT_plus), "CoT_plus_mpcc": num(fin.CoT_plus),
            "rel_diff_CoT_plus": num(fin.rel_diff_CoT_plus),
            "max_phi_dev": num(fin.max_phi_dev), "order": num(self.order),
            "event_status": ev.status_name, "event_message": ev.message,
            "modes_event": list(self.event_modes),
            "per_steps": [_row_summary(r, ev) for r in self.rows],
            "checks": {k: {"value": num(v), "threshold": t if isinstance(t, str) else num(t), "passed": bool(p)}
                       for k, (v, t, p) in self.checks.items()},
            "tolerances": {"rel_S": self.tolerances.rel_S, "rel_W_plus": self.tolerances.rel_W_plus,
                           "rel_CoT_plus": self.tolerances.rel_CoT_plus,
                           "max_phi_dev": self.tolerances.max_phi_dev, "min_order": self.tolerances.min_order,
                           "event_lag_steps": list(self.tolerances.event_lag_steps),
                           "rel_S_floor": self.tolerances.rel_S_floor,
                           "S_floor": self.tolerances.S_floor},
        }

    def table(self) -> str:
        ev = self.event
        lines = [f"Cross-check: MPCC time-stepping vs event-driven ({ev.gravity} gravity)",
                 f"event-driven: {ev.message}",
                 f"  S = {units.distance(ev.S, 6)}, W+ = {units.work(ev.W_plus, 6)}, "
                 f"CoT+ = {units.cot(ev.CoT_plus, CROSSCHECK_DIGITS)}",
                 "",
                 f"{'N':>6} {'S_mpcc [mm]':>14} {'rel dS':>10} {'W+_mpcc [mJ]':>13} {'rel dW+':>10} "
                 f"{'CoT+_mpcc':>11} {'rel dCoT+':>10} {'max|dphi| [rad]':>16} {'modes':>6} {'time [s]':>9}"]
        for r in self.rows:
            lines.append(f"{r.steps:>6d} {units.fixed(r.S, 6, 1e3):>14} {units.scientific(r.rel_diff_S, 3):>10} "
                         f"{units.fixed(r.W_plus, 6, 1e3):>13} {units.scientific(r.rel_diff_W_plus, 3):>10} "
                         f"{units.cot(r.CoT_plus, CROSSCHECK_DIGITS):>11} "
                         f"{units.scientific(r.rel_diff_CoT_plus, 3):>10} {units.scientific(r.max_phi_dev, 3):>16} "
                         f"{'same' if r.modes_match else 'DIFF':>6} {units.fixed(r.time, 2):>9}")
            if not r.success:
                lines.append(f"       run failed: {r.message}")
        lines.append(f"measured convergence order of S: {self.order:.3f}" if math.isfinite(self.order) else
                     "measured convergence order of S: none (fewer than two errors above the round-off floor "
                     f"{self.tolerances.rel_S_floor:g} max(|S|, L): no discretisation error left)")
        lines.append("")
        lines.append(f"mode sequence over the steady cycle, event phases (event-driven) vs step phases "
                     f"(N = {self.finest.steps}):")
        lines.append("  event-driven: " + " -> ".join(f"{m['mode']}@{m['phase']:.5f}" for m in self.event_modes))
        lines.append("  time-stepping: " + " -> ".join(f"{m['mode']}@{m['phase']:.5f}" for m in self.finest.modes))
        for k, m, te, ts, lag in self.finest.event_lags:
            step = "unmatched" if ts is None else f"step phase {ts:.5f} (lag {lag:+.2f} steps)"
            lines.append(f"  {k:<12} -> {m:<12} event phase {te:.5f}  {step}")
        lines.append("")
        for name, (value, thr, ok) in self.checks.items():
            val = f"{value:.3g}" if isinstance(value, float) else str(value)
            lines.append(f"  [{'PASS' if ok else 'FAIL'}] {name}: {val} (threshold {thr})")
        lines.append(f"overall: {'PASS' if self.passed else 'FAIL'}")
        return "\n".join(lines)


def _row_summary(r: CrossCheckRow, ev: CrawlResult) -> dict:
    """JSON-safe summary of the comparison at one N (non-finite numbers are None)."""
    num = finite_or_none
    return {"steps": r.steps, "success": r.success, "message": r.message, "S_mpcc": num(r.S),
            "W_plus_mpcc": num(r.W_plus), "CoT_plus_mpcc": num(r.CoT_plus), "rel_diff_S": num(r.rel_diff_S),
            "abs_diff_S": num(abs(r.S - ev.S)), "rel_diff_W_plus": num(r.rel_diff_W_plus),
            "rel_diff_CoT_plus": num(r.rel_diff_CoT_plus), "max_phi_dev": num(r.max_phi_dev),
            "modes_mpcc": list(r.modes), "modes_match": r.modes_match,
            "event_lags": [{"kind": k, "mode_after": m, "event_phase": num(te),
                            "step_phase": None if ts is None else num(ts),
                            "lag_steps": None if lag is None else num(lag)} for k, m, te, ts, lag in r.event_lags],
            "time": num(r.time)}


def _event_lags(ev: CrawlResult, res: CrawlResult, N: int) -> list[tuple]:
    """Match each steady event of the event-driven run with the time-stepping mode change of the same kind."""
    ts_events = [(e.t - res.t0, e.mode_before, e.mode_after) for e in res.events
                 if res.t0 + 1e-12 < e.t <= res.t0 + 1 + 1e-12]
    out = []
    for e in ev.steady_events():
        te = e.t - ev.t0
        cands = [t for t, mb, ma in ts_events if ma == e.mode_after and mb == e.mode_before]
        if not cands:
            out.append((e.kind, e.mode_after, te, None, None))
            continue
        # cyclic phase difference in (-1/2, 1/2]
        lags = [((t - te + 0.5) % 1.0) - 0.5 for t in cands]
        j = int(np.argmin(np.abs(lags)))
        out.append((e.kind, e.mode_after, te, cands[j], lags[j] * N))
    return out


def _checks(ev: CrawlResult, rows: list, tol: CrossCheckTolerances, L: float) -> tuple[float, dict]:
    """The measured order of S (over the errors above the round-off floor, ``rel_S_floor`` max(|S|, L) with the
    robot's length L [m]) and the named checks (value, threshold, passed) of a cross-check (module docstring)."""
    errors = [abs(r.S - ev.S) for r in rows]
    steps = [r.steps for r in rows]
    floor = tol.rel_S_floor * max(abs(ev.S), L)
    above = [(n, e) for n, e in zip(steps, errors) if not e <= floor]
    order = convergence_order(*zip(*above)) if len(above) >= 2 else float("nan")
    fin = rows[-1]
    judged = [r for r in rows if r.steps >= min(200, fin.steps)]
    worst = max(judged, key=lambda r: r.rel_diff_S)
    lo, hi = tol.event_lag_steps
    lags = [lag for *_, lag in fin.event_lags]
    lags_ok = all(lag is not None and lo <= lag <= hi for lag in lags)
    all_ok = ev.success and all(r.success for r in rows)
    decreasing = all(b < a or b <= floor for a, b in zip(errors, errors[1:]))
    checks = {
        "all runs succeeded": (float(all_ok), "1", all_ok),
        f"max rel diff S at N >= {judged[0].steps}": (worst.rel_diff_S, tol.rel_S, worst.rel_diff_S <= tol.rel_S),
        f"S error decreasing in N (or <= {tol.rel_S_floor:g} max(|S|, L))": (float(decreasing), "1", decreasing),
        f"rel diff W+ at N={fin.steps}": (fin.rel_diff_W_plus, tol.rel_W_plus, fin.rel_diff_W_plus <= tol.rel_W_plus),
        f"max |phi dev| at N={fin.steps} [rad]": (fin.max_phi_dev, tol.max_phi_dev, fin.max_phi_dev <= tol.max_phi_dev),
        "mode sequences agree": (float(fin.modes_match), "1", fin.modes_match),
        f"event lags within {list(tol.event_lag_steps)} steps": (
            max((abs(x) for x in lags if x is not None), default=0.0) if lags_ok else math.inf,
            f"{lo}..{hi}", lags_ok),
    }
    if abs(ev.S) >= tol.S_floor:
        checks[f"rel diff CoT+ at N={fin.steps}"] = (fin.rel_diff_CoT_plus, tol.rel_CoT_plus,
                                                     fin.rel_diff_CoT_plus <= tol.rel_CoT_plus)
        if len(above) >= 2:
            checks["convergence order of S"] = (order, tol.min_order, bool(order >= tol.min_order))
    else:
        # no net motion: CoT+ is infinite for both, and the errors of S are round-off without an order
        checks["convergence order of S (no motion: S errors)"] = (max(errors), tol.S_floor, max(errors) <= tol.S_floor)
    return order, checks


def crosscheck(model: Model, torque, steps=(50, 100, 200, 400), tolerances: CrossCheckTolerances | None = None,
               mpcc_options: TimeSteppingOptions | MPCCOptions | None = None,
               hybrid_options: HybridOptions | None = None) -> CrossCheckResult:
    """Run the event-driven and the MPCC time-stepping simulators on ``torque`` and compare them (see module doc).

    ``steps``: increasing numbers of steps per cycle (at least two for the convergence order).
    """
    steps = tuple(int(n) for n in steps)
    if len(steps) < 2 or any(n < 4 for n in steps) or list(steps) != sorted(set(steps)):
        raise ValueError(f"steps must be at least two strictly increasing integers >= 4, got {steps!r}")
    tol = CrossCheckTolerances() if tolerances is None else tolerances
    if not isinstance(tol, CrossCheckTolerances):
        raise TypeError(f"tolerances must be CrossCheckTolerances, got {type(tol).__name__}")
    torque = as_signal(torque)
    if mpcc_options is None or isinstance(mpcc_options, MPCCOptions):
        mpcc_options = TimeSteppingOptions() if mpcc_options is None else TimeSteppingOptions(mpcc=mpcc_options)
    ev = simulate(model, torque, "event", hybrid_options)
    event_modes = tuple(mode_sequence(ev))
    rows = []
    for N in steps:
        t_start = time.perf_counter()
        res = simulate(model, torque, "mpcc", replace(mpcc_options, steps=N))
        elapsed = time.perf_counter() - t_start
        if not (res.success and ev.success):
            rows.append(CrossCheckRow(N, res.success, res.message, res.S, res.W_plus, res.CoT_plus, math.inf,
                                      math.inf, math.inf, math.inf, tuple(mode_sequence(res)), (), False, elapsed))
            continue
        ev_n = simulate(model, torque, "event", hybrid_options, t_eval=res.t - res.t0)
        dev = float(np.max(np.abs(ev_n.phi - res.phi))) if ev_n.success else math.inf
        modes = tuple(mode_sequence(res))
        match = _same_cycle(_cyclic([m["mode"] for m in event_modes]), _cyclic([m["mode"] for m in modes]))
        rows.append(CrossCheckRow(
            N, True, res.message, res.S, res.W_plus, res.CoT_plus, _rel(res.S, ev.S, tol.S_floor),
            _rel(res.W_plus, ev.W_plus), _rel(res.CoT_plus, ev.CoT_plus) if abs(ev.S) >= tol.S_floor else math.nan,
            dev, modes, tuple(_event_lags(ev, res, N)), match, elapsed))
    order, checks = _checks(ev, rows, tol, model.robot.L)
    passed = all(ok for *_, ok in checks.values())
    return CrossCheckResult(ev, tuple(rows), order, tol, checks, passed, event_modes)
