"""No silent success: a ``success`` result satisfies every physical invariant.

Random VALID problems are drawn over the schema's keys (robot, harmonic gait with per-joint values,
both gravity conventions, torque drive) and built through ``problem_from_dict`` (inputs the schema
rejects are skipped) and run with ``run_problem``.  A result that is not ``success`` is not checked
here (test_properties_hybrid checks that failures are clean).  Every successful result is checked
against computations that do not use the stepper:

* **periodicity**: the sampled state at the end of the reported cycle equals the state at its start
  (the stepper declares a gait periodic when the cycle-end states differ by <= periodic_tol);
* **contact**: f_n1, f_n2 > 0 and d > 0; x2 - x1 = d at every sample;
* **friction cone**: |f_t| <= mu_i f_n,i at both feet; in a slip mode the slipping foot is on its
  limit, f_t = sigma mu_i f_n,i (both feet in slip-slip); in stick-stick d and the feet are fixed;
* **equilibrium**: the model's joint residual F(phi, tau, f_t) (``Model.equilibrium_residual``,
  not the stepper's mode system) vanishes at every sample;
* **stability**: the stability margin of :mod:`ocp_crawl.model.stability` in the sample's mode is
  positive at every sample;
* **continuity**: no jump of x = (phi1, phi2, f_t/(M g)) between consecutive samples (see
  :func:`continuity_violations` for the bound from the derivative);
* **energy balance**: input work = potential change + friction dissipation over the cycle, with the
  three terms recomputed from a fine sampled run by quadrature (see :func:`energy_terms`).

The first four are hard assertions in :func:`test_success_satisfies_the_static_invariants`.  The
last three failed for some successes before the stepper checked stability, jumps and the energy
balance (snap-through and unstable equilibria reported as success):
:func:`test_success_is_stable_continuous_and_balanced` asserts them, with the issue's two
counterexamples as explicit examples.

The example count is small and derandomised by default (fast CI); set
``OCP_CRAWL_HYPOTHESIS_EXAMPLES`` for a large random run, e.g.
``OCP_CRAWL_HYPOTHESIS_EXAMPLES=10000 python -m pytest tests/test_success_properties.py
--hypothesis-show-statistics``.
"""
import json
import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, event, example, given, reject, settings
from hypothesis import strategies as st

from ocp_crawl import Mode, ProblemError, problem_from_dict, run_problem
from ocp_crawl.model.stability import stability_margins
from ocp_crawl.model.statics import AUX, call_mapped, symbolic
from ocp_crawl.sim.event_guards import SYMMETRY_TOL
from ocp_crawl.sim.event_state import mode_q
from _counterexamples import SNAP_THROUGH

#: file to which a large run appends the successes that violate the counted invariants (JSON lines)
LOG = os.environ.get("OCP_CRAWL_SUCCESS_LOG")
EXAMPLES = int(os.environ.get("OCP_CRAWL_HYPOTHESIS_EXAMPLES", "30"))
SETTINGS = settings(max_examples=EXAMPLES, deadline=None,
                    derandomize="OCP_CRAWL_HYPOTHESIS_EXAMPLES" not in os.environ,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
                    database=None)

#: points of the fine output grid of the energy check (plus the event phases)
FINE_POINTS = 4001
#: energy balance tolerance, relative to the gross work (see :func:`energy_terms`)
ENERGY_TOL = 1e-4
#: continuity: the trapezoid defect of an interval may not exceed this fraction of h max|x'| (see
#: :func:`continuity_violations`)
DEFECT_FRACTION = 0.5


def log_uniform(lo, hi):
    return st.floats(math.log(lo), math.log(hi)).map(math.exp)


@st.composite
def problem_dicts(draw):
    """Problem files (as dicts) over the schema's keys: mass 1 g-1 t, length 1 mm-10 m, stiffness
    ratio k/(M g L) 1e-3..1e4, friction 0-2 (one mu or one per foot), any gravity; gamma over
    (0, 360) or near the paper's 90 deg, amplitudes 0-120 deg, psi over [-360, 360]; per-joint gamma
    and A at times."""
    M, L = draw(log_uniform(1e-3, 1e3)), draw(log_uniform(1e-3, 10.0))
    g = draw(st.one_of(st.sampled_from([9.81, 1.62, 3.71]), log_uniform(0.1, 100.0)))
    mu = st.one_of(st.floats(0.0, 2.0), st.just(0.0), log_uniform(1e-3, 2.0))
    robot = {"M": M, "L": L, "beta": draw(log_uniform(0.1, 10.0)),
             "k": draw(log_uniform(1e-3, 1e4)) * M * g * L, "g": g}
    if draw(st.booleans()):
        robot["mu"] = draw(mu)
    else:
        robot["mu1"], robot["mu2"] = draw(mu), draw(mu)
    angle = st.one_of(st.floats(30.0, 150.0), st.floats(0.5, 359.5))
    amplitude = st.one_of(st.floats(0.0, 60.0), st.floats(0.0, 120.0))
    gait = {"drive": "torque", "gamma_deg": draw(angle), "A_deg": draw(amplitude),
            "psi_deg": draw(st.floats(-360, 360))}
    if draw(st.integers(0, 3)) == 0:
        gait["gamma1_deg"], gait["gamma2_deg"] = (gait["gamma_deg"],
                                                  gait["gamma_deg"] + draw(st.floats(-20.0, 20.0)))
        gait["A1_deg"], gait["A2_deg"] = gait["A_deg"], draw(amplitude)
    return {"robot": robot, "gait": gait,
            "model": {"gravity": draw(st.sampled_from(["physical", "paper"]))}}


def build(data: dict):
    """The problem of a drawn dict; inputs the schema rejects are skipped (hypothesis
    ``reject``)."""
    try:
        return problem_from_dict(data)
    except ProblemError:
        reject()


# ------------------------------------------------------------------------------------- invariants
def static_violations(problem, res) -> list[str]:
    """Periodicity, contact, friction cone and equilibrium residual of a successful result (messages
    of the violated ones).  Round-off: f_t and the joint balance carry errors ~1e-16 (M g L + k)
    (the stiffness fixes the angles; f_t absorbs the joint balance's round-off), so their tolerances
    scale with 1 + k/(M g L)."""
    robot, model = problem.robot, problem.model
    Mg, L, MgL = robot.M * robot.g, robot.L, robot.MgL
    stiff = 1.0 + robot.k / MgL
    out = []
    tol_p = problem.options.periodic_tol
    dphi = np.max(np.abs(res.phi[:, -1] - res.phi[:, 0]))
    dft = abs(res.f_t[-1] - res.f_t[0]) / Mg
    if not (res.t[0] == res.t0 and res.t[-1] == res.t0 + 1):
        out.append(f"periodicity: samples span [{res.t[0]}, {res.t[-1]}], "
                   f"not the cycle from t0 = {res.t0}")
    if not (dphi <= 1.01 * tol_p and dft <= 1.01 * tol_p):
        out.append(f"periodicity: state changes over the cycle by {dphi:.3g} rad, f_t/(M g) "
                   f"by {dft:.3g} > {tol_p:g}")
    if not (np.all(res.f_n1 > 0) and np.all(res.f_n2 > 0) and np.all(res.d > 0)):
        out.append(f"contact: min f_n1 {res.f_n1.min():.3g} N, f_n2 {res.f_n2.min():.3g} N, "
                   f"d {res.d.min():.3g} m")
    if not np.allclose(res.x2 - res.x1, res.d, rtol=0, atol=1e-9 * L):
        out.append(f"kinematics: x2 - x1 - d up to {np.max(np.abs(res.x2 - res.x1 - res.d)):.3g} m")
    out += friction_violations(robot, res, 1e-9 * Mg * stiff)
    F = np.array([model.equilibrium_residual(res.phi[:, j], res.tau[:, j],
                                             res.f_t[j]) for j in range(res.t.size)])
    worst = float(np.max(np.abs(F))) if F.size else 0.0
    if not worst <= 1e-8 * MgL * stiff:
        out.append(f"equilibrium: joint residual {worst:.3g} N m > 1e-8 (M g L + k)")
    return out


def friction_violations(robot, res, tol: float) -> list[str]:
    """Coulomb's law at every sample: the cone at both feet, the slipping foot on its limit opposing
    the slip, fixed feet in stick-stick (``tol``: force tolerance [N]).

    Slip-slip (both feet at their limits) is the stepper's documented approximation of the
    non-generic case mu1 f_n1 = mu2 f_n2: it is kept while |mu1 f_n1 - mu2 f_n2| <= SYMMETRY_TOL M
    g, with f_t the mean of the two limits; there the test checks exactly that contract (limits
    within SYMMETRY_TOL M g, f_t their mean, so within half their difference of each limit and of
    the cone).
    """
    lim = {1: robot.mu1 * res.f_n1, 2: robot.mu2 * res.f_n2}
    ft = res.f_t
    both = np.isin(res.mode, [Mode.SLIP_BOTH_POS, Mode.SLIP_BOTH_NEG])
    split = np.where(both, 0.5 * np.abs(lim[1] - lim[2]), 0.0)
    out = []
    over = np.abs(ft) - np.minimum(lim[1], lim[2]) - split
    if not np.all(over <= tol):
        out.append(f"friction cone: |f_t| exceeds min(mu_i f_ni) by {over.max():.3g} N")
    if np.any(both) and not np.all(2 * split[both] <= SYMMETRY_TOL * robot.M * robot.g + tol):
        out.append(f"slip-slip: limits differ by {2 * split.max():.3g} N > SYMMETRY_TOL M g")
    for code in np.unique(res.mode):
        m, sel = Mode(int(code)), res.mode == code
        target = {0: [], 1: [lim[1]], 2: [lim[2]], 3: [0.5 * (lim[1] + lim[2])]}[m.foot]
        for limit in target:
            off = np.max(np.abs(ft[sel] - m.sigma * limit[sel]))
            if not off <= tol:
                out.append(f"friction: in {m.label} f_t is {off:.3g} N off its friction limit")
    stick = np.nonzero(res.mode == Mode.STICK)[0]
    runs = np.split(stick, np.nonzero(np.diff(stick) > 1)[0] + 1) if stick.size else []
    for r in runs:
        moved = max(np.ptp(res.x1[r]), np.ptp(res.x2[r]), np.ptp(res.d[r])) if r.size > 1 else 0.0
        if not moved <= 1e-9 * robot.L:
            out.append(f"stick-stick: feet move by {moved:.3g} m while both stick")
    return out


def mode_vectors(modes: np.ndarray) -> np.ndarray:
    """The mode-parameter vectors q (4, n) of the samples' mode codes."""
    return np.stack([mode_q(Mode(int(m))) for m in modes], axis=1)


def stability_violations(problem, res) -> list[str]:
    """Samples whose equilibrium is not stable in their mode (margin <= 0, model.stability)."""
    X = np.vstack([res.phi, res.f_t / (problem.robot.M * problem.robot.g)])
    margins = stability_margins(problem.model, X, mode_vectors(res.mode))
    bad = np.nonzero(~(margins > 0))[0]
    if not bad.size:
        return []
    j = int(bad[np.argmin(margins[bad])])
    return [f"stability: margin {margins[j]:.3g} <= 0 at {bad.size} samples, "
            f"worst at phase {res.t[j] - res.t0:.5f} in {Mode(int(res.mode[j])).label}"]


def state_rates(problem, res, modes: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """d/dt (phi1, phi2, f_t/(M g)) [per cycle] at samples ``cols`` along the solution of ``modes``:
    the implicit-function derivative of the model's mode equations, -J^-1 G_tau tau' (statics
    ``evaluate``)."""
    Mg = problem.robot.M * problem.robot.g
    t = res.t[cols]
    X = np.vstack([res.phi[:, cols], res.f_t[cols] / Mg])
    sig = problem.torque
    aux = call_mapped(symbolic().evaluate, X, sig(t).reshape(2, -1),
                      sig.derivative(t).reshape(2, -1), mode_vectors(modes), problem.model.p)
    return np.vstack([aux[AUX["dphi1"]], aux[AUX["dphi2"]], aux[AUX["dft"]] / Mg])


def interval_defects(problem, res, a, b):
    """The trapezoid defects |x_j+1 - x_j - h (a + b)/2| of x = (phi1, phi2, f_t/(M g)) on each
    interval between samples, rates ``a``, ``b`` at its ends, and their bounds (see
    :func:`continuity_violations`); both (3, n - 1)."""
    h = np.diff(res.t)
    X = np.vstack([res.phi, res.f_t / (problem.robot.M * problem.robot.g)])
    defect = np.abs(np.diff(X, axis=1) - 0.5 * h * (a + b))
    floor = np.array([1e-9, 1e-9, 1e-9 * (1 + problem.robot.k / problem.robot.MgL)])[:, None]
    return defect, DEFECT_FRACTION * h * np.maximum(np.abs(a), np.abs(b)) + floor


def continuity_violations(problem, res) -> list[str]:
    """Jumps of x = (phi1, phi2, f_t/(M g)) between consecutive samples t_j < t_j+1 (h = t_j+1 -
    t_j).

    Each interval lies in one mode (every event phase is a sample; an event's sample belongs to the
    mode before it, the interval after it to the mode of its right end).  With the rates a, b of
    that mode at both ends (:func:`state_rates`), a path that is C^3 on the interval has the
    trapezoid defect
    |x_j+1 - x_j - h (a + b)/2| = h^3 |x'''|/12 at some point; the bound is
    DEFECT_FRACTION * h * max(|a|, |b|) + 1e-9 (1e-9 (1 + k/(M g L)) for f_t/(M g), its round-off),
    which a smooth path exceeds only if it varies on a phase scale comparable with the sampling step
    (1/200 of a cycle).  A jump J of the state while the rates stay bounded gives a defect of
    about |J|.
    """
    n = res.t.size
    if n < 2:
        return []
    j = np.arange(n - 1)
    modes = res.mode[1:]
    defect, bound = interval_defects(problem, res, state_rates(problem, res, modes, j),
                                     state_rates(problem, res, modes, j + 1))
    bad = np.nonzero(np.any(defect > bound, axis=0))[0]
    if not bad.size:
        return []
    i = int(bad[np.argmax(np.max(defect[:, bad] - bound[:, bad], axis=0))])
    X = np.vstack([res.phi, res.f_t / (problem.robot.M * problem.robot.g)])
    jump = np.diff(X, axis=1)[:, i]
    return [f"continuity: {bad.size} intervals jump, worst at phase "
            f"{res.t[i] - res.t0:.5f}-{res.t[i + 1] - res.t0:.5f} ({Mode(int(res.mode[i])).label} "
            f"-> {Mode(int(res.mode[i + 1])).label}): dphi "
            f"= {np.degrees(jump[:2]).round(3).tolist()} deg, d(f_t/Mg) = {jump[2]:.3g}"]


def energy_terms(problem, fine) -> dict:
    """Input work, potential change, friction dissipation and gross work [J] of the cycle, by
    quadrature of a fine sampled run (FINE_POINTS phases plus every event phase, so each interval
    lies in one mode), and the round-off floor of these sums [J].

    Riemann-Stieltjes trapezoid sums: input work sum_i tau_i,avg dphi_i, dissipation |f_t,avg dd|
    per interval (f_t d' keeps its sign in a mode; zero in stick-stick), gross work |tau_i,avg
    dphi_i|; the potential change is ``Model.potential`` at the cycle's ends.  On a smooth stretch
    the trapezoid error is (h^2/12) of the integral of the integrand's second derivative: with h =
    1/4000 and the rates of a harmonic gait (a few 2 pi per cycle) it is ~1e-6 of the gross work;
    ENERGY_TOL = 1e-4 leaves a factor 100 for steep stretches, while a snap-through loses a finite
    fraction (4.4 % in the example below).  Round-off: each of the n terms carries ~2
    eps |tau| |phi| (the samples' last bits), so the sums are exact to ``floor`` = 4 n eps (sum_i
    max|tau_i| max|phi_i| + max|f_t| max|d|) + 1e-12 M g L, which matters for gaits that hardly move
    (zero amplitude: every term is round-off).
    """
    tau_avg = 0.5 * (fine.tau[:, 1:] + fine.tau[:, :-1])
    dW = tau_avg * np.diff(fine.phi, axis=1)
    diss = np.abs(0.5 * (fine.f_t[1:] + fine.f_t[:-1]) * np.diff(fine.d))
    dV = float(problem.model.potential(fine.phi[:, -1]) - problem.model.potential(fine.phi[:, 0]))
    mags = np.sum(np.max(np.abs(fine.tau), axis=1) * np.max(np.abs(fine.phi), axis=1)) + \
        np.max(np.abs(fine.f_t)) * np.max(np.abs(fine.d))
    floor = 4 * fine.t.size * np.finfo(float).eps * mags + 1e-12 * problem.robot.MgL
    return {"input_work": float(dW.sum()), "potential_change": dV, "dissipation": float(diss.sum()),
            "gross_work": float(np.abs(dW).sum()), "floor": float(floor)}


def energy_violations(problem, res) -> list[str]:
    """The energy balance of the cycle, recomputed on a fine grid (:func:`energy_terms`), and its
    agreement with the result's own energy terms: each to ENERGY_TOL of the gross work plus the
    round-off floor."""
    events = [e.t - res.t0 for e in res.steady_events()]
    te = np.unique(np.clip(np.concatenate([np.linspace(0.0, 1.0, FINE_POINTS), events]), 0.0, 1.0))
    fine = run_problem(problem, t_eval=te)
    if not fine.success:
        return [f"energy: the rerun on the fine grid ends with {fine.status_name}"]
    return energy_violations_on(problem, res, fine)


def energy_violations_on(problem, res, fine) -> list[str]:
    """:func:`energy_violations` with the fine grid's result ``fine`` given."""
    e = energy_terms(problem, fine)
    tol = ENERGY_TOL * max(e["gross_work"], abs(e["dissipation"])) + e["floor"]
    out = []
    residual = e["input_work"] - e["potential_change"] - e["dissipation"]
    if not abs(residual) <= tol:
        out.append(f"energy: balance residual {residual:.3g} J > {tol:.3g} J (input "
                   f"{e['input_work']:.4g} J, potential {e['potential_change']:.4g} J, "
                   f"dissipation {e['dissipation']:.4g} J, gross {e['gross_work']:.4g} J)")
    for name in ("input_work", "dissipation", "potential_change"):
        if not abs(e[name] - res.energy[name]) <= tol:
            out.append(f"energy: {name} {res.energy[name]:.6g} J of the result, "
                       f"{e[name]:.6g} J by quadrature")
    return out


def dynamic_violations(problem, res) -> dict[str, list[str]]:
    """The invariants that need the stepper's new checks: stability, continuity, energy."""
    return {"stability": stability_violations(problem, res),
            "continuity": continuity_violations(problem, res),
            "energy": energy_violations(problem, res)}


# ------------------------------------------------------------------------------------- tests
#: counterexample 2: the paper gait with k = 0.002 N m/rad settles on a maximum of the potential
UNSTABLE = {"robot": {"M": 0.052, "L": 0.120, "beta": 2.0, "k": 0.002, "mu": 0.389, "g": 9.81},
            "gait": {"drive": "torque", "gamma_deg": 90.0, "A_deg": 30.0, "psi_deg": 45.0},
            "model": {"gravity": "physical"}}


#: found by this test: a Newton iterate went NaN while its compiled residual norm read 0, and the
#: run ended in an internal error (brentq: "function value is NaN"; with A = 21 deg: "SVD did not
#: converge")
NAN_ITERATE = {"robot": {"M": 1.0, "L": 1.0, "beta": 1.0, "k": 9.81, "g": 9.81, "mu": 1.0},
               "gait": {"drive": "torque", "gamma_deg": 61.0, "A_deg": 20.0, "psi_deg": 0.0},
               "model": {"gravity": "paper"}}


@pytest.mark.slow
@SETTINGS
@example(data=NAN_ITERATE)
@example(data={**NAN_ITERATE, "gait": {**NAN_ITERATE["gait"], "A_deg": 21.0}})
@given(data=problem_dicts())
def test_success_satisfies_the_static_invariants(data):
    """Hard: periodicity, contact, friction cone, equilibrium.  Counted (events): stability,
    continuity and energy violations, which today's stepper does not yet turn into failure
    statuses."""
    problem = build(data)
    res = run_problem(problem)
    event(f"status {res.status_name}")
    if not res.success:
        return
    assert not static_violations(problem, res), (static_violations(problem, res), data)
    found = dynamic_violations(problem, res)
    for name, msgs in found.items():
        if msgs:
            event(f"success violating {name}")
    if LOG and any(found.values()):  # the examples behind the counts, for a report
        with open(LOG, "a") as f:
            f.write(json.dumps({"data": data, "S": res.S, "violations": found}) + "\n")


@pytest.mark.slow
@SETTINGS
@example(data=SNAP_THROUGH)
@example(data=UNSTABLE)
@given(data=problem_dicts())
def test_success_is_stable_continuous_and_balanced(data):
    """No success at an unstable equilibrium, across a jump of the state or with an energy
    imbalance."""
    problem = build(data)
    res = run_problem(problem)
    if not res.success:
        return
    found = dynamic_violations(problem, res)
    assert not any(found.values()), (found, data)


@pytest.mark.parametrize("data, invariant", [(SNAP_THROUGH, "continuity"), (SNAP_THROUGH, "energy"),
                                             (UNSTABLE, "stability")])
def test_the_checks_see_the_counterexamples(data, invariant):
    """The invariant checks are not vacuous: each flags its counterexample, or the run is not a
    success and says so."""
    problem = problem_from_dict(data)
    res = run_problem(problem)
    if res.success:
        assert dynamic_violations(problem, res)[invariant]
    elif res.status_name == "no_start":  # a start that can only settle on an unstable equilibrium
        assert "unstable equilibrium" in res.message, res.message
    else:
        assert res.status_name in ("unstable", "snap_through", "energy_imbalance",
                                   "fold"), res.message
