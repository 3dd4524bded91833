"""Convergence in the number of nodes N, shown rather than assumed: :func:`converge_in_nodes`.

The OCP is solved at each N of an increasing list: the first N by
:func:`~ocp_crawl.ocp.solve.optimize_gait` (harmonic baseline and multi-start), every further N
warm-started from the previous N's optimum (its node profile, linear in phase, sampled at the new
nodes, and its period: for N doubling, the previous profile exactly; its homotopy stages loose, the
last one too, and the polish tight: :data:`WARM_STAGE_TOL`; if that solve is not judged a success,
the same start once more with the cold solve's relaxation and barrier settings; settings with their
own homotopy, :func:`own_homotopy`, keep it, with the warm barrier, after a first try of the
tightened NLP alone on the branches of the previous profile's simulated guess, kept when judged a
success and not worse than the previous optimum), or, while no N has given an optimum whose replay
succeeds, again from the baseline and its starts.  Each optimum is judged by its event-driven
replay.  The table gives, per N, the OCP's and the replay's objective, the change from the previous
N and the observed order

    p = log(|d_i| / |d_i+1|) / log(r),   d_i = J(N_i) - J(N_i-1),   r = N_i / N_i-1 = N_i+1 / N_i

(p = log2(|d_(N/2 -> N)| / |d_(N -> 2N)|) for doubling), defined where three successive N have a
constant ratio and both changes are finite and non-zero.  If J(N) = J* + C N^-p, this p is exact.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ocp_crawl.io.files import jsonable
from ocp_crawl.model.statics import GravityConvention
from ocp_crawl.nlp.homotopy import observed_elsewhere
from ocp_crawl.ocp.asymmetry import check_friction_asymmetry
from ocp_crawl.ocp.judge import is_better, replay_signal
from ocp_crawl.ocp.limits import NODES_BOUNDS
from ocp_crawl.ocp.plant import AnyRobot, Plant
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.solve import OCPResult, optimize_gait, solve_from
from ocp_crawl.ocp.solver import GaitSolver
from ocp_crawl.ocp.transcription import GaitOCP
from ocp_crawl.status import Status
from ocp_crawl.workers import overlap

#: first relaxation parameter of a solve warm-started from the previous N's optimum (then down to
#: the settings' sigma_min, or a tenth of it if smaller).  1e-4 like a cold solve: with slip onsets
#: and the held-tie rules at a sub-step's start, the simulated guess at the finer N starts slips
#: inside sub-steps where two events share an interval, and at sigma 1e-6 IPOPT took > 2000
#: iterations to repair it (max_speed, N = 100 from N = 50)
WARM_SIGMA0 = 1e-4
#: IPOPT tolerance of every stage of a warm-started solve, the last one included (``loose_last``:
#: only the polish is tight; the settings' ``stage_tol`` or sigma_min if tighter; not the cold
#: solve's looser default): the monotone barrier starts at mu = 1e-6, below a loose tolerance, so a
#: stage at 1e-4 would stop after a few dozen iterations and leave the work to the stage at
#: sigma_min, where IPOPT struggles (max_speed, N = 200 from N = 100: max_iter).  Measured,
#: max_speed N = 50..400, one run each, a tight last stage: 1e-4: 442 s; 1e-6: 295 s; 1e-8: 742 s (a
#: 1832-iteration polish at N = 400); 1e-10: 397 s.  With the last stage at 1e-6 too: 169 s, the
#: same optima to 1e-5 (the tight last stage had taken 300 to 860 iterations, up to 0.2 s each at N
#: = 400).  A further loose stage at sigma = 1e-8 helped max_speed (139 s) but not min_cot (502 s
#: instead of 218 s: a 1392-iteration polish at N = 400)
WARM_STAGE_TOL = 1e-6
#: IPOPT options of a solve warm-started from the previous N's optimum (the settings' own ipopt
#: options win)
WARM_IPOPT = {"mu_strategy": "monotone", "mu_init": 1e-6, "bound_push": 1e-8, "bound_frac": 1e-8,
              "slack_bound_push": 1e-8, "slack_bound_frac": 1e-8}
#: first relaxation parameter of a warm-started solve with the settings' own homotopy
#: (:func:`own_homotopy`; when below their sigma0 and above their sigma_min): the previous optimum
#: is complementary (robust_speed's to 5e-7), and stages above it only relax it and let IPOPT
#: wander.  Measured, robust_speed N = 400 from the N = 200 optimum that the file's own homotopy had
#: reached (70.419 mm/s; the other core busy): from sigma = 1e-3, max_iter at sigma = 1e-6 after
#: 2527 s; from 1e-5, success, 70.256 mm/s in 2420 s
WARM_OWN_SIGMA0 = 1e-5
#: relative shortfall of a finer N's replayed optimum below the previous N's, beyond both rows'
#: OCP-replay differences, from which its row says so (the finer N can represent the previous
#: profile when it is a multiple of the previous N: a worse optimum is then another local optimum,
#: not a discretisation effect)
WORSE_TOL = 1e-4


def observed_orders(nodes: list[int], values: list[float]) -> list[float]:
    """Observed order of convergence at each N (NaN where undefined; see the module docstring).

    Parameters
    ----------
    nodes : list of int
        Increasing numbers of nodes N_0 < N_1 < ...
    values : list of float
        The objective J(N_i) at each (any unit).

    Returns
    -------
    list of float
        p_i = log(|d_i| / |d_i+1|) / log(r) at index i (the middle N of the three), NaN at the ends,
        where the ratio N_i / N_i-1 differs from N_i+1 / N_i, or where a change is zero or not
        finite.
    """
    out = [math.nan] * len(nodes)
    for i in range(1, len(nodes) - 1):
        r = nodes[i] / nodes[i - 1]
        d0, d1 = values[i] - values[i - 1], values[i + 1] - values[i]
        if not (r > 1 and math.isclose(nodes[i + 1] / nodes[i], r, rel_tol=1e-12)):
            continue
        if math.isfinite(d0) and math.isfinite(d1) and d0 != 0 and d1 != 0:
            out[i] = math.log(abs(d0) / abs(d1)) / math.log(r)
    return out


@dataclass
class ConvergenceRow:
    """One N of the convergence table."""

    nodes: int
    status: Status
    message: str
    T: float
    """period [s]"""
    value_ocp: float
    """the OCP's objective (speeds [m/s], CoT+ [-])"""
    value_replay: float
    """the replay's objective (same unit)"""
    rel_diff_replay: float
    change: float = math.nan
    """value_replay minus the previous N's (same unit)"""
    rel_change: float = math.nan
    """change / |value_replay| [-]"""
    order: float = math.nan
    """observed order p of the replayed objective at this N (see :func:`observed_orders`)"""
    order_ocp: float = math.nan
    """observed order of the OCP's objective"""
    solve_time_s: float = math.nan
    result: OCPResult | None = field(default=None, repr=False)
    """the full result at this N"""

    def to_dict(self) -> dict:
        """JSON-able (the status as its label, without the full result)."""
        data = {k: v for k, v in vars(self).items() if k != "result"}
        return jsonable(dict(data, status=self.status.label))


@dataclass
class ConvergenceTable:
    """The OCP solved at each N: :class:`ConvergenceRow` per N, in increasing N."""

    objective: str
    rows: list
    unit: str
    """the objective's unit (:meth:`~ocp_crawl.ocp.settings.OCPSettings.objective_unit`)"""

    @property
    def success(self) -> bool:
        """True when the judge accepted the optimum at every N."""
        return bool(self.rows) and all(r.status == Status.SUCCESS for r in self.rows)

    def to_dict(self) -> dict:
        """JSON-able: the objective, its unit, the units of the rows' numbers and the rows."""
        unit = self.unit
        units = {"T": "s", "value_ocp": unit, "value_replay": unit, "change": unit,
                 "rel_diff_replay": "-",
                 "rel_change": "-", "order": "-", "order_ocp": "-", "solve_time_s": "s"}
        return jsonable({"objective": self.objective, "unit": unit, "units": units,
                         "success": self.success, "rows": [r.to_dict() for r in self.rows]})


def check_nodes(nodes) -> list[int]:
    """The list of N, validated: integers in NODES_BOUNDS, strictly increasing, at least one;
    ValueError naming the first bad value otherwise."""
    out: list[int] = []
    for n in nodes:
        low, high = NODES_BOUNDS
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not low <= n <= high:
            raise ValueError(f"nodes: {n!r} is not an integer in [{NODES_BOUNDS[0]}, "
                             f"{NODES_BOUNDS[1]}]")
        if out and n <= out[-1]:
            raise ValueError(f"nodes must increase strictly, got {n} after {out[-1]}")
        out.append(int(n))
    if not out:
        raise ValueError("nodes: give at least one N")
    return out


def converge_in_nodes(robot: AnyRobot, gravity: GravityConvention, settings: OCPSettings, nodes,
                      log=None, jobs: int | None = None) -> ConvergenceTable:
    """Solve the OCP at each N of ``nodes``, warm-starting each from the previous optimum, replay
    each.

    Parameters
    ----------
    robot : Robot or Chain
        The robot (SI units).
    gravity : str
        The gravity convention ("physical" or "paper").
    settings : OCPSettings
        The OCP's settings; ``nodes`` replaces its N.
    nodes : list of int
        Strictly increasing N (each in NODES_BOUNDS), e.g. [50, 100, 200, 400].
    log : callable, optional
        ``log(text)`` after each N (progress).
    jobs : int, optional
        Worker processes of the harmonic baseline's search at the first N (None: the CPUs
        available).

    Returns
    -------
    ConvergenceTable
        One row per N: status, period [s], OCP and replayed objective, change from the previous N,
        observed order, time [s], and the full :class:`~ocp_crawl.ocp.result.OCPResult`.
    """
    nodes = check_nodes(nodes)
    rows, warm, ready = [], None, None
    for i, N in enumerate(nodes):
        t0 = time.perf_counter()
        s = replace(settings, nodes=N)
        if warm is None:
            res, ready = optimize_gait(robot, gravity, s, jobs=jobs), None
        else:
            res, ready = _warm_row(robot, gravity, s, warm, ready, nodes[i + 1:])
        if math.isfinite(res.value_replay):
            # a profile the simulator follows (a failed replay would not start the next N)
            warm = res
        rows.append(ConvergenceRow(N, res.status, res.message, res.T_ocp, res.value_ocp,
                                   res.value_replay,
                                   res.rel_diff_replay, solve_time_s=time.perf_counter() - t0,
                                   result=res))
        if log is not None:
            log(f"N = {N}: {res.status.label} ({time.perf_counter() - t0:.1f} s)")
    _changes(rows, settings.objective)
    return ConvergenceTable(settings.objective, rows, settings.objective_unit)


def _warm_row(robot: AnyRobot, gravity: GravityConvention, settings: OCPSettings, prev: OCPResult,
              ready: GaitSolver | None, later: list[int]) -> tuple[OCPResult, GaitSolver | None]:
    """The warm solve at settings.nodes (on the transcription ``ready`` if it is of this N: built
    while the previous row solved) and the next N's transcription: when a finer N follows, the solve
    runs in a forked process while this one builds it (:func:`~ocp_crawl.workers.overlap`; the
    homotopy's records still reach this process's observers, and the same solve runs here where fork
    is not safe).  Returns (result, the next N's transcription or None)."""
    solver = ready if ready is not None and ready.settings.nodes == settings.nodes else None
    if not later:
        return _warm_solve(robot, gravity, settings, prev, solver), None
    task, forward = observed_elsewhere(lambda: _warm_solve(robot, gravity, settings, prev, solver))
    return overlap(task,
                   lambda: warm_transcription(robot, gravity, replace(settings, nodes=later[0])),
                   forward)


def warm_transcription(robot: AnyRobot, gravity: GravityConvention,
                       settings: OCPSettings) -> GaitSolver:
    """The transcription of a solve warm-started from the previous N's optimum (:func:`_near`) and
    its solver, the first IPOPT solver built (:meth:`~ocp_crawl.ocp.solver.GaitSolver.prepare`: at
    N = 400, about 8 s of derivative generation)."""
    solver = GaitSolver(GaitOCP(robot, gravity, _near(settings)[0]))
    solver.prepare()
    return solver


def _near(settings: OCPSettings) -> tuple[OCPSettings, str]:
    """The settings of a solve warm-started from the previous N's optimum, and how they were chosen
    (in words): the warm schedule, or the settings' own homotopy when they have one
    (:func:`own_homotopy`), with the warm barrier, from sigma = :data:`WARM_OWN_SIGMA0` where that
    is below its sigma0 and above its sigma_min."""
    # the previous optimum is near the new one: a small, monotone barrier parameter stays with it
    # (IPOPT's adaptive barrier raised mu to 1e-2 and threw the iterate away: N = 400 took > 600
    # iterations)
    ipopt = {**WARM_IPOPT, **settings.ipopt}
    if own_homotopy(settings):
        if settings.sigma_min < WARM_OWN_SIGMA0:
            sigma0 = tuple(dict.fromkeys(min(s0, WARM_OWN_SIGMA0) for s0 in settings.sigma0))
            return (replace(settings, sigma0=sigma0, ipopt=ipopt),
                    f"with the settings' own homotopy from sigma = {sigma0[0]:.0e}")
        return replace(settings, ipopt=ipopt), "with the settings' own homotopy"
    sigma_min = min(settings.sigma_min, WARM_SIGMA0 / 10)
    return (replace(settings, sigma0=(WARM_SIGMA0,), sigma_min=sigma_min, loose_last=True,
                    ipopt=ipopt,
                    # loose_last: <= sigma_min
                    stage_tol=min(settings.stage_tol, WARM_STAGE_TOL, sigma_min)),
            "with the warm schedule")


def _warm_solve(robot: AnyRobot, gravity: GravityConvention, settings: OCPSettings, prev: OCPResult,
                solver: GaitSolver | None = None) -> OCPResult:
    """The OCP at settings.nodes from the previous optimum's profile and period (the baseline as
    before), with the settings of :func:`_near` (on ``solver`` when given: their transcription's
    solver); settings with their own homotopy (:func:`own_homotopy`) or tightened starts
    (``start_solve``) first solve only the tightened NLP on the branches of the previous profile's
    simulated guess (:meth:`~ocp_crawl.ocp.solver.GaitSolver.solve_tightened`), kept if the judge
    accepts it and it is not worse than the previous optimum (:func:`_shortfall`); then the
    homotopy; if that is not a success, the same start with the cold solve's settings.  A judged
    success of the tightened NLP that is worse than the previous optimum is still the row when the
    homotopy gives no success or a worse one.  The row's ``solve_time_s`` [s] is that of every
    attempt made (tightened, homotopy, cold retry), whichever gave the row."""
    models = [Plant(r, gravity) for r in settings.scenarios(robot)]
    signal = replay_signal(prev.phase, prev.tau)
    n_prev = prev.tau.shape[1]
    near, how = _near(settings)
    solver = solver or GaitSolver(GaitOCP(robot, gravity, near))
    tight, tried, attempts = None, "", []
    if own_homotopy(settings) or settings.start_solve != "homotopy":
        tight = solve_from(solver, models, signal, prev.T_ocp, prev.harmonic, tightened=True,
                           baselines=prev.baselines)
        attempts.append(tight)
        worse = _shortfall(settings.objective, _numbers(prev), _numbers(tight))
        base, note = tight.message, (f", {worse:.2%} worse than N = {n_prev}" if worse else "")
        tight.message = (f"{base} (warm start from the optimum at N = {n_prev}: the tightened NLP "
                         f"on its branches{note})")
        if tight.status == Status.SUCCESS and not worse:
            check_friction_asymmetry(tight, models)
            return tight
        tried = f"; the tightened NLP on its branches gave: {base}{note}"
    res = solve_from(solver, models, signal, prev.T_ocp, prev.harmonic, baselines=prev.baselines)
    attempts.append(res)
    res.message += f" (warm start from the optimum at N = {n_prev}, {how}{tried})"
    if res.status != Status.SUCCESS:  # the same start with the cold solve's relaxation and barrier
        warm_msg = res.message
        res = solve_from(GaitSolver(GaitOCP(robot, gravity, settings)), models, signal, prev.T_ocp,
                         prev.harmonic, baselines=prev.baselines)
        attempts.append(res)
        res.message += (f" (from the optimum at N = {n_prev} with the cold solve's settings; the "
                        f"warm settings gave: {warm_msg})")
    row = res
    if tight is not None and tight.status == Status.SUCCESS and (
            res.status != Status.SUCCESS
            or is_better(settings.objective, tight.value_replay, res.value_replay)):
        tight.message += f"; kept: the homotopy then gave {res.status.label}: {res.message}"
        row = tight
    # the row's solve: every attempt, not the kept one's alone
    row.solve_time_s = sum(a.solve_time_s for a in attempts)
    check_friction_asymmetry(row, models)
    return row


def _numbers(res: OCPResult) -> tuple[int, float, float]:
    """(N, replayed objective, OCP-replay relative difference) of a result, for
    :func:`_shortfall`."""
    return res.settings.nodes, res.value_replay, res.rel_diff_replay


def _shortfall(objective: str, prev: tuple, row: tuple) -> float:
    """How much worse (relative) a replayed optimum is than the previous N's, each given as (N,
    replayed objective, OCP-replay relative difference): the relative difference when N is a
    multiple of the previous N (it can represent the previous profile) and the finer one is worse
    beyond :data:`WORSE_TOL` plus both OCP-replay differences; else 0."""
    (n0, v0, r0), (n1, v1, r1) = prev, row
    rel = (v1 - v0) / abs(v1) if v1 else math.nan
    if n1 % n0 == 0 and abs(rel) > WORSE_TOL + abs(r0) + abs(r1) and is_better(objective, v0, v1):
        return abs(rel)
    return 0.0


def own_homotopy(settings: OCPSettings) -> bool:
    """Whether the settings have their own homotopy (sigma0, sigma_factor, sigma_min or
    stage_tol_ratio not the defaults, as in ocp_robust.toml): then a warm-started solve keeps it,
    with the warm barrier (:data:`WARM_SIGMA0` and :data:`WARM_STAGE_TOL` are tuned on the default
    path).  On robust_speed's mean the warm schedule (1e-4 down to 1e-11, loose last stage) spent
    thousands of IPOPT iterations in its deepest stages and ended below the coarser N's optimum,
    and the file's own homotopy with the cold barrier left the start in its first stage and ended
    at max_iter, where the same homotopy with the warm barrier converges."""
    default = OCPSettings()
    return any(getattr(settings, key) != getattr(default, key)
               for key in ("sigma0", "sigma_factor", "sigma_min", "stage_tol_ratio"))


def _changes(rows: list[ConvergenceRow], objective: str) -> None:
    """Fill each row's change from the previous N and the observed orders; a success worse than the
    previous N's success beyond :data:`WORSE_TOL` plus both OCP-replay differences (its N a multiple
    of the previous one) says so in its message."""
    for prev, row in zip(rows, rows[1:]):
        row.change = row.value_replay - prev.value_replay
        row.rel_change = row.change / abs(row.value_replay) if row.value_replay else math.nan
        worse = _shortfall(objective, (prev.nodes, prev.value_replay, prev.rel_diff_replay),
                           (row.nodes, row.value_replay, row.rel_diff_replay))
        if Status.SUCCESS == prev.status == row.status and worse:
            row.message += (f"; {worse:.2%} worse than the optimum at N = {prev.nodes}, whose "
                            f"profile N = {row.nodes} can represent: another local optimum")
    nodes = [r.nodes for r in rows]
    for row, p, q in zip(rows, observed_orders(nodes, [r.value_replay for r in rows]),
                         observed_orders(nodes, [r.value_ocp for r in rows])):
        row.order, row.order_ocp = p, q
