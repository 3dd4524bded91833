"""Fuzz: no random problem ends in a silent success, an exception or a failure without a reason.

Random VALID problems are drawn over robots (mass 1 g - 1 t, length 1 mm - 10 m, stiffness ratio
k/(M g L) 1e-2 - 1e4, friction 0.01 - 2, often unequal, several g, both gravity conventions),
waveforms (harmonic, Fourier, pulses: trapezoids, triangles, near-square and half-cosine edges,
samples tables with linear and PCHIP interpolation, of torques or reference angles), drives
(torque, angles) and solvers (event, MPCC at 50 - 200 steps, MuJoCo), built with
``problem_from_dict`` (what the schema refuses is counted as rejected, not run) and run with
``run_problem``.  Every result must be a ``Status`` with a non-empty message; every ``success`` is
checked against invariants computed without the solver that produced it:

* torque drive, event solver: periodicity, contact, kinematics, Coulomb friction (cone, slipping
  foot on its limit, fixed feet in stick-stick) and the joint equilibrium residual of the model
  (:func:`test_success_properties.static_violations`) at the solver's own samples and on a fine
  re-sampled cycle (1201 phases, 65 in each piece of the input between its knots, every event and
  every knot); S unchanged by the re-sampling; stability margins in the sample's mode; continuity
  of the state between samples (the trapezoid defect of each interval, with rates taken inside it
  so that a kink of the input at a sample is not a jump; intervals that fail are re-sampled finer,
  where a jump stays and a steep continuous stretch passes); the energy balance by quadrature on
  the fine cycle (at 8 times the phases before a failure is reported);
* torque drive, MPCC: periodicity, contact, friction and equilibrium at the tolerances of its IPOPT
  steps, stability, an energy balance recomputed from its samples within the O(1/N^2) of its
  quadrature, and S against the event solver on the same problem: |S_mpcc - S_event| must be within
  the bound of MPCC's own error estimate (``extra["S_error_bound"]``) -- a discretisation error that
  the estimate misses would be a coarse answer called success;
* angles drive: the prescribed angles reproduced, contact on a fine grid, equilibrium, Coulomb's
  law, feet and S against an independent integration, the energy balance and the dissipation by
  quadrature (the checks of :func:`_properties_common.check_success`; the S oracle at two
  resolutions, :func:`angles_feet`);
* MuJoCo (a dynamic engine, where the quasistatic invariants do not apply): finite S, W+ and
  samples.

Each problem is reproducible from (seed, index) alone.  The run is heavy (skipped by default)::

    OCP_CRAWL_HEAVY=1 OCP_CRAWL_FUZZ=5000 OCP_CRAWL_FUZZ_SEED=1 \\
    OCP_CRAWL_FUZZ_LOG=fuzz.jsonl python -m pytest -q -p no:xdist tests/test_fuzz.py

``OCP_CRAWL_FUZZ`` is the number of problems (default 100), ``OCP_CRAWL_FUZZ_SEED`` the seed
(default 1), ``OCP_CRAWL_FUZZ_INDICES`` (comma-separated) runs only those problems, and
``OCP_CRAWL_FUZZ_LOG`` a JSON-lines file receiving one line per problem (its dict, key, status,
time, S and, for MPCC, the comparison with the event solver; ``silent`` lists the violated
invariants of a success), then one line with the counts per (waveform, drive, solver).
"""
from __future__ import annotations

import collections
import dataclasses
import json
import math
import os
import time
import traceback
from types import SimpleNamespace

import numpy as np
import pytest

from ocp_crawl import Mode, ProblemError, Status, problem_from_dict, run_problem
from ocp_crawl.status import STATUS_MESSAGES

import _properties_common as C
from test_success_properties import (energy_violations_on, friction_violations,
                                     interval_defects, stability_violations, state_rates,
                                     static_violations)

COUNT = int(os.environ.get("OCP_CRAWL_FUZZ", "100"))
#: only these problem indices (comma-separated), e.g. to re-check the problems of a log
INDICES = os.environ.get("OCP_CRAWL_FUZZ_INDICES")
SEED = int(os.environ.get("OCP_CRAWL_FUZZ_SEED", "1"))
LOG = os.environ.get("OCP_CRAWL_FUZZ_LOG")

#: share of each (drive, solver) in the mix, sized so that 5,000 problems take about an hour on one
#: core: an event or angles problem costs ~0.1-0.5 s with its checks, an MPCC one ~5-20 s (its check
#: run, plus the event solver's run for the comparison), a MuJoCo one ~1-3 s
MIX = (("torque", "event", 0.63), ("angles", "angles", 0.31), ("torque", "mpcc", 0.05),
       ("torque", "mujoco", 0.01))
#: share of the MPCC problems drawn near the case its error estimate is about (soft robot, unequal
#: friction, linear pulses, 50 steps)
MPCC_SOFT = 0.7
#: points of the fine re-sampled cycle of the event solver's checks (plus events and knots), and
#: the least number of them in each piece of the input between its knots
FINE_POINTS, PIECE_POINTS = 1201, 65
#: re-sampling of intervals that look like jumps: points per interval, levels, most intervals
REFINE_POINTS, REFINE_LEVELS, MAX_REFINED = 65, 3, 50
#: MPCC: IPOPT's equation and complementarity tolerances (scaled; MPCCOptions defaults 1e-9, 1e-8),
#: with a factor 2 for round-off in the recomputation (as tests/test_properties_mpcc.py)
MPCC_EQ_TOL, MPCC_COMP_TOL = 2e-9, 2e-8
#: MPCC: bound on N^2 |energy residual| / gross work recomputed from the samples (the solver's own
#: energy_tol_n2 is 10; the trapezoid rule on its samples differs from its midpoint rule by
#: O(1/N^2))
MPCC_BALANCE_N2 = 40.0


# ------------------------------------------------------------------------------------- drawing
def log_uniform(rng, lo, hi):
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def draw_robot(rng, wide: bool = True) -> dict:
    """A robot over wide ranges (or physical ones, ``wide=False``), unequal friction half the
    time."""
    if wide:
        M, L = log_uniform(rng, 1e-3, 1e3), log_uniform(rng, 1e-3, 10.0)
        g = float(rng.choice([9.81, 1.62, 3.71]))
        g = g if rng.random() < 0.7 else log_uniform(rng, 0.1, 100)
        ratio, beta = log_uniform(rng, 1e-2, 1e4), log_uniform(rng, 0.1, 10.0)
    else:
        M, L, g = log_uniform(rng, 0.005, 5.0), log_uniform(rng, 0.02, 1.0), 9.81
        ratio, beta = log_uniform(rng, 0.3, 100.0), log_uniform(rng, 0.5, 4.0)
    robot = {"M": M, "L": L, "beta": beta, "k": ratio * M * g * L, "g": g}
    mu1 = log_uniform(rng, 0.01, 2.0)
    if rng.random() < 0.5:
        robot["mu"] = mu1
    else:
        robot["mu1"], robot["mu2"] = mu1, mu1 * log_uniform(rng, 1 / 3, 3.0)
    return robot


def draw_centre(rng, gait: dict, amp_max: float) -> None:
    """gamma (or gamma1, gamma2), A (or A1, A2) [deg] of ``gait``, in place."""
    gamma = float(rng.uniform(60, 130)) if rng.random() < 0.85 else float(rng.uniform(20, 170))
    amp = float(rng.uniform(0, amp_max))
    if rng.random() < 0.3:
        gait["gamma1_deg"], gait["gamma2_deg"] = gamma, gamma + float(rng.uniform(-20, 20))
        gait["A1_deg"], gait["A2_deg"] = amp, float(rng.uniform(0, amp_max))
    else:
        gait["gamma_deg"], gait["A_deg"] = gamma, amp


def draw_pulse(rng, gait: dict, shape: str) -> None:
    """Pulse keys of a trapezoid, triangle, near-square or half-cosine pulse, in place."""
    gait.update(waveform="pulse", ramp="cosine" if shape == "cosine" else "linear")
    if shape == "triangle":
        rise, hold = 0.5, 0.0
    elif shape == "square":
        rise = float(rng.uniform(0.003, 0.03))
        hold = float(rng.uniform(0, 1 - 2 * rise))
    else:
        rise = float(rng.uniform(0.02, 0.35))
        hold = float(rng.uniform(0, 1 - 2 * rise)) if rng.random() < 0.8 else 0.0
    gait.update(rise=rise, hold=hold)


def draw_samples(rng, gait: dict, robot: dict, drive: str, interp: str, amp_max: float) -> None:
    """A samples table (3-12 knots, spacing >= 1/60 cycle) of reference angles, or of torques
    (torque drive, half the time), in place."""
    n = int(rng.integers(3, 13))
    w = rng.uniform(0.2, 1.0, n)
    offset = rng.uniform(0, 0.99) * w[-1]
    phase = (np.concatenate([[0.0], np.cumsum(w[:-1])]) + offset) / w.sum()
    centre = rng.uniform(60, 130, 2) if rng.random() < 0.85 else rng.uniform(20, 170, 2)
    phi = centre[:, None] + rng.uniform(0, amp_max) * rng.uniform(-1, 1, (2, n))
    gait.update(waveform="samples", interpolation=interp, phase=phase.tolist())
    if drive == "torque" and rng.random() < 0.5:
        tau = robot["k"] * (np.radians(phi) - math.pi)
        gait.update(tau1=tau[0].tolist(), tau2=tau[1].tolist())
    else:
        gait.update(phi1_ref_deg=phi[0].tolist(), phi2_ref_deg=phi[1].tolist())


WAVEFORMS = ("harmonic", "fourier", "pulse-trapezoid", "pulse-triangle", "pulse-square",
             "pulse-cosine", "samples-linear", "samples-pchip")
#: the waveforms' shares (harmonic and pulses, the families the solvers special-case, most)
WAVEFORM_P = (0.24, 0.06, 0.16, 0.1, 0.08, 0.1, 0.13, 0.13)


def draw_gait(rng, robot: dict, drive: str, waveform: str, amp_max: float) -> dict:
    gait = {"drive": drive}
    if waveform.startswith("samples"):
        draw_samples(rng, gait, robot, drive, waveform.split("-")[1], amp_max)
        return gait
    draw_centre(rng, gait, amp_max)
    if waveform == "fourier":
        A = gait.pop("A_deg") if "A_deg" in gait else gait.pop("A1_deg")
        gait.pop("A2_deg", None)
        for key in ("cos1_deg", "sin1_deg", "cos2_deg", "sin2_deg"):
            order = int(rng.integers(1, 4))
            gait[key] = (A * rng.uniform(-1, 1, order) / np.arange(1, order + 1)).tolist()
        gait["waveform"] = "fourier"
        return gait
    gait["psi_deg"] = float(rng.uniform(-360, 360)) if rng.random() < 0.3 else \
        float(rng.uniform(-180, 180))
    if waveform.startswith("pulse"):
        draw_pulse(rng, gait, waveform.split("-")[1])
    return gait


def draw_soft_pulse(rng) -> dict:
    """A soft robot (k 0.2-3 M g L), unequal friction and linear pulses: where a coarse MPCC grid
    misses a stop at a corner of the input."""
    M, L = log_uniform(rng, 0.01, 1.0), log_uniform(rng, 0.05, 0.5)
    mu1 = log_uniform(rng, 0.1, 0.8)
    robot = {"M": M, "L": L, "beta": log_uniform(rng, 0.5, 4.0), "g": 9.81, "mu1": mu1,
             "mu2": mu1 * log_uniform(rng, 1.03, 1.6) ** float(rng.choice([-1, 1])),
             "k": log_uniform(rng, 0.2, 3.0) * M * 9.81 * L}
    gamma = float(rng.uniform(75, 105))
    rise = float(rng.uniform(0.03, 0.3)) if rng.random() < 0.85 else 0.5
    gait = {"drive": "torque", "waveform": "pulse", "ramp": "linear", "gamma1_deg": gamma,
            "gamma2_deg": gamma + float(rng.uniform(-5, 5)), "A1_deg": float(rng.uniform(3, 25)),
            "A2_deg": float(rng.uniform(3, 25)), "psi_deg": float(rng.uniform(-180, 180)),
            "rise": rise, "hold": float(rng.uniform(0, 1 - 2 * rise))}
    return {"robot": robot, "gait": gait}


def draw_problem(index: int) -> tuple[tuple[str, str, str], dict]:
    """((waveform, drive, solver), problem dict) of problem ``index``, a function of (SEED,
    index) alone."""
    rng = np.random.default_rng([SEED, index])
    u, acc = rng.random(), 0.0
    drive, solver = next(((d, s) for d, s, p in MIX if (acc := acc + p) > u), MIX[0][:2])
    if solver == "mpcc" and rng.random() < MPCC_SOFT:
        data, waveform = draw_soft_pulse(rng), "pulse-soft"
    else:
        waveform = str(rng.choice(WAVEFORMS, p=WAVEFORM_P))
        robot = draw_robot(rng, wide=solver in ("event", "angles"))
        amp_max = 45.0 if drive == "torque" else 25.0
        data = {"robot": robot, "gait": draw_gait(rng, robot, drive, waveform, amp_max)}
    gravity = "physical" if solver == "mujoco" else str(rng.choice(["physical", "paper"]))
    data["model"] = {"gravity": gravity}
    if solver == "mpcc":
        steps = 50 if rng.random() < 0.8 else int(rng.integers(51, 201))
        data["simulation"] = {"solver": "mpcc", "steps": steps}
    elif solver == "mujoco":
        data["simulation"] = {"solver": "mujoco", "period": float(rng.uniform(2.0, 5.0))}
    return (waveform, drive, solver), data


# ------------------------------------------------------------------------------------- checks
def input_knots(problem) -> np.ndarray:
    """Phases in [0, 1) where the input's rate (or curvature) may jump: the knots of the signal."""
    sig = problem.signal
    knots = getattr(getattr(sig, "reference", sig), "t_knots", None)
    if knots is None:
        knots = getattr(sig, "t_knots", ())
    return np.mod(np.asarray(knots, float), 1.0)


def fine_cycle(problem, res, points: int = FINE_POINTS, extra=()):
    """The steady cycle re-sampled at ``points`` phases, at least PIECE_POINTS in each piece of the
    input between its knots (short edges of pulses move fast), every event, every knot and the
    phases ``extra``: each interval lies in one mode and one smooth piece of the input."""
    events = [e.t - res.t0 for e in res.steady_events()]
    knots = np.unique(np.concatenate([[0.0, 1.0], input_knots(problem)]))
    pieces = [np.linspace(lo, hi, PIECE_POINTS) for lo, hi in zip(knots[:-1], knots[1:])]
    te = np.concatenate([np.linspace(0.0, 1.0, points), events, *pieces, *extra])
    return run_problem(problem, t_eval=np.unique(np.clip(te, 0.0, 1.0)))


def one_sided_rates(problem, res, modes, cols, shift) -> np.ndarray:
    """:func:`state_rates` at the phases t[cols] + shift (the state at t[cols]): the rate inside
    an interval next to a sample that is a knot of the input."""
    view = SimpleNamespace(t=res.t.copy(), phi=res.phi, f_t=res.f_t)
    view.t[cols] += shift
    return state_rates(problem, view, modes, cols)


def continuity_violations(problem, res) -> tuple[list[str], np.ndarray]:
    """Jumps of x = (phi1, phi2, f_t/(M g)) between consecutive samples: the trapezoid defect of
    each interval against DEFECT_FRACTION h max(|a|, |b|) + round-off (as the function of the same
    name in test_success_properties), with the rates a, b taken inside the interval (1e-3 h from its
    ends), so that a kink of the input at a sample does not count as a jump.  Returns the messages
    and the indices of the intervals that fail."""
    n = res.t.size
    if n < 2:
        return [], np.zeros(0, int)
    j = np.arange(n - 1)
    h = np.diff(res.t)
    modes = res.mode[1:]
    defect, bound = interval_defects(problem, res,
                                     one_sided_rates(problem, res, modes, j, 1e-3 * h),
                                     one_sided_rates(problem, res, modes, j + 1, -1e-3 * h))
    X = np.vstack([res.phi, res.f_t / (problem.robot.M * problem.robot.g)])
    bad = np.nonzero(np.any(defect > bound, axis=0))[0]
    if not bad.size:
        return [], bad
    i = int(bad[np.argmax(np.max(defect[:, bad] - bound[:, bad], axis=0))])
    jump = np.diff(X, axis=1)[:, i]
    return [f"continuity: {bad.size} intervals jump, worst at phase {res.t[i] - res.t0:.6f}-"
            f"{res.t[i + 1] - res.t0:.6f} ({Mode(int(res.mode[i])).label} -> "
            f"{Mode(int(res.mode[i + 1])).label}): dphi = {np.degrees(jump[:2]).tolist()} deg, "
            f"d(f_t/Mg) = {jump[2]:.3g}"], bad


def refined_continuity(problem, res, fine) -> list[str]:
    """Continuity on the fine cycle; the intervals that fail are re-sampled REFINE_POINTS times
    finer, up to REFINE_LEVELS times: a jump keeps its size at any sampling, while a steep but
    continuous stretch (near a fold, the state can turn by 16 deg within 1e-3 cycle) passes once
    its samples resolve it."""
    found, bad = continuity_violations(problem, fine)
    extra = []
    for _ in range(REFINE_LEVELS):
        if not found:
            return []
        t = fine.t - fine.t0
        extra += [np.linspace(t[i], t[i + 1], REFINE_POINTS) for i in bad[:MAX_REFINED]]
        fine = fine_cycle(problem, res, extra=extra)
        if not fine.success:
            return found + [f"refined rerun ends with {fine.status_name}"]
        found, bad = continuity_violations(problem, fine)
    return found


def energy_violations(problem, res, fine) -> list[str]:
    """The cycle's energy balance by quadrature on the fine cycle, and the result's own terms."""
    return energy_violations_on(problem, res, fine)


def event_violations(problem, res) -> list[str]:
    """Every invariant of an event-driven success, at its samples and on the fine cycle."""
    out = static_violations(problem, res) + stability_violations(problem, res)
    fine = fine_cycle(problem, res)
    if not fine.success:
        return out + [f"rerun on the fine cycle ends with {fine.status_name}: {fine.message}"]
    if abs(fine.S - res.S) > 1e-9 * problem.robot.L + 1e-9 * abs(res.S):
        out.append(f"S {res.S!r} changes to {fine.S!r} with the output phases")
    fine_static = [m for m in static_violations(problem, fine) if not m.startswith("periodicity")]
    out += [f"fine cycle: {m}" for m in fine_static]
    out += [f"fine cycle: {m}" for m in stability_violations(problem, fine)]
    out += refined_continuity(problem, res, fine)
    energy = energy_violations(problem, res, fine)
    if energy:  # the quadrature at 8 times the phases: a steep stretch needs them
        fine = fine_cycle(problem, res, 8 * FINE_POINTS)
        energy = energy_violations(problem, res, fine) if fine.success else energy
    return out + energy


def mpcc_static_violations(problem, res) -> list[str]:
    """Periodicity, contact, kinematics, Coulomb friction and equilibrium of an MPCC success, at
    the tolerances of its IPOPT steps (forces MPCC_COMP_TOL M g, torques MPCC_EQ_TOL (M g L +
    k))."""
    robot, model = problem.robot, problem.model
    Mg, L = robot.M * robot.g, robot.L
    stiff = 1.0 + robot.k / robot.MgL
    out = []
    tol_p = problem.options.periodic_tol
    dphi = float(np.max(np.abs(res.phi[:, -1] - res.phi[:, 0])))
    dft = abs(res.f_t[-1] - res.f_t[0]) / Mg
    if not (dphi <= 1.01 * tol_p and dft <= 1.01 * tol_p + MPCC_COMP_TOL * stiff):
        out.append(f"periodicity: the cycle changes phi by {dphi:.3g}, f_t/(M g) by {dft:.3g}")
    if not (np.all(res.f_n1 > 0) and np.all(res.f_n2 > 0) and np.all(res.d > 0)):
        out.append(f"contact: min f_n1 {res.f_n1.min():.3g}, f_n2 {res.f_n2.min():.3g}, "
                   f"d {res.d.min():.3g}")
    if not np.allclose(res.x2 - res.x1, res.d, rtol=0, atol=1e-9 * L):
        worst = np.max(np.abs(res.x2 - res.x1 - res.d))
        out.append(f"kinematics: x2 - x1 - d up to {worst:.3g}")
    out += [m for m in friction_violations(robot, res, MPCC_COMP_TOL * Mg * stiff)
            if not m.startswith("stick-stick")]
    # in stick-stick the feet may creep by the complementarity tolerance per step
    stick = res.mode == Mode.STICK
    creep = np.abs(np.diff(res.x1))[stick[1:] & stick[:-1]]
    if creep.size and not creep.max() <= MPCC_COMP_TOL * L:
        out.append(f"stick-stick: foot 1 moves by {creep.max():.3g} m in a step where both stick")
    F = np.array([model.equilibrium_residual(res.phi[:, j], res.tau[:, j], res.f_t[j])
                  for j in range(res.t.size)])
    if not np.max(np.abs(F)) <= MPCC_EQ_TOL * robot.MgL * stiff:
        out.append(f"equilibrium: joint residual {np.max(np.abs(F)):.3g} N m")
    return out


def mpcc_energy_violations(problem, res, steps: int) -> list[str]:
    """Input work - potential change - dissipation by the trapezoid rule on the samples (steps and
    located events), within MPCC_BALANCE_N2 / N^2 of the gross work."""
    tau_avg = 0.5 * (res.tau[:, 1:] + res.tau[:, :-1])
    dW = tau_avg * np.diff(res.phi, axis=1)
    diss = float(np.sum(np.abs(0.5 * (res.f_t[1:] + res.f_t[:-1]) * np.diff(res.d))))
    dV = float(problem.model.potential(res.phi[:, -1]) - problem.model.potential(res.phi[:, 0]))
    gross = float(np.abs(dW).sum())
    residual = float(dW.sum()) - dV - diss
    tol = MPCC_BALANCE_N2 / steps**2 * max(gross, diss) + 1e-12 * problem.robot.MgL
    if abs(residual) <= tol:
        return []
    return [f"energy: balance residual by the trapezoid rule {residual:.3g} J > {tol:.3g} J "
            f"(gross work {gross:.3g} J, N = {steps})"]


def mpcc_vs_event(data: dict, res) -> dict:
    """The event solver on the same problem and |S_mpcc - S_event| against MPCC's own bound."""
    ev_data = {**data, "simulation": {"solver": "event"}}
    ev = run_problem(problem_from_dict(ev_data))
    out = {"event_status": ev.status_name, "S_error": res.S_error,
           "bound": res.extra.get("S_error_bound")}
    if ev.success:
        diff = abs(res.S - ev.S)
        rel = diff / max(abs(ev.S), 1e-6 * problem_length(data))
        out.update(S_event=ev.S, diff=diff, rel=rel,
                   ratio=diff / out["bound"] if out["bound"] else math.inf)
    return out


def problem_length(data: dict) -> float:
    return float(data["robot"]["L"])


def mujoco_violations(res) -> list[str]:
    out = [f"{name} is not finite" for name in ("S", "W_plus")
           if not math.isfinite(getattr(res, name))]
    return out + [f"samples {name} not finite" for name, arr in res.arrays().items()
                  if not np.all(np.isfinite(arr))]


def angles_violations(problem, res) -> list[str]:
    """The checks of _properties_common (outputs and prescribed angles, contact, equilibrium and
    friction as they are; feet and energy by :func:`angles_feet` and :func:`angles_energy`), as
    messages."""
    out = []
    checks = (C._check_outputs, C._check_contact, C._check_friction, angles_feet, angles_energy)
    for check in checks:
        try:
            check(problem.model, problem.signal, res)
        except AssertionError as exc:
            where = traceback.extract_tb(exc.__traceback__)[-1]
            out.append(f"angles, {check.__name__} line {where.lineno}: {where.line} "
                       f"{str(exc)[:300]}")
    return out


def angles_feet(model, angles, res) -> None:
    """_properties_common._check_feet, with S against the displacement oracle at FINE and 10 FINE
    phases: that oracle's own bound counts the intervals whose ends or midpoint see the slipping
    foot change, and misses a change and its return inside one interval (a switch lasting 4e-6
    cycle left it 3.9e-8 m off, above its bound of 2.6e-8 m, while at 10 and 100 times the
    phases it converges to the solver's S); the difference of the two resolutions is added to
    the finer one's bound."""
    L = model.robot.L
    np.testing.assert_allclose(res.x2 - res.x1, res.d, rtol=0, atol=1e-12 * L)
    assert res.d[-1] == pytest.approx(res.d[0], abs=1e-12 * L)
    assert res.x1[-1] - res.x1[0] == pytest.approx(res.S, abs=1e-12 * L)
    assert res.x2[-1] - res.x2[0] == pytest.approx(res.S, abs=1e-12 * L)
    modes = [Mode(int(m)) for m in res.mode]
    for j in range(res.t.size - 1):
        if res.mode[j] == res.mode[j + 1] and modes[j].foot in (0, 1, 2):
            for i, x in ((1, res.x1), (2, res.x2)):
                assert modes[j].foot == i or x[j + 1] == x[j], (j, i)
    assert res.periodicity_residual <= 1e-12
    S, bound = C.displacement_oracle(model, angles)
    if abs(res.S - S) > bound + 1e-10 * L:
        S_fine, bound_fine = C.displacement_oracle(model, angles, 10 * C.FINE)
        assert abs(res.S - S_fine) <= bound_fine + abs(S - S_fine) + 1e-10 * L, \
            (res.S, S, bound, S_fine, bound_fine)


def angles_energy(model, angles, res) -> None:
    """The energy balance per cycle, W+ and the cost of transport of the angles solver, the
    dissipation against its oracle (``_properties_common._check_energy``, at its tolerances)."""
    C._check_energy(model, angles, res)


def failure_violations(res) -> list[str]:
    """A failure is a Status other than success with a message."""
    try:
        status = Status(res.status)
    except ValueError:
        return [f"status {res.status!r} is not a Status"]
    out = [] if status != Status.SUCCESS else ["success flag false with status success"]
    if not (isinstance(res.message, str) and res.message.strip()):
        out.append("empty message")
    elif not res.message.startswith(STATUS_MESSAGES.get(status, "")):
        out.append(f"message does not start with the status text: {res.message[:120]!r}")
    return out


# ------------------------------------------------------------------------------------- the run
def success_violations(key, data, problem, res, row) -> list[str]:
    """The invariants of a success, by (drive, solver); MPCC's comparison goes into ``row``."""
    _, drive, solver = key
    if not math.isfinite(res.S):
        return [f"success with S = {res.S!r}"]
    if solver == "mujoco":
        return mujoco_violations(res)
    if drive == "angles":
        diss = C.dissipation_oracle(problem.model, problem.signal)[0]
        row["diss_rel"] = abs(res.energy["dissipation"] - diss) / max(diss, 1e-300)
        row["balance"] = res.energy["balance_residual"]
        return angles_violations(problem, res)
    if solver == "event":
        return event_violations(problem, res)
    steps = data["simulation"]["steps"]
    out = mpcc_static_violations(problem, res) + stability_violations(problem, res)
    out += mpcc_energy_violations(problem, res, steps)
    cmp = mpcc_vs_event(data, res)
    row["mpcc"] = cmp
    if not res.S_error <= cmp["bound"]:
        out.append(f"S_error {res.S_error!r} above its bound {cmp['bound']!r}")
    if "diff" in cmp and not cmp["diff"] <= cmp["bound"]:
        out.append(f"S {res.S!r} is {cmp['diff']:.3g} m ({100 * cmp['rel']:.3g} %) off the event "
                   f"solver's {cmp['S_event']!r}, above the error bound {cmp['bound']:.3g} m")
    return out


def run_one(index: int) -> dict:
    """Draw, build, run and check problem ``index``: one row of the log."""
    key, data = draw_problem(index)
    row = {"i": index, "key": list(key), "data": data}
    start = time.perf_counter()
    try:
        problem = problem_from_dict(data)
    except ProblemError as exc:
        row.update(status="rejected", why=str(exc)[:200], time=time.perf_counter() - start)
        return row
    try:
        res = run_problem(problem)
        row.update(status=res.status_name, message=res.message[:200], S=res.S)
        if res.success:
            row["silent"] = success_violations(key, data, problem, res, row)
        else:
            found = failure_violations(res)
            row["bad_failure"] = [m for m in found if not m.startswith("message does not")]
            row["message_format"] = [m for m in found if m.startswith("message does not")]
    except Exception:  # noqa: BLE001 -- an exception is a finding, logged with its problem
        row.update(status="exception", error=traceback.format_exc()[-2000:])
    row["time"] = time.perf_counter() - start
    return row


def counts_table(rows: list[dict]) -> tuple[dict, str]:
    """Counts per (waveform, drive, solver) of every outcome, time, and the table as text."""
    counts = collections.defaultdict(collections.Counter)
    times = collections.Counter()
    for r in rows:
        k = "/".join(r["key"])
        counts[k][r["status"]] += 1
        counts[k]["silent"] += bool(r.get("silent"))
        times[k] += r["time"]
    statuses = sorted({s for c in counts.values() for s in c if s != "silent"},
                      key=lambda s: (s != "success", s != "rejected", s))
    head = f"{'waveform/drive/solver':34} {'n':>5} {'time/s':>7} " + \
        " ".join(f"{s[:12]:>12}" for s in statuses + ["silent"])
    lines = [head]
    for k in sorted(counts):
        c = counts[k]
        n = sum(v for s, v in c.items() if s != "silent")
        lines.append(f"{k:34} {n:5d} {times[k]:7.0f} " +
                     " ".join(f"{c[s]:12d}" for s in statuses + ["silent"]))
    table = {k: {**dict(c), "time": times[k]} for k, c in counts.items()}
    return table, "\n".join(lines)


def mpcc_summary(rows: list[dict]) -> dict:
    """The largest |S_mpcc - S_event| of the MPCC successes, relative and against the bound."""
    cmp = [(r["i"], r["mpcc"]) for r in rows if "diff" in r.get("mpcc", {})]
    if not cmp:
        return {"compared": 0}
    i_rel, worst_rel = max(cmp, key=lambda c: c[1]["rel"])
    i_ratio, worst_ratio = max(cmp, key=lambda c: c[1]["ratio"])
    return {"compared": len(cmp), "successes": sum(1 for r in rows if "mpcc" in r),
            "largest_rel": worst_rel["rel"], "largest_rel_i": i_rel,
            "largest_ratio_to_bound": worst_ratio["ratio"], "largest_ratio_i": i_ratio,
            "over_bound": sum(1 for _, c in cmp if c["diff"] > c["bound"])}


@pytest.mark.heavy
def test_fuzz_no_silent_success(capsys):
    """COUNT random problems: no exception, failures with a status and a message, every success
    within the invariants (see the module docstring)."""
    log = open(LOG, "w") if LOG else None
    rows, start = [], time.perf_counter()
    try:
        indices = [int(i) for i in INDICES.split(",")] if INDICES else range(COUNT)
        for index in indices:
            row = run_one(index)
            rows.append(row)
            if log:
                log.write(json.dumps(row, default=float) + "\n")
                log.flush()
        table, text = counts_table(rows)
        summary = {"seed": SEED, "count": COUNT, "wall_time": time.perf_counter() - start,
                   "counts": table, "mpcc": mpcc_summary(rows),
                   "silent": [r["i"] for r in rows if r.get("silent")],
                   "exceptions": [r["i"] for r in rows if r["status"] == "exception"],
                   "bad_failures": [r["i"] for r in rows if r.get("bad_failure")],
                   "message_format": [r["i"] for r in rows if r.get("message_format")]}
        if log:
            log.write(json.dumps({"summary": summary}, default=float) + "\n")
    finally:
        if log:
            log.close()
    with capsys.disabled():
        print(f"\n{text}\n{json.dumps({k: v for k, v in summary.items() if k != 'counts'})}")
    bad = {k: summary[k] for k in ("silent", "exceptions", "bad_failures") if summary[k]}
    assert not bad, bad


#: the paper's robot with unequal friction and its harmonic gait
PAPER = {"robot": {"M": 0.052, "L": 0.120, "beta": 2.0, "k": 0.1677, "mu1": 0.35, "mu2": 0.43,
                   "g": 9.81},
         "gait": {"gamma_deg": 90.0, "A_deg": 30.0, "psi_deg": 45.0}}


def test_the_checks_see_a_wrong_success():
    """The checks are not vacuous: a correct success passes them, the same result with a wrong
    friction force or a wrong S does not (event solver and angles drive)."""
    problem = problem_from_dict(PAPER)
    res = run_problem(problem)
    assert res.success and not event_violations(problem, res)
    bad = dataclasses.replace(res, f_t=1.01 * res.f_t)
    assert any(m.startswith("friction") for m in event_violations(problem, bad))
    bad = dataclasses.replace(res, S=1.001 * res.S)
    assert any("changes to" in m for m in event_violations(problem, bad))
    problem = problem_from_dict({**PAPER, "gait": {**PAPER["gait"], "drive": "angles"}})
    res = run_problem(problem)
    assert res.success and not angles_violations(problem, res)
    bad = dataclasses.replace(res, S=res.S + 1e-6, x1=res.x1 + 1e-6 * res.t,
                              x2=res.x2 + 1e-6 * res.t)
    assert any("angles_feet" in m for m in angles_violations(problem, bad))
