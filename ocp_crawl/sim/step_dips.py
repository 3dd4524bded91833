"""The contact guards between the incremental steps: where a joint, a normal force or the feet's
distance first reaches zero inside a step.

The incremental (time-stepping) simulators check the contacts at the steps' ends.  A guard can dip
below zero and back inside a step and pass that test, so that a run in which a joint goes under
the ground would end as a success; and a guard found below zero at a step's end reached zero
somewhere inside the step, not at its end.  Here each step of one contact mode is looked into:
every contact guard is interpolated by the cubic Hermite polynomial of its values and exact rates
(along the mode's solution, the models' ``evaluate``) at the step's ends, and where that cubic
dips below zero (or would within its error estimate, the trapezoid defect of the ends' values and
rates, as in the event-driven stepper's test), or the guard is not positive at the end, the step
is solved inside (the mode's step from the step's start to the phase, as the steps themselves
are) and the first zero located by Brent's method on those solutions: the interpolant only says
where to look, the steps' own solutions decide.  :func:`first_zero` is that search;
:func:`three_link_dip` its use by the three-link MPCC steps (:mod:`ocp_crawl.sim.timestepping`);
the chain's steps have theirs in :mod:`ocp_crawl.sim.chain_mpcc_checks`.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from ocp_crawl.model.statics import AUX_NAMES, call_mapped
from ocp_crawl.sim.chain_pieces import ChainPieces
from ocp_crawl.sim.event_guards import interior
from ocp_crawl.sim.event_state import mode_q
from ocp_crawl.sim.oracle import ENUM_MODES, solve_step_enumerate
from ocp_crawl.sim.result import Mode
from ocp_crawl.sim.step import StepState, step_outputs, step_params
from ocp_crawl.sim.step_split import slip_pair
from ocp_crawl.status import Status

#: a scaled guard (heights and distance / L, normal forces / (M g)) whose interpolant falls below
#: -DIP_FLOOR inside a step is looked at [-]
DIP_FLOOR = 1e-12
#: phase tolerance of the located first zero of a guard [cycles]
DIP_XTOL = 1e-12
#: the mode's solution at a step's end is the step's end when their angles agree to this [rad]
SAME_BRANCH = 1e-6
#: the statuses of a lost contact
CONTACT = (Status.LIFT_OFF, Status.FEET_CROSSED, Status.JOINT_ON_GROUND)


def contact_guards(m: int) -> list[tuple[str, str, Status]]:
    """(value, rate, status) of the contact guards of a robot with m joints: the rows of the
    models' ``evaluate`` outputs and the status a zero of the guard ends a run with."""
    out = [("fn1", "dfn1", Status.LIFT_OFF), ("fn2", "dfn2", Status.LIFT_OFF),
           ("d", "ddot", Status.FEET_CROSSED)]
    return out + [(f"zj{j}", f"dzj{j}", Status.JOINT_ON_GROUND) for j in range(1, m + 1)]


def describe(name: str) -> str:
    """The guard ``name`` in words."""
    return {"fn1": "foot 1's normal force", "fn2": "foot 2's normal force",
            "d": "the feet's distance"}.get(name, f"joint {name[2:]}'s height")


def _suspects(spans: list, ends: dict, m: int) -> list[tuple[float, int, str]]:
    """(phase, step k, guard) of each guard whose cubic dips below zero inside step k, comes near
    zero or would dip within its error estimate (:func:`~ocp_crawl.sim.event_guards.interior`), or
    that is not positive at its end (at the end); earliest first."""
    K, found = len(spans), []
    for name, rate, _ in contact_guards(m):
        g, r = ends[name], ends[rate]
        for k, (ta, tb) in enumerate(spans):
            g0, g1, h = g[k], g[K + k], tb - ta
            if not g1 > 0:
                found.append((tb, k, name))
                continue
            kind, s = interior(g0, g1, h * r[k], h * r[K + k], -DIP_FLOOR, contact=True)
            if kind is not None:   # (a dip, a near touch, or a dip within the error estimate)
                found.append((ta + s * h, k, name))
    return sorted(found)


def _zero(g: Callable[[float], float], ta: float, tb: float, t_min: float) -> tuple | None:
    """(first zero, phase of the lowest value found, that value) of g on [ta, tb] from the
    cubic's guess t_min; None where g stays positive or a solve fails."""
    from scipy.optimize import brentq, minimize_scalar   # (not at import: the parser's modules)
    lowest = t_min
    if not g(t_min) <= 0:
        found = minimize_scalar(g, bounds=(ta, tb), method="bounded",
                                options={"xatol": 1e-9 * (tb - ta), "maxiter": 60})
        if not found.fun <= 0:
            return None
        lowest = float(found.x)
    g_start = g(ta)
    if not np.isfinite(g_start):
        return None
    try:
        t0 = brentq(g, ta, lowest, xtol=DIP_XTOL) if g_start > 0 else ta
    except ValueError:   # (a failed solve inside: nan)
        return None
    return t0, lowest, g(lowest)


def first_zero(spans: list, ends: dict, m: int,
               probe: Callable[[int, str], Callable[[float], float]]) -> tuple | None:
    """The first zero of a contact guard inside the steps ``spans`` [(ta, tb)] [cycles].

    ``ends``: the scaled guards and their rates [1/cycle] (rows of :func:`contact_guards`) at
    the steps' starts (columns 0..K-1) and ends (K..2K-1) in each step's mode; ``probe(k, name)``:
    the scaled guard on the mode's solutions of step k as a function of the phase (nan where a
    solve fails, :func:`step_probes`).  Returns (phase of the zero, the step k, guard, phase of
    the lowest value found, that value) or None when every guard stays positive."""
    best = None
    # (the suspects in phase order are in step order: every guard of the first step with a zero)
    for t_min, k, name in _suspects(spans, ends, m):
        if best is not None and k != best[1]:
            break
        z = _zero(probe(k, name), *spans[k], t_min)
        if z is not None and (best is None or z[0] < best[0]):
            best = (z[0], k, name, z[1], z[2])
    return best


def step_probes(solve: Callable[[int, float], tuple | None], ends_phi: list,
                spans: list) -> Callable[[int, str], Callable[[float], float]]:
    """``probe(k, name)`` for :func:`first_zero` from ``solve(k, t)`` -> (phi [rad], the scaled
    guards by name) of step k's mode at phase t, or None when the solve fails.  A step whose
    mode's solution at its end is not the step's end ``ends_phi[k]`` (another branch, or a mode
    change the step did not locate) is not looked into: its probe is nan."""
    known: dict = {}

    def at(k: int, t: float) -> tuple | None:
        if (k, t) not in known:
            known[(k, t)] = solve(k, t)
        return known[(k, t)]

    def probe(k: int, name: str) -> Callable[[float], float]:
        end = at(k, spans[k][1])
        if end is None or not np.max(np.abs(end[0] - ends_phi[k])) <= SAME_BRANCH:
            return lambda t: np.nan

        def g(t: float) -> float:
            got = at(k, t)
            return np.nan if got is None else float(got[1][name])
        return g
    return probe


def dip_report(zero: tuple, spans: list, m: int, Mg: float, L: float) -> tuple:
    """(phase, status, step k, message) of a zero found by :func:`first_zero` (``Mg``, ``L``:
    the weight [N] and length [m] that scale the guards)."""
    t0, k, name, lowest, value = zero
    status = next(s for n, _, s in contact_guards(m) if n == name)
    scale = Mg if name.startswith("fn") else L
    return t0, status, k, (f"{describe(name)} reaches zero at t = {t0:.6f} in the step "
                           f"[{spans[k][0]:.6f}, {spans[k][1]:.6f}] ({value * scale:.4g} at "
                           f"t = {lowest:.6f})")


def _mode_end(stepper, row: tuple, t: float, mode: Mode) -> tuple | None:
    """The row of ``mode``'s equilibrium at phase t on the step from ``row`` (the
    mode-enumeration oracle's candidate, which may have lost a contact), or None."""
    tau = np.asarray(stepper.torque(t), float)
    if mode not in ENUM_MODES or not np.all(np.isfinite(tau)):
        return None
    state = StepState(row[1], row[4], row[5], row[6])
    res = solve_step_enumerate(stepper.model, state, tau)
    cand = next(c for c in res.extra["candidates"] if c["mode"] == mode.label)
    if not cand["converged"]:
        return None
    nan = float("nan")
    return (t, np.asarray(cand["phi"]), nan, row[3], nan, nan, cand["f_t"], nan, nan, int(mode))


def guard_ends(torque, a: list, b: list, x: np.ndarray, q: np.ndarray, evaluate: Callable,
               Mg: float, L: float) -> dict:
    """The scaled contact guards and their rates [1/cycle] (rows of :func:`contact_guards`) of the
    steps a[k] -> b[k] (rows, phase first) at their starts (columns 0..K-1) and ends (K..2K-1):
    ``evaluate(x, tau, dtau, q)`` -> the model's outputs by name at the states ``x`` in the modes
    ``q`` (columns), the torques' rates read after a kink at a start and before it at an end."""
    pieces = ChainPieces(torque)
    ts = np.array([r[0] for r in a + b])
    tr = np.array([pieces.rate_phase(r[0]) for r in a]
                  + [pieces.rate_phase(r[0], left=True) for r in b])
    m = x.shape[0] - 1
    tau = np.asarray(torque(ts), float).reshape(m, -1)
    dtau = np.asarray(torque.derivative(tr), float).reshape(m, -1)
    out = evaluate(x, tau, dtau, q)
    return {n: np.asarray(out[n]) / (Mg if n.startswith(("fn", "dfn")) else L)
            for v, r, _ in contact_guards(m) for n in (v, r)}


def three_link_dip(stepper, rows: list, located: set, end: tuple | None = None) -> tuple | None:
    """:func:`first_zero` in the three-link MPCC steps ``rows`` ((t, phi, theta, d, x1, x2, f_t,
    f_n1, f_n2, mode) of :class:`~ocp_crawl.sim.timestepping.TimeStepper`; ``located``: the phases
    of its located events, each the start of a step in the mode after it) and, with ``end`` =
    (phase, mode), the step from the last row to that phase in that mode (the step the run
    stopped in).  Returns (phase, status, mode, message) or None."""
    if end is not None and rows:
        last = _mode_end(stepper, rows[-1], *end)
        rows = rows if last is None else [*rows, last]
    # (an event row carries the mode before the event: the step after it is in the next row's;
    # both feet slipping is not a mode the steps are solved in one at a time)
    idx = [i for i in range(1, len(rows)) if rows[i][0] > rows[i - 1][0]
           and (rows[i][9] == rows[i - 1][9] or rows[i - 1][0] in located)
           and Mode(rows[i][9]) in ENUM_MODES]
    if not idx:
        return None
    model, Mg, L = stepper.model, stepper.Mg, stepper.model.robot.L
    modes = [Mode(rows[i][9]) for i in idx]
    a, b = [rows[i - 1] for i in idx], [rows[i] for i in idx]
    x = np.array([np.append(r[1], r[6] / Mg) for r in a + b]).T
    q = np.array([mode_q(mode, r[3]) for mode, r in zip(modes + modes, a + a)]).T

    def evaluate(*args) -> dict:
        return dict(zip(AUX_NAMES, call_mapped(model.sym.evaluate, *args, model.p)))

    ends = guard_ends(stepper.torque, a, b, x, q, evaluate, Mg, L)

    def solve(k: int, t: float) -> tuple | None:
        state = StepState(a[k][1], a[k][4], a[k][5], a[k][6])
        tau = np.asarray(stepper.torque(t), float).reshape(2)
        sol = stepper.step.solve_in_mode(state, tau, slip_pair(modes[k]))
        if not (sol.accepted and sol.eq <= stepper.step.options.eq_tol):
            return None
        out = np.asarray(step_outputs()(sol.x[:8], step_params(model, state, tau))).ravel()
        kin = model.kinematics(sol.x[:2])
        # (f_n / (M g) and d [m] of the step's outputs)
        return sol.x[:2], {"fn1": out[0], "fn2": out[1], "d": out[2] / L,
                           "zj1": kin["zj1"] / L, "zj2": kin["zj2"] / L}

    spans = [(r[0], s[0]) for r, s in zip(a, b)]
    zero = first_zero(spans, ends, 2, step_probes(solve, [r[1] for r in b], spans))
    if zero is None:
        return None
    t0, status, k, message = dip_report(zero, spans, 2, Mg, L)
    return t0, status, modes[k], message
