"""ocp_crawl: hybrid-quasistatic simulation, analysis and optimal control of soft inchworm crawlers.

The front door: the public API is re-exported here and from each subpackage (see ARCHITECTURE.md).
"""
from ocp_crawl.io.lazy import lazy_exports
from ocp_crawl.version import __version__

#: public name -> the module that defines it (imported on first use: start-up time, see io/lazy.py)
_EXPORTS = {
    "Status": "ocp_crawl.status", "STATUS_MESSAGES": "ocp_crawl.status",
    "Model": "ocp_crawl.model", "Robot": "ocp_crawl.model", "Harmonic": "ocp_crawl.model",
    "FourierSeries": "ocp_crawl.model", "PeriodicSpline": "ocp_crawl.model",
    "PeriodicLinear": "ocp_crawl.model",
    "PeriodicPchip": "ocp_crawl.model", "CallableSignal": "ocp_crawl.model",
    "PeriodicSignal": "ocp_crawl.model",
    "ReferenceTorque": "ocp_crawl.model", "as_signal": "ocp_crawl.model",
    "simulate": "ocp_crawl.sim", "SOLVERS": "ocp_crawl.sim", "HybridOptions": "ocp_crawl.sim",
    "TimeSteppingOptions": "ocp_crawl.sim", "AnglesOptions": "ocp_crawl.sim",
    "CycleOptions": "ocp_crawl.sim",
    "CrawlResult": "ocp_crawl.sim", "Event": "ocp_crawl.sim", "Mode": "ocp_crawl.sim",
    "SimulationError": "ocp_crawl.sim", "MujocoOptions": "ocp_crawl.sim",
    "simulate_torque": "ocp_crawl.sim.event",
    "simulate_angles": "ocp_crawl.sim.angles",
    "simulate_mpcc": "ocp_crawl.sim.timestepping",
    "Problem": "ocp_crawl.problem", "ProblemError": "ocp_crawl.problem",
    "load_problem": "ocp_crawl.problem",
    "paper_problem": "ocp_crawl.problem", "problem_from_dict": "ocp_crawl.problem",
    "run_problem": "ocp_crawl.problem", "optimize_problem": "ocp_crawl.problem",
    **{name: "ocp_crawl.problem.work" for name in (
        "Work", "WorkLimit", "simulation_work", "optimize_work", "sweep_work", "fit_work",
        "crosscheck_work", "dynamics_work")},
}

__all__ = [
    "__version__", "Status", "STATUS_MESSAGES", "Model", "Robot", "Harmonic", "FourierSeries",
    "PeriodicSpline",
    "PeriodicLinear", "PeriodicPchip", "CallableSignal", "PeriodicSignal", "ReferenceTorque",
    "as_signal",
    "simulate", "SOLVERS", "HybridOptions", "TimeSteppingOptions", "AnglesOptions", "CycleOptions",
    "CrawlResult",
    "Event", "Mode", "SimulationError", "simulate_torque", "simulate_angles", "simulate_mpcc",
    "Problem",
    "ProblemError", "load_problem", "paper_problem", "problem_from_dict", "run_problem",
    "optimize_problem",
    "MujocoOptions", "Work", "WorkLimit", "simulation_work", "optimize_work", "sweep_work",
    "fit_work", "crosscheck_work", "dynamics_work",
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
