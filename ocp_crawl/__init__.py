"""ocp_crawl: hybrid-quasistatic simulation, analysis and optimal control of soft inchworm crawlers."""
from .model import Model, Robot
from .inputs import (CallableSignal, FourierSeries, Harmonic, PeriodicSignal, PeriodicSpline, ReferenceTorque,
                     as_signal)
from .result import CrawlResult, Event, Mode, SimulationError, Status
from .hybrid import HybridOptions, simulate_torque

__all__ = [
    "Model", "Robot", "Harmonic", "FourierSeries", "PeriodicSpline", "CallableSignal", "PeriodicSignal",
    "ReferenceTorque", "as_signal", "CrawlResult", "Event", "Mode", "Status", "SimulationError",
    "HybridOptions", "simulate_torque",
]
__version__ = "0.1.0"
