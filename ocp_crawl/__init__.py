"""ocp_crawl: hybrid-quasistatic simulation, analysis and optimal control of soft inchworm crawlers."""
from ocp_crawl.model.statics import Model, Robot
from ocp_crawl.model.inputs import (CallableSignal, FourierSeries, Harmonic, PeriodicLinear, PeriodicPchip, PeriodicSignal,
                     PeriodicSpline, ReferenceTorque, as_signal)
from ocp_crawl.sim.result import CrawlResult, Event, Mode, SimulationError, Status
from ocp_crawl.sim.event import HybridOptions, simulate_torque
from ocp_crawl.sim.angles import simulate_angles
from ocp_crawl.problem import Problem, ProblemError, load_problem, problem_from_dict, run_problem

__all__ = [
    "Model", "Robot", "Harmonic", "FourierSeries", "PeriodicSpline", "PeriodicLinear", "PeriodicPchip", "CallableSignal", "PeriodicSignal",
    "ReferenceTorque", "as_signal", "CrawlResult", "Event", "Mode", "Status", "SimulationError",
    "HybridOptions", "simulate_torque", "simulate_angles", "Problem", "ProblemError", "load_problem",
    "problem_from_dict", "run_problem",
]
__version__ = "0.1.0"
