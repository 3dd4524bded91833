"""ocp_crawl: hybrid-quasistatic simulation, analysis and optimal control of soft inchworm crawlers."""
from .model import Model, Robot
from .inputs import (CallableSignal, FourierSeries, Harmonic, PeriodicLinear, PeriodicPchip, PeriodicSignal,
                     PeriodicSpline, ReferenceTorque, as_signal)
from .result import CrawlResult, Event, Mode, SimulationError, Status
from .hybrid import HybridOptions, simulate_torque
from .prescribed import simulate_angles
from .problem import Problem, ProblemError, load_problem, problem_from_dict, run_problem

__all__ = [
    "Model", "Robot", "Harmonic", "FourierSeries", "PeriodicSpline", "PeriodicLinear", "PeriodicPchip", "CallableSignal", "PeriodicSignal",
    "ReferenceTorque", "as_signal", "CrawlResult", "Event", "Mode", "Status", "SimulationError",
    "HybridOptions", "simulate_torque", "simulate_angles", "Problem", "ProblemError", "load_problem",
    "problem_from_dict", "run_problem",
]
__version__ = "0.1.0"
