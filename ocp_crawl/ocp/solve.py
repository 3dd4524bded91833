"""Solve the periodic-gait OCP and prove the optimum by replay: :func:`optimize_gait` (its result:
:class:`~ocp_crawl.ocp.result.OCPResult`).

The first start is the best harmonic gait of the family
(:func:`~ocp_crawl.ocp.search.best_baselines`), then a Fourier-order start and perturbed starts
(:mod:`~ocp_crawl.ocp.starts`, ``settings.starts`` in all); from each, the transcription
(:class:`~ocp_crawl.ocp.transcription.GaitOCP`) is solved by the relaxation homotopy, every stage
read through the IPOPT status table, and the optimum is judged by its event-driven replay
(:func:`~ocp_crawl.ocp.judge.judge_replay`: the transcription's own linear interpolant, the OCP's
period).  The reported optimum is the best by replay among the starts the judge accepts, with the
spread of the others; its gain is measured by replay against the best member of each simple waveform
family (harmonic, triangle, pulse: ``settings.baselines``) and against the best of them.  The
harmonic family is searched first (the start); the others, comparators only, are searched in a
forked process while this one solves the OCP (:func:`~ocp_crawl.workers.overlap`).  With
``endgame_sigma`` the homotopy may end early (:mod:`~ocp_crawl.ocp.endgame`), judged by replay here.
With ``start_solve`` = "tightened" every family is searched first and each family's best member is
a start too, each start solved by the tightened NLP on its simulated branches alone; with "both"
those tightened starts follow the homotopy's (:func:`~ocp_crawl.ocp.starts.family_starts`).
"""
from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from ocp_crawl.io import units
from ocp_crawl.model.chain import Chain
from ocp_crawl.model.statics import GravityConvention
from ocp_crawl.nlp.homotopy import Stage, observed_elsewhere
from ocp_crawl.nlp.ipopt import ipopt_status, result_status
from ocp_crawl.ocp.baseline import Baselines, WaveChoice, cycle_of, objective_value, value_from
from ocp_crawl.ocp.quantities import cycle_values, profile_of_nodes
from ocp_crawl.ocp.asymmetry import check_friction_asymmetry
from ocp_crawl.ocp.dynamic_margin import check_dynamic_margin
from ocp_crawl.ocp.endgame import Endgame
from ocp_crawl.ocp.gains import harmonic_peaks, measure_gains
from ocp_crawl.ocp.plant import AnyRobot, Plant, as_plant
from ocp_crawl.ocp.judge import (first_failure, is_better, judge_replay, replay_signal, spread_text,
                                 value_text)
from ocp_crawl.ocp.result import OCPResult, StartRecord
from ocp_crawl.ocp.search import best_baselines
from ocp_crawl.ocp.chain_search import (SHAPES as CHAIN_SHAPES, ChainWaveChoice,
                                        best_chain_baselines, family_shapes)
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.starts import StartGuess, family_starts, given_start, start_guesses
from ocp_crawl.ocp.solver import GaitSolver
from ocp_crawl.ocp.transcription import GaitOCP
from ocp_crawl.workers import overlap
from ocp_crawl.sim.result import cost_of_transport
from ocp_crawl.status import Status


def baseline_gait(harm, robot: AnyRobot, settings: OCPSettings) -> tuple:
    """The harmonic baseline (a :class:`~ocp_crawl.ocp.baseline.WaveChoice`, or a chain's
    :class:`~ocp_crawl.ocp.chain_search.ChainWaveChoice`) as a start: its torque signal
    (``signal(t)`` [N m] at phases t [cycles]) and its period T [s]."""
    return harm.signal_for(robot, settings), harm.T


def optimize_gait(robot: AnyRobot, gravity: GravityConvention = "physical",
                  settings: OCPSettings | None = None, replay: bool = True, jobs: int | None = None,
                  start: tuple | None = None) -> OCPResult:
    """Solve the periodic-gait OCP from several starts, judge each optimum by replay, report the
    best.

    Parameters
    ----------
    robot : Robot or Chain
        The robot (SI units): the three-link robot, or an n-link chain (n - 1 torque profiles; its
        baselines are travelling waves, harmonic and triangle,
        :func:`~ocp_crawl.ocp.chain_search.best_chain_baselines`).
    gravity : str
        The gravity convention ("physical" or "paper").
    settings : OCPSettings, optional
        The OCP's settings (None: the defaults), ``settings.starts`` starts.
    replay : bool
        Judge each optimum by its event-driven replay (default).  False: the OCP's own verdict only,
        the best start by the OCP's value (a solver test; the message says that nothing was
        replayed).
    jobs : int, optional
        Worker processes of the baselines' search (:func:`~ocp_crawl.ocp.search.best_baselines`;
        None: the CPUs available): the harmonic family's first, then the other families' while the
        OCP solves.  The result does not depend on it.
    start : (callable, float), optional
        A first start in place of the harmonic baseline: a torque signal tau(t) [N m] of the phase t
        [cycles] (e.g. a previous optimum's :func:`~ocp_crawl.ocp.judge.replay_signal`) and its
        period [s] (:func:`~ocp_crawl.ocp.starts.given_start`); the baselines are searched as
        without it.

    Returns
    -------
    OCPResult
        The best start by replay among those the judge accepts (else the best replayed, else the
        first start's failure): SUCCESS, INFEASIBLE, SOLVER_FAILURE, NOT_COMPLEMENTARY,
        NO_INITIAL_GUESS (no harmonic gait simulates), REPLAY_FAILED, REPLAY_MISMATCH or
        WORSE_THAN_BASELINE (confirmed by replay but worse than the harmonic baseline it started
        from); ``starts`` holds every start's outcome.
    """
    settings = settings or OCPSettings()
    t_start = time.perf_counter()
    shapes = _shapes(robot, settings)
    solver = GaitSolver(GaitOCP(robot, gravity, settings))
    # tightened starts need every family's best before the solve; else the harmonic one only
    first = shapes if settings.start_solve == "tightened" else ("harmonic",)
    found = _baselines(robot, gravity, settings, first, jobs, solver.prepare)
    harm = found.choices["harmonic"]
    if harm is None:
        return _no_harmonic(settings, solver.ocp.n_joints)
    models = [Plant(r, gravity) for r in settings.scenarios(robot)]
    tightened = settings.start_solve == "tightened"

    def solve_starts() -> list[tuple[StartGuess, OCPResult]]:
        guesses = _guesses(settings, robot, solver.ocp.n_joints, found, models, start)
        return _solve_guesses(solver, models, guesses, found, replay, tightened,
                              parallel=tightened and jobs != 1)

    def from_families(base: Baselines, parallel: bool) -> list[tuple[StartGuess, OCPResult]]:
        # with "both": the tightened starts from every family's best member, after the homotopy's
        if settings.start_solve != "both":
            return []
        return _solve_guesses(solver, models, family_starts(base, settings, robot, models=models),
                              base, replay, True, parallel=parallel)
    others = tuple(s for s in shapes if s not in first)

    def comparators() -> tuple[Baselines, list]:
        # the other families (the gains' comparators) searched on all the workers while the OCP
        # solves, then their tightened starts on the core the search leaves
        rest = _baselines(robot, gravity, settings, others, jobs)
        return rest, from_families(found.merged(rest), False)
    if others:
        task, forward = observed_elsewhere(comparators)
        (rest, more), solved = overlap(task, solve_starts, forward)
        base = found.merged(rest)
    else:
        solved, base = solve_starts(), found
        more = from_families(base, jobs != 1)
    res = _best_start(solved + more, base, models, settings, replay)
    res.solve_time_s = time.perf_counter() - t_start
    return res


def _shapes(robot: AnyRobot, settings: OCPSettings) -> tuple[str, ...]:
    """The families searched: the settings' (a chain's are its travelling waves: harmonic and
    triangle)."""
    if isinstance(robot, Chain) and settings.baselines not in ("all", *CHAIN_SHAPES):
        raise ValueError(f"optimize_gait: a chain's baselines are travelling waves of the shapes "
                         f"{CHAIN_SHAPES} ('all': both), got {settings.baselines!r}")
    return family_shapes(settings, isinstance(robot, Chain))


def _guesses(settings: OCPSettings, robot: AnyRobot, m: int, found: Baselines, models: list,
             start: tuple | None) -> list[StartGuess]:
    """The starts: the harmonic baseline (or the ``start`` given) and the settings' further starts
    (:func:`~ocp_crawl.ocp.starts.start_guesses`); with ``start_solve`` = "tightened", labelled so
    and followed by every other family's best member of ``found``."""
    N = settings.nodes
    phase = np.arange(N) / N
    harm = found.choices["harmonic"]
    signal, T0 = baseline_gait(harm, robot, settings)

    def follows(tau: np.ndarray) -> bool:
        return all(p.simulate(replay_signal(phase, tau)).success for p in models)
    guesses = start_guesses(settings, robot, signal(phase).reshape(m, N), T0, follows)
    if start is not None:
        guesses[0] = given_start(settings, robot, np.asarray(start[0](phase)).reshape(m, N),
                                 start[1])
    if settings.start_solve != "tightened":
        return guesses
    # the harmonic best member is the first start unless a start is given
    return ([replace(g, label=f"{g.label}, tightened") for g in guesses]
            + family_starts(found, settings, robot, skip=("harmonic",) if start is None else (),
                            models=models))


def _solve_guesses(solver: GaitSolver, models: list, guesses: list[StartGuess], base: Baselines,
                   replay: bool, tightened: bool,
                   parallel: bool = False) -> list[tuple[StartGuess, OCPResult]]:
    """Each start solved from its node profile (by the homotopy, or by the tightened NLP alone at
    most ``endgame_max_iter`` iterations per candidate) and judged: (start, result) pairs, in the
    order of ``guesses``.  ``parallel``: the second half of the starts in a forked process while
    this one solves the first (:func:`~ocp_crawl.workers.overlap`; each solve is deterministic, so
    the results are those of one after the other)."""
    settings = solver.settings
    phase = np.arange(settings.nodes) / settings.nodes
    cap = settings.endgame_max_iter if tightened else None

    def solve(some: list[StartGuess]) -> list[tuple[StartGuess, OCPResult]]:
        return [(g, solve_from(solver, models, replay_signal(phase, g.tau), g.T,
                               base.choices["harmonic"], replay, tightened=tightened,
                               baselines=base, max_iter=cap)) for g in some]
    if not parallel or len(guesses) < 2:
        return solve(guesses)
    half = (len(guesses) + 1) // 2
    task, forward = observed_elsewhere(lambda: solve(guesses[half:]))
    later, first = overlap(task, lambda: solve(guesses[:half]), forward)
    return first + later


def _no_harmonic(settings: OCPSettings, joints: int) -> OCPResult:
    """NO_INITIAL_GUESS: no member of the harmonic family simulates (its torques: none, of
    ``joints`` rows)."""
    return OCPResult(success=False, status=Status.NO_INITIAL_GUESS, objective=settings.objective,
                     settings=settings, tau=np.zeros((joints, 0)),
                     message="no harmonic gait of the family simulates successfully: no initial "
                             "guess")


def _baselines(robot: AnyRobot, gravity: GravityConvention, settings: OCPSettings, shapes,
               jobs: int | None, meanwhile=None) -> Baselines:
    """The best member of each family of ``shapes`` (a chain's: its travelling waves);
    ``meanwhile`` runs while the workers scan (the OCP's solvers built)."""
    if isinstance(robot, Chain):
        return best_chain_baselines(robot, gravity, settings, shapes, jobs, meanwhile)
    return best_baselines(robot, gravity, settings, shapes, jobs=jobs, meanwhile=meanwhile)


def _best_start(solved: list, base: Baselines, models: list, settings: OCPSettings,
                replay: bool) -> OCPResult:
    """The best of the starts' outcomes (``solved``: (guess, result) pairs), each measured against
    the baselines ``base``, with the record of every start and their spread."""
    guesses, runs = [g for g, _ in solved], [r for _, r in solved]
    for r in runs:
        r.baselines = base
        if replay:
            measure_gains(r, models)
    res = _pick(runs, settings, replay)
    if replay:
        harmonic_peaks(res, models)
        check_dynamic_margin(res, models)
        check_friction_asymmetry(res, models)
    res.starts = [StartRecord(g.label, r.status, g.T, r.value_ocp, r.value_replay, r.message,
                              sum(stage.iterations for stage in r.homotopy))
                  for g, r in zip(guesses, runs)]
    if len(guesses) > 1:
        spread = spread_text(settings.objective, *res.spread)   # (low, high, converged)
        res.message += f"; best of {len(guesses)} starts ({spread})"
    return res


def _pick(runs: list[OCPResult], settings: OCPSettings, replay: bool) -> OCPResult:
    """The reported start: the best by replay among the judged successes (by the OCP's value without
    replay), else the best replayed one, else the first start."""
    key = "value_replay" if replay else "value_ocp"
    for pool in ([r for r in runs if r.success],
                 [r for r in runs if math.isfinite(r.value_replay)]):
        best = None
        for r in pool:
            if best is None or is_better(settings.objective, getattr(r, key), getattr(best, key)):
                best = r
        if best is not None:
            return best
    return runs[0]


def solve_from(solver: GaitSolver, models: list, signal, T: float,
               harmonic: WaveChoice | ChainWaveChoice | None = None, replay: bool = True,
               tightened: bool = False,
               baselines: Baselines | None = None, max_iter: int | None = None) -> OCPResult:
    """Solve the OCP from one start and judge its optimum by replay.

    Parameters
    ----------
    solver : GaitSolver
        The solver of the transcription (both built once for its settings:
        :class:`~ocp_crawl.ocp.solver.GaitSolver` of a
        :class:`~ocp_crawl.ocp.transcription.GaitOCP`).
    models : list of Plant (or Model, ChainModel)
        The friction scenarios' models (the judge's replays), in the order of
        ``solver.settings.scenarios``.
    signal : callable
        The start's torques ``signal(t)`` [N m] at phases t [cycles] (must simulate successfully).
    T : float
        The start's period [s].
    harmonic : WaveChoice, optional
        The harmonic baseline (an optimum significantly worse than it, its first start, is not one).
    replay : bool
        Judge the optimum by replay (default).
    tightened : bool
        Solve only the tightened NLP on the branches of the start's simulated guess, no homotopy
        (:meth:`~ocp_crawl.ocp.solver.GaitSolver.solve_tightened`: a coarser N's optimum refined);
        default False.
    baselines : Baselines, optional
        The best member of each waveform family (the gains are measured against them; without them,
        against ``harmonic``).
    max_iter : int, optional
        With ``tightened``: at most this many IPOPT iterations per candidate of the tightened NLP
        (None: the solvers' own limit).

    Returns
    -------
    OCPResult
        The start's outcome (``starts`` empty; ``solve_time_s`` of this start).
    """
    settings, ocp = solver.settings, solver.ocp
    t_start = time.perf_counter()
    res = OCPResult(success=False, status=Status.SOLVER_FAILURE, message="",
                    objective=settings.objective, tau=np.zeros((ocp.n_joints, 0)),
                    settings=settings, harmonic=harmonic, baselines=baselines)
    bad = first_failure(models, signal)
    if bad is not None:
        res.status = Status.NO_INITIAL_GUESS
        res.message = (f"{Status.NO_INITIAL_GUESS.text}: the start gait fails in the simulator: "
                       f"{bad.message}")
        return res
    x0 = ocp.initial_guess(signal, T)
    endgame = None if tightened or not replay else _endgame(solver, models)
    x, hist, failed, status = (solver.solve_tightened(x0, max_iter) if tightened
                               else solver.solve(x0, endgame=endgame))
    res.homotopy = hist
    res.path = "; ".join(endgame.outcome) if endgame is not None else ""
    if not _accept(res, solver, x, failed, status):
        res.message += f"; {res.path}" if res.path else ""
        res.message += _cap_hint(hist if failed is not None else [],
                                 max_iter if tightened else None, settings.start_solve)
        res.solve_time_s = time.perf_counter() - t_start
        return res
    if replay:
        _judge(res, models)
    else:
        res.message += "; not replayed (the judge did not run)"
    res.solve_time_s = time.perf_counter() - t_start
    return res


def _cap_hint(records: list, max_iter: int | None, start_solve: str) -> str:
    """What to try when a tightened start (at most ``max_iter`` IPOPT iterations a candidate; None:
    not one) failed and one of its IPOPT calls (``records``) stopped at a limit; '' otherwise."""
    if max_iter is None or not any(ipopt_status(r.return_status).kind == "limit" for r in records):
        return ""
    more = ", or add the homotopy (start_solve = \"both\")" if start_solve == "tightened" else ""
    return (f"; a tightened start stopped at its {max_iter} IPOPT iterations: raise [ocp] "
            f"endgame_max_iter{more}")


def _endgame(solver: GaitSolver, models: list) -> Endgame | None:
    """The settings' endgame (None without ``endgame_sigma``), judged by replay: the endgame's point
    is kept when the replay judge accepts it and its replayed objective is at least that of the
    point it is compared with (the stage's profile, or the homotopy's optimum on both paths)."""
    settings, ocp = solver.settings, solver.ocp
    if settings.endgame_sigma is None:
        return None
    phase = np.arange(settings.nodes) / settings.nodes

    def replays(x: np.ndarray) -> tuple[list, float]:
        u = ocp.unpack(x)
        return [as_plant(m).simulate(replay_signal(phase, u["tau"])) for m in models], u["T"]

    def guess(x_stage: np.ndarray) -> np.ndarray | None:
        runs, T = replays(x_stage)
        if not all(r.success for r in runs):
            return None
        return ocp.initial_guess(replay_signal(phase, ocp.unpack(x_stage)["tau"]), T)

    def keep(x: np.ndarray, x_ref: np.ndarray, against: str) -> tuple[bool, str]:
        trial = OCPResult(success=False, status=Status.SOLVER_FAILURE, message="",
                          objective=settings.objective, settings=settings)
        fill_solution(trial, solver, x)
        verdict = judge_replay(models, settings, trial.tau, trial.T_ocp, trial.value_ocp,
                               trial.S_ocp)
        if not verdict.ok:
            return False, f"the replay judge: {verdict.message}"
        runs, T = replays(x_ref)
        ref = objective_value(settings, runs, T, enforce=False,
                              profile=profile_of_nodes(ocp.unpack(x_ref)["tau"]))
        text = (f"replay {value_text(settings.objective, verdict.value)} against {against}'s "
                f"{value_text(settings.objective, ref)}")
        return not is_better(settings.objective, ref, verdict.value), text
    return Endgame(settings.endgame_sigma, settings.endgame_max_iter, guess,
                   lambda x, max_iter: solver.solve_tightened(x, max_iter, kind="endgame"), keep,
                   both=settings.endgame_paths == "both")


def _accept(res: OCPResult, solver: GaitSolver, x, failed: str | None, status: str) -> bool:
    """Fill res from the solve's outcome; True if the OCP converged to a usable, complementary
    point."""
    outcome = ipopt_status(status)
    if failed is not None:
        # every homotopy failed: the status table decides infeasible vs solver failure
        res.failed_stage = failed
        res.status = result_status(outcome, usable=False)
        res.message = (f"{'infeasible' if res.status == Status.INFEASIBLE else 'IPOPT failed'}: "
                       f"IPOPT {outcome.describe()} at {failed}")
    if x is None:
        return False
    fill_solution(res, solver, x)
    if failed is not None:
        res.message += "; the last accepted iterate is reported (not an optimum)"
        return False
    if not _check_solution(res, solver.settings, outcome):
        res.message += _not_kept(solver.kept_run)
        return False
    res.success = True
    res.status = Status.SUCCESS
    res.message = (f"optimal {solver.settings.objective} profile found ({len(res.homotopy)} IPOPT "
                   "calls, final IPOPT status "
                   f"{status}){_not_kept(solver.kept_run)}{'; ' + res.path if res.path else ''}")
    return True


def _not_kept(run: list) -> str:
    """A note on the IPOPT calls after the kept point that IPOPT did not accept, the last of each
    kind: the polish, and the loose last stage solved again tightly
    (:meth:`~ocp_crawl.ocp.solver.GaitSolver.solve`); '' if none."""
    last: dict[str, Stage] = {}
    for stage in reversed(run):
        if stage.accepted:
            break
        last.setdefault(stage.kind, stage)
    what = {"polish": "polish", "homotopy": "the last stage solved again tightly"}
    return "".join(f"; {what.get(kind, kind)} not kept: IPOPT "
                   f"{stage.message}" for kind, stage in last.items())


def fill_solution(res: OCPResult, solver: GaitSolver, x: np.ndarray) -> None:
    """The profile, period, trajectories, S, v, W+, CoT+ and residuals of the NLP point x."""
    ocp = solver.ocp
    un = solver.unpack(x)
    res.phase = np.arange(ocp.settings.nodes) / ocp.settings.nodes
    res.tau = un["tau"]
    res.T_ocp = un["T"]
    for sc, model in zip(un["scen"], ocp.scen):
        res.phi.append(sc["phi"])
        res.x1.append(sc["x1"])
        res.f_t.append(sc["f_t"])
        res.modes.append(sc["modes"])
        res.theta.append(sc["theta"])
        res.S_ocp.append(sc["S"])
        res.v_ocp.append(sc["v"])
        w = sc["W_plus"]
        res.W_plus_ocp.append(w)
        res.CoT_plus_ocp.append(cost_of_transport(w, model.robot, sc["S"]))
    res.complementarity_residual = max(sc["comp"] for sc in un["scen"])
    res.periodicity_residual = max(sc["periodic"] for sc in un["scen"])
    res.equation_residual = ocp.equation_residual(x)
    cycle = cycle_of(ocp.settings, res.S_ocp, res.W_plus_ocp, res.CoT_plus_ocp, res.T_ocp,
                     profile_of_nodes(res.tau))
    res.value_ocp = value_from(ocp.settings, res.S_ocp, res.CoT_plus_ocp, res.T_ocp, cycle=cycle)


def _check_solution(res: OCPResult, settings: OCPSettings, outcome) -> bool:
    """False (with the status and message set) if the accepted point has non-finite values or is not
    complementary."""
    numbers = [*res.S_ocp, res.T_ocp, *res.W_plus_ocp, res.complementarity_residual,
               res.periodicity_residual, res.equation_residual, *np.ravel(res.tau)]
    if not all(math.isfinite(v) for v in numbers):
        res.status = Status.SOLVER_FAILURE
        res.message = f"IPOPT returned {outcome.describe()} but the solution has NaN or Inf values"
        return False
    if not res.complementarity_residual <= settings.comp_tol:
        res.status = Status.NOT_COMPLEMENTARY
        res.message = (f"complementarity residual {res.complementarity_residual:.2e} above "
                       f"{settings.comp_tol:.1e} after the homotopy")
        return False
    return True


def _judge(res: OCPResult, models: list) -> None:
    """Replay the optimal profile (every scenario) and let the judge decide; the gain over the
    baseline."""
    verdict = judge_replay(models, res.settings, res.tau, res.T_ocp, res.value_ocp, res.S_ocp)
    res.replay = verdict.replay
    res.envelope_excess, res.rate_ratio = verdict.envelope_excess, verdict.rate_ratio
    res.accel_ratio, res.joint_rate_ratio = verdict.accel_ratio, verdict.joint_rate_ratio
    res.peak_joint_rate_deg_s = [list(p.joint_rate_deg_s) for p in verdict.peaks]
    res.peak_slip_speed_m_s = [list(p.slip_speed_m_s) for p in verdict.peaks]
    res.S_replay, res.v_replay = verdict.S, verdict.speed
    res.W_plus_replay, res.CoT_plus_replay = verdict.W_plus, verdict.CoT_plus
    res.value_replay, res.rel_diff_replay = verdict.value, verdict.rel_diff
    if verdict.cycle is not None:
        res.requirements = [{"text": c.text(), "constraint": c.to_dict(),
                             "replay": cycle_values(c, verdict.cycle)}
                            for c in res.settings.requirements]
    if not verdict.ok:
        res.success = False
        res.status = verdict.status
        res.message = verdict.message
    else:
        res.message += ("; confirmed by the event-driven replay (objective within "
                        f"{units.ratio(verdict.rel_diff)}, replay_tol "
                        f"{units.ratio(res.settings.replay_tol)})")
    measure_gains(res, models)
