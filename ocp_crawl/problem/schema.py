"""The schema of problem files: every section and key with its type, unit, default and rule.

One table (:data:`SECTIONS`) lists every section and key; loading, ``--set`` overrides, error
messages and the docs' key reference (:func:`schema_markdown`) are all driven by it.  To add a
section (e.g. ``[sweep]``), append a :class:`Section`; its validated values (defaults filled in)
appear in ``Problem.sections[name]`` without any other change.

Defaults are defined once, on the dataclass field the key feeds (``Robot``, ``Model``, the options
of the registry's solvers, ``OCPSettings``); the schema reads them from there with
:func:`field_default`.
"""
from __future__ import annotations

from types import MappingProxyType
from typing import Literal, Mapping

from ocp_crawl.model.pressure import PAPER_FORM_AMPLITUDE_BAR, PRESSURE_FORMS, BendingMap
from ocp_crawl.model.pulse import PULSE_RAMPS
from ocp_crawl.model.robot import BETA_BOUNDS, MAGNITUDE, MU_BOUNDS
from ocp_crawl.model.statics import GRAVITY_CONVENTIONS, Model, Robot
from ocp_crawl.ocp import OCPSettings
from ocp_crawl.problem.keys import (ANGLE, COEFFICIENT, GE0, GT0, PHASE, Key, Rule, Section, Tables,
                                   field_default, within)
from ocp_crawl.problem.design_schema import DESIGN
from ocp_crawl.problem.messages import format_value
from ocp_crawl.ocp.objectives import SENSES
from ocp_crawl.ocp.quantities import QUANTITIES, Constraint
from ocp_crawl.ocp.limits import (BASELINE_CHOICES, BASELINE_EVALUATIONS_BOUNDS,
                                  BASELINE_SAMPLES_BOUNDS, BASELINE_STARTS_BOUNDS,
                                  ENDGAME_MAX_ITER_BOUNDS, ENDGAME_PATHS, FOURIER_ORDER_BOUNDS,
                                  HARMONIC_A_BOUNDS, HARMONIC_PSI_BOUNDS, LAYER_OF, NODES_BOUNDS,
                                  OBJECTIVE_CHOICES, PERTURBATIONS, PHYSICAL_BOUNDS, REMOVED_KEYS,
                                  START_SOLVES, STARTS_BOUNDS, WARM_BARRIERS)
from ocp_crawl.sim import DEFAULT_SOLVER, SOLVERS
from ocp_crawl.sim.options import MAX_CYCLES_BOUNDS, MAX_STEP_BOUNDS, STEPS_BOUNDS
from ocp_crawl.sim.dynamic import CONES

Drive = Literal["torque", "angles"]
DRIVES = ("torque", "angles")
#: the solvers a problem of the torque drive may name in ``[simulation] solver`` (the registry's
#: torque solvers)
TORQUE_SOLVERS = tuple(name for name, spec in SOLVERS.items() if spec.drive == "torque")


# ---- bounds of the robot's parameters and of every key that sizes work
# (docs/guide/problem_files.md, "Bounds") ----
#: the robot's bounds (MAGNITUDE, MU_BOUNDS, BETA_BOUNDS) are the model's own, checked by Robot too
_MAGNITUDE_WHY = ("so that M g L, k/(M g L) and their squares stay far inside the floating-point "
                  "range")
_MU_WHY = ("a frictionless foot, mu = 0, is outside the quasistatic model (docs: Problem files, "
           "Bounds); friction forces below 1e-4 M g sink into the solvers' force tolerances")

MAGNITUDE_RULE = within(*MAGNITUDE, _MAGNITUDE_WHY)
MU_RULE = within(*MU_BOUNDS, _MU_WHY)
BETA_RULE = within(*BETA_BOUNDS, "a link shorter than 1 % of another makes the geometry degenerate")
MAX_STEP = within(*MAX_STEP_BOUNDS,
                  "at most 1e4 continuation steps per cycle, about 0.3 s per cycle of the paper "
                  "gait; events are located to event_xtol whatever the step")
CYCLES = within(*MAX_CYCLES_BOUNDS,
                "periodic gaits settle in a few cycles; 500 cycles of the smallest max_step take "
                "a few minutes")
STEPS = within(*STEPS_BOUNDS,
               "each step is an IPOPT solve of about 2 ms: 1e4 steps take about 20 s per cycle")

def _robot(name: str):
    return field_default(Robot, name)


def _hybrid(name: str):
    return field_default(SOLVERS["event"].options, name)


def _mujoco(name: str):
    return field_default(SOLVERS["mujoco"].options, name)


def _physical(name: str) -> Rule:
    """The rule of an [ocp] number with a physical meaning: its bounds and reason in the OCP's
    settings."""
    return within(*PHYSICAL_BOUNDS[name])


def _ocp(name: str):
    value = field_default(OCPSettings, name)
    return "none" if value is None else value


#: the keys of a chain that replace the three-link shorthand M, L, beta, k
_CHAIN = ("lengths", "masses", "stiffness")

_ROBOT = Section("robot", "physical parameters (paper Table I)", required=True, keys=(
    Key("M", float, "kg", "total mass", required=True, rule=MAGNITUDE_RULE,
        required_unless=_CHAIN),
    Key("L", float, "m", "total length", required=True, rule=MAGNITUDE_RULE,
        required_unless=_CHAIN),
    Key("beta", float, "-", "body-to-leg length ratio", default=_robot("beta"), rule=BETA_RULE),
    Key("k", float, "N m/rad", "torsion stiffness", required=True, rule=MAGNITUDE_RULE,
        required_unless=_CHAIN),
    Key("mu", float, "-", "friction coefficient of both feet", required=True, rule=MU_RULE,
        required_unless=("mu1", "mu2"), exclusive_with=("mu1", "mu2")),
    Key("mu1", float, "-", "friction coefficient of foot 1 (left)", rule=MU_RULE,
        requires=("mu2",)),
    Key("mu2", float, "-", "friction coefficient of foot 2 (right)", rule=MU_RULE,
        requires=("mu1",)),
    Key("g", float, "m/s^2", "gravitational acceleration", default=_robot("g"),
        rule=MAGNITUDE_RULE),
    Key("lengths", list, "m", "a chain of n >= 3 links instead of M, L, beta, k: the length of "
        "each link from foot 1 to foot 2 (the longest at most 100 times the shortest)",
        rule=MAGNITUDE_RULE, requires=("masses", "stiffness")),
    Key("masses", list, "kg", "chain: the mass of each link (n entries)",
        rule=within(0.0, MAGNITUDE[1], "a link may be massless; the total mass is a magnitude"),
        requires=("lengths",)),
    Key("stiffness", list, "N m/rad", "chain: the torsion stiffness of each joint (n - 1 "
        "entries, joint j between links j and j + 1)", rule=MAGNITUDE_RULE,
        requires=("lengths",)),
    Key("com", list, "-", "chain: the centre of mass of each link, as the fraction of its length "
        "from its foot-1 end (absent: 0.5 each)", rule=within(0.0, 1.0, "inside the link"),
        requires=("lengths",)),
    Key("rest_deg", list, "deg", "chain: the rest bend of each joint's spring from straight "
        "(the spring is relaxed at phi_j = 180 deg + rest_j; absent: 0 each)",
        rule=Rule(lambda v: -180 < v < 180, "in (-180, 180)"), requires=("lengths",)),
))

#: the waveforms of ``[gait] waveform``: the reference angles (or torques) over one cycle
WAVEFORMS = ("harmonic", "fourier", "samples", "pulse", "pressure")
#: interpolations of ``[gait] waveform = "samples"`` (the classes of ocp_crawl.model.sampled)
INTERPOLATIONS = ("pchip", "linear", "spline")
_HFP, _HP = ("harmonic", "fourier", "pulse"), ("harmonic", "pulse")
_FOURIER_WHY = "harmonics n = 1, 2, ... of the reference angle; at most 100"
_SAMPLES_WHY = "samples over one cycle at the phases of gait.phase"

_GAIT = Section("gait", "reference angles or torques over one cycle", required=True,
                selector="waveform",
                keys=(
    Key("drive", str, "-", "actuation: spring torque tau = k (phi_ref - pi), or prescribed angles",
        default=DRIVES[0], choices=DRIVES),
    Key("waveform", str, "-",
        "shape of the input over one cycle: harmonic (the paper's gait), Fourier series, samples "
        "(inline or a CSV file), pulses of soft actuators, or the pressures of the [pressure] "
        "actuator",
        default=WAVEFORMS[0], choices=WAVEFORMS),
    Key("period", float, "s",
        "duration of one cycle, for the mean speed abs(S) / period (the quasistatic S per "
        "cycle does not depend on it; absent: no speed)", rule=GT0),
    Key("gamma_deg", float, "deg",
        "nominal joint angle (Fourier: mean; pulse: centre of the swing)", required=True,
        rule=ANGLE, required_unless=("gamma1_deg", "gamma2_deg"), variants=_HFP),
    Key("A_deg", float, "deg", "amplitude (pulse: half swing)", required=True, rule=GE0,
        required_unless=("A1_deg", "A2_deg"), variants=_HP),
    Key("psi_deg", float, "deg", "phase lead of joint 1 over joint 2 (a chain: of each joint over "
        "the next)", required=True, rule=PHASE,
        variants=(*_HP, "pressure")),
    Key("p0_bar", float, "bar",
        "pressure: nominal pressure p0 of both segments (the [pressure] form \"raised\": "
        "the peak)", required=True,
        rule=within(0, 1e3, "a gauge pressure; far beyond any soft actuator"),
        variants=("pressure",)),
    Key("gamma1_deg", float, "deg", "nominal angle of joint 1 (overrides gamma_deg)", rule=ANGLE,
        variants=_HFP),
    Key("gamma2_deg", float, "deg", "nominal angle of joint 2 (overrides gamma_deg)", rule=ANGLE,
        variants=_HFP),
    Key("A1_deg", float, "deg", "amplitude of joint 1 (overrides A_deg)", rule=GE0, variants=_HP),
    Key("A2_deg", float, "deg", "amplitude of joint 2 (overrides A_deg)", rule=GE0, variants=_HP),
    Key("gamma_joints_deg", list, "deg", "chain ([robot] lengths): the nominal angle of each "
        "joint (instead of gamma_deg; pulse: the centre of each swing)", rule=ANGLE, variants=_HP,
        exclusive_with=("gamma_deg",)),
    Key("A_joints_deg", list, "deg", "chain ([robot] lengths): the amplitude of each joint "
        "(instead of A_deg; pulse: each half swing)", rule=GE0, variants=_HP,
        exclusive_with=("A_deg",)),
    Key("cos1_deg", list, "deg", f"fourier: cosine amplitudes of joint 1 ({_FOURIER_WHY})",
        default=(), rule=COEFFICIENT, variants=("fourier",)),
    Key("sin1_deg", list, "deg", f"fourier: sine amplitudes of joint 1 ({_FOURIER_WHY})",
        default=(), rule=COEFFICIENT, variants=("fourier",)),
    Key("cos2_deg", list, "deg", f"fourier: cosine amplitudes of joint 2 ({_FOURIER_WHY})",
        default=(), rule=COEFFICIENT, variants=("fourier",)),
    Key("sin2_deg", list, "deg", f"fourier: sine amplitudes of joint 2 ({_FOURIER_WHY})",
        default=(), rule=COEFFICIENT, variants=("fourier",)),
    Key("rise", float, "cycles", "pulse: duration of each edge (rise and fall)", required=True,
        rule=Rule(lambda v: 0 < v <= 0.5, "in (0, 0.5]",
                  "an edge takes time; rise -> 0 tends to a square wave"),
        variants=("pulse",)),
    Key("hold", float, "cycles", "pulse: duration at the high level (2 rise + hold <= 1)",
        required=True, rule=Rule(lambda v: 0 <= v < 1, "in [0, 1)"), variants=("pulse",)),
    Key("ramp", str, "-",
        "pulse: edge shape, straight (trapezoid) or half-cosine (continuous slope)",
        default=PULSE_RAMPS[0], choices=PULSE_RAMPS, variants=("pulse",)),
    Key("file", str, "-",
        "samples: CSV file with 'phase [-]' and 'tau1 [N m]', 'tau2 [N m]' or 'phi1_ref [deg]', "
        "'phi2_ref [deg]' (relative to the problem file)", variants=("samples",),
        exclusive_with=("phase",)),
    Key("phase", list, "cycles",
        "samples: phases in [0, 1), increasing (a last sample at 1 must repeat the first)",
        rule=Rule(lambda v: 0 <= v <= 1, "in [0, 1]"), variants=("samples",)),
    Key("phi1_ref_deg", list, "deg", f"samples: reference angle of joint 1 ({_SAMPLES_WHY})",
        rule=ANGLE, variants=("samples",),
        requires=("phase", "phi2_ref_deg"), exclusive_with=("tau1", "tau2")),
    Key("phi2_ref_deg", list, "deg", f"samples: reference angle of joint 2 ({_SAMPLES_WHY})",
        rule=ANGLE, variants=("samples",),
        requires=("phase", "phi1_ref_deg")),
    Key("tau1", list, "N m", f"samples: torque of joint 1 ({_SAMPLES_WHY}); torque drive",
        variants=("samples",), requires=("phase", "tau2")),
    Key("tau2", list, "N m", f"samples: torque of joint 2 ({_SAMPLES_WHY}); torque drive",
        variants=("samples",), requires=("phase", "tau1")),
    Key("interpolation", str, "-", "samples: periodic interpolation between the samples",
        default=INTERPOLATIONS[0], choices=INTERPOLATIONS, variants=("samples",)),
))

_PRESSURE_WHY = "Table I's bending map a_i p^2 + b_i p of segment i"
_PRESSURE = Section("pressure",
                    "the pressure actuator of the soft robot (paper Section III): bending map, "
                    "rest angle, input form; read by [gait] waveform = \"pressure\" and by "
                    "ocp-crawl fit",
                    selector="form", keys=(
    Key("form", str, "-",
        "pressure input: the paper's form, p0 + A_p sin(2 pi t +- psi/2), or the raised "
        "sine from 0 to the peak p0", default=PRESSURE_FORMS[0], choices=PRESSURE_FORMS),
    Key("a1", float, "rad/bar^2", f"quadratic coefficient of segment 1 ({_PRESSURE_WHY})",
        default=field_default(BendingMap, "a1")),
    Key("a2", float, "rad/bar^2", f"quadratic coefficient of segment 2 ({_PRESSURE_WHY})",
        default=field_default(BendingMap, "a2")),
    Key("b1", float, "rad/bar", f"linear coefficient of segment 1 ({_PRESSURE_WHY})",
        default=field_default(BendingMap, "b1")),
    Key("b2", float, "rad/bar", f"linear coefficient of segment 2 ({_PRESSURE_WHY})",
        default=field_default(BendingMap, "b2")),
    Key("phi_rest_deg", float, "deg",
        "joint angle at zero pressure (absent: the form's, 180 deg for \"paper\", "
        "the stored fitted rest angle of the gravity convention for \"raised\")", rule=ANGLE),
    Key("amplitude_bar", float, "bar", "pressure amplitude A_p of the paper's form (at most p0)",
        default=PAPER_FORM_AMPLITUDE_BAR, rule=GE0, variants=("paper",)),
    Key("segments", list, "-", "chain: the segment (1 or 2) of each joint, segment 1's first; a "
        "segment of several joints bends as an arc, each taking an equal share of its bend "
        "(absent: one joint per segment, a chain of three links)",
        rule=Rule(lambda v: v in (1, 2), "1 or 2")),
))

_MODEL = Section("model", "model conventions", keys=(
    Key("gravity", str, "-",
        "sign of the gravity term: physical (virtual work) or paper (as printed)",
        default=field_default(Model, "gravity"), choices=GRAVITY_CONVENTIONS),
))

_SIMULATION = Section("simulation", "simulator of the torque drive and its options", keys=(
    Key("solver", str, "-", "simulator of the torque drive: event-driven, MPCC time-stepping, or "
        "dynamic in MuJoCo (the angles drive has its own, or mujoco: servos hold the angles)",
        default=DEFAULT_SOLVER["torque"],
        choices=TORQUE_SOLVERS),
    Key("max_step", float, "cycles", "event solver: largest continuation step",
        default=_hybrid("max_step"), rule=MAX_STEP),
    Key("event_xtol", float, "cycles", "event solver: event location tolerance",
        default=_hybrid("event_xtol"),
        rule=Rule(lambda v: 0 < v <= 1e-6, "in (0, 1e-6]",
                  "events located less precisely leave the contact mode " "after them unreliable")),
    Key("max_cycles", int, "-", "cycles before the gait is declared non-periodic",
        default=_hybrid("max_cycles"), rule=CYCLES),
    Key("periodic_tol", float, "rad", "periodicity tolerance (angles; f_t/(M g) likewise)",
        default=_hybrid("periodic_tol"), rule=GT0),
    Key("steps", int, "-", "mpcc solver: time steps per cycle",
        default=field_default(SOLVERS["mpcc"].options, "steps"), rule=STEPS),
    Key("period", float, "s", "mujoco solver: period T of one cycle of the input",
        default=_mujoco("period"), rule=GT0),
    Key("timestep", float, "s", "mujoco solver: integration step (contact time constant 5 steps)",
        default=_mujoco("timestep"),
        rule=within(1e-6, 1e-2, "the contact time constant is 5 steps: above 1e-2 s the feet sink "
                    "into the ground")),
    Key("cone", str, "-", "mujoco solver: friction cone", default=_mujoco("cone"), choices=CONES),
    Key("s_tol", float, "-", "mujoco solver: periodicity, relative change of S between two cycles",
        default=_mujoco("s_tol"), rule=GT0),
    Key("s_error_tol", float, "-", "mpcc solver: bound on the estimated discretisation error of S, "
        "s_error_tol (abs(S) + 1e-3 L), above which the result is coarse_steps (0: not estimated)",
        default=field_default(SOLVERS["mpcc"].options, "s_error_tol"),
        rule=Rule(lambda v: 0 <= v < 1, "in [0, 1)", "the estimate re-runs the steady cycle with "
                  "2 steps + 1 steps; 0 skips it")),
))

def _constraint_ok(value) -> bool:
    """Whether ``value`` is a valid ``[[ocp.constraint]]`` table (its message:
    :func:`constraint_error`)."""
    return constraint_error(value) is None


def constraint_error(value) -> str | None:
    """What is wrong with an ``[[ocp.constraint]]`` table, or None."""
    try:
        Constraint.of(value)
    except (TypeError, ValueError) as exc:
        return str(exc).replace("OCPSettings.constraints: ", "")
    return None


_OCP = Section("ocp", "periodic-gait optimal control (ocp-crawl optimize)", selector="objective",
               keys=(
    Key("objective", str, "-", "what to optimise: a named objective, or a cycle quantity "
        "\"min:<quantity>\" or \"max:<quantity>\" (\"max:speed\" is max_speed, \"min:CoT_plus\" "
        "min_cot), or \"min:sum\" of [ocp.terms]", default=_ocp("objective"),
        choices=OBJECTIVE_CHOICES),
    Key("terms", dict, "-",
        "objective min:sum: one [ocp.terms] table of quantity = weight (the sum "
        "of weight times each quantity in its SI unit, a scenario quantity as its mean over the "
        "scenarios; a negative weight maximises it)", required=True, variants=("min:sum",),
        rule=Rule(lambda v: True, "a table of quantity = weight (numbers), the quantities "
                  + ", ".join(SENSES))),
    Key("nodes", int, "-", "steps per cycle of the transcription", default=_ocp("nodes"),
        rule=within(*NODES_BOUNDS,
                    "the shipped files use 50: 15 to 30 s per start with one friction scenario, "
                    "about 70 s with robust_speed's three; the cost grows at least linearly")),
    Key("direction", int, "-", "sign of S to pursue (-1: towards foot 1, as psi > 0 gaits)",
        default=_ocp("direction"), rule=Rule(lambda v: v in (-1, 1), "-1 or 1")),
    Key("A_max_deg", float, "deg",
        "half-width of the reference-angle envelope around gait.gamma_deg",
        default=_ocp("A_max_deg"), rule=Rule(lambda v: 0 < v < 90, "in (0, 90)")),
    Key("parametrization", str, "-", "torques free at every node or a Fourier series",
        default=_ocp("parametrization"), choices=("free", "fourier")),
    Key("fourier_order", int, "-", "order of the Fourier series", default=_ocp("fourier_order"),
        rule=within(*FOURIER_ORDER_BOUNDS,
                    "dense coefficient columns slow every IPOPT iteration; for finer "
                    "profiles use the free parametrization")),
    Key("max_rate_deg_s", float, "deg/s",
        "actuator bandwidth: largest absolute reference-angle rate, "
        "abs(d phi_ref/dt), of each joint",
        default=_ocp("max_rate_deg_s"), rule=_physical("max_rate_deg_s")),
    Key("max_accel_deg_s2", float, "deg/s^2",
        "optional smoothness bound: largest reference-angle acceleration "
        "(absent: no bound)", rule=_physical("max_accel_deg_s2")),
    Key("max_joint_rate_deg_s", float, "deg/s", "optional bound on the actual joint rates "
        "abs(d phi/dt) of the gait, not only the references' (absent: no bound)",
        rule=_physical("max_joint_rate_deg_s")),
    Key("regularization", float, "-", "weight of the torque-rate regularisation",
        default=_ocp("regularization"), rule=_physical("regularization")),
    Key("speed_min", float, "m/s", "min_cot: smallest mean speed direction * S / T",
        default=_ocp("speed_min"),
        rule=_physical("speed_min"), variants=("min_cot", "min:CoT_plus")),
    Key("mu_ratio_eps", float, "-",
        "friction uncertainty as a set: the objective over the scenarios "
        "mu1/mu2 in {1 - eps, 1, 1 + eps}, each replayed (absent: 0.1 for robust_speed, else 0: "
        "the robot's friction only)", rule=_physical("mu_ratio_eps")),
    Key("mu_levels", list, "-", "friction levels: the objective and the constraints also at these "
        "factors on both feet's coefficients, e.g. [1.0, 0.5] (with mu_ratio_eps: every ratio at "
        "every "
        "level; absent: the robot's level only)",
        rule=within(1e-3, 10.0, "a factor on mu; mu itself "
                    "stays within its bounds")),
    Key("constraint", Tables, "-", "bounds on cycle quantities, one [[ocp.constraint]] table each: "
        "quantity (" + ", ".join(f"{q.name} [{q.unit}]" for q in QUANTITIES.values())
        + "), min and/or " "max in its unit, over = \"every\" scenario (default) or their \"mean\"",
        rule=Rule(_constraint_ok, "a table of quantity, min, max, over (docs: Optimal gaits, "
                  "Constraints)")),
    Key("ipopt", dict, "-",
        "IPOPT options of every solve of the OCP, one [ocp.ipopt] table (e.g. max_iter = "
        "500, output_file = \"ipopt.log\", file_print_level = 5), over the package's own; names "
        "and ranges checked by IPOPT when the file is read"),
    Key("robust", str, "-",
        "over a friction set: optimise the mean or the worst of the objective (speed, "
        "or CoT+ with speed_min in every scenario)", default=_ocp("robust"),
        choices=("mean", "worst")),
    Key("harmonic_psi", int, "-", "psi values of the harmonic sweep (initial guess, comparison)",
        default=_ocp("harmonic_psi"),
        rule=within(*HARMONIC_PSI_BOUNDS, "one event-driven run per psi, amplitude "
                    "and friction scenario; 180 is a 2 deg grid")),
    Key("harmonic_A", int, "-", "amplitudes of the harmonic sweep, up to A_max_deg (initial "
        "guess, comparison)", default=_ocp("harmonic_A"),
        rule=within(*HARMONIC_A_BOUNDS, "one event-driven run per amplitude, psi and friction "
                    "scenario")),
    Key("baselines", str, "-",
        "waveform families an optimum is compared with (the harmonic one is also its "
        "first start)", default=_ocp("baselines"), choices=BASELINE_CHOICES),
    Key("baseline_samples", int, "-",
        "Sobol points of each family's whole box in the baselines' scan "
        "(asymmetric members)", default=_ocp("baseline_samples"),
        rule=within(*BASELINE_SAMPLES_BOUNDS,
                    "one event-driven run per point and friction scenario")),
    Key("baseline_starts", int, "-",
        "local searches of each waveform family from its best scan points",
        default=_ocp("baseline_starts"),
        rule=within(*BASELINE_STARTS_BOUNDS,
                    "each is up to baseline_evaluations event-driven runs")),
    Key("baseline_evaluations", int, "-",
        "most members each local search of the baselines asks for beyond the scan",
        default=_ocp("baseline_evaluations"),
        rule=within(*BASELINE_EVALUATIONS_BOUNDS,
                    "one event-driven run per member and friction scenario")),
    Key("starts", int, "-", "starts of the OCP (harmonic baseline, perturbed, Fourier-order)",
        default=_ocp("starts"),
        rule=within(*STARTS_BOUNDS, "each start is a full homotopy of the NLP")),
    Key("sigma0", float, "-",
        "homotopy: first relaxation parameter (complementarity products <= sigma)",
        default=_ocp("sigma0")[0], rule=Rule(lambda v: 0 < v < 1, "in (0, 1)")),
    Key("sigma_factor", float, "-", "homotopy: ratio of successive relaxation parameters",
        default=_ocp("sigma_factor"), rule=Rule(lambda v: 0 < v < 1, "in (0, 1)")),
    Key("sigma_min", float, "-",
        "homotopy: last relaxation parameter (then the polish, unless already within "
        "comp_tol)", default=_ocp("sigma_min"), rule=Rule(lambda v: 0 < v < 1, "in (0, 1)")),
    Key("stage_tol_ratio", float, "-",
        f"homotopy: a stage before the last is solved to IPOPT tol = "
        f"min({_ocp('stage_tol'):g}, stage_tol_ratio * sigma) (absent: {_ocp('stage_tol'):g})",
        rule=Rule(lambda v: 0 < v <= 1, "in (0, 1]")),
    Key("start_solve", str, "-",
        "homotopy (from each start), tightened (every family's best member a start too, each "
        "solved on its simulated branches alone) or both", default=_ocp("start_solve"),
        choices=START_SOLVES),
    Key("endgame_sigma", float, "-",
        "homotopy: after the stage at this sigma, the tightened NLP on its simulated "
        "profile's branches (absent: the whole homotopy)",
        rule=Rule(lambda v: 0 < v < 1, "in (0, 1)")),
    Key("endgame_paths", str, "-",
        "endgame_first (the homotopy goes on only if the endgame is not kept) or both "
        "(in parallel, the better by replay)", default=_ocp("endgame_paths"),
        choices=ENDGAME_PATHS),
    Key("endgame_max_iter", int, "-", "most IPOPT iterations of the endgame",
        default=_ocp("endgame_max_iter"),
        rule=within(*ENDGAME_MAX_ITER_BOUNDS, "each is a factorisation of the KKT system")),
    Key("perturbation", str, "-",
        "IPOPT perturbs the Hessian as_needed (its rule) or always (from the first "
        "factorisation; the path may change)", default=_ocp("perturbation"), choices=PERTURBATIONS),
    Key("warm_barrier", str, "-",
        "homotopy: IPOPT's barrier strategy in the warm-started solves (every stage after "
        "the first, the polish); monotone starts from mu = 1e-6", default=_ocp("warm_barrier"),
        choices=WARM_BARRIERS),
    Key("dynamic_margin", float, "-", "optional: the optimum's period T must be at least this "
        "factor times the shortest period at which MuJoCo's S is within 5 % of the quasistatic S "
        "(a few MuJoCo runs; absent: not computed, not required)",
        rule=_physical("dynamic_margin")),
    Key("replay_tol", float, "-",
        "relative tolerance of the replay judge (objective, speed requirement)",
        default=_ocp("replay_tol"), rule=_physical("replay_tol")),
))


def removed_key(section: str, name: str) -> str | None:
    """The message for a key that earlier versions had and this one no longer has (``[ocp]`` keys of
    :data:`~ocp_crawl.ocp.settings.REMOVED_KEYS`): what replaces it; None for any other key."""
    if section != "ocp" or name not in REMOVED_KEYS:
        return None
    return f"[ocp] {name} no longer exists; use {REMOVED_KEYS[name]}"

#: The schema: every section and key of a problem file, in the order they are validated and
#: reported.
SECTIONS: tuple[Section, ...] = (_ROBOT, _GAIT, _MODEL, _SIMULATION, _OCP, _PRESSURE, DESIGN)

#: the sections of :data:`SECTIONS` by name (read-only)
SCHEMA: Mapping[str, Section] = MappingProxyType({s.name: s for s in SECTIONS})


def _requirement(k: Key, selector: str | None) -> str:
    if k.required and k.required_unless:
        req = "required unless " + " and ".join(f"`{u}`" for u in k.required_unless) + " given"
    elif k.required:
        req = "required"
    elif k.requires:
        req = "optional, with " + ", ".join(f"`{r}`" for r in k.requires)
    elif k.default is None:
        req = "optional"
    else:
        req = f"default `{format_value(k.default)}`"
    if k.exclusive_with:
        req += "; not with " + ", ".join(f"`{e}`" for e in k.exclusive_with)
    if k.variants:
        req += f"; {selector} " + ", ".join(f"`{format_value(v)}`" for v in k.variants)
    return req


def schema_markdown() -> str:
    """The schema as a Markdown table (section, key, type, unit, required/default, valid values,
    meaning; an ``[ocp]`` key's meaning starts with its layer,
    :data:`~ocp_crawl.ocp.limits.LAYERS`)."""
    rows = ["| key | type | unit | required / default | valid | meaning |",
            "|---|---|---|---|---|---|"]
    for sec in SECTIONS:
        for k in sec.keys:
            kind = {float: "float", int: "int", str: "string", list: "array",
                    Tables: "array of tables", dict: "table"}[k.type]
            valid = (k.rule.explained if k.rule is not None and not k.choices
                     and k.type not in (list, Tables, dict) else k.valid_text)
            layer = f"({LAYER_OF[k.name]}) " if sec.name == "ocp" and k.name in LAYER_OF else ""
            rows.append(f"| `{sec.name}.{k.name}` | {kind} | {k.unit} | "
                        f"{_requirement(k, sec.selector)} | {valid} | {layer}{k.help} |")
    return "\n".join(rows)
