"""The periodic-gait optimal control problem: settings, harmonic baseline, transcription, solve and replay."""
from ocp_crawl.ocp.baseline import HarmonicChoice, best_harmonic, objective_value
from ocp_crawl.ocp.settings import OBJECTIVES, OCPSettings
from ocp_crawl.ocp.solve import OCPResult, optimize_gait, replay_signal
from ocp_crawl.ocp.transcription import GaitOCP

__all__ = ["GaitOCP", "HarmonicChoice", "OBJECTIVES", "OCPResult", "OCPSettings", "best_harmonic", "objective_value",
           "optimize_gait", "replay_signal"]
