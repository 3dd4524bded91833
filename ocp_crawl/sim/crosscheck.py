"""Cross-check of the MPCC time-stepping simulator against the event-driven hybrid stepper.

Both simulators run the same model (the three-link robot's or an n-link chain's) and torque input.
For every number of steps per cycle N the time-stepping result is compared with the event-driven
one on the step phases of the steady cycle (the event-driven stepper is evaluated exactly there
through ``t_eval``): S, W+ and CoT+ and their relative differences, phi at the step phases, the
contact-mode sequences of the steady cycle and, for each mode change of the event-driven stepper,
the phase of the matching mode change of the time-stepping (its lag, in steps).

The steady cycle is a circle: mode changes are taken modulo one cycle, so that an event at the
cycle boundary is one event whether a solver lists it at phase 0 or at phase 1.  A *sub-step
excursion* is a visit A -> B -> A of at most one step whose two mode changes the other solver does
not have: the time-stepping cannot see one inside a step (the step starts and ends in A), and at a
kink of the input it can show one that the event-driven stepper has not.  Excursions are taken out
of both sequences before they are compared, and listed; their cost is judged by the S criterion.

PASS/FAIL is decided by :func:`criteria` only (the table of docs/guide/simulators.md, each with its
value and bound).  The order of S and the largest deviation of phi are information: where S carries
an error its size is what the S criterion bounds; phi follows the foot positions, whose net change
(S) and switches (the events) are judged.

What to expect. Inside a mode the step equations are the mode's equations at t_n, so the
time-stepping is exact there; errors come from transitions. Switch-exact steps
(:mod:`ocp_crawl.sim.step_split`) split a step at the root of the starting mode's guard, the slip
rate read on one piece of the input between its kinks: events agree to about 1e-6 steps and S to
the solvers' tolerance accumulated over the steps (|dS|/|S| <= 2e-8 at N = 50..400 on harmonic
gaits, <= 3e-7 on the OCP's piecewise-linear optima). W+ (midpoint rule) is O(h^2). Plain steps
(``TimeSteppingOptions(switch_exact=False)``) take a change of mode at the first step after the
event: O(h) in S when the slipping foot changes (1.2 / 2.5 / 0.7 / 0.9 % at N = 50 / 100 / 200 /
400 on problems/unequal_friction.toml).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ocp_crawl.checks import finite_or_none, real
from ocp_crawl.io import units
from ocp_crawl.model.inputs import as_signal
from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.model.statics import Model
from ocp_crawl.sim.event import HybridOptions
from ocp_crawl.sim.mpcc import MPCCOptions
from ocp_crawl.sim.registry import simulate
from ocp_crawl.sim.result import CrawlResult, Event, Mode
from ocp_crawl.sim.timestepping import TimeSteppingOptions

#: significant digits of CoT+ in the cross-check table (it compares two solvers: more than 3)
CROSSCHECK_DIGITS = 5
#: mode changes of one transition closer than this modulo one cycle are one event [cycles]: the
#: copies of a boundary event at the ends of the steady cycle (event location to 1e-13)
BOUNDARY_TOL = 1e-9


@dataclass(frozen=True)
class CrossCheckTolerances:
    """Bounds of PASS/FAIL criteria (docs/guide/simulators.md, "Cross-checking the simulators")."""

    rel_S: float = 1e-4
    """largest relative difference of S at every N >= 200 (at the finest N if all are smaller)"""
    rel_W_plus: float = 5e-3
    """largest relative difference of W+ at the finest N [-]"""
    rel_CoT_plus: float = 1e-2
    """largest relative difference of CoT+ at the finest N [-] (gaits that move)"""
    rel_S_floor: float = 1e-7
    """S errors below rel_S_floor max(|S|, L) [m] are the solvers' round-off (the per-step IPOPT
    tolerance accumulated over the run; measured <= 2e-8 |S| at N = 400 on the shipped gaits, about
    1e-8 L on gaits with little net motion): they need not decrease with N and carry no order"""
    event_lag_steps: tuple[float, float] = (-1e-3, 1e-3)
    """window of the lag (step phase - event phase) of a mode change at the finest N, in steps
    (switch-exact steps put each event on a step boundary, up to the slip rate's difference width
    of 1e-3 steps at kinks of the input)"""
    S_floor: float = 1e-6
    """|S| below this [m] counts as no motion: relative differences of S use this instead, and CoT+
    (infinite for both) is not compared"""

    def __post_init__(self) -> None:
        for name in ("rel_S", "rel_W_plus", "rel_CoT_plus", "S_floor", "rel_S_floor"):
            object.__setattr__(self, name, real(f"CrossCheckTolerances.{name}",
                                                getattr(self, name), positive=True))
        lo, hi = (real("CrossCheckTolerances.event_lag_steps", v) for v in self.event_lag_steps)
        if not lo < hi:
            raise ValueError(f"CrossCheckTolerances.event_lag_steps must be (lo, hi) with lo < hi, "
                             f"got {self.event_lag_steps!r}")
        object.__setattr__(self, "event_lag_steps", (lo, hi))


@dataclass(frozen=True)
class Criterion:
    """One PASS/FAIL criterion: what was measured, its value and its bound."""

    what: str
    value: float | bool
    bound: float | bool | tuple
    relation: str
    """"<=" (value at most bound), "==" (value equal to bound), "in" (lo <= value <= hi)"""
    passed: bool

    def text(self) -> str:
        if (self.relation, self.bound) in (("==", True), ("<=", 0)):   # "same", "none": no bound
            must = "the same" if self.relation == "==" else "none"
            shown = _shown(self.value) if self.relation == "==" else str(self.value or "none")
            return f"{self.what}: {shown}" + ("" if self.passed else f", must be {must}")
        bound = (f"[{self.bound[0]:g}, {self.bound[1]:g}]" if self.relation == "in"
                 else _shown(self.bound))
        return f"{self.what} = {_shown(self.value)} (bound {self.relation} {bound})"

    def to_dict(self) -> dict:
        bound = list(self.bound) if isinstance(self.bound, tuple) else self.bound
        value = self.value if isinstance(self.value, bool) else finite_or_none(self.value)
        return {"what": self.what, "value": value, "bound": bound, "relation": self.relation,
                "passed": bool(self.passed)}


def _shown(x) -> str:
    if isinstance(x, bool):
        return "same" if x else "different"
    return f"{x + 0.0:.3g}" if isinstance(x, float) else str(x)   # + 0.0: never "-0"


def convergence_order(steps, errors) -> float:
    """Least-squares slope p of log(error) = c - p log(N); NaN with fewer than two errors > 0."""
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


# ------------------------------------------------------------------------------ the cycle's modes
def cycle_events(events, t0: float) -> list[Event]:
    """The mode changes of the steady cycle [t0, t0 + 1] as events whose ``t`` is the phase modulo
    one cycle, in [-BOUNDARY_TOL, 1 - BOUNDARY_TOL), sorted; an event at the cycle boundary, listed
    at phase 0, at phase 1 or at both, is one event.  Events that keep the mode (grazes) are left
    out: they are no mode change."""
    out: list[Event] = []
    for e in events:
        if not (t0 - BOUNDARY_TOL <= e.t <= t0 + 1 + BOUNDARY_TOL) or e.mode_before == e.mode_after:
            continue
        phase = (e.t - t0) % 1.0
        if phase >= 1.0 - BOUNDARY_TOL:
            phase -= 1.0
        if not any(abs(o.t - phase) <= BOUNDARY_TOL and (o.mode_before, o.mode_after)
                   == (e.mode_before, e.mode_after) for o in out):
            out.append(replace(e, t=phase))
    return sorted(out, key=lambda e: e.t)


def mode_sequence(res: CrawlResult) -> list[dict]:
    """Modes over the steady cycle: the mode at its start (unless an event is there), then one
    entry per mode change (phase within the cycle, modulo one cycle)."""
    if len(res.mode) == 0:
        return []
    evs = cycle_events(res.events, res.t0)
    seq = [{"phase": max(e.t, 0.0), "mode": e.mode_after, "kind": e.kind} for e in evs]
    if not evs or evs[0].t > BOUNDARY_TOL:
        start = evs[-1].mode_after if evs else Mode(int(res.mode[0])).label
        seq.insert(0, {"phase": 0.0, "mode": start, "kind": "start"})
    return seq


@dataclass(frozen=True)
class Excursion:
    """A sub-step excursion taken out of a mode sequence: mode_before -> mode -> mode_before."""

    mode_before: str
    mode: str
    phase: float
    """phase at which the excursion starts [cycles]"""
    steps: float
    """its length [steps]"""


def take_out_excursions(events: list[Event], steps: int, slack: float,
                        matched=frozenset()) -> tuple[list[Event], list[Excursion]]:
    """The cycle's mode changes (:func:`cycle_events`) without their sub-step excursions, and the
    excursions.  An excursion is a visit A -> B -> A of at most (1 + ``slack``) steps (``slack``:
    how far its two ends together may lie off step boundaries) whose two mode changes are not in
    ``matched`` (the indices of those the other solver has too); the shortest goes first."""
    kept, out = list(enumerate(events)), []
    limit = (1.0 + slack) / steps
    while len(kept) >= 2:
        pairs = [(kept[i], kept[(i + 1) % len(kept)]) for i in range(len(kept))]
        short = [((b.t - a.t) % 1.0, i) for i, ((ia, a), (ib, b)) in enumerate(pairs)
                 if (b.t - a.t) % 1.0 <= limit and a.mode_before == b.mode_after
                 and ia not in matched and ib not in matched]
        if not short:
            break
        length, i = min(short)
        a = kept[i][1]
        out.append(Excursion(a.mode_before, a.mode_after, max(a.t, 0.0), length * steps))
        kept = [e for k, e in enumerate(kept) if k not in (i, (i + 1) % len(kept))]
    return [e for _, e in kept], out


def _modes(kept: list[Event], out: list[Excursion], start: str) -> list[str]:
    """Cyclic mode sequence of the mode changes left (``start``: a cycle without any)."""
    if kept:
        return _cyclic([e.mode_after for e in kept])
    return [out[-1].mode_before] if out else [start]


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


def _nearest(e: Event, others: list[Event], N: int) -> tuple[int | None, float | None]:
    """The change of ``others`` between the same modes as ``e`` nearest to it modulo one cycle:
    (its index, lag in steps), or (None, None)."""
    cands = [(((o.t - e.t + 0.5) % 1.0) - 0.5, j) for j, o in enumerate(others)
             if (o.mode_before, o.mode_after) == (e.mode_before, e.mode_after)]
    if not cands:
        return None, None
    lag, j = min(cands, key=lambda c: abs(c[0]))
    return j, lag * N


# -------------------------------------------------------------------------------- the result
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
    """the time-stepping's modes over the steady cycle (:func:`mode_sequence`)"""
    event_lags: tuple
    """(kind, mode_after, event phase, step phase or None, lag in steps or None) per mode change
    of the event-driven cycle that is not part of an excursion"""
    modes_match: bool
    """the mode sequences agree once the sub-step excursions are taken out"""
    time: float
    """wall time of the time-stepping run [s]"""
    excursions_event: tuple = ()
    """sub-step excursions of the event-driven cycle (:class:`Excursion`)"""
    excursions_mpcc: tuple = ()
    """sub-step excursions of the time-stepping cycle"""


def compare_modes(ev: CrawlResult, res: CrawlResult, N: int,
                  tol: CrossCheckTolerances) -> tuple[bool, tuple, tuple, tuple]:
    """(sequences agree, event lags, excursions of ev, excursions of res) at N steps per cycle.

    Each mode change of the event-driven cycle is matched with the time-stepping's nearest change
    between the same modes; matched within the lag window, neither is part of an excursion."""
    lo, hi = tol.event_lag_steps
    ev_all, ts_all = cycle_events(ev.events, ev.t0), cycle_events(res.events, res.t0)
    near = [_nearest(e, ts_all, N) for e in ev_all]
    matched = {i for i, (j, lag) in enumerate(near) if j is not None and lo <= lag <= hi}
    ev_kept, ev_out = take_out_excursions(ev_all, N, hi - lo, matched)
    ts_kept, ts_out = take_out_excursions(ts_all, N, hi - lo, {near[i][0] for i in matched})
    start_ev = Mode(int(ev.mode[0])).label if len(ev.mode) else ""
    start_ts = Mode(int(res.mode[0])).label if len(res.mode) else ""
    match = _same_cycle(_modes(ev_kept, ev_out, start_ev), _modes(ts_kept, ts_out, start_ts))
    lags = []
    for e, (j, lag) in zip(ev_all, near):
        if any(e is k for k in ev_kept):
            step = None if j is None else max(ts_all[j].t, 0.0)
            lags.append((e.kind, e.mode_after, max(e.t, 0.0), step, lag))
    return match, tuple(lags), tuple(ev_out), tuple(ts_out)


@dataclass(frozen=True)
class CrossCheckResult:
    """Outcome of :func:`crosscheck`; ``summary()`` is JSON-able, ``table()`` readable."""

    event: CrawlResult
    rows: tuple
    order: float
    tolerances: CrossCheckTolerances
    checks: dict = field(default_factory=dict)
    """name -> :class:`Criterion`: the criteria that decide PASS/FAIL"""
    passed: bool = False
    event_modes: tuple = ()
    information: dict = field(default_factory=dict)
    """name -> (value, note): what is reported and does not decide"""

    @property
    def finest(self) -> CrossCheckRow:
        return self.rows[-1]

    def summary(self) -> dict:
        """JSON-safe summary (non-finite numbers are None)."""
        num, tol = finite_or_none, self.tolerances
        ev, fin = self.event, self.finest
        return {
            "passed": bool(self.passed),
            "steps": [r.steps for r in self.rows],
            "S_event": num(ev.S), "S_mpcc": num(fin.S), "rel_diff_S": num(fin.rel_diff_S),
            "W_plus_event": num(ev.W_plus), "W_plus_mpcc": num(fin.W_plus),
            "rel_diff_W_plus": num(fin.rel_diff_W_plus),
            "CoT_plus_event": num(ev.CoT_plus), "CoT_plus_mpcc": num(fin.CoT_plus),
            "rel_diff_CoT_plus": num(fin.rel_diff_CoT_plus),
            "max_phi_dev": num(fin.max_phi_dev), "order": num(self.order),
            "event_status": ev.status_name, "event_message": ev.message,
            "modes_event": list(self.event_modes),
            "per_steps": [_row_summary(r, ev) for r in self.rows],
            "checks": {k: c.to_dict() for k, c in self.checks.items()},
            "information": {k: {"value": num(v), "note": note}
                            for k, (v, note) in self.information.items()},
            "tolerances": {k: list(v) if isinstance(v, tuple) else v
                           for k, v in vars(tol).items()},
        }

    def table(self) -> str:
        """Readable report: the runs, the mode sequences and lags at the finest N, the criteria
        (PASS/FAIL) and the information (not deciding)."""
        ev, fin, lines = self.event, self.finest, []
        lines += [f"Cross-check: MPCC time-stepping vs event-driven ({ev.gravity} gravity)",
                  f"event-driven: {ev.message}",
                  f"  S = {units.distance(ev.S, 6)}, W+ = {units.work(ev.W_plus, 6)}, "
                  f"CoT+ = {units.cot(ev.CoT_plus, CROSSCHECK_DIGITS)}", "",
                  f"{'N':>6} {'S_mpcc [mm]':>14} {'rel dS':>10} {'W+_mpcc [mJ]':>13} "
                  f"{'rel dW+':>10} {'CoT+_mpcc':>11} {'rel dCoT+':>10} {'max|dphi| [rad]':>16} "
                  f"{'modes':>6} {'time [s]':>9}"]
        for r in self.rows:
            lines.append(_row_text(r))
            if not r.success:
                lines.append(f"       run failed: {r.message}")
        lines += ["", f"mode sequence over the steady cycle, event phases (event-driven) vs step "
                      f"phases (N = {fin.steps}):",
                  "  event-driven: " + _sequence_text(self.event_modes),
                  "  time-stepping: " + _sequence_text(fin.modes)]
        for k, m, te, ts, lag in fin.event_lags:
            step = "unmatched" if ts is None else f"step phase {ts:.5f} (lag {lag + 0:+.2e} steps)"
            lines.append(f"  {k:<12} -> {m:<12} event phase {te:.5f}  {step}")
        for who, found in (("event-driven", fin.excursions_event),
                           ("time-stepping", fin.excursions_mpcc)):
            for x in found:
                lines.append(f"  sub-step excursion taken out ({who}): {x.mode_before} -> {x.mode} "
                             f"-> {x.mode_before} at phase {x.phase:.5f}, {x.steps:.4f} steps")
        lines += ["", "criteria:"]
        lines += [f"  [{'PASS' if c.passed else 'FAIL'}] {name}: {c.text()}"
                  for name, c in self.checks.items()]
        lines.append("information (does not decide):")
        for name, (value, note) in self.information.items():
            shown = "none" if math.isnan(value) else f"{value:.3g}"
            lines.append(f"  {name}: {shown} ({note})")
        lines.append(f"overall: {'PASS' if self.passed else 'FAIL'}")
        return "\n".join(lines)


def _row_text(r: CrossCheckRow) -> str:
    return (f"{r.steps:>6d} {units.fixed(r.S, 6, 1e3):>14} {units.scientific(r.rel_diff_S, 3):>10} "
            f"{units.fixed(r.W_plus, 6, 1e3):>13} {units.scientific(r.rel_diff_W_plus, 3):>10} "
            f"{units.cot(r.CoT_plus, CROSSCHECK_DIGITS):>11} "
            f"{units.scientific(r.rel_diff_CoT_plus, 3):>10} "
            f"{units.scientific(r.max_phi_dev, 3):>16} "
            f"{'same' if r.modes_match else 'DIFF':>6} {units.fixed(r.time, 2):>9}")


def _sequence_text(modes) -> str:
    return " -> ".join(f"{m['mode']}@{m['phase']:.5f}" for m in modes)


def _row_summary(r: CrossCheckRow, ev: CrawlResult) -> dict:
    """JSON-safe summary of the comparison at one N (non-finite numbers are None)."""
    num = finite_or_none
    return {"steps": r.steps, "success": r.success, "message": r.message, "S_mpcc": num(r.S),
            "W_plus_mpcc": num(r.W_plus), "CoT_plus_mpcc": num(r.CoT_plus),
            "rel_diff_S": num(r.rel_diff_S), "abs_diff_S": num(abs(r.S - ev.S)),
            "rel_diff_W_plus": num(r.rel_diff_W_plus),
            "rel_diff_CoT_plus": num(r.rel_diff_CoT_plus), "max_phi_dev": num(r.max_phi_dev),
            "modes_mpcc": list(r.modes), "modes_match": r.modes_match,
            "event_lags": [{"kind": k, "mode_after": m, "event_phase": num(te),
                            "step_phase": None if ts is None else num(ts),
                            "lag_steps": None if lag is None else num(lag)}
                           for k, m, te, ts, lag in r.event_lags],
            "excursions_event": [dict(vars(x)) for x in r.excursions_event],
            "excursions_mpcc": [dict(vars(x)) for x in r.excursions_mpcc],
            "time": num(r.time)}


# ------------------------------------------------------------------------------ the criteria
def criteria(ev: CrawlResult, rows: list, tol: CrossCheckTolerances,
             L: float) -> tuple[dict, dict, float]:
    """The PASS/FAIL criteria (name -> :class:`Criterion`, the documented list), the information
    (name -> (value, note)) and the measured order of S, fitted over the S errors above the
    round-off floor ``rel_S_floor`` max(|S|, L) with the robot's length L [m]."""
    errors = [abs(r.S - ev.S) for r in rows]
    floor = tol.rel_S_floor * max(abs(ev.S), L)
    above = [(r.steps, e) for r, e in zip(rows, errors) if not e <= floor]
    order = convergence_order(*zip(*above)) if len(above) >= 2 else math.nan
    fin = rows[-1]
    judged = [r for r in rows if r.steps >= min(200, fin.steps)]
    worst = max(r.rel_diff_S for r in judged)
    failed = int(not ev.success) + sum(not r.success for r in rows)
    stalls = sum(not (b < a or b <= floor) for a, b in zip(errors, errors[1:]))
    lo, hi = tol.event_lag_steps
    lags = [lag for *_, lag in fin.event_lags]
    worst_lag = (math.inf if any(lag is None for lag in lags)
                 else max(lags, key=abs, default=0.0))
    at = f"at N = {fin.steps}"
    checks = {
        "runs succeeded": Criterion(
            f"failed runs of the {1 + len(rows)} (event-driven, time-stepping at each N)",
            failed, 0, "<=", failed == 0),
        "S": Criterion(f"largest relative S error at N >= {judged[0].steps}", worst, tol.rel_S,
                       "<=", worst <= tol.rel_S),
        "S decreasing": Criterion(
            f"S errors above the round-off floor {floor:.2g} m not below the previous N's",
            stalls, 0, "<=", stalls == 0),
        "W+": Criterion(f"relative W+ error {at}", fin.rel_diff_W_plus, tol.rel_W_plus, "<=",
                        fin.rel_diff_W_plus <= tol.rel_W_plus),
    }
    if abs(ev.S) >= tol.S_floor:  # without net motion CoT+ is infinite for both
        cot = fin.rel_diff_CoT_plus
        checks["CoT+"] = Criterion(f"relative CoT+ error {at}", cot, tol.rel_CoT_plus, "<=",
                                   cot <= tol.rel_CoT_plus)
    n_out = len(fin.excursions_event) + len(fin.excursions_mpcc)
    out = f" ({units.plural(n_out, 'sub-step excursion')} taken out)" if n_out else ""
    checks["mode sequence"] = Criterion(f"mode sequences {at}{out}", bool(fin.modes_match), True,
                                        "==", bool(fin.modes_match))
    checks["event lags"] = Criterion(
        f"largest lag of the event-driven mode changes {at} [steps]", worst_lag, (lo, hi), "in",
        lo <= worst_lag <= hi)
    information = {
        "convergence order of S": (order, "least-squares slope over the S errors above the "
                                          "round-off floor; none: fewer than two"),
        f"largest |phi deviation| {at} [rad]": (fin.max_phi_dev, "at the step phases"),
    }
    return checks, information, order


def crosscheck(model: Model | ChainModel, torque, steps=(50, 100, 200, 400),
               tolerances: CrossCheckTolerances | None = None,
               mpcc_options: TimeSteppingOptions | MPCCOptions | None = None,
               hybrid_options: HybridOptions | None = None) -> CrossCheckResult:
    """Run the event-driven and the MPCC time-stepping simulators on ``torque`` and compare them.

    ``steps``: increasing numbers of steps per cycle (at least two, for the S errors' trend).  The
    event solver checks every step count, so the MPCC's own estimate of S's error is not made.
    """
    steps = tuple(int(n) for n in steps)
    if len(steps) < 2 or any(n < 4 for n in steps) or list(steps) != sorted(set(steps)):
        raise ValueError(f"steps must be at least two strictly increasing integers >= 4, "
                         f"got {steps!r}")
    tol = CrossCheckTolerances() if tolerances is None else tolerances
    if not isinstance(tol, CrossCheckTolerances):
        raise TypeError(f"tolerances must be CrossCheckTolerances, got {type(tol).__name__}")
    torque = as_signal(torque)
    if mpcc_options is None or isinstance(mpcc_options, MPCCOptions):
        mpcc_options = (TimeSteppingOptions(s_error_tol=0.0) if mpcc_options is None
                        else TimeSteppingOptions(mpcc=mpcc_options, s_error_tol=0.0))
    ev = simulate(model, torque, "event", hybrid_options)
    rows = []
    for N in steps:
        t_start = time.perf_counter()
        res = simulate(model, torque, "mpcc", replace(mpcc_options, steps=N))
        elapsed = time.perf_counter() - t_start
        if not (res.success and ev.success):
            rows.append(CrossCheckRow(N, res.success, res.message, res.S, res.W_plus, res.CoT_plus,
                                      math.inf, math.inf, math.inf, math.inf,
                                      tuple(mode_sequence(res)), (), False, elapsed))
            continue
        ev_n = simulate(model, torque, "event", hybrid_options, t_eval=res.t - res.t0)
        dev = float(np.max(np.abs(ev_n.phi - res.phi))) if ev_n.success else math.inf
        match, lags, ev_out, ts_out = compare_modes(ev, res, N, tol)
        moving = abs(ev.S) >= tol.S_floor
        rows.append(CrossCheckRow(
            N, True, res.message, res.S, res.W_plus, res.CoT_plus, _rel(res.S, ev.S, tol.S_floor),
            _rel(res.W_plus, ev.W_plus), _rel(res.CoT_plus, ev.CoT_plus) if moving else math.nan,
            dev, tuple(mode_sequence(res)), lags, match, elapsed, ev_out, ts_out))
    length = model.chain.L if isinstance(model, ChainModel) else model.robot.L
    checks, information, order = criteria(ev, rows, tol, length)
    passed = all(c.passed for c in checks.values())
    return CrossCheckResult(ev, tuple(rows), order, tol, checks, passed,
                            tuple(mode_sequence(ev)), information)
