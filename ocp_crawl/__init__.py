"""ocp_crawl: hybrid-quasistatic simulation, analysis and optimal control of soft inchworm crawlers.

The front door: the public API is re-exported here and from each subpackage (see ARCHITECTURE.md).
"""
from ocp_crawl.version import __version__
from ocp_crawl.status import STATUS_MESSAGES, Status
from ocp_crawl.model import (CallableSignal, FourierSeries, Harmonic, Model, PeriodicLinear, PeriodicPchip,
                             PeriodicSignal, PeriodicSpline, ReferenceTorque, Robot, as_signal)
from ocp_crawl.sim import (SOLVERS, AnglesOptions, CrawlResult, CycleOptions, Event, HybridOptions, Mode,
                           SimulationError, TimeSteppingOptions, simulate)
from ocp_crawl.sim.event import simulate_torque
from ocp_crawl.sim.angles import simulate_angles
from ocp_crawl.sim.timestepping import simulate_mpcc
from ocp_crawl.problem import Problem, ProblemError, load_problem, paper_problem, problem_from_dict, run_problem

__all__ = [
    "__version__", "Status", "STATUS_MESSAGES",
    "Model", "Robot", "Harmonic", "FourierSeries", "PeriodicSpline", "PeriodicLinear", "PeriodicPchip",
    "CallableSignal", "PeriodicSignal", "ReferenceTorque", "as_signal",
    "simulate", "SOLVERS", "HybridOptions", "TimeSteppingOptions", "AnglesOptions", "CycleOptions",
    "CrawlResult", "Event", "Mode", "SimulationError", "simulate_torque", "simulate_angles", "simulate_mpcc",
    "Problem", "ProblemError", "load_problem", "paper_problem", "problem_from_dict", "run_problem",
]
