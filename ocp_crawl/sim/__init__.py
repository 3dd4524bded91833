"""Simulators of the hybrid-quasistatic crawler, their one entry :func:`simulate` and the result they share."""
from ocp_crawl.sim.event import HybridOptions
from ocp_crawl.sim.options import CycleOptions
from ocp_crawl.sim.registry import DEFAULT_SOLVER, SOLVERS, AnglesOptions, Solver, simulate, solver_named
from ocp_crawl.sim.result import CrawlResult, Event, Mode, SimulationError, Status
from ocp_crawl.sim.timestepping import TimeSteppingOptions

__all__ = ["DEFAULT_SOLVER", "SOLVERS", "AnglesOptions", "CycleOptions", "HybridOptions", "Solver",
           "TimeSteppingOptions", "simulate", "solver_named", "CrawlResult", "Event", "Mode", "SimulationError",
           "Status"]
