"""Simulators of the hybrid-quasistatic crawler, their one entry :func:`simulate` and the result they share."""
from ocp_crawl.sim.registry import DEFAULT_SOLVER, SOLVERS, AnglesOptions, Solver, simulate, solver_named
from ocp_crawl.sim.result import CrawlResult, Event, Mode, SimulationError, Status

__all__ = ["DEFAULT_SOLVER", "SOLVERS", "AnglesOptions", "Solver", "simulate", "solver_named", "CrawlResult", "Event",
           "Mode", "SimulationError", "Status"]
