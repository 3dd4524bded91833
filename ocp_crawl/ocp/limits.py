"""The choices and bounds of the OCP's settings: what each option may be and why.

The API (:class:`~ocp_crawl.ocp.settings.OCPSettings`) and the problem files
(:mod:`ocp_crawl.problem.schema`) refuse the same values with the same reasons, from these tables.
"""
from __future__ import annotations

from typing import Literal

from ocp_crawl.checks import real
from ocp_crawl.ocp.objectives import OBJECTIVES, VOCABULARY

Objective = Literal["max_speed", "min_cot", "robust_speed"]
#: every value ``objective`` takes: the named objectives and the vocabulary's
#: (:mod:`~ocp_crawl.ocp.objectives`: "max:speed", "min:W_plus", "min:sum", ...)
OBJECTIVE_CHOICES = OBJECTIVES + VOCABULARY
PARAMETRIZATIONS = ("free", "fourier")
#: IPOPT barrier strategies of the warm-started homotopy solves (:attr:`OCPSettings.warm_barrier`)
WARM_BARRIERS = ("adaptive", "monotone")
#: when IPOPT perturbs the Hessian (:attr:`OCPSettings.perturbation`)
PERTURBATIONS = ("as_needed", "always")
#: the paths after the endgame's stage (:attr:`OCPSettings.endgame_paths`)
ENDGAME_PATHS = ("endgame_first", "both")
#: how the starts are solved (:attr:`OCPSettings.start_solve`)
START_SOLVES = ("homotopy", "tightened", "both")
#: keys of earlier versions that no longer exist, and what replaces each (problem files and
#: OCPSettings)
REMOVED_KEYS = {
    "friction_tol": "mu_ratio_eps with robust = \"worst\": a set of friction ratios mu1/mu2 over "
                    "which the gait must keep its objective (a margin on the friction tie "
                    "guaranteed no speed under a friction asymmetry)",
    "S_min": "speed_min [m/s], the smallest mean speed direction * S / T (a per-cycle S rewarded "
             "packing strokes)",
    "rate_limit": "max_rate_deg_s [deg/s], the actuators' largest reference-angle rate (a physical "
                  "bandwidth)",
    "max_rate": "max_rate_deg_s [deg/s], the actuators' largest reference-angle rate (a physical "
                "bandwidth)",
    "curvature_limit": "max_accel_deg_s2 [deg/s^2], an optional physical smoothness bound, off by "
                       "default",
    "tie_margin": "nothing: the switch-exact transcription places every change of the slipping "
                  "foot on a sub-step boundary",
}

#: bounds of the settings that size the work (a solve within minutes; see
#: docs/guide/problem_files.md, "Bounds"): the nodes of the transcription, the Fourier order, the
#: psi values and amplitudes of the harmonic scan
NODES_BOUNDS = (8, 1000)
FOURIER_ORDER_BOUNDS = (1, 25)
HARMONIC_PSI_BOUNDS = (4, 180)
HARMONIC_A_BOUNDS = (1, 20)
STARTS_BOUNDS = (1, 20)
BASELINE_SAMPLES_BOUNDS = (0, 4096)
BASELINE_STARTS_BOUNDS = (0, 20)
BASELINE_EVALUATIONS_BOUNDS = (1, 5000)
ENDGAME_MAX_ITER_BOUNDS = (1, 10000)
#: the ``baselines`` choices: every waveform family, or one
BASELINE_CHOICES = ("all", "harmonic", "triangle", "pulse")


#: bounds of the numbers that carry a physical meaning, (low, high, why), inclusive: the API and the
#: problem files refuse the same values with the same reason
PHYSICAL_BOUNDS = {
    "max_rate_deg_s": (1e-2, 1e4,
                       "below 0.01 deg/s a cycle of the envelope takes hours; above 1e4 deg/s "
                       "(cycles of about 10 ms) inertia is not negligible and the quasistatic "
                       "model fails"),
    "max_joint_rate_deg_s": (1e-2, 1e4, "the actual joint rate: the bounds of max_rate_deg_s"),
    "max_accel_deg_s2": (1e-2, 1e7, "the rate bounds reached within 1 ms to 1 s"),
    "regularization": (0.0, 1e-2,
                       "a tie-breaker between equally good profiles: a larger weight trades the "
                       "objective for smoothness (bound the profile with max_accel_deg_s2 "
                       "instead)"),
    "speed_min": (0.0, 10.0, "10 m/s is far beyond any quasistatic crawler"),
    "mu_ratio_eps": (0.0, 0.5,
                     "friction ratios beyond 1 +- 0.5 are another robot: give robot.mu1 and "
                     "robot.mu2"),
    "dynamic_margin": (1.0, 20.0, "a factor on the shortest period at which MuJoCo's S is "
                       "within 5 % of the quasistatic S: 1 asks it at the gait's own period; "
                       "above 20 a 1 s gait is run at 50 ms, fewer than 100 MuJoCo steps per "
                       "cycle"),
    "replay_tol": (1e-9, 0.1,
                   "1e-9 is the judge's own bound tolerance; above 0.1 it would accept an "
                   "optimum a tenth off"),
}


def check_physical(name: str, value, optional: bool = False):
    """``value`` of the setting ``name`` as a float within :data:`PHYSICAL_BOUNDS` (None passes when
    ``optional``); ValueError naming the setting, its bounds and their reason."""
    if value is None and optional:
        return None
    low, high, why = PHYSICAL_BOUNDS[name]
    v = real(f"OCPSettings.{name}", value)
    if not low <= v <= high:
        raise ValueError(f"OCPSettings.{name} must be in [{low:g}, {high:g}] ({why}), got "
                         f"{value!r}")
    return v


#: most homotopy stages a schedule may have (sigma0 down to sigma_min by sigma_factor): each is an
#: IPOPT solve
MAX_STAGES = 40


#: the layer of the OCP each setting belongs to: what is asked ("problem": the optimum changes with
#: it), how it becomes an NLP ("transcription": the optimum converges as it is refined), how the NLP
#: is solved ("solver": the path, and so which local optimum is found), what the optimum is compared
#: with ("baselines") and when it is accepted ("judge")
LAYERS = {
    "problem": ("objective", "terms", "user_objective", "direction", "gamma_deg",
                "gamma_joints_deg", "A_max_deg", "max_rate_deg_s", "max_accel_deg_s2",
                "max_joint_rate_deg_s", "speed_min",
                "constraints", "mu_ratio_eps", "mu_ratios", "mu_levels", "robust"),
    "transcription": ("nodes", "parametrization", "fourier_order", "regularization"),
    "solver": ("starts", "sigma0", "sigma_min", "sigma_factor", "stage_tol", "stage_tol_ratio",
               "loose_last", "start_solve", "endgame_sigma", "endgame_paths", "endgame_max_iter",
               "perturbation",
               "warm_barrier", "ipopt", "verbose"),
    "baselines": ("baselines", "harmonic_psi", "harmonic_A", "baseline_samples", "baseline_starts",
                  "baseline_evaluations"),
    "judge": ("replay_tol", "comp_tol", "periodic_tol", "dynamic_margin"),
}
#: the layer of each setting
LAYER_OF = {name: layer for layer, names in LAYERS.items() for name in names}
