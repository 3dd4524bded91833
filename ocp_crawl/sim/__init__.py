"""Simulators of the hybrid-quasistatic crawler, their one entry :func:`simulate` and the result
they share."""
from ocp_crawl.io.lazy import lazy_exports

#: public name -> the module that defines it (imported on first use: start-up time, see io/lazy.py)
_EXPORTS = {
    "DEFAULT_SOLVER": "ocp_crawl.sim.registry", "SOLVERS": "ocp_crawl.sim.registry",
    "AnglesOptions": "ocp_crawl.sim.registry", "Solver": "ocp_crawl.sim.registry",
    "simulate": "ocp_crawl.sim.registry", "solver_named": "ocp_crawl.sim.registry",
    "CycleOptions": "ocp_crawl.sim.options",
    "HybridOptions": "ocp_crawl.sim.event",
    "TimeSteppingOptions": "ocp_crawl.sim.timestepping",
    "MujocoOptions": "ocp_crawl.sim.dynamic", "unavailable_solvers": "ocp_crawl.sim.registry",
    "unusable": "ocp_crawl.sim.registry", "MUJOCO_SOLVERS": "ocp_crawl.sim.registry",
    "CrawlResult": "ocp_crawl.sim.result", "Event": "ocp_crawl.sim.result",
    "Mode": "ocp_crawl.sim.result", "simulate_chain_angles": "ocp_crawl.sim.chain_angles",
    "simulate_chain_torque": "ocp_crawl.sim.chain_torque",
    "ChainReferenceTorque": "ocp_crawl.model.chain_inputs",
    "simulate_chain_mpcc": "ocp_crawl.sim.chain_mpcc",
    "SimulationError": "ocp_crawl.sim.result", "Status": "ocp_crawl.sim.result",
}

__all__ = [
    "DEFAULT_SOLVER", "SOLVERS", "AnglesOptions", "CycleOptions", "HybridOptions", "Solver",
    "TimeSteppingOptions",
    "MujocoOptions", "MUJOCO_SOLVERS", "unavailable_solvers", "unusable", "simulate",
    "solver_named", "CrawlResult", "Event", "Mode", "SimulationError", "Status",
    "simulate_chain_angles", "simulate_chain_torque", "ChainReferenceTorque", "simulate_chain_mpcc",
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
