"""Running a problem: the simulation through the solver registry, the OCP settings, the paper's
problem."""
from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np

from ocp_crawl.model.inputs import Harmonic
from ocp_crawl.model.pulse import Pulse
from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.ocp import OCPSettings
from ocp_crawl.ocp.plant import joints_of
from ocp_crawl.problem.problem import Problem, freeze, problem_from_dict, thaw
from ocp_crawl.problem.messages import format_value
from ocp_crawl.problem.keys import ProblemError
from ocp_crawl.problem.schema import SCHEMA
from ocp_crawl.sim import simulate
from ocp_crawl.sim.event import HybridStepper
from ocp_crawl.sim.result import CrawlResult


def run_problem(problem: Problem, t_eval=None) -> CrawlResult:
    """Simulate the problem with its solver (``problem.solver`` of the registry,
    ``problem.options``).

    Parameters
    ----------
    problem : Problem
        A validated problem (:func:`load_problem`, :func:`problem_from_dict`,
        :func:`paper_problem`).
    t_eval : array_like of float, optional
        Output phases [cycles] in the steady cycle (in [0, 1]); None for the solver's own sampling.

    Returns
    -------
    CrawlResult
        ``status``/``success``/``message``, the displacement per cycle ``S`` [m] (< 0: towards foot
        1), the positive work ``W_plus`` [J], the cost of transport ``CoT_plus`` [-], the events and
        the sampled trajectories.  A numerical failure (fold, lift-off, ...) is a status, not an
        exception.
    """
    if not isinstance(problem, Problem):
        raise TypeError(f"run_problem needs a Problem, got {type(problem).__name__}")
    return simulate(problem.model, problem.signal, problem.solver, problem.options, t_eval)


def no_start_reason(problem: Problem) -> str | None:
    """Why the torque-driven ``problem`` has no released equilibrium at t = 0 (status no_start), or
    None.

    Cheap (one equilibrium solve), for checking before a long run; every torque solver starts there.
    The angles drive returns None: its contact is checked over the whole cycle when the problem is
    built.
    """
    if problem.drive != "torque":
        return None
    model = problem.model
    try:
        if isinstance(model, ChainModel):
            from ocp_crawl.sim.chain_torque import ChainTorqueStepper   # (scipy: at run time)

            ChainTorqueStepper(model, problem.torque, max_step=problem.hybrid.max_step,
                               min_step=problem.hybrid.min_step,
                               event_xtol=problem.hybrid.event_xtol,
                               trial_step=problem.hybrid.trial_step,
                               quad_h=problem.hybrid.quad_h).start()
        else:
            HybridStepper(model, problem.torque, problem.hybrid).initial_state(0.0)
    except ValueError as exc:
        return str(exc)
    return None


#: phases at which a sampled or Fourier reference is averaged for its centre (exact for Fourier
#: orders below it)
CENTRE_GRID = 720


def centre_deg(problem: Problem) -> float:
    """The centre of the problem's reference angles [deg], mean of both joints: (gamma1 + gamma2)/2
    for the harmonic and pulse waveforms, else the mean over the cycle (the OCP's envelope is
    centred there)."""
    gait = problem.gait
    if isinstance(gait, (Harmonic, Pulse)):
        return math.degrees(0.5 * (gait.gamma1 + gait.gamma2))
    return math.degrees(float(np.mean(gait(np.arange(CENTRE_GRID) / CENTRE_GRID))))


def check_start_robot(problem: Problem, start: Problem) -> None:
    """ProblemError when the start's robot has another number of joints than the problem's."""
    m, m_start = joints_of(problem.robot), joints_of(start.robot)
    if m_start != m:
        raise ProblemError(f"{start.source}: a start needs a robot of the problem's {m} joints, "
                           f"got {m_start}")


def joint_centres_deg(problem: Problem) -> tuple[float, ...]:
    """A chain's reference angles' centre per joint [deg], the mean over the cycle (the OCP's
    envelope of each joint is centred there)."""
    ref = np.asarray(problem.gait(np.arange(CENTRE_GRID) / CENTRE_GRID), float)
    return tuple(float(v) for v in np.degrees(ref.mean(axis=1)))


def ocp_settings(problem: Problem) -> OCPSettings:
    """OCPSettings from the problem's ``[ocp]`` section (defaults when absent) and its gait's gamma
    (a chain's: its centre per joint, ``gamma_joints_deg``).

    ``A_max_deg`` [deg] must keep the envelope gamma +- A_max_deg inside (0, 180) deg (a chain's
    joints: inside (0, 360) deg); ProblemError otherwise, as for any other rule between keys that
    OCPSettings checks (e.g. sigma_min < sigma0, at most MAX_STAGES stages).
    """
    sec = dict(problem.sections.get("ocp", {}))
    if not sec:  # a problem built in code: the schema's defaults
        sec = {k.name: k.default for k in SCHEMA["ocp"].keys if k.default is not None}
    if problem.is_chain:
        if sec.get("baselines", "all") not in ("all", "harmonic", "triangle"):
            raise ProblemError(f"{problem.source}: [ocp] baselines = "
                               f"{format_value(sec['baselines'])} with a chain ([robot] lengths): "
                               "a chain's baselines are travelling waves, \"harmonic\" or "
                               "\"triangle\" (\"all\": both)")
        if sec.get("dynamic_margin") is not None:
            raise ProblemError(f"{problem.source}: [ocp] dynamic_margin = "
                               f"{format_value(sec['dynamic_margin'])} with a chain ([robot] "
                               "lengths): MuJoCo models the three-link robot only")
        centres, a = joint_centres_deg(problem), sec["A_max_deg"]
        bad = next((j for j, c in enumerate(centres) if not (0 < c - a and c + a < 360)), None)
        if bad is not None:
            raise ProblemError(f"{problem.source}: [ocp] A_max_deg = {format_value(a)} with the "
                               f"[gait] centre of joint {bad + 1}, {centres[bad]:g} deg, is "
                               "invalid: each joint's envelope centre +- A_max_deg must lie in "
                               f"(0, 360) deg (here {centres[bad] - a:g} to {centres[bad] + a:g})")
        return _settings(problem, sec, gamma_joints_deg=centres)
    gamma = centre_deg(problem)
    if not (0 < gamma - sec["A_max_deg"] and gamma + sec["A_max_deg"] < 180):
        gait = problem.sections.get("gait", {})
        given = ", ".join(f"{k} = "
                          f"{format_value(gait[k])}" for k in ("gamma_deg", "gamma1_deg",
                                                               "gamma2_deg")
                          if k in gait)
        raise ProblemError(f"{problem.source}: [ocp] A_max_deg = {format_value(sec['A_max_deg'])} "
                           f"with [gait] {given or f'gamma = {gamma:g} deg'} is invalid: the "
                           "envelope gamma +- A_max_deg must lie in (0, 180) deg (here "
                           f"{gamma - sec['A_max_deg']:g} to {gamma + sec['A_max_deg']:g})")
    return _settings(problem, sec, gamma_deg=gamma)


def _settings(problem: Problem, sec: dict, **centre) -> OCPSettings:
    """OCPSettings of the ``[ocp]`` values ``sec`` and the envelope's ``centre``; ProblemError for
    a rule between keys or a friction scenario that makes an invalid robot."""
    if "constraint" in sec:  # one [[ocp.constraint]] table per bound
        sec["constraints"] = tuple(dict(c) for c in sec.pop("constraint"))
    if "ipopt" in sec:
        sec["ipopt"] = dict(sec["ipopt"])
    try:
        settings = OCPSettings(**sec, **centre)
    except ValueError as exc:  # a rule between keys (each key alone passed the schema)
        raise ProblemError(f"{problem.source}: [ocp] {exc}".replace("OCPSettings: ",
                                                                    "").replace("OCPSettings.",
                                                                                "")) \
            from None
    try:  # every friction scenario a valid robot (a level or ratio may take mu out of its bounds)
        settings.scenarios(problem.robot)
    except ValueError as exc:
        raise ProblemError(f"{problem.source}: [ocp] a friction scenario (mu_levels, mu_ratio_eps) "
                           f"makes an invalid robot: {exc}") from None
    return settings


def optimize_problem(problem: Problem, *, jobs: int | None = None, start: Problem | None = None,
                     verbose: bool = False):
    """Solve the OCP of a problem's ``[ocp]`` section (:func:`~ocp_crawl.ocp.optimize_gait`).

    Parameters
    ----------
    problem : Problem
        A validated problem of the torque drive (robot, gravity convention, gait centre, ``[ocp]``).
    jobs : int, optional
        Worker processes of the baselines' search (None: the CPUs available).
    start : Problem, optional
        A gait to start from instead of the harmonic baseline: its torque input and
        ``[gait] period`` (e.g. a previous optimum's ``optimal_gait.toml``).
    verbose : bool
        IPOPT's log on stdout.

    Returns
    -------
    OCPResult
        The optimum and its verdict; ``result.scenarios()`` names each friction scenario's numbers.

    Raises
    ------
    ProblemError
        For a problem of the angles drive, a start without a period, or ``[ocp]`` values that break
        a rule between keys.
    """
    from dataclasses import replace

    from ocp_crawl.ocp import optimize_gait

    if start is not None:
        check_start_robot(problem, start)
    if problem.drive != "torque":
        raise ProblemError(f"{problem.source}: optimize designs joint torques: it needs [gait] "
                           f"drive = \"torque\", got {format_value(problem.drive)}")
    if start is not None and (start.drive != "torque" or start.period is None):
        raise ProblemError(f"{start.source}: a start needs a torque-drive gait with a [gait] "
                           "period [s] (as the optimal_gait.toml that optimize --out writes)")
    settings = replace(ocp_settings(problem), verbose=verbose)
    given = None if start is None else (start.torque, start.period)
    return optimize_gait(problem.robot, problem.gravity, settings, jobs=jobs, start=given)


#: The paper's robot (Table I) and gait (gamma 90, A 30, psi 45 deg); same values as
#: problems/paper_gait.toml.
PAPER_GAIT: Mapping[str, Mapping[str, Any]] = freeze({
    "robot": {"M": 0.052, "L": 0.120, "beta": 2.0, "k": 0.1677, "mu": 0.389, "g": 9.81},
    "gait": {"drive": "torque", "gamma_deg": 90.0, "A_deg": 30.0, "psi_deg": 45.0},
    "model": {"gravity": "physical"},
})


def paper_problem(overrides: Sequence[str] = ()) -> Problem:
    """The paper's gait as a Problem, built in code (available without the problems/ directory).

    The Table I robot (M = 0.052 kg, L = 0.120 m, beta = 2, k = 0.1677 N m/rad, mu = 0.389,
    g = 9.81 m/s^2) with the gait gamma = 90 deg, A = 30 deg, psi = 45 deg, torque drive, physical
    gravity: the values of ``problems/paper_gait.toml`` (:data:`PAPER_GAIT`).

    Parameters
    ----------
    overrides : sequence of str
        ``SECTION.KEY=VALUE`` texts as ``--set``, e.g. ``["model.gravity=paper"]``.

    Returns
    -------
    Problem
        The validated problem, ``source`` ``"<paper gait>"``.
    """
    return problem_from_dict(thaw(PAPER_GAIT), source="<paper gait>", overrides=overrides)
