"""The paper's studies, their figures, the statement checks and ``reproduce``.

One module per group of studies: :mod:`~ocp_crawl.studies.gaits` (one gait in detail, the psi-gamma
map, the friction band), :mod:`~ocp_crawl.studies.cot` (amplitude and CoT+, higher friction,
stiffness and the friction threshold), :mod:`~ocp_crawl.studies.pressure` (the pressure-driven
robot); what they share is :mod:`~ocp_crawl.studies.common`.  :mod:`~ocp_crawl.studies.gait_plots`
(the gait studies) and :mod:`~ocp_crawl.studies.plots` (the others) draw them;
:mod:`~ocp_crawl.studies.statements` checks the paper's statements,
:mod:`~ocp_crawl.studies.report` writes ``report.md`` and
:func:`ocp_crawl.studies.reproduce.reproduce` runs it all (``ocp-crawl reproduce``).  The function
``reproduce`` is not re-exported here: the name is its module's, which the CLI and the tests use.
"""
from ocp_crawl.io.lazy import lazy_exports

#: public name -> the module that defines it (imported on first use: start-up time, see io/lazy.py)
_EXPORTS = {
    "SweepOptions": "ocp_crawl.studies.common", "base_problem": "ocp_crawl.studies.common",
    "REALISTIC_K_RATIO": "ocp_crawl.studies.common", "COT_K_RATIOS": "ocp_crawl.studies.common",
    "COT_K_LABELS": "ocp_crawl.studies.common", "LOW_K_RATIO": "ocp_crawl.studies.common",
    "STUCK_TOL": "ocp_crawl.studies.common",
    "GaitComparison": "ocp_crawl.studies.gaits", "gait_comparison": "ocp_crawl.studies.gaits",
    "PsiGammaMap": "ocp_crawl.studies.gaits", "psi_gamma_map": "ocp_crawl.studies.gaits",
    "FrictionBand": "ocp_crawl.studies.gaits", "friction_band": "ocp_crawl.studies.gaits",
    "AmplitudeStudy": "ocp_crawl.studies.cot", "amplitude_study": "ocp_crawl.studies.cot",
    "HigherFriction": "ocp_crawl.studies.cot", "higher_friction": "ocp_crawl.studies.cot",
    "StiffnessStudy": "ocp_crawl.studies.cot", "stiffness_study": "ocp_crawl.studies.cot",
    "PressureFit": "ocp_crawl.studies.pressure", "PressureStudy": "ocp_crawl.studies.pressure",
    "pressure_study": "ocp_crawl.studies.pressure", "pressure_curves": "ocp_crawl.studies.pressure",
    "evaluate_fit": "ocp_crawl.studies.pressure", "fit_rest_angle": "ocp_crawl.studies.pressure",
    "simulate_pressure": "ocp_crawl.studies.pressure",
    "DynamicsScan": "ocp_crawl.studies.dynamics", "dynamics_scan": "ocp_crawl.studies.dynamics",
    "plot_dynamics": "ocp_crawl.studies.dynamics",
    "GRIDS": "ocp_crawl.studies.suite", "Grids": "ocp_crawl.studies.suite",
    "StudySet": "ocp_crawl.studies.suite", "run_studies": "ocp_crawl.studies.suite",
    "STATEMENTS": "ocp_crawl.studies.statements", "Statement": "ocp_crawl.studies.statements",
    "check_statements": "ocp_crawl.studies.statements",
    "FIGURES": "ocp_crawl.studies.reproduce", "ReproduceResult": "ocp_crawl.studies.reproduce",
}

__all__ = [
    "SweepOptions", "base_problem", "REALISTIC_K_RATIO", "COT_K_RATIOS", "COT_K_LABELS",
    "LOW_K_RATIO", "STUCK_TOL",
    "GaitComparison", "gait_comparison", "PsiGammaMap", "psi_gamma_map", "FrictionBand",
    "friction_band",
    "AmplitudeStudy", "amplitude_study", "HigherFriction", "higher_friction", "StiffnessStudy",
    "stiffness_study",
    "PressureFit", "PressureStudy", "pressure_study", "pressure_curves", "evaluate_fit",
    "fit_rest_angle",
    "simulate_pressure", "GRIDS", "Grids", "StudySet", "run_studies", "STATEMENTS", "Statement",
    "check_statements",
    "FIGURES", "ReproduceResult", "DynamicsScan", "dynamics_scan", "plot_dynamics",
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
