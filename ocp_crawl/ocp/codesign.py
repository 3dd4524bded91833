"""Co-design: the robot parameters and the gait of the best objective together
(:func:`codesign_gait`, its result :class:`CodesignResult`).

The design space (:class:`~ocp_crawl.ocp.design.Design`: joint stiffnesses, link lengths at a fixed
total length) is first scanned: the given robot and ``scan - 1`` designs of a scrambled Sobol
sequence over the bounds (stiffnesses on a log scale; the link lengths drawn within their bounds
with the last one closing the total), each with its own best harmonic travelling wave
(:func:`~ocp_crawl.ocp.chain_search.best_chain_baselines`), the designs on worker processes.  From
the best scanned design and its wave, the NLP with the design's variables
(:class:`~ocp_crawl.ocp.transcription.GaitOCP` with a design) is solved by the relaxation homotopy:
a local optimum of design and gait.  It is then proved as any optimum is: at the design it chose,
the gait NLP of that fixed robot is solved on the branches of the optimum's simulated profile (the
same point, to the solver's tolerance) and judged by its event-driven replay
(:func:`~ocp_crawl.ocp.solve.solve_from`); and it must beat every scanned design's best harmonic
gait, else WORSE_THAN_BASELINE.
"""
from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from ocp_crawl.io.files import jsonable
from ocp_crawl.model.chain import Chain
from ocp_crawl.model.robot import Robot
from ocp_crawl.model.statics import GravityConvention
from ocp_crawl.nlp.ipopt import ipopt_status, result_status
from ocp_crawl.ocp.asymmetry import check_friction_asymmetry
from ocp_crawl.ocp.chain_search import ChainWaveChoice, best_chain_baselines
from ocp_crawl.ocp.design import Design
from ocp_crawl.ocp.design_search import ROUNDS, DesignSearch, nlp_value
from ocp_crawl.ocp.judge import first_failure, gain_over, is_better, replay_signal, value_text
from ocp_crawl.ocp.plant import AnyRobot, Plant
from ocp_crawl.ocp.result import OCPResult
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.solve import solve_from
from ocp_crawl.ocp.solver import GaitSolver
from ocp_crawl.ocp.transcription import GaitOCP
from ocp_crawl.status import Status
from ocp_crawl.workers import default_jobs, worker_pool

#: designs drawn per scan point at most, where bounds of the link lengths reject draws
DRAWS_PER_POINT = 64


@dataclass
class ScannedDesign:
    """One design of the scan: its variables' values (SI units) and its best harmonic travelling
    wave (None: none simulates)."""

    values: list
    harmonic: ChainWaveChoice | None

    @property
    def value(self) -> float:
        """The best harmonic wave's objective value (NaN: none, or not meeting the
        requirements)."""
        h = self.harmonic
        return h.value if h is not None and h.feasible else float("nan")

    def to_dict(self) -> dict:
        return jsonable(dict(asdict(self), value=self.value))


@dataclass
class CodesignResult:
    """Outcome of :func:`codesign_gait`.

    ``names``: the design variables (``stiffness[j]`` [N m/rad], ``lengths[i]`` [m]); ``initial``,
    ``low``, ``high``, ``chosen`` their values (SI units); ``result`` the gait at the chosen design,
    judged by replay (an :class:`~ocp_crawl.ocp.result.OCPResult`, None when the co-design NLP did
    not converge); ``scan`` every scanned design, ``start`` the index of the one the NLP started
    from; ``value_nlp`` the co-design NLP's objective value (a speed [m/s] or CoT+ [-])."""

    success: bool
    status: Status
    message: str
    objective: str
    names: list
    initial: list
    low: list
    high: list
    chosen: list = field(default_factory=list)
    robot: Chain | None = None
    """the chain with the chosen design"""
    value_nlp: float = float("nan")
    result: OCPResult | None = None
    given: OCPResult | None = None
    """the optimal gait of the given robot (its design fixed), judged by replay (None: its
    harmonic wave does not simulate)"""
    scan: list = field(default_factory=list)
    start: int | None = None
    """the index in ``scan`` of the design the co-design NLP started from (None: none)"""
    unit: str = "m/s"
    """the objective value's unit (:attr:`~ocp_crawl.ocp.settings.OCPSettings.objective_unit`)"""
    iterations: int = 0
    """IPOPT iterations of the co-design NLP's homotopy and local search"""
    probes: list = field(default_factory=list)
    """the neighbouring designs the local search probed (:attr:`~ocp_crawl.ocp.design_search.
    DesignSearch.probes`)"""
    time_s: float = float("nan")

    @property
    def value_replay(self) -> float:
        """The chosen design's gait, its objective by replay (NaN: not replayed)."""
        return self.result.value_replay if self.result is not None else float("nan")

    @property
    def best_scanned(self) -> ScannedDesign | None:
        """The scanned design whose best harmonic wave is best (None: none simulates)."""
        found = [d for d in self.scan if math.isfinite(d.value)]
        if not found:
            return None
        best = found[0]
        for d in found[1:]:
            if is_better(self.objective, d.value, best.value):
                best = d
        return best

    @property
    def at_bounds(self) -> list[str]:
        """The design variables at a bound (within 1e-6 relative), with the bound's side (not
        those whose bounds are equal: fixed)."""
        out = []
        for name, v, lo, hi in zip(self.names, self.chosen, self.low, self.high):
            if lo == hi:
                continue
            if abs(v - lo) <= 1e-6 * lo:
                out.append(f"{name} at its low bound")
            elif abs(v - hi) <= 1e-6 * hi:
                out.append(f"{name} at its high bound")
        return out

    def gains(self) -> dict:
        """Relative gains [-] of the replayed optimum over the best scanned design's harmonic wave
        (``over_scan``), over the given robot's (``over_initial``, the scan's first design) and
        over the given robot's optimal gait (``over_given_optimum``: what the design adds)."""
        v = self.value_replay
        best = self.best_scanned
        given = (self.given.value_replay if self.given is not None and self.given.success
                 else math.nan)
        return {"over_scan": gain_over(self.objective, v, best.value if best else math.nan),
                "over_initial": gain_over(self.objective, v,
                                          self.scan[0].value if self.scan else math.nan),
                "over_given_optimum": gain_over(self.objective, v, given)}

    def to_dict(self) -> dict:
        out = {k: getattr(self, k) for k in ("success", "message", "objective", "names", "initial",
                                            "low", "high", "chosen", "value_nlp", "start",
                                            "iterations", "probes", "time_s", "unit")}
        out.update(status=self.status.label, value_replay=self.value_replay,
                   at_bounds=self.at_bounds, gains=self.gains(),
                   scan=[d.to_dict() for d in self.scan],
                   robot=None if self.robot is None else asdict(self.robot),
                   given=None if self.given is None else self.given.summary(),
                   result=None if self.result is None else self.result.summary())
        return jsonable(out)


def design_points(chain: Chain, design: Design, count: int, seed: int = 0) -> list[np.ndarray]:
    """The scan's designs (SI values in :meth:`~ocp_crawl.ocp.design.Design.names` order): the
    robot's own first, then up to ``count - 1`` of a scrambled Sobol sequence (``seed``) over the
    bounds; fewer where the length bounds reject too many draws."""
    from scipy.stats import qmc

    design = design.checked(chain)
    lo, hi = design.limits()
    m = chain.n_joints if design.stiffness else 0
    free = m + (chain.n - 1 if design.lengths else 0)  # the last length closes the total
    points = [design.initial(chain)]
    if count <= 1:
        return points
    u = qmc.Sobol(free, scramble=True, seed=seed).random_base2(
        math.ceil(math.log2(DRAWS_PER_POINT * count)))
    for row in u:
        k = lo[:m] * (hi[:m] / lo[:m]) ** row[:m]  # log-uniform stiffnesses
        lengths = np.zeros(0)
        if design.lengths:
            lengths = lo[m:-1] + row[m:] * (hi[m:-1] - lo[m:-1])
            last = chain.L - lengths.sum()
            if not lo[-1] <= last <= hi[-1]:
                continue
            lengths = np.r_[lengths, last]
        points.append(np.r_[k, lengths])
        if len(points) == count:
            break
    return points


_SCAN: dict = {}


def _init_scan(chain: Chain, design: Design, gravity: GravityConvention,
               settings: OCPSettings) -> None:
    _SCAN.update(chain=chain, design=design, gravity=gravity, settings=settings)


def _scan_one(values: np.ndarray) -> ChainWaveChoice | None:
    """The best harmonic travelling wave of one design (in a worker of the scan)."""
    chain = _SCAN["design"].chain_of(_SCAN["chain"], values)
    base = best_chain_baselines(chain, _SCAN["gravity"], _SCAN["settings"], jobs=1)
    return base.choices["harmonic"]


def scan_designs(chain: Chain, design: Design, gravity: GravityConvention,
                 settings: OCPSettings, points: list, jobs: int | None = None
                 ) -> list[ScannedDesign]:
    """Each design of ``points`` with its best harmonic travelling wave, the designs on ``jobs``
    worker processes (None: the CPUs available; 1: in this process)."""
    jobs = default_jobs() if jobs is None else jobs
    if jobs <= 1 or len(points) <= 1:
        _init_scan(chain, design, gravity, settings)
        waves = [_scan_one(v) for v in points]
    else:
        pool = worker_pool(min(jobs, len(points)), _init_scan, (chain, design, gravity, settings))
        try:
            waves = list(pool.map(_scan_one, points))
        finally:
            pool.shutdown(cancel_futures=True)
    return [ScannedDesign([float(v) for v in p], w) for p, w in zip(points, waves)]


def codesign_gait(robot: AnyRobot, design: Design, gravity: GravityConvention = "physical",
                  settings: OCPSettings | None = None, scan: int = 9,
                  jobs: int | None = None, log=None, search_rounds: int = ROUNDS
                  ) -> CodesignResult:
    """The design and the gait of the best objective together (see the module docstring).

    Parameters
    ----------
    robot : Robot or Chain
        The given robot (SI units; the three-link robot as its chain,
        :meth:`~ocp_crawl.model.chain.Chain.from_robot`): the design's scales and first scanned
        design, and the totals M, L it keeps.
    design : Design
        The parameters the OCP chooses and their bounds.
    gravity : str
        The gravity convention ("physical" or "paper").
    settings : OCPSettings, optional
        The OCP's settings (objective, envelope, bandwidth, nodes, homotopy; the harmonic search's
        sizes for each scanned design).
    scan : int
        Designs scanned, the given robot's included (>= 1).
    jobs : int, optional
        Worker processes of the scan (None: the CPUs available).
    log : callable, optional
        Called with a line of text as each stage starts (the command's progress on a terminal).
    search_rounds : int
        Rounds of the local search at most (:class:`~ocp_crawl.ocp.design_search.DesignSearch`;
        0: the homotopy's optimum as it is); most of the time after the scan.

    Returns
    -------
    CodesignResult
        SUCCESS (the replayed optimum beats every scanned design's best harmonic wave),
        WORSE_THAN_BASELINE, NO_INITIAL_GUESS (no scanned design has a harmonic gait), the
        statuses of the NLP (INFEASIBLE, SOLVER_FAILURE, NOT_COMPLEMENTARY) and those of the
        judge at the chosen design (REPLAY_FAILED, REPLAY_MISMATCH).
    """
    t0 = time.perf_counter()
    settings = settings or OCPSettings()
    chain = Chain.from_robot(robot) if isinstance(robot, Robot) else robot
    design = design.checked(chain)
    lo, hi = design.limits()
    if settings.dynamic_margin is not None:
        raise ValueError("codesign_gait: dynamic_margin is the three-link robot's (MuJoCo's "
                         "model); a design is a chain's: set it to None")
    out = CodesignResult(False, Status.NO_INITIAL_GUESS, "", settings.objective,
                         design.names(chain), list(design.initial(chain)), list(lo), list(hi),
                         unit=settings.objective_unit)
    say = log or (lambda text: None)
    say(f"scanning {scan} designs, each with its best harmonic gait")
    out.scan = scan_designs(chain, design, gravity, settings,
                            design_points(chain, design, scan), jobs)
    best = out.best_scanned
    if best is None:
        out.message = (f"{Status.NO_INITIAL_GUESS.text}: no scanned design has a harmonic gait "
                       "that simulates and meets the requirements; widen the bounds or the "
                       "envelope")
        out.time_s = time.perf_counter() - t0
        return out
    out.start = out.scan.index(best)
    if out.scan[0].harmonic is not None:
        say("the given robot's optimal gait")
        out.given = _fixed_optimum(chain, gravity, settings, out.scan[0].harmonic)
    say(f"the co-design NLP from scanned design {out.start + 1} and its local search")
    _solve_design(out, chain, design, gravity, settings, best, search_rounds)
    out.time_s = time.perf_counter() - t0
    return out


def _fixed_optimum(chain: Chain, gravity: GravityConvention, settings: OCPSettings,
                   wave: ChainWaveChoice) -> OCPResult:
    """The optimal gait of the fixed robot ``chain`` from its harmonic wave, judged by replay."""
    models = [Plant(r, gravity) for r in settings.scenarios(chain)]
    solver = GaitSolver(GaitOCP(chain, gravity, settings))
    return solve_from(solver, models, wave.signal_for(chain, settings), wave.T, harmonic=wave)


def _solve_design(out: CodesignResult, chain: Chain, design: Design,
                  gravity: GravityConvention, settings: OCPSettings,
                  start: ScannedDesign, rounds: int = ROUNDS) -> None:
    """The co-design NLP from ``start``'s design and wave and its local search
    (:class:`~ocp_crawl.ocp.design_search.DesignSearch`), then the gait at the chosen design
    judged by replay and against the scan (fills ``out``)."""
    assert start.harmonic is not None
    base = design.chain_of(chain, start.values)
    ocp = GaitOCP(base, gravity, settings, design=design,
                  stability=design.min_reduced_stiffness)
    solver = GaitSolver(ocp)
    x0 = ocp.initial_guess(start.harmonic.signal_for(base, settings), start.harmonic.T)
    x, hist, failed, status = solver.solve(x0)
    out.iterations = sum(r.iterations for r in hist)
    if x is None or failed is not None:
        out.status = result_status(ipopt_status(status), usable=False)
        out.message = f"the co-design NLP did not converge: IPOPT {status} at {failed}"
        return
    if max(sc["comp"] for sc in ocp.unpack(x)["scen"]) > settings.comp_tol:
        out.status = Status.NOT_COMPLEMENTARY
        out.message = "the co-design NLP's point is not complementary (a relaxed, unphysical gait)"
        return
    search = DesignSearch(solver, chain, rounds)
    x = search.run(x)
    out.iterations += search.iterations
    out.probes = search.probes
    u = ocp.unpack(x)
    out.chosen = [float(v) for v in ocp.design_values(x)]
    out.value_nlp = nlp_value(solver, x)
    out.robot = design.chain_of(chain, out.chosen)
    models = [Plant(r, gravity) for r in settings.scenarios(out.robot)]
    fixed = search.fixed_solver(np.asarray(out.chosen))
    phase = np.arange(settings.nodes) / settings.nodes
    signal = replay_signal(phase, u["tau"])
    bad = first_failure(models, signal)
    if bad is not None:
        # the co-design NLP's own profile is the start of the fixed robot's solve
        out.status = Status.REPLAY_FAILED
        out.message = (f"the co-design optimum's profile at the chosen design fails in the "
                       f"simulator: {bad.message}; try another ocp.nodes, or a friction set "
                       f"(ocp.mu_ratio_eps with ocp.robust = \"worst\") if a friction tie "
                       f"decides its slips")
        return
    out.result = res = solve_from(fixed, models, signal, u["T"], tightened=True)
    if not res.success:
        out.status, out.message = res.status, f"the gait at the chosen design: {res.message}"
        return
    check_friction_asymmetry(res, models)
    _judge_design(out, settings, res)


def _judge_design(out: CodesignResult, settings: OCPSettings, res: OCPResult) -> None:
    """The chosen design's replayed optimum ``res`` against the best scanned design's harmonic
    wave and the given robot's optimal gait: SUCCESS, or WORSE_THAN_BASELINE (fills ``out``)."""
    obj = settings.objective
    best = out.best_scanned
    assert best is not None
    text = (f"replay {value_text(obj, res.value_replay)} against the best scanned design's "
            f"harmonic wave {value_text(obj, best.value)}")
    if is_better(obj, best.value, res.value_replay):
        out.status = Status.WORSE_THAN_BASELINE
        out.message = f"the co-design optimum is worse than a scanned design: {text}"
        return
    given = out.given
    if given is None or not given.success:
        why = ("its harmonic wave does not simulate" if given is None
               else f"{given.status.label}: {given.message}")
        text += f"; the given robot's optimal gait not compared (none: {why})"
    else:
        text += f", the given robot's optimal gait {value_text(obj, given.value_replay)}"
        if is_better(obj, given.value_replay, res.value_replay):
            out.status = Status.WORSE_THAN_BASELINE
            out.message = (f"the co-design optimum (a local one) is worse than the given robot's "
                           f"optimal gait: {text}; try more scanned designs (design.scan)")
            return
    out.success, out.status = True, Status.SUCCESS
    bounds = "; " + ", ".join(out.at_bounds) if out.at_bounds else ""
    out.message = (f"optimal design and {obj} gait found (a local optimum, started from the "
                   f"best of {len(out.scan)} scanned designs): {text}{bounds}")
