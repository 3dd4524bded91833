"""The work of a request, estimated before it starts.

Every count that sizes a run is bounded on its own (``simulation.steps``, ``max_cycles``,
``ocp.nodes``, the samples of a table, the rows of a fit), but their products are not: MPCC
``steps = 10000`` with ``max_cycles = 500`` is five million IPOPT solves, hours, though each count
is in its range.  So each command estimates its work from the counts that size it, times a cost
per unit, and

* refuses a request above its limit (``--max-hours``, default :data:`DEFAULT_MAX_HOURS`) before it
  starts, with one line naming the keys that size it (:class:`WorkLimit`, exit 2 on the command
  line);
* announces a request whose typical run is above :data:`ANNOUNCE_SECONDS` on standard error
  (``estimated about ..., up to ...``).

The commands check (``ocp-crawl simulate``, ``animate``, ``crosscheck``, ``sweep``, ``optimize``,
``codesign``, ``fit``, ``dynamics``); the library functions run what they are given, and a program
asks first, e.g. ``simulation_work(problem).check(max_hours=1)``.

The unit costs (:data:`UNIT_COST`) are those measured on the benchmarks page's machine (2 cores,
``scripts/bench.py work`` prints them against the estimates), a slow one: a faster machine takes
less. Where the request's own limits bound the count (``max_cycles``, ``max_nfev``) the estimate
checked is an upper bound (``up to``), and a typical run (a gait periodic after
:data:`TYPICAL_CYCLES` cycles) is announced beside it; the optimiser's IPOPT iterations are not
bounded that way, so its estimate is of a typical run (:data:`OCP_ITERATIONS` per start, measured on
the shipped files).
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

#: a request estimated above this many hours is refused unless its command's --max-hours allows it
DEFAULT_MAX_HOURS = 2.0
#: a request estimated above this [s] is announced on standard error before it starts
ANNOUNCE_SECONDS = 60.0
#  the cost of a unit of work [s]: an event-solver step, an MPCC time step (an IPOPT solve), the
# MPCC's  set-up (its start and the NLP), a MuJoCo step, an OCP node of one friction scenario in one
# IPOPT  iteration, a member of a baseline family
UNIT_COST = {"event_step": 1.5e-4, "mpcc_step": 1e-2, "mpcc_setup": 4.0, "mujoco_step": 3e-5,
             "ocp_node_iteration": 1.5e-3, "family_member": 0.025, "chain_event_cycle": 0.0035}
#  (chain_event_cycle: a typical cycle of the event-driven chain simulator per link [s]; a cycle of
# n = 3..7 links took 0.010 to 0.014 s, 0.002 to 0.0035 n s: docs/benchmarks.md)
#: IPOPT iterations of a typical OCP start (the shipped files take 700 to 1,200 over all stages)
OCP_ITERATIONS = 1000
#: IPOPT iterations of a typical tightened start (``ocp.start_solve``: 56 to 500 on the shipped
#: files and the tests' problems)
TIGHTENED_ITERATIONS = 300
#  event-solver steps per cycle at least (steps shorten near events: 20 to 400 on the shipped
# gaits),  and in a typical cycle
EVENT_STEPS, EVENT_STEPS_TYPICAL = 1000, 200
#: cycles of a typical run: the released start's transient, then two equal cycles
TYPICAL_CYCLES = 3
#: event-solver steps per input knot (a step ends at each knot; an event costs a few more)
STEPS_PER_KNOT = 4


__all__ = ["Work", "WorkLimit", "simulation_work", "optimize_work", "sweep_work", "fit_work",
           "crosscheck_work", "dynamics_work", "DEFAULT_MAX_HOURS"]


class WorkLimit(ValueError):
    """A request whose estimated work is above its limit (bad input: exit 2 on the command line)."""


@dataclass(frozen=True)
class Work:
    """The estimated work of a request.

    Attributes
    ----------
    seconds : float
        The estimate [s] on the benchmarks page's machine that the limit is checked against: an
        upper bound where the request's own limits bound every count (``max_cycles``, ``max_nfev``),
        else a typical run (the optimiser's iterations).
    detail : str
        What it counts, e.g. ``"MPCC 10000 steps x 500 cycles at ~10 ms"``.
    keys : tuple of str
        The settings that size it, named in a refusal.
    typical : float, optional
        A typical run [s] (a periodic gait ends after :data:`TYPICAL_CYCLES` cycles); None: equal
        to ``seconds``.  A run is announced by it.
    """

    seconds: float
    detail: str
    keys: tuple[str, ...] = ()
    # None stands for ``seconds``: replaced in __post_init__, a float from then on
    typical: float = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        if self.typical is None:
            object.__setattr__(self, "typical", self.seconds)

    def __add__(self, other: Work) -> Work:
        keys = tuple(dict.fromkeys((*self.keys, *other.keys)))
        return Work(self.seconds + other.seconds, f"{self.detail}; {other.detail}", keys,
                    self.typical + other.typical)

    def times(self, factor: float, why: str) -> Work:
        """This work ``factor`` times (``why``: what the factor counts)."""
        return Work(self.seconds * factor, f"{why}: {factor:g} x ({self.detail})", self.keys,
                    self.typical * factor)

    @property
    def text(self) -> str:
        """``about 3 s, up to 2.8 h`` (an upper bound above a typical run) or ``about 12 min``."""
        if self.typical < self.seconds:
            return f"about {duration(self.typical)}, up to {duration(self.seconds)}"
        return f"about {duration(self.seconds)}"

    def check(self, max_hours: float | None = None, option: str = "--max-hours") -> None:
        """Raise :class:`WorkLimit` when the estimate is above ``max_hours`` [h] (None: the default
        :data:`DEFAULT_MAX_HOURS`; ``math.inf``: no limit); ``option`` is how the caller raises
        it."""
        limit = DEFAULT_MAX_HOURS if max_hours is None else max_hours
        if not self.seconds <= limit * 3600.0:
            keys = ", ".join(self.keys) or "the request's sizes"
            need = math.ceil(self.seconds / 3600.0 * 10) / 10
            raise WorkLimit(f"estimated {self.text} ({self.detail}), above the limit of "
                            f"{duration(limit * 3600.0)}: lower {keys}, or allow it with "
                            f"{option} {need:g}")


def duration(seconds: float) -> str:
    """``seconds`` as ``42 s``, ``12 min`` or ``2.8 h``."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.2g} h"


def simulation_work(problem) -> Work:
    """The work of simulating ``problem`` (a :class:`~ocp_crawl.problem.Problem`) with its solver:
    ``seconds`` an upper bound (its ``max_cycles`` cycles run in full), ``typical`` a gait periodic
    after :data:`TYPICAL_CYCLES` cycles."""
    opts, solver = problem.options, problem.solver or "event"
    if solver == "angles":   # closed form at every phase, sized by the samples of its input
        return Work(0.5, "prescribed angles", ("gait.drive",))
    cycles = opts.max_cycles
    if solver == "event" and problem.is_chain:   # (its steps: a Newton solve of n - 1 joints)
        n = problem.robot.n
        cycle = UNIT_COST["chain_event_cycle"] * n
        return Work(cycle * cycles * EVENT_STEPS / EVENT_STEPS_TYPICAL,
                    f"chain event solver, {n} links: ~{cycle:.2g} s a typical cycle, up to "
                    f"{EVENT_STEPS // EVENT_STEPS_TYPICAL}x that x {cycles} cycles",
                    ("simulation.max_cycles",), cycle * TYPICAL_CYCLES)
    if solver == "mpcc":
        check = (2 * opts.steps + 1) * (opts.s_error_tol > 0)   # the error estimate's run
        seconds = [UNIT_COST["mpcc_setup"] + (opts.steps * n + check) * UNIT_COST["mpcc_step"]
                   for n in (cycles, TYPICAL_CYCLES)]
        return Work(seconds[0], f"MPCC {opts.steps} steps x {cycles} cycles at ~{_ms('mpcc_step')}",
                    ("simulation.steps", "simulation.max_cycles"), seconds[1])
    if solver in ("mujoco", "mujoco_angles"):
        work = _mujoco(opts.period, opts.timestep, cycles)
        return replace(work, typical=_mujoco(opts.period, opts.timestep, TYPICAL_CYCLES).seconds)
    knots = max(len(getattr(signal, "t_knots", ())) for signal in (problem.torque, problem.gait))
    per_cycle = [max(1.0 / opts.max_step, floor) + STEPS_PER_KNOT * knots
                 for floor in (EVENT_STEPS, EVENT_STEPS_TYPICAL)]
    keys = ("simulation.max_step", "simulation.max_cycles") + (("gait.phase",) if knots else ())
    return Work(per_cycle[0] * cycles * UNIT_COST["event_step"],
                f"event solver {per_cycle[0]:.3g} steps x {cycles} cycles at ~{_ms('event_step')}",
                keys, per_cycle[1] * TYPICAL_CYCLES * UNIT_COST["event_step"])


def optimize_work(problem, settings, nodes: list[int] | None = None) -> Work:
    """The work of ``optimize`` on ``problem`` with :class:`~ocp_crawl.ocp.OCPSettings` ``settings``
    at each N of ``nodes`` (default: ``settings.nodes``): a typical run, :data:`OCP_ITERATIONS`
    IPOPT iterations per start (:data:`TIGHTENED_ITERATIONS` per tightened one), plus the harmonic
    baseline's search (the OCP's start; the other families are searched in another process while
    the OCP solves), or with tightened starts every family's."""
    from ocp_crawl.ocp.chain_search import family_shapes

    nodes = list(nodes or [settings.nodes])
    scen = len(settings.scenarios(problem.robot))
    # a sub-step's variables grow with the joints m: m + 10, 12 for the three-link robot
    size = (problem.robot.n_joints + 10) / 12 if problem.is_chain else 1.0
    per_it = sum(nodes) * scen * size * UNIT_COST["ocp_node_iteration"]
    how = settings.start_solve
    shapes = family_shapes(settings, problem.is_chain)
    families = len(shapes) if how != "homotopy" else 0
    starts = settings.starts if how != "tightened" else families + settings.starts - 1
    per_start = TIGHTENED_ITERATIONS if how == "tightened" else OCP_ITERATIONS
    tightened = families * TIGHTENED_ITERATIONS if how == "both" else 0
    solve = Work(per_it * (per_start * starts + tightened),
                 f"{starts} starts x {per_start} iterations"
                 f"{f' + {families} tightened starts' if tightened else ''} x N = "
                 f"{'+'.join(map(str, nodes))} x {scen} scenarios at ~{_ms('ocp_node_iteration')}",
                 ("ocp.nodes", "ocp.starts", "ocp.start_solve", "--nodes"))
    # tightened starts: every family searched before the solve; else the harmonic one
    first = shapes if how == "tightened" else ("harmonic",)
    if problem.is_chain:   # its travelling waves, each a simulation of the chain
        from ocp_crawl.ocp.chain_search import local_budget, scan_points as chain_points

        members = len(first) * (len(chain_points(settings))
                                + settings.baseline_starts * local_budget(settings))
        member = simulation_work(problem)
        return solve + Work(members * scen * member.typical,
                            f"{members} travelling waves x {scen} scenarios x a typical "
                            f"({member.detail})",
                            ("ocp.harmonic_A", "ocp.harmonic_psi", "ocp.baseline_starts"))
    from ocp_crawl.ocp.search import scan_points

    members = len(first) * (len(scan_points(settings))
                            + settings.baseline_starts * settings.baseline_evaluations)
    search = Work(members * scen * UNIT_COST["family_member"],
                  f"{members} {'+'.join(first)} members x {scen} scenarios at "
                  f"~{_ms('family_member')}",
                  ("ocp.harmonic_psi", "ocp.baseline_samples", "ocp.baseline_evaluations"))
    return solve + search


def codesign_work(problem, settings, design, scan: int, rounds: int, jobs: int = 1) -> Work:
    """The work of ``codesign`` on ``problem`` (:class:`~ocp_crawl.ocp.OCPSettings` ``settings``, a
    :class:`~ocp_crawl.ocp.design.Design` ``design``): the scan of ``scan`` designs, each with its
    best travelling waves (simulations of the chain, on ``jobs`` workers), then typical OCP solves
    (as :func:`optimize_work`'s, on the chain): the given robot's, the co-design NLP's, each of at
    most ``rounds`` rounds of the local search (each free variable moved either way, then the
    co-design NLP) and the chosen design's."""
    from ocp_crawl.ocp.chain_search import local_budget, scan_points as chain_points

    n = problem.robot.n if problem.is_chain else 3
    scen = len(settings.scenarios(problem.robot))
    per_it = settings.nodes * scen * (n - 1 + 10) / 12 * UNIT_COST["ocp_node_iteration"]
    free = sum(1 for low, high in zip(*design.limits()) if high > low)   # (not pinned)
    solves = 3 + rounds * (2 * free + 1)
    members = len(chain_points(settings)) + settings.baseline_starts * local_budget(settings)
    member = UNIT_COST["chain_event_cycle"] * n * TYPICAL_CYCLES
    share = scan / max(jobs, 1)
    return (Work(members * scen * member * share,
                 f"{scan} designs / {jobs} workers x {members} travelling waves x {scen} scenarios "
                 f"x a typical chain simulation (~{member:.2g} s)",
                 ("design.scan", "ocp.harmonic_A", "ocp.harmonic_psi", "--jobs"))
            + Work(per_it * OCP_ITERATIONS * solves,
                   f"{solves} OCP solves ({free} free variables, {rounds} rounds) x "
                   f"{OCP_ITERATIONS} iterations x N = {settings.nodes} x {scen} scenarios at "
                   f"~{_ms('ocp_node_iteration')}",
                   ("design.search_rounds", "ocp.nodes")))


def fit_work(problem, rows: int, max_nfev: int, n_params: int, jobs: int = 1,
             starts: int = 0) -> Work:
    """The work of fitting ``n_params`` parameters of ``problem`` to ``rows`` measured rows in at
    most ``max_nfev`` evaluations (each simulates every row, a Jacobian ``n_params`` times more),
    after ``starts`` evaluations of a sample, on ``jobs`` workers, each row a typical run
    (:func:`simulation_work`)."""
    row = simulation_work(problem)
    sims = rows * (max_nfev * (1 + n_params) + starts) / max(jobs, 1)
    sample = f" + {rows} rows x {starts} starts" if starts else ""
    return Work(sims * row.typical,
                f"{rows} rows x {max_nfev} evaluations x {1 + n_params} (Jacobian){sample} / "
                f"{jobs} workers x a typical ({row.detail})",
                ("DATA.csv rows", "--max-nfev", *(("--starts",) if starts else ()), *row.keys))


def _ms(unit: str) -> str:
    value = UNIT_COST[unit]
    return f"{value:g} s" if value >= 1 else f"{value * 1e3:.2g} ms"


def sweep_work(problem, grid, jobs: int = 1) -> Work:
    """The work of a sweep of ``problem`` over ``grid`` (axis name -> values) on ``jobs`` workers:
    the points times the costliest point's :func:`simulation_work` over the axes that size a
    simulation ([simulation] keys, the drive, the waveform; the others at their first value)."""
    from ocp_crawl.problem.keys import ProblemError

    sizing = [k for k in grid
              if k.startswith("simulation.") or k in ("gait.drive", "gait.waveform")]
    first = {k: v[0] for k, v in grid.items() if k not in sizing}
    worst = None
    for values in itertools.product(*(list(grid[k]) for k in sizing)):
        try:
            w = simulation_work(problem.with_values(dict(first, **dict(zip(sizing, values)))))
        except ProblemError:   # an invalid point is a row of status bad_input: no work
            continue
        worst = w if worst is None or w.seconds > worst.seconds else worst
    worst = worst or simulation_work(problem)
    points = math.prod(len(v) for v in grid.values())
    keys = tuple(dict.fromkeys((*worst.keys, "--grid")))
    share = points / max(jobs, 1)
    return Work(worst.seconds * share, f"{points} points / {jobs} workers x ({worst.detail})", keys,
                worst.typical * share)


def crosscheck_work(problem, steps: list[int]) -> Work:
    """The work of ``crosscheck``: the event solver, and the MPCC at each of ``steps`` (without
    its own error estimate: the event solver checks every step count)."""
    total = simulation_work(replace(problem, solver="event", options=problem.hybrid))
    for n in steps:
        mpcc = _mpcc_options(problem, n)
        total = total + simulation_work(replace(problem, solver="mpcc", options=mpcc))
    return Work(total.seconds, f"event solver and MPCC at steps {' '.join(map(str, steps))}",
                ("--steps", "simulation.max_cycles"), total.typical)


def dynamics_work(problem, periods: list[float]) -> Work:
    """The work of ``dynamics``: a MuJoCo run of ``problem`` at each period [s] of ``periods``."""
    opts = problem.options
    seconds, typical = (sum(_mujoco(t, opts.timestep, n).seconds for t in periods)
                        for n in (opts.max_cycles, TYPICAL_CYCLES))
    return Work(seconds, f"MuJoCo at T = {' + '.join(f'{t:g}' for t in periods)} s x "
                f"{problem.options.max_cycles} cycles, step {problem.options.timestep:g} s "
                f"at ~{_ms('mujoco_step')}",
                ("--periods", "simulation.timestep", "simulation.max_cycles"), typical)


def _mujoco(period: float, timestep: float, cycles: int) -> Work:
    """A MuJoCo run of ``cycles`` cycles of ``period`` [s] at ``timestep`` [s], after settling."""
    from ocp_crawl.sim.dynamic import SETTLE_TIME

    per_cycle = period / timestep
    return Work((per_cycle * cycles + SETTLE_TIME / timestep) * UNIT_COST["mujoco_step"],
                f"MuJoCo {per_cycle:.3g} steps x {cycles} cycles at ~{_ms('mujoco_step')}",
                ("simulation.period", "simulation.timestep", "simulation.max_cycles"))


def _mpcc_options(problem, steps: int):
    from ocp_crawl.problem.problem import solver_options

    opts = solver_options("mpcc", problem.sections.get("simulation", {}))
    return replace(opts, steps=steps, s_error_tol=0.0)
