"""The search of the waveform families for their best members: a scan of each family's whole box,
then local refinement from its best distinct points, on worker processes.

The scan (:func:`scan_points`) has two parts: the symmetric members (gamma1 = gamma2, A1 = A2) on a
grid of ``harmonic_A`` amplitudes, centres at both edges and the middle of what the envelope leaves,
and ``harmonic_psi`` phases; and ``baseline_samples`` points of a scrambled Sobol sequence over the
whole box (every coordinate free: unequal centres, amplitudes, and for pulses rise and duty), which
finds the asymmetric members that robots with unequal feet prefer.  The ``local_starts`` best scan
points at least 6/harmonic_psi apart start bounded Nelder-Mead searches (:func:`local_search`): a
symmetric point first in the symmetric sub-family, then every point in rounds over every coordinate.

Every member's simulation is deterministic and the Sobol sequence has a fixed seed, so the result
does not depend on the number of worker processes.
"""
from __future__ import annotations

import contextlib
import time
from concurrent.futures import FIRST_COMPLETED, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Callable

import numpy as np

from ocp_crawl.model.statics import GravityConvention, Robot
from ocp_crawl.checks import real
from ocp_crawl.ocp.baseline import (FAIL_RANK, Baselines, WaveChoice, choice_of, search_rank,
                                     value_of)
from ocp_crawl.ocp.family import Evaluation, WaveFamily, shape_box
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.workers import default_jobs, worker_pool

#: Nelder-Mead's stopping tolerances (box coordinates; search ranks, i.e. m/s or CoT+): both must
#: hold.  The searches end by their evaluation budgets.  A tolerance of 5e-6 relative saved a
#: quarter of the harmonic family's evaluations but moved its best member by 7e-6, which put
#: robust_speed's homotopy on another path (twice the IPOPT iterations, another local optimum)
NM_TOL = {"xatol": 1e-7, "fatol": 1e-12}
#: centre offsets w of the symmetric scan (gamma_i = gamma + w (A_max - A_i)): both edges and the
#: middle
SCAN_W = (-1.0, 0.0, 1.0)
#: the pulse's (r, d) coordinates on the symmetric scan: rise 0.25 cycles, equal high and low levels
PULSE_SCAN = (0.2 / 0.45, 0.5)
#: seed of the scrambled Sobol sample (a fixed seed: the same scan every run)
SOBOL_SEED = 20240917
#: first simplex of each round of a local search in every coordinate: steps per coordinate
FULL_STEPS = (0.05, 0.05, 0.03, 0.05, 0.02, 0.1, 0.1)
#: evaluations of one round of a local search, and the relative gain below which no round follows
ROUND_FEV, ROUND_RTOL = 120, 1e-4


def _sym_index(shape: str) -> list[int]:
    """Coordinates y of the symmetric sub-family within z: (w, u, p[, r, d])."""
    return [0, 2, 4] + ([5, 6] if shape == "pulse" else [])


def _full(y) -> np.ndarray:
    """z of the symmetric coordinates y = (w, u, p[, r, d]): w1 = w2 = w, q = 0."""
    return np.array([y[0], y[0], y[1], 0.0, *y[2:]])


def scan_points(settings: OCPSettings, shape: str = "harmonic") -> list[np.ndarray]:
    """Box coordinates of the scan of a shape's family (see the module docstring): the symmetric
    grid, then the Sobol sample of the whole box."""
    n_a = settings.harmonic_A
    extra = list(PULSE_SCAN) if shape == "pulse" else []
    out: list[np.ndarray] = []
    for u in np.linspace(1.0 / n_a, 1.0, n_a):
        for w in (SCAN_W if u < 1 else (0.0,)):
            out.extend(np.array([w, w, u, 0.0, p, *extra])
                       for p in np.linspace(-1.0, 1.0, settings.harmonic_psi + 1)[1:])
    n = settings.baseline_samples
    if n:
        from scipy.stats import qmc

        box = np.array(shape_box(shape))
        sample = qmc.Sobol(len(box), scramble=True, seed=SOBOL_SEED).random(n)
        out.extend(box[:, 0] + sample * (box[:, 1] - box[:, 0]))
    return out


def seeds(scored: list[tuple[float, np.ndarray]], count: int, min_dist: float) -> list[np.ndarray]:
    """The ``count`` best scan points of (rank, z) at least ``min_dist`` apart in box
    coordinates."""
    chosen: list = []
    for rank, z in sorted(scored, key=lambda x: x[0]):
        if len(chosen) >= count:
            break
        if rank < FAIL_RANK and all(np.linalg.norm(z - c) >= min_dist for c in chosen):
            chosen.append(z)
    return chosen


def first_simplex(z: np.ndarray, steps, box) -> np.ndarray:
    """Nelder-Mead's first simplex: z and one point per coordinate, ``steps`` away inside
    ``box``."""
    pts = [z]
    for i, h in enumerate(steps):
        y = z.copy()
        lo, hi = box[i]
        y[i] = min(max(z[i] + h if z[i] + h <= hi else z[i] - h, lo), hi)
        pts.append(y)
    return np.array(pts)


def _symmetric(z: np.ndarray) -> bool:
    return z[0] == z[1] and z[3] == 0


def local_search(fam: WaveFamily, z0: np.ndarray, maxfev: int,
                 scan: list[Evaluation] | tuple = ()) -> tuple[dict, list[Evaluation]]:
    """Local search from the box point ``z0`` on :func:`~ocp_crawl.ocp.baseline.search_rank`.

    From a symmetric point: bounded Nelder-Mead in the symmetric sub-family first (at most a third
    of ``maxfev`` evaluations).  Then rounds of bounded Nelder-Mead in every coordinate, each from a
    fresh small simplex at the previous round's end point (:data:`ROUND_FEV` evaluations each),
    until a round improves the rank by less than :data:`ROUND_RTOL` or ``maxfev`` is spent: a
    simplex in five or seven coordinates degenerates on the objective's ridges long before it
    converges, and a fresh one goes on (on an asymmetric robot one search of 600 evaluations gained
    2.6 % over one of 200).  The budget counts the members this search asks for that are neither
    among ``scan`` (the family's scan evaluations) nor asked for by it before: not what else the
    family's cache holds, so that a search ends the same in any process,
    after any other search.  Returns the start's summary (seed and end point, their objective
    values, the members counted) and the evaluations it asked for, in the order of their first
    request."""
    from scipy.optimize import minimize

    settings, box = fam.settings, shape_box(fam.shape)
    scanned = frozenset(fam.key(ev.params) for ev in scan)
    asked: dict = {}

    def rank(z):
        params = fam.member(z)
        key = fam.key(params)
        if key not in asked:
            asked[key] = fam.evaluate(params)
        return search_rank(settings, asked[key])

    def spent() -> int:
        return sum(k not in scanned and ev.params.simulated() for k, ev in asked.items())
    z, f = np.asarray(z0, float), rank(z0)
    if _symmetric(z):
        idx = _sym_index(fam.shape)
        sym_box = tuple(box[i] for i in idx)
        first = (0.25, 0.5 / settings.harmonic_A, 1.0 / settings.harmonic_psi, 0.2, 0.2)[:len(idx)]
        sym = minimize(lambda y: rank(_full(y)), z[idx], method="Nelder-Mead", bounds=sym_box,
                       options={**NM_TOL, "maxfev": maxfev // 3,
                                "initial_simplex": first_simplex(z[idx], first, sym_box)})
        if sym.fun <= f:
            z, f = _full(sym.x), sym.fun
    while spent() < maxfev:
        left = min(ROUND_FEV, maxfev - spent())
        out = minimize(rank, z, method="Nelder-Mead", bounds=box, options={
            **NM_TOL, "maxfev": left,
            "initial_simplex": first_simplex(z, FULL_STEPS[:len(box)], box)})
        gained = f - out.fun
        if out.fun <= f:
            z, f = out.x, out.fun
        if not gained > ROUND_RTOL * max(abs(f), 1e-12):
            break
    seed, end = (fam.evaluate(fam.member(x)) for x in (z0, z))
    return ({"seed": seed.params.as_dict(), "seed_value": value_of(settings, seed),
             "end": end.params.as_dict(), "end_value": value_of(settings, end),
             "evaluations": spent()}, list(asked.values()))


def search_families(robot: Robot, gravity: GravityConvention, settings: OCPSettings, shapes,
                    local_starts: int,
                    maxfev: int, jobs: int, meanwhile: Callable[[], object] | None = None
                    ) -> dict[str, tuple[WaveFamily, list[dict]]]:
    """Scan and local searches of every shape's family: per shape, the family (every evaluation, in
    the order of a serial search) and the local searches' summaries.  On ``jobs`` worker processes
    when more than one (all shapes' scans, then all their local searches, share the pool: the pulse
    search from the triangle's best starts as soon as the triangle's searches end);
    ``meanwhile`` runs in this process while the workers scan.  A broken pool (a worker killed)
    starts the search over here."""
    try:
        return _search(robot, gravity, settings, tuple(shapes), local_starts, maxfev, jobs,
                       meanwhile)
    except BrokenProcessPool:
        return _search(robot, gravity, settings, tuple(shapes), local_starts, maxfev, 1, meanwhile)


def _search(robot, gravity, settings, shapes, local_starts, maxfev, jobs, meanwhile):
    fams = {s: WaveFamily(robot, gravity, settings, s) for s in shapes}
    points = {s: scan_points(settings, s) for s in shapes}
    with _pool(robot, gravity, settings, shapes, jobs) as pool:
        chunks = [(s, list(c)) for s in shapes
                  for c in np.array_split(np.array(points[s]), 4 * jobs) if len(c)]
        # every chunk sent at once
        scanned = pool.map(_scan_chunk, chunks) if pool is not None else []
        if meanwhile is not None:
            meanwhile()
        for (s, _), evs in zip(chunks, scanned):
            fams[s].absorb(evs)
        starts = {}
        for s in shapes:
            fam = fams[s]
            scored = [(search_rank(settings, fam.evaluate(fam.member(z))), z) for z in points[s]]
            starts[s] = seeds(scored, local_starts, 6.0 / settings.harmonic_psi)
        scan = {s: fams[s].evaluated() for s in shapes}
        if pool is None:
            summaries = {s: [local_search(fams[s], z, maxfev, scan[s])[0] for z in starts[s]]
                         for s in shapes}
            if {"triangle", "pulse"} <= set(shapes):
                summaries["pulse"].append(local_search(fams["pulse"], _as_pulse(fams["triangle"]),
                                                       maxfev, scan["pulse"])[0])
        else:
            summaries = _local_searches(pool, fams, starts, maxfev, jobs, scan)
    return {s: (fams[s], summaries[s]) for s in shapes}


def _local_searches(pool, fams: dict, starts: dict, maxfev: int, jobs: int,
                    scan: dict) -> dict[str, list]:
    """The local searches of every family on the pool's ``jobs`` workers, each sent when a worker
    is free: the triangle family's first, then the pulse family's, then the others'; the pulse
    search from the triangle's best (index -1) goes next as soon as the triangle's have ended.
    Each search is the serial one (its budget does not depend on the worker's cache:
    :func:`local_search`), and the members it asked for are added to its family in the order of a
    serial search (each family's own searches, then the pulse one from the triangle's best), so
    each family's best is the serial search's.  ``scan``: each family's scan evaluations."""
    first = {"triangle": 0, "pulse": 1}
    queue = [(s, i) for s in sorted(fams, key=lambda s: first.get(s, 2))
             for i in range(len(starts[s]))]
    chained = "triangle" in fams and "pulse" in fams
    if chained and not starts["triangle"]:
        queue.insert(0, ("pulse", -1))
    out: dict = {s: [None] * len(starts[s]) + [None] for s in fams}  # [-1]: from the triangle
    running: dict = {}
    while queue or running:
        while queue and len(running) < jobs:
            s, i = queue.pop(0)
            z = starts[s][i] if i >= 0 else _as_pulse(fams["triangle"])
            running[pool.submit(_local_task, s, z, maxfev, scan[s])] = (s, i)
        done, _ = wait(running, return_when=FIRST_COMPLETED)
        for future in done:
            s, i = running.pop(future)
            out[s][i] = future.result()
            if chained and s == "triangle" and all(r is not None for r in out[s][:-1]):
                for _, evs in out[s][:-1]:
                    fams[s].absorb(evs)
                queue.insert(0, ("pulse", -1))
    summaries = {}
    for s, runs in out.items():
        runs = [r for r in runs if r is not None]
        if not (chained and s == "triangle"):
            for _, evs in runs:
                fams[s].absorb(evs)
        summaries[s] = [summary for summary, _ in runs]
    return summaries


def _as_pulse(triangles: WaveFamily) -> np.ndarray:
    """The pulse family's box point of the triangle family's best member: a triangle is the pulse of
    rise 0.5 (r = 1; its duty, of no time left, is moot).  A pulse search from there makes the
    superset's best at least the subset's, which the pulse scan, on its own, need not find."""
    settings = triangles.settings
    best = min(triangles.evaluated(), key=lambda ev: search_rank(settings, ev))
    lo, hi = np.array(shape_box("pulse")).T   # (to_box's round-off may leave the box by 1e-16)
    return np.clip(np.concatenate([best.params.to_box(settings), [1.0, 0.5]]), lo, hi)


#: the families of a worker process by shape (set by :func:`_init_worker`)
_WORKER: dict = {}


@contextlib.contextmanager
def _pool(robot: Robot, gravity: GravityConvention, settings: OCPSettings, shapes, jobs: int):
    """A pool of ``jobs`` worker processes, each with the families of the problem (None for one
    job)."""
    if jobs < 2:
        yield None
        return
    pool = worker_pool(jobs, _init_worker, (robot, gravity, settings, shapes))
    try:
        yield pool
    except BaseException:  # Ctrl-C or an error here: the chunks not started yet are dropped
        pool.shutdown(cancel_futures=True)
        raise
    pool.shutdown()


def _init_worker(robot: Robot, gravity: GravityConvention, settings: OCPSettings, shapes) -> None:
    _WORKER.update({s: WaveFamily(robot, gravity, settings, s) for s in shapes})


def _scan_chunk(chunk) -> list:
    """The evaluations of scan points (box coordinates) of one shape, in a worker."""
    shape, points = chunk
    fam = _WORKER[shape]
    return [fam.evaluate(fam.member(z)) for z in points]


def _local_task(shape: str, z0: np.ndarray, maxfev: int, scan: list) -> tuple[dict, list]:
    """One local search (:func:`local_search`) in a worker, after the family's scan evaluations
    ``scan``: its summary and the evaluations it asked for, in the order of its first requests."""
    fam = _WORKER[shape]
    fam.absorb(scan)
    return local_search(fam, z0, maxfev, scan)


def best_baselines(robot: Robot, gravity: GravityConvention, settings: OCPSettings, shapes=None,
                   local_starts: int | None = None, maxfev: int | None = None,
                   jobs: int | None = None,
                   meanwhile: Callable[[], object] | None = None) -> Baselines:
    """The best member of each waveform family of the envelope and bandwidth for the objective.

    Parameters
    ----------
    robot : Robot
        The robot (SI units); ``settings.scenarios(robot)`` gives the friction scenarios.
    gravity : str
        Its gravity convention ("physical" or "paper").
    settings : OCPSettings
        The envelope (gamma_deg, A_max_deg), the bandwidth (max_rate_deg_s), the objective (and
        speed_min, robust, direction), the scan sizes (harmonic_A, harmonic_psi, baseline_samples),
        the local searches (baseline_starts) and the families (``baseline_shapes``).
    shapes : sequence of str, optional
        The families to search (None: ``settings.baseline_shapes``).
    local_starts : int, optional
        Best distinct scan points refined by local searches, per family (None: ``baseline_starts``).
    maxfev : int, optional
        Most members each local search asks for beyond the scan (None: ``baseline_evaluations``).
    jobs : int, optional
        Worker processes (None: the CPUs this process may use; 1: all in this process).  The result
        does not depend on it (each local search is the same in any process:
        :func:`local_search`).
    meanwhile : callable, optional
        Called in this process while the workers scan (first, when there are none), e.g. to build
        the OCP's solvers (:meth:`~ocp_crawl.ocp.solver.GaitSolver.prepare`).

    Returns
    -------
    Baselines
        Per family the best member found over the scan and the local searches (every member
        simulated with the event-driven stepper in every scenario at its shortest period); for
        min_cot, when no member meets speed_min, the one nearest to it (value +inf, ``feasible``
        False) as an initial guess only; None when no member simulates successfully.
    """
    t0 = time.perf_counter()
    shapes = tuple(settings.baseline_shapes if shapes is None else shapes)
    for s in shapes:
        shape_box(s)
    jobs = default_jobs() if jobs is None else int(real("jobs", jobs, integer=True, low=1))
    starts = settings.baseline_starts if local_starts is None else local_starts
    maxfev = settings.baseline_evaluations if maxfev is None else maxfev
    found = search_families(robot, gravity, settings, shapes, starts, maxfev, jobs, meanwhile)
    dt = time.perf_counter() - t0
    choices = {}
    for s, (fam, summaries) in found.items():
        rank, best = min(((search_rank(settings, ev), ev) for ev in fam.evaluated()),
                         key=lambda x: x[0], default=(FAIL_RANK, None))
        choice = None if rank >= FAIL_RANK or best is None else choice_of(settings, best)
        if choice is not None:
            choice.evaluated, choice.starts, choice.time_s = fam.evaluations, summaries, dt
        choices[s] = choice
    return Baselines(settings.objective, choices, dt)


def best_harmonic(robot: Robot, gravity: GravityConvention, settings: OCPSettings,
                  local_starts: int | None = None,
                  maxfev: int | None = None, jobs: int | None = None,
                  meanwhile: Callable[[], object] | None = None) -> WaveChoice | None:
    """The best member of the harmonic family alone (:func:`best_baselines` with ``shapes`` =
    ("harmonic",)): the OCP's first start; None when no member simulates successfully."""
    return best_baselines(robot, gravity, settings, ("harmonic",), local_starts, maxfev, jobs,
                          meanwhile).choices["harmonic"]
