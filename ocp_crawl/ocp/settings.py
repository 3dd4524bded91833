"""Settings of the periodic-gait optimal control problem: the objectives and their options.

Every OCP default is defined here once, as an :class:`OCPSettings` field; the problem schema
(``[ocp]`` section of a problem file) reads its defaults from these fields, key by key of the same
name.  The choices and bounds each field is checked against are in :mod:`ocp_crawl.ocp.limits`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from ocp_crawl.checks import is_real, real
from ocp_crawl.model.statics import Robot
from ocp_crawl.nlp.homotopy import schedule as sigma_schedule
from ocp_crawl.nlp.ipopt import check_ipopt_options
from ocp_crawl.ocp.limits import (BASELINE_CHOICES, BASELINE_EVALUATIONS_BOUNDS,
                                  BASELINE_SAMPLES_BOUNDS, BASELINE_STARTS_BOUNDS,
                                  ENDGAME_MAX_ITER_BOUNDS, ENDGAME_PATHS, FOURIER_ORDER_BOUNDS,
                                  HARMONIC_A_BOUNDS, HARMONIC_PSI_BOUNDS, LAYERS, MAX_STAGES,
                                  NODES_BOUNDS, PARAMETRIZATIONS, PERTURBATIONS, PHYSICAL_BOUNDS,
                                  START_SOLVES, STARTS_BOUNDS, WARM_BARRIERS, check_physical)
from ocp_crawl.ocp.objectives import resolve_objective
from ocp_crawl.ocp.plant import (AnyRobot, joint_accel_bounds, joint_rate_bounds,
                                 joint_torque_bounds, with_friction)
from ocp_crawl.ocp.quantities import Constraint, UserObjective, minimises


def _bounds_speed_below(c: Constraint) -> bool:
    """Whether ``c`` bounds the speed from below in every scenario (min_cot's speed requirement)."""
    return c.quantity == "speed" and c.min is not None and c.over == "every"


@dataclass(frozen=True)
class OCPSettings:
    """Settings of the periodic-gait optimal control problem (the ``[ocp]`` keys of a problem
    file)."""

    objective: str = "max_speed"
    """what to optimise: a named objective (max_speed, min_cot, robust_speed) or one of the
    vocabulary of cycle quantities (:data:`~ocp_crawl.ocp.objectives.VOCABULARY`: "max:speed" is
    max_speed, "min:CoT_plus" min_cot, kept under those names; "min:W_plus", "max:distance",
    "min:mean_torque_sq", ..., and "min:sum" of ``terms``)"""
    terms: dict | None = None
    """objective "min:sum": the weighted sum's terms, quantity -> weight (weight times the quantity,
    in its SI unit; a quantity of the friction scenarios as its mean over them; a negative weight
    maximises it), e.g. ``{"W_plus": 1.0, "mean_torque_sq": 10.0}``"""
    nodes: int = 100
    """steps per cycle N, in NODES_BOUNDS"""
    direction: int = -1
    """sign of S to pursue: -1 towards foot 1 (the direction of psi > 0 gaits), +1 towards foot 2"""
    gamma_deg: float = 90.0
    """centre of the reference-angle envelope [deg] (a problem file gives it as
    ``[gait] gamma_deg``)"""
    A_max_deg: float = 30.0
    """half-width of the reference-angle envelope [deg]"""
    gamma_joints_deg: tuple | None = None
    """an n-link chain's envelope centre per joint [deg] (a problem file gives it as ``[gait]
    gamma_joints_deg``); None (default): gamma_deg for every joint"""
    parametrization: str = "free"
    """'free' torque at every node (default, sparse), or 'fourier' series of order fourier_order
    (band-limited, but its dense coefficient columns make IPOPT iterations much slower)"""
    fourier_order: int = 4
    max_rate_deg_s: float = 180.0
    """bandwidth of each joint's actuator: the largest reference-angle rate |d phi_ref,i / d t|
    [deg/s] (a torque rate k times it).  Time is explicit: a gait of period T [s] (a variable of the
    OCP) moves its reference at most this fast, so the mean speed S/T is what max_speed maximises
    and a profile repeated twice per cycle (period doubled) is neither better nor worse than once"""
    max_accel_deg_s2: float | None = None
    """optional smoothness bound: the largest reference-angle acceleration |d^2 phi_ref,i / d t^2|
    [deg/s^2] of each actuator; None (default): no bound (the formulation and the switch-exact
    transcription prevent chattering without it)"""
    max_joint_rate_deg_s: float | None = None
    """optional bound on the actual joint rates |d phi_i / d t| [deg/s] of the quasistatic gait (the
    joint angles, not their references: springs, gravity and slips make them faster or slower than
    the references); None (default): no bound.  The transcription bounds each interval's and
    sub-step's mean rate (:func:`~ocp_crawl.ocp.substeps.joint_rate_rows`), the replay judge the
    replay's peak rate (:mod:`ocp_crawl.ocp.rates`)"""
    regularization: float = 1e-5
    """weight of N * sum_k |tau_k - tau_{k-1}|^2/(M g L)^2 in the objective (a tie-breaker where the
    objective is flat, e.g. during stick phases; its share of the objective is reported)"""
    speed_min: float = 0.0
    """min_cot: smallest mean speed direction * S / T [m/s]"""
    mu_ratio_eps: float | None = None
    """every objective: friction scenarios mu1/mu2 in {1 - eps, 1, 1 + eps} (mu1 mu2 fixed), in [0,
    1): the friction uncertainty as a set, one profile and one period for all, each scenario
    simulated (replayed) as it is; None (default): 0.1 for robust_speed, else 0 (the robot's
    friction only)"""
    mu_ratios: tuple | None = None
    """every objective: the scenarios mu1/mu2 (mu1 = mu sqrt(r), mu2 = mu / sqrt(r)) given
    explicitly; None (default): from mu_ratio_eps"""
    mu_levels: tuple | None = None
    """every objective: friction levels, each a factor on both feet's coefficients (mu1 and mu2
    times it), e.g. (1.0, 0.5) for a gait that must also move on a surface of half the friction;
    with a ratio set (mu_ratio_eps, mu_ratios) every ratio at every level.  None (default): the
    robot's level only"""
    constraints: tuple = ()
    """bounds on cycle quantities (:class:`~ocp_crawl.ocp.quantities.Constraint`, or mappings of its
    fields: a problem file's ``[[ocp.constraint]]`` tables), stated in the NLP, met by every
    baseline and checked on the replay within replay_tol: e.g.
    ``{"quantity": "peak_torque", "max": 0.3}``"""
    user_objective: UserObjective | None = None
    """an objective of the user's (:class:`~ocp_crawl.ocp.quantities.UserObjective`: its expression
    in the transcription's symbols and its value on a simulated gait), Python only; ``objective``
    then becomes its label, "min:<name>" or "max:<name>"; None (default): ``objective`` names it"""
    robust: str = "mean"
    """with several friction scenarios: optimise the 'mean' or the 'worst' of the objective over
    them (the speed of max_speed and robust_speed, CoT+ of min_cot, whose speed_min holds in every
    scenario); 'worst' bounds it at every scenario (the ends of the set and its middle, not between
    them), 'mean' only their average (one scenario may be slow where the others are fast)"""
    sigma0: tuple = (1e-4,)
    """first relaxation parameter(s) of the homotopy from the initial guess; with several, a
    homotopy is run from each (in turn, until one improves on the guess) and the best accepted
    result is kept.  The relaxation path decides the local optimum: a loose start (1e-2) explores
    but converges to non-physical points and took half of each solve; 1e-4 stays in the physical
    region"""
    sigma_min: float = 1e-6
    """last relaxation parameter; the polish then solves the NLP with every pair on its identified
    branch (complementarity exactly 0), unless the last stage's point is within comp_tol already
    (then no polish)"""
    sigma_factor: float = 0.01
    stage_tol: float = 1e-4
    """IPOPT tolerance (``tol``) of the homotopy's stages before the last, which only lead to the
    next one; the last stage (unless ``loose_last``) and the polish keep OCP_IPOPT's 1e-10 (a
    ``tol`` in ``ipopt`` at or above stage_tol: no loose stages;
    the profile-fixed check, ``GaitSolver.solve(fix_profile=True)``, is tight throughout).
    The first stage at sigma = 1e-4 spent 40 % of its IPOPT iterations refining its sixth digit:
    1e-4 halves it, with the same max_speed optimum at N = 50; min_cot's path changed and one start
    reached another local optimum (0.5 % better)"""
    stage_tol_ratio: float | None = None
    """a loose stage at sigma is solved to IPOPT ``tol`` = min(stage_tol, stage_tol_ratio * sigma)
    (a stage's point then stays as close to its relaxed optimum as the relaxation itself; where that
    is not looser than the tight tolerance, the stage is tight); None (default): stage_tol at every
    sigma.  robust_speed's file uses 0.1 with sigma from 1e-3 down to 1e-11: its first stage at
    sigma = 1e-4 to tol 1e-4 ended at a poor point and the next stage at max_iter"""
    loose_last: bool = False
    """the last homotopy stage loose too (at ``stage_tol``, which must then be at most sigma_min, or
    by ``stage_tol_ratio``), so that only the polish is tight; if the polish fails, the last stage
    is solved again at the tight tolerance and polished once more.
    For starts already near an optimum (the convergence run's warm solves,
    :mod:`~ocp_crawl.ocp.convergence`): max_speed N = 50..400 took 169 s instead of 334 s, min_cot
    218 s instead of 466 s, with the same optima.  Off by default: from the harmonic baseline
    (max_speed, N = 20, the last stage to 1e-4) it reached another optimum, 2 % slower"""
    start_solve: str = "homotopy"
    """how the starts are solved: "homotopy" (default); "tightened" (each family's best member a
    start too, every start solved by the tightened NLP alone on its simulated gait's branches, at
    most ``endgame_max_iter`` iterations a candidate); "both" (the homotopy, then those)"""
    endgame_sigma: float | None = None
    """the endgame (:mod:`~ocp_crawl.ocp.endgame`): after the homotopy's stage at this sigma (one of
    the schedule's stages before the last), the tightened NLP on the branches of that stage's
    simulated profile, kept when the replay judge accepts it and it is at least as good as the
    stage's profile by replay, else the homotopy goes on; None (default): the whole homotopy"""
    endgame_paths: str = "endgame_first"
    """with ``endgame_sigma``: "endgame_first" (default: the endgame, and the rest of the homotopy
    only when it is not kept) or "both" (the endgame and the rest of the homotopy, in parallel where
    a process can be forked, the better by replay kept: never worse than the whole homotopy, as slow
    as it)"""
    endgame_max_iter: int = 500
    """most IPOPT iterations of the endgame's tightened NLP (beyond them the homotopy goes on) and
    of each candidate of a tightened start (``start_solve``), in ENDGAME_MAX_ITER_BOUNDS"""
    perturbation: str = "as_needed"
    """when IPOPT perturbs the Hessian of its KKT system: "as_needed" (default: IPOPT's own rule, an
    unperturbed factorisation first at every iteration) or "always" (from the first factorisation:
    the NLP gets one more variable, in neither the objective nor the constraints, so that IPOPT
    finds the Hessian structurally degenerate).  Where almost every iteration needs the perturbation
    (robust_speed: 313 of 319 first-stage iterations, two or more factorisations each) "always"
    saves one per iteration; the path, and so the local optimum, may change (measured per file:
    docs/benchmarks.md)"""
    warm_barrier: str = "adaptive"
    """IPOPT's barrier strategy in the warm-started solves of a homotopy (every stage after the
    first, the polish): "adaptive" (default, as the first stage) or "monotone" (from mu = 1e-6 at
    the previous stage's point).  robust_speed's file uses "monotone": at N = 50 its nine stages
    took 952 IPOPT iterations instead of 1144 (the whole file 69 s instead of 83 s) to the same
    optimum; on the default path (max_speed, min_cot) it took 2.3x and 1.6x the iterations.  A
    ``mu_strategy`` in ``ipopt`` overrides it; the convergence run's warm rows use the monotone
    barrier whatever it is (:data:`~ocp_crawl.ocp.convergence.WARM_IPOPT`)"""
    comp_tol: float = 1e-6
    """largest accepted complementarity residual max_j |min(s_j/L, c_j/(M g))|"""
    periodic_tol: float = 1e-8
    harmonic_psi: int = 36
    """psi values of the coarse harmonic scan that seeds the harmonic-family optimisation, over
    (-180, 180] deg"""
    harmonic_A: int = 4
    """amplitudes of the coarse harmonic scan, up to A_max"""
    baseline_samples: int = 64
    """points of a Sobol sample of each waveform family's whole box in the baselines' scan (the
    asymmetric members: unequal centres and amplitudes, a pulse's rise and duty), in
    BASELINE_SAMPLES_BOUNDS; 0: the symmetric scan only (:mod:`~ocp_crawl.ocp.search`)"""
    baseline_starts: int = 2
    """local searches of each waveform family, from its best distinct scan points, in
    BASELINE_STARTS_BOUNDS"""
    baseline_evaluations: int = 400
    """most members each local search of the baselines asks for beyond the scan (a chain's: most
    simulated members), in BASELINE_EVALUATIONS_BOUNDS"""
    baselines: str = "all"
    """the waveform families an optimum is compared with: "all" (harmonic, triangle, pulse) or one
    of them (:mod:`~ocp_crawl.ocp.family`); the harmonic family is searched always (it is the OCP's
    first start)"""
    starts: int = 4
    """starts of the OCP (multi-start): the harmonic baseline first, then perturbed and
    Fourier-order starts; the best replayed optimum is reported with the spread of the others"""
    replay_tol: float = 5e-3
    """relative tolerance of the replay judge: the event-driven replay must agree with the OCP's
    objective and meet speed_min within this fraction (envelope and bandwidth within 1e-9
    relative)"""
    dynamic_margin: float | None = None
    """optional factor c >= 1: the optimum is accepted only when its period T is at least c times
    the shortest period at which MuJoCo's S of its replay is within 5 % of the quasistatic S (a few
    MuJoCo runs, :mod:`ocp_crawl.ocp.dynamic_margin`; needs MuJoCo and physical gravity); None
    (default): not computed, not required"""
    ipopt: dict = field(default_factory=dict)
    """IPOPT options passed through (copied per instance); override
    :data:`~ocp_crawl.nlp.ipopt.OCP_IPOPT`"""
    verbose: bool = False

    def __post_init__(self) -> None:
        self._check_choices()
        self._check_numbers()
        object.__setattr__(self, "ipopt", check_ipopt_options("OCPSettings.ipopt", self.ipopt))

    def _set(self, name: str, value) -> None:
        object.__setattr__(self, name, value)

    @property
    def minimises(self) -> bool:
        """Whether the objective is minimised (min_cot, a "min:" user objective) rather than
        maximised."""
        return minimises(self.objective)

    def layer(self, name: str) -> dict:
        """The settings of one layer (:data:`~ocp_crawl.ocp.limits.LAYERS`: "problem",
        "transcription", "solver", "baselines", "judge"), by field name."""
        if name not in LAYERS:
            raise ValueError(f"OCPSettings.layer: one of {tuple(LAYERS)}, got {name!r}")
        return {field: getattr(self, field) for field in LAYERS[name]}

    @property
    def objective_unit(self) -> str:
        """The objective value's unit: m/s (the speeds), - (CoT+), a user objective's own."""
        if self.user_objective is not None:
            return self.user_objective.unit
        return "-" if self.objective == "min_cot" else "m/s"

    def _check_objective(self) -> None:
        objective, user, terms = resolve_objective(self.objective, self.user_objective, self.terms,
                                                   self.robust)
        self._set("objective", objective)
        self._set("user_objective", user)
        self._set("terms", terms)

    def _check_choices(self) -> None:
        self._check_objective()
        for name, choices in (("parametrization", PARAMETRIZATIONS),
                              ("warm_barrier", WARM_BARRIERS), ("baselines", BASELINE_CHOICES),
                              ("perturbation", PERTURBATIONS), ("endgame_paths", ENDGAME_PATHS),
                              ("start_solve", START_SOLVES)):
            if getattr(self, name) not in choices:
                raise ValueError(f"OCPSettings.{name} must be one of {choices}, got "
                                 f"{getattr(self, name)!r}")
        if self.direction not in (-1, 1):
            raise ValueError(f"OCPSettings.direction must be -1 or +1, got {self.direction!r}")
        if self.robust not in ("mean", "worst"):
            raise ValueError(f"OCPSettings.robust must be 'mean' or 'worst', got {self.robust!r}")
        if not isinstance(self.loose_last, bool):
            raise TypeError("OCPSettings.loose_last must be True or False, got "
                            f"{self.loose_last!r}")

    def _check_joint_centres(self) -> None:
        """A chain's envelope centres: one per joint, each inside (A_max, 360 - A_max) deg."""
        if self.gamma_joints_deg is None:
            return
        a = self.A_max_deg
        g = tuple(real(f"OCPSettings.gamma_joints_deg[{i}]", v, low=a, high=360.0 - a)
                  for i, v in enumerate(self.gamma_joints_deg))
        if len(g) < 2:
            raise ValueError("OCPSettings.gamma_joints_deg needs one angle per joint (at least 2), "
                             f"got {len(g)}")
        self._set("gamma_joints_deg", g)

    def _check_numbers(self) -> None:
        for name, (low, high) in (("nodes", NODES_BOUNDS), ("fourier_order", FOURIER_ORDER_BOUNDS),
                                  ("harmonic_psi", HARMONIC_PSI_BOUNDS),
                                  ("harmonic_A", HARMONIC_A_BOUNDS), ("starts", STARTS_BOUNDS),
                                  ("baseline_samples", BASELINE_SAMPLES_BOUNDS),
                                  ("baseline_starts", BASELINE_STARTS_BOUNDS),
                                  ("baseline_evaluations", BASELINE_EVALUATIONS_BOUNDS),
                                  ("endgame_max_iter", ENDGAME_MAX_ITER_BOUNDS)):
            self._set(name,
                      real(f"OCPSettings.{name}", getattr(self, name), integer=True, low=low,
                           high=high))
        for name in ("gamma_deg", "A_max_deg", "sigma_min", "sigma_factor", "stage_tol", "comp_tol",
                     "periodic_tol"):
            self._set(name, real(f"OCPSettings.{name}", getattr(self, name), positive=True))
        for name in PHYSICAL_BOUNDS:
            optional = name in ("mu_ratio_eps", "max_accel_deg_s2", "max_joint_rate_deg_s",
                                "dynamic_margin")
            self._set(name, check_physical(name, getattr(self, name), optional))
        if self.dynamic_margin is not None:
            from ocp_crawl.sim.dynamic import INSTALL, mujoco_available

            if not mujoco_available():
                raise ValueError("OCPSettings.dynamic_margin needs MuJoCo, which is not "
                                 f"importable: install it with {INSTALL}")
        if not 0 < self.A_max_deg < 90:
            raise ValueError(f"OCPSettings.A_max_deg must be in (0, 90), got {self.A_max_deg}")
        if not (0 < self.gamma_deg - self.A_max_deg and self.gamma_deg + self.A_max_deg < 180):
            raise ValueError("OCPSettings: the envelope gamma +- A_max must lie in (0, 180) deg")
        self._check_joint_centres()
        s0 = (self.sigma0,) if is_real(self.sigma0) else tuple(self.sigma0)
        if not s0 or any(not is_real(v) or not 0 < v < 1 for v in s0):
            raise ValueError(f"OCPSettings.sigma0 must be numbers in (0, 1), got {self.sigma0!r}")
        self._set("sigma0", tuple(float(v) for v in s0))
        if not self.sigma_factor < 1 or not all(self.sigma_min < v for v in self.sigma0):
            raise ValueError("OCPSettings: need sigma_factor < 1 and sigma_min < sigma0")
        stages = max(math.ceil(math.log(self.sigma_min / v) / math.log(self.sigma_factor))
                     + 1 for v in self.sigma0)
        if stages > MAX_STAGES:
            raise ValueError(f"OCPSettings: sigma0 {max(self.sigma0):g} to sigma_min "
                             f"{self.sigma_min:g} in steps of sigma_factor {self.sigma_factor:g} "
                             f"makes {stages} homotopy stages, more than {MAX_STAGES} (each is an "
                             "IPOPT solve)")
        if self.endgame_sigma is not None:
            self._set("endgame_sigma",
                      real("OCPSettings.endgame_sigma", self.endgame_sigma, positive=True))
            if not any(abs(v - self.endgame_sigma) <= 1e-6 * v for v in self.schedule()[:-1]):
                raise ValueError("OCPSettings.endgame_sigma must be one of the homotopy's stages "
                                 f"before the last {self.schedule()[:-1]}, got "
                                 f"{self.endgame_sigma!r}")
        if self.stage_tol_ratio is not None:
            self._set("stage_tol_ratio",
                      real("OCPSettings.stage_tol_ratio", self.stage_tol_ratio, positive=True))
            if not self.stage_tol_ratio <= 1:
                raise ValueError("OCPSettings.stage_tol_ratio must be in (0, 1], got "
                                 f"{self.stage_tol_ratio!r}")
        if (self.loose_last and self.stage_tol_ratio is None and not self.stage_tol
            <= self.sigma_min):
            raise ValueError("OCPSettings.loose_last needs stage_tol <= sigma_min (a last stage at "
                             "sigma_min solved only to stage_tol would stop at once), got "
                             f"stage_tol {self.stage_tol:g}, sigma_min {self.sigma_min:g}")
        if self.mu_ratios is not None:
            ratios = tuple(float(r) for r in self.mu_ratios)
            if not ratios or any(not (math.isfinite(r) and r > 0) for r in ratios):
                raise ValueError("OCPSettings.mu_ratios must be positive numbers, got "
                                 f"{self.mu_ratios!r}")
            self._set("mu_ratios", ratios)
        if self.mu_levels is not None:
            levels = tuple(float(r) for r in self.mu_levels)
            if not levels or any(not (math.isfinite(r) and 0 < r <= 10) for r in levels):
                raise ValueError("OCPSettings.mu_levels must be numbers in (0, 10], got "
                                 f"{self.mu_levels!r}")
            self._set("mu_levels", levels)
        if isinstance(self.constraints, (dict, Constraint)):
            raise ValueError("OCPSettings.constraints must be a sequence of constraints, got one")
        self._set("constraints", tuple(Constraint.of(c) for c in self.constraints))
        if self.objective == "min_cot" and self.speed_min > 0 and self._own_speed_min():
            raise ValueError("OCPSettings: speed_min and a speed constraint with min in every "
                             "scenario both give min_cot's speed requirement: give one (to change "
                             "a file's speed constraint: --set 'ocp.constraint=[{quantity = "
                             "\"speed\", min = 0.05}]')")

    def schedule(self) -> tuple[float, ...]:
        """The relaxation parameters of the homotopy from the first sigma0 (sigma0, sigma0
        sigma_factor, ..., sigma_min)."""
        return tuple(float(f"{v:.12g}") for v in sigma_schedule(self.sigma0[0], self.sigma_factor,
                                                                self.sigma_min))

    def scenarios(self, robot: AnyRobot) -> list[AnyRobot]:
        """The robots (a Robot or a Chain) of the friction scenarios: each level of :attr:`levels`,
        at it each ratio of :attr:`friction_ratios` (just ``robot`` without a set)."""
        if not self.friction_set:
            return [robot]
        if not self.ratio_set:  # levels of the robot's own coefficients
            return [with_friction(robot, level * robot.mu1, level * robot.mu2)
                    for level in self.levels]
        mu = math.sqrt(robot.mu1 * robot.mu2)
        return [with_friction(robot, level * mu * math.sqrt(r), level * mu / math.sqrt(r))
                for level in self.levels for r in self.friction_ratios]

    @property
    def ratio_set(self) -> bool:
        """True when the scenarios set the ratio mu1/mu2 (``mu_ratios``, or eps > 0) rather than
        keep the robot's own."""
        return self.mu_ratios is not None or self.ratio_eps > 0

    @property
    def levels(self) -> tuple[float, ...]:
        """The friction levels (factors on both coefficients): mu_levels, else (1,)."""
        return self.mu_levels if self.mu_levels is not None else (1.0,)

    def scenario_pairs(self) -> list[tuple[float, float | None]]:
        """(level, ratio) of each scenario, in the order of :meth:`scenarios` (ratio None: the
        robot's own)."""
        ratios = self.friction_ratios if self.ratio_set else (None,)
        return [(level, r) for level in self.levels for r in ratios]

    @property
    def requirements(self) -> tuple[Constraint, ...]:
        """Every bound on a cycle quantity: min_cot's speed requirement (a speed at least speed_min
        in every scenario; unless a constraint bounds the speed from below in every scenario
        itself), or a sum with a CoT+ term moving forwards (speed >= 0: CoT+ = W+ / (M g d S) turns
        negative backwards, where the judge's CoT+ is +inf), then :attr:`constraints`."""
        if self._own_speed_min():
            return self.constraints
        if self.objective == "min_cot":
            return (Constraint("speed", min=self.speed_min),) + self.constraints
        if self.terms is not None and "CoT_plus" in self.terms:
            return (Constraint("speed", min=0.0),) + self.constraints
        return self.constraints

    @property
    def speed_requirement(self) -> Constraint | None:
        """min_cot's speed requirement (speed >= speed_min in every scenario, or the constraint of
        ``constraints`` that says so, the first); None for the other objectives."""
        if self.objective != "min_cot":
            return None
        return next((c for c in self.requirements if _bounds_speed_below(c)), None)

    def _own_speed_min(self) -> bool:
        return any(_bounds_speed_below(c) for c in self.constraints)

    @property
    def ratio_eps(self) -> float:
        """The half-width eps of the friction set: mu_ratio_eps, else 0.1 for robust_speed and 0 for
        the other objectives."""
        if self.mu_ratio_eps is not None:
            return self.mu_ratio_eps
        return 0.1 if self.objective == "robust_speed" else 0.0

    @property
    def friction_ratios(self) -> tuple[float, ...]:
        """The scenarios mu1/mu2: mu_ratios, else {1 - eps, 1, 1 + eps} (eps = :attr:`ratio_eps`
        > 0) or (1,)."""
        if self.mu_ratios is not None:
            return self.mu_ratios
        eps = self.ratio_eps
        return (1 - eps, 1.0, 1 + eps) if eps > 0 else (1.0,)

    @property
    def friction_set(self) -> bool:
        """True when the objective is taken over a set of friction scenarios (not only the robot's
        own friction): explicit ``mu_ratios`` or ``mu_levels``, or a set half-width eps > 0."""
        return self.mu_ratios is not None or self.mu_levels is not None or self.ratio_eps > 0

    @property
    def baseline_shapes(self) -> tuple[str, ...]:
        """The waveform families searched for baselines: the harmonic one first (the OCP's start),
        then those of ``baselines``."""
        rest = BASELINE_CHOICES[2:] if self.baselines == "all" else (self.baselines,)
        return ("harmonic",) + tuple(s for s in rest if s != "harmonic")

    def rate_bound(self, robot: Robot) -> float:
        """Largest torque rate |d tau_i / d t| [N m/s] of the three-link robot's joints: k times the
        reference-angle rate bound (a chain's, per joint:
        :func:`~ocp_crawl.ocp.plant.joint_rate_bounds`)."""
        return float(joint_rate_bounds(self, robot)[0])

    def accel_bound(self, robot: Robot) -> float | None:
        """Largest torque acceleration |d^2 tau_i / d t^2| [N m/s^2] of the three-link robot's
        joints, or None (no bound)."""
        accel = joint_accel_bounds(self, robot)
        return None if accel is None else float(accel[0])

    def joint_rate_step(self) -> float | None:
        """The joint-rate bound as the transcription uses it: the largest change of a joint angle
        [rad] over a whole interval at T_hat = 1, radians(max_joint_rate_deg_s) period_ref / N (a
        sub-step of the fraction l of its interval and the scaled period T_hat moves each joint by
        at most this times l T_hat); None: no bound."""
        if self.max_joint_rate_deg_s is None:
            return None
        return math.radians(self.max_joint_rate_deg_s) * self.period_ref() / self.nodes

    def period_ref(self) -> float:
        """Reference period [s]: the shortest period of the envelope's full harmonic gait (amplitude
        A_max) under the bandwidth, 2 pi A_max / max_rate (the OCP scales its period variable by
        it)."""
        return 2 * math.pi * self.A_max_deg / self.max_rate_deg_s

    def min_period(self, A1_deg: float, A2_deg: float) -> float:
        """Shortest period [s] of a harmonic gait of amplitudes A1, A2 [deg] under the bandwidth:
        2 pi max(A1, A2) / max_rate (its peak reference rate 2 pi A / T equals the bound)."""
        return 2 * math.pi * max(A1_deg, A2_deg) / self.max_rate_deg_s

    def torque_bounds(self, robot: Robot) -> tuple[float, float]:
        """Torque range [N m] of the three-link robot's joints that keeps phi_ref = pi + tau/k
        inside the envelope (a chain's, per joint:
        :func:`~ocp_crawl.ocp.plant.joint_torque_bounds`)."""
        lo, hi = joint_torque_bounds(self, robot)
        return float(lo[0]), float(hi[0])
