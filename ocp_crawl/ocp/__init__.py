"""The periodic-gait optimal control problem: settings, harmonic baseline, transcription, solve and replay."""
from ocp_crawl.ocp.gait import (GaitOCP, HarmonicChoice, OCPResult, OCPSettings, best_harmonic, objective_value,
                                optimize_gait, replay_signal)

__all__ = ["GaitOCP", "HarmonicChoice", "OCPResult", "OCPSettings", "best_harmonic", "objective_value",
           "optimize_gait", "replay_signal"]
