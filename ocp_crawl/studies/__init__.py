"""The paper's studies, their figures, the statement checks and ``reproduce``.

One module per group of studies: :mod:`~ocp_crawl.studies.gaits` (one gait in detail, the psi-gamma
map, the friction band), :mod:`~ocp_crawl.studies.cot` (amplitude and CoT+, higher friction,
stiffness and the friction threshold), :mod:`~ocp_crawl.studies.pressure` (the pressure-driven
robot); what they share is :mod:`~ocp_crawl.studies.common`.  :mod:`~ocp_crawl.studies.plots` draws
them; :mod:`~ocp_crawl.studies.statements` checks the paper's statements, :mod:`~ocp_crawl.studies.report`
writes ``report.md`` and :func:`ocp_crawl.studies.reproduce.reproduce` runs it all (``ocp-crawl reproduce``).
The function ``reproduce`` is not re-exported here: the name is its module's, which the CLI and the
tests use.
"""
from ocp_crawl.studies.common import (COT_K_LABELS, COT_K_RATIOS, LOW_K_RATIO, REALISTIC_K_RATIO, STUCK_TOL, SweepOptions,
                                      base_problem)
from ocp_crawl.studies.cot import (AmplitudeStudy, HigherFriction, StiffnessStudy, amplitude_study, higher_friction,
                                   stiffness_study)
from ocp_crawl.studies.gaits import FrictionBand, GaitComparison, PsiGammaMap, friction_band, gait_comparison, psi_gamma_map
from ocp_crawl.studies.pressure import (PressureFit, PressureStudy, evaluate_fit, fit_rest_angle, pressure_curves,
                                        pressure_study, simulate_pressure)
from ocp_crawl.studies.reproduce import FIGURES, ReproduceResult
from ocp_crawl.studies.statements import STATEMENTS, Statement, check_statements
from ocp_crawl.studies.suite import GRIDS, Grids, StudySet, run_studies

__all__ = [
    "SweepOptions", "base_problem", "REALISTIC_K_RATIO", "COT_K_RATIOS", "COT_K_LABELS", "LOW_K_RATIO", "STUCK_TOL",
    "GaitComparison", "gait_comparison", "PsiGammaMap", "psi_gamma_map", "FrictionBand", "friction_band",
    "AmplitudeStudy", "amplitude_study", "HigherFriction", "higher_friction", "StiffnessStudy", "stiffness_study",
    "PressureFit", "PressureStudy", "pressure_study", "pressure_curves", "evaluate_fit", "fit_rest_angle",
    "simulate_pressure", "GRIDS", "Grids", "StudySet", "run_studies", "STATEMENTS", "Statement", "check_statements",
    "FIGURES", "ReproduceResult",
]
