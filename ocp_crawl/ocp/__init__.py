"""The periodic-gait optimal control problem: settings, waveform baselines, transcription, solve and
replay, and the co-design of the robot's parameters with its gait."""
from ocp_crawl.io.lazy import lazy_exports

#: public name -> the module that defines it (imported on first use: start-up time, see io/lazy.py)
_EXPORTS = {
    "GaitOCP": "ocp_crawl.ocp.transcription", "GaitSolver": "ocp_crawl.ocp.solver",
    "VOCABULARY": "ocp_crawl.ocp.objectives",
    "WaveChoice": "ocp_crawl.ocp.baseline", "Baselines": "ocp_crawl.ocp.baseline",
    "objective_value": "ocp_crawl.ocp.baseline",
    "best_harmonic": "ocp_crawl.ocp.search", "best_baselines": "ocp_crawl.ocp.search",
    "WaveParams": "ocp_crawl.ocp.family", "SHAPES": "ocp_crawl.ocp.family",
    "OBJECTIVES": "ocp_crawl.ocp.objectives", "OCPSettings": "ocp_crawl.ocp.settings",
    "OCPResult": "ocp_crawl.ocp.result", "optimize_gait": "ocp_crawl.ocp.solve",
    "replay_signal": "ocp_crawl.ocp.judge", "judge_replay": "ocp_crawl.ocp.judge",
    "ConvergenceRow": "ocp_crawl.ocp.convergence", "converge_in_nodes": "ocp_crawl.ocp.convergence",
    "observed_orders": "ocp_crawl.ocp.convergence",
    "Constraint": "ocp_crawl.ocp.quantities", "UserObjective": "ocp_crawl.ocp.quantities",
    "QUANTITIES": "ocp_crawl.ocp.quantities", "Plant": "ocp_crawl.ocp.plant",
    "best_chain_baselines": "ocp_crawl.ocp.chain_search",
    "ChainWaveChoice": "ocp_crawl.ocp.chain_search",
    "Design": "ocp_crawl.ocp.design", "CodesignResult": "ocp_crawl.ocp.codesign",
    "codesign_gait": "ocp_crawl.ocp.codesign",
}

__all__ = [
    "Baselines", "ChainWaveChoice", "CodesignResult", "Constraint", "ConvergenceRow", "Design",
    "GaitOCP", "GaitSolver", "OBJECTIVES", "OCPResult", "OCPSettings", "Plant", "QUANTITIES",
    "SHAPES", "UserObjective", "VOCABULARY", "WaveChoice", "WaveParams", "best_baselines",
    "best_chain_baselines", "best_harmonic", "codesign_gait", "converge_in_nodes", "judge_replay",
    "objective_value", "observed_orders", "optimize_gait", "replay_signal",
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
