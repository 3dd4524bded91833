"""A problem's co-design: its ``[design]`` section as a :class:`~ocp_crawl.ocp.design.Design`,
solved with its ``[ocp]`` settings (:func:`codesign_problem`), and the problem of the chosen
robot (:func:`chosen_problem_dict`)."""
from __future__ import annotations

from ocp_crawl.model.chain import Chain
from ocp_crawl.ocp.design import Design
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.plant import joints_of
from ocp_crawl.problem.keys import ProblemError
from ocp_crawl.problem.messages import format_value
from ocp_crawl.problem.problem import Problem, chain_section
from ocp_crawl.problem.run import ocp_settings


def _pairs(problem: Problem, name: str, size: int, what: str) -> list | None:
    """``[design] name_min`` and ``name_max`` as (low, high) pairs, one per joint or link (one
    entry: every one); None when absent."""
    d = problem.sections.get("design", {})
    lo, hi = d.get(f"{name}_min"), d.get(f"{name}_max")
    if lo is None or hi is None:
        return None
    for key, values in ((f"{name}_min", lo), (f"{name}_max", hi)):
        if len(values) not in (1, size):
            raise ProblemError(f"{problem.source}: [design] {key} = {format_value(list(values))} "
                               f"has {len(values)} entries: give one per {what} ({size}) or one "
                               "for all")
    lo = list(lo) * (size if len(lo) == 1 else 1)
    hi = list(hi) * (size if len(hi) == 1 else 1)
    return list(zip(lo, hi))


def design_of(problem: Problem) -> Design:
    """The problem's ``[design]`` as a :class:`~ocp_crawl.ocp.design.Design`, checked against its
    robot (the three-link robot as its chain).  Raises ProblemError (one line naming the key)."""
    chain = (problem.robot if isinstance(problem.robot, Chain)
             else Chain.from_robot(problem.robot))
    k = _pairs(problem, "stiffness", joints_of(problem.robot), "joint")
    lengths = _pairs(problem, "lengths", chain.n, "link")
    if k is None and lengths is None:
        raise ProblemError(f"{problem.source}: no [design] bounds: codesign needs stiffness_min "
                           "and stiffness_max [N m/rad] or lengths_min and lengths_max [m] (see "
                           "problems/codesign_stiffness.toml)")
    try:
        return Design(k, lengths, float(problem.sections["design"]["min_reduced_stiffness"])
                      ).checked(chain)
    except ValueError as exc:
        raise ProblemError(f"{problem.source}: [design] {exc}") from None


def codesign_problem(problem: Problem, *, jobs: int | None = None, log=None):
    """The co-design of a problem (:func:`~ocp_crawl.ocp.codesign.codesign_gait`): its robot, its
    ``[design]`` bounds and scan, its ``[ocp]`` settings.

    Parameters
    ----------
    problem : Problem
        A validated problem of the torque drive with ``[design]`` bounds.
    jobs : int, optional
        Worker processes of the scan (None: the CPUs available).
    log : callable, optional
        Called with a line of text as each stage starts.

    Returns
    -------
    CodesignResult
        The chosen design, its gait judged by replay, the scan.

    Raises
    ------
    ProblemError
        For the angles drive, a problem without bounds, bounds that exclude the robot, a length
        design of a body whose masses are not proportional to its lengths, or ``[ocp]
        dynamic_margin``.
    """
    from ocp_crawl.ocp.codesign import codesign_gait

    design, settings = codesign_inputs(problem)
    return codesign_gait(problem.robot, design, problem.gravity, settings,
                         scan=int(problem.sections["design"]["scan"]), jobs=jobs, log=log,
                         search_rounds=int(problem.sections["design"]["search_rounds"]))


def codesign_inputs(problem: Problem) -> tuple[Design, OCPSettings]:
    """The problem's design and OCP settings for :func:`codesign_problem`, every input checked:
    ProblemError (one line naming the key) for the angles drive, missing or bad ``[design]``
    bounds, or ``[ocp] dynamic_margin``."""
    if problem.drive != "torque":
        raise ProblemError(f"{problem.source}: codesign designs joint torques: it needs [gait] "
                           f"drive = \"torque\", got {format_value(problem.drive)}")
    design = design_of(problem)
    settings = ocp_settings(problem)
    if settings.dynamic_margin is not None:
        raise ProblemError(f"{problem.source}: [ocp] dynamic_margin is the three-link robot's "
                           "(MuJoCo's model); codesign designs a chain: drop the key")
    return design, settings


def chosen_problem_dict(problem: Problem, chain: Chain) -> dict:
    """The problem (as ``Problem.to_dict()``) with the chosen robot ``chain`` and no
    ``[design]``: the problem of the co-designed robot."""
    out = problem.to_dict()
    out["robot"] = chain_section(chain)
    out.pop("design", None)
    return out
