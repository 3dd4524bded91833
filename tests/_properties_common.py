"""Shared by the property-based tests (hypothesis) of the prescribed-angle simulator, the input
signals and the problem files (tests/test_properties_prescribed.py, test_properties_signals.py and
test_properties_problem_files.py): the example settings, the strategies more than one of them draws
from, and the independent checks of a prescribed-angle result.

The number of examples per property comes from ``OCP_CRAWL_HYPOTHESIS_EXAMPLES``; without it, a
fixed set: 10 for the properties that simulate, 100 for the cheap ones.
"""
from __future__ import annotations

import json
import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, event, note, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from ocp_crawl import Mode, Model, Status
from ocp_crawl.sim.angles import TIE, simulate_angles
from ocp_crawl.status import STATUS_MESSAGES

EXAMPLES = int(os.environ.get("OCP_CRAWL_HYPOTHESIS_EXAMPLES", "25"))
#: expensive properties (one or more simulations per example)
#: (a small fixed set by default, as docs/benchmarks.md says, so that CI is deterministic; random
#: with the variable set)
DERANDOMIZE = "OCP_CRAWL_HYPOTHESIS_EXAMPLES" not in os.environ
SIMS = settings(max_examples=EXAMPLES if not DERANDOMIZE else 10, deadline=None,
                derandomize=DERANDOMIZE,
                suppress_health_check=[HealthCheck.too_slow])
#: cheap properties (microseconds to milliseconds per example) get more examples for the same time
CHEAP = settings(max_examples=4 * EXAMPLES, deadline=None, derandomize=DERANDOMIZE,
                 suppress_health_check=[HealthCheck.too_slow])


# ============================================================================================
# strategies: joint angles, knots, non-finite numbers
# ============================================================================================
gammas = st.floats(40.0, 175.0)  # nominal joint angle [deg]; pi = flat, legs down below it
amplitudes = st.floats(0.0, 50.0)  # [deg]


@st.composite
def knots(draw, n_min=3, n_max=9):
    """Strictly increasing knots in [0, 1), spacing at least 1/25 of a cycle."""
    n = draw(st.integers(n_min, n_max))
    w = np.array([draw(st.floats(0.2, 1.0)) for _ in range(n)])
    total = w.sum()
    t = np.concatenate([[0.0], np.cumsum(w[:-1])]) / total
    t0 = draw(st.floats(0.0, 0.999)) * w[-1] / total
    return t + t0


BAD_NUMBERS = st.sampled_from([math.nan, math.inf, -math.inf])


# ============================================================================================
# independent checks of a prescribed-angle result
# ============================================================================================
GUARDS = ("d", "fn1", "fn2", "zj1", "zj2")
#: fine grid for the independent checks (not a multiple of the simulator's scan of 512 phases)
FINE = 3000


def guard_scales(robot):
    return {"d": robot.L, "fn1": robot.M * robot.g, "fn2": robot.M * robot.g, "zj1": robot.L,
            "zj2": robot.L}


def valid_config(kin) -> np.ndarray:
    return np.all([kin[n] > 0 for n in GUARDS], axis=0)


def run_prescribed(model: Model, angles):
    """simulate_angles, or None when the input is rejected up front; a rejection must be
    justified."""
    try:
        return simulate_angles(model, angles)
    except ValueError as exc:
        msg = str(exc)
        assert "\n" not in msg and msg.startswith("prescribed configuration at t = 0:"), msg
        # documented rejection: the start configuration has a foot off the ground, a joint on it, or
        # d <= 0
        assert not valid_config(model.kinematics(angles(0.0))), msg
        event("rejected: no valid start configuration")
        return None


def slip_weight(model: Model, kin) -> np.ndarray:
    """Share of d' taken by foot 1: 1 if its friction limit is the smaller, 0 if foot 2's, 1/2 for a
    tie."""
    r = model.robot
    h = (r.mu1 * kin["fn1"] - r.mu2 * kin["fn2"]) / (r.M * r.g)
    return np.where(np.abs(h) <= TIE, 0.5, np.where(h < 0, 1.0, 0.0))


def displacement_oracle(model: Model, angles, n: int = FINE) -> tuple[float, float]:
    """S = -integral of w dd (foot 1 moves by -dd when it slips) on a fine grid, and its error
    bound:
    |dd| of every interval in which the slipping foot changes (elsewhere the sum is exact)."""
    t = np.linspace(0.0, 1.0, 2 * n + 1)
    kin = model.kinematics(angles(t))
    w = slip_weight(model, kin)
    d = kin["d"]
    dd = d[2::2] - d[:-2:2]
    wm = w[1::2]
    switching = (w[:-2:2] != wm) | (w[2::2] != wm)
    return -float(np.sum(wm * dd)), float(np.sum(np.abs(dd[switching])))


def dissipation_oracle(model: Model, angles, n: int = FINE) -> tuple[float, float]:
    """Integral over the cycle of min(mu1 f_n1, mu2 f_n2) |d'| by Gauss-Legendre panels between
    the kinks (d' = 0, equal friction limits, knots of a sampled input) located here; the error
    estimate is the change from halving the panels."""
    r = model.robot

    def parts(t):
        t = np.atleast_1d(t)
        kin = model.kinematics(angles(t))
        dphi = angles.derivative(t).reshape(2, -1)
        ddot = kin["grad_d1"] * dphi[0] + kin["grad_d2"] * dphi[1]
        h = r.mu1 * kin["fn1"] - r.mu2 * kin["fn2"]
        return ddot, h, np.minimum(r.mu1 * kin["fn1"], r.mu2 * kin["fn2"]) * np.abs(ddot)

    t = np.linspace(0.0, 1.0, n + 1)
    ddot, h, _ = parts(t)
    kinks = list(np.asarray(getattr(angles, "t_knots", ()), float))
    for v, i in ((ddot, 0), (h, 1)):
        for j in np.nonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0)[0]:
            kinks.append(brentq(lambda x: float(parts(x)[i][0]), t[j], t[j + 1], xtol=1e-15))
    edges = np.unique(np.concatenate([[0.0, 1.0], np.clip(kinks, 0.0, 1.0)]))

    def gauss(refine):
        # panels of at most 1/64 cycle, their count times ``refine`` (a piece shorter than a panel
        # gets 1 and 2 panels: with a width halved instead it would keep one, and a zero estimate)
        x, w = np.polynomial.legendre.leggauss(8)
        nodes, weights = [], []
        for lo, hi in zip(edges[:-1], edges[1:]):
            e = np.linspace(lo, hi, refine * max(1, int(np.ceil((hi - lo) * 64))) + 1)
            mid, half = 0.5 * (e[1:] + e[:-1])[:, None], 0.5 * (e[1:] - e[:-1])[:, None]
            nodes.append((mid + half * x).ravel())
            weights.append((half * w).ravel())
        return float(np.sum(np.concatenate(weights) * parts(np.concatenate(nodes))[2]))

    coarse, fine = gauss(1), gauss(2)
    return fine, abs(fine - coarse)


def check_success(model: Model, angles, res) -> None:
    """Every property of a successful prescribed-angle run (each part below), against the model and
    oracles."""
    _check_outputs(model, angles, res)
    _check_contact(model, angles, res)
    _check_friction(model, angles, res)
    _check_feet(model, angles, res)
    _check_energy(model, angles, res)


def _check_outputs(model: Model, angles, res) -> None:
    """Shapes, finite values, output phases and the prescribed angles."""
    n = res.t.size
    # shapes and no NaN anywhere
    assert res.success and res.status == Status.SUCCESS and res.message
    assert res.phi.shape == (2, n) and res.tau.shape == (2, n)
    for name in ("theta", "d", "x1", "x2", "f_t", "f_n1", "f_n2", "mode"):
        assert getattr(res, name).shape == (n,), name
    for name, arr in res.arrays().items():
        assert np.all(np.isfinite(arr)), name
    for name in ("S", "W_plus", "periodicity_residual"):
        assert math.isfinite(getattr(res, name)), name
    assert np.all(np.isfinite(res.W_plus_joint))
    assert all(v is None or math.isfinite(v) for v in res.summary()["energy"].values())
    assert set(res.energy) >= {"input_work", "potential_change", "dissipation", "balance_residual"}
    assert all(math.isfinite(v) for v in res.energy.values())
    # the default output phases cover the cycle, switching instants included
    assert res.t[0] == 0.0 and res.t[-1] == 1.0 and np.all(np.diff(res.t) > 0)
    for ev in res.events:
        assert ev.kind in EVENT_KINDS and 0 <= ev.t <= 1
        assert np.min(np.abs(res.t - ev.t)) == 0.0
    # the angles are the prescribed ones
    np.testing.assert_allclose(res.phi, angles(res.t), rtol=0, atol=1e-14)


def _check_contact(model: Model, angles, res) -> None:
    """Contact and joint equilibrium at the samples and on a fine grid."""
    r = model.robot
    Mg, L = r.M * r.g, r.L
    torque_scale = r.MgL + r.k
    kin = model.kinematics(res.phi)
    # contact: positive normal forces, joints above the ground, feet apart, at the samples ...
    for name in GUARDS:
        assert np.all(kin[name] > 0), name
    np.testing.assert_allclose(res.f_n1, kin["fn1"], rtol=1e-13, atol=1e-13 * Mg)
    np.testing.assert_allclose(res.d, kin["d"], rtol=1e-13, atol=1e-13 * L)
    # ... and on a fine grid of the whole cycle (a loss of contact between the scan phases is a
    # failure)
    fine = model.kinematics(angles(np.linspace(0.0, 1.0, FINE + 1)))
    for name in GUARDS:
        assert np.min(fine[name]) > 0, \
            f"{name} reaches {np.min(fine[name]):.3g} although the run succeeded"
    # joint equilibrium with the holding torques, residual relative to the torque scale
    for j in range(res.t.size):
        F = model.equilibrium_residual(res.phi[:, j], res.tau[:, j], res.f_t[j])
        assert np.max(np.abs(F)) <= 1e-11 * torque_scale, (j, F)


def _check_friction(model: Model, angles, res) -> None:
    """Coulomb's law: the friction limits, the slipping foot, friction opposing the slip."""
    r = model.robot
    Mg, L = r.M * r.g, r.L
    n = res.t.size
    # Coulomb: |f_t| on the friction limit of the slipping foot, which is the smaller limit
    lim1, lim2 = r.mu1 * res.f_n1, r.mu2 * res.f_n2
    # (with both feet slipping, |mu1 f_n1 - mu2 f_n2| <= TIE M g: a tie in the model's definition)
    tie = np.array([Mode(int(m)).foot == 3 for m in res.mode])
    tol = 1e-12 * np.maximum(Mg, np.maximum(lim1, lim2)) + np.where(tie, TIE * Mg, 0.0)
    assert np.all(np.abs(res.f_t) <= np.minimum(lim1, lim2) + tol)
    modes = [Mode(int(m)) for m in res.mode]
    slip = np.array([m.foot != 0 for m in modes])
    slip_lim = np.array([lim1[j] if m.foot in (1, 3) else lim2[j] for j, m in enumerate(modes)])
    assert np.all(np.abs(np.abs(res.f_t[slip]) - slip_lim[slip])
                  <= 1e-12 * np.maximum(Mg, slip_lim[slip]))
    # friction opposes the slip: f_t d' >= 0, d' from central differences of the kinematics
    h = 1e-7
    ddot = (model.kinematics(angles(res.t + h))["d"]
            - model.kinematics(angles(res.t - h))["d"]) / (2 * h)
    smooth = np.ones(n, bool)
    # the derivative of a sampled input may jump at its knots
    for knot in getattr(angles, "t_knots", ()):
        smooth &= np.abs((res.t - knot + 0.5) % 1.0 - 0.5) > 2 * h
    clear = smooth & (np.abs(ddot) > 1e-5 * L * (1 + np.max(np.abs(ddot)) / L))
    sig = np.array([m.sigma for m in modes])
    assert np.all(sig[clear] == np.sign(ddot[clear]))
    # stick-stick only where the angles hold still (d' = 0 on a stretch)
    assert np.all(np.abs(ddot[~slip & smooth]) <= 1e-6 * L)
    assert np.all(res.f_t[clear] * ddot[clear] >= 0)


def _check_feet(model: Model, angles, res) -> None:
    """The feet's positions, periodicity and S against an independent integration."""
    L = model.robot.L
    n = res.t.size
    modes = [Mode(int(m)) for m in res.mode]
    # feet: x2 - x1 = d; the sticking foot stays; both feet advance by S over the cycle (periodic)
    np.testing.assert_allclose(res.x2 - res.x1, res.d, rtol=0, atol=1e-12 * L)
    assert res.d[-1] == pytest.approx(res.d[0], abs=1e-12 * L)
    assert res.x1[-1] - res.x1[0] == pytest.approx(res.S, abs=1e-12 * L)
    assert res.x2[-1] - res.x2[0] == pytest.approx(res.S, abs=1e-12 * L)
    for j in range(n - 1):
        if res.mode[j] == res.mode[j + 1] and modes[j].foot in (0, 1, 2):
            for stuck in [(res.x1, res.x2)[i] for i in (0, 1) if modes[j].foot != i + 1]:
                assert stuck[j + 1] == stuck[j]
    assert res.periodicity_residual <= 1e-12
    np.testing.assert_allclose(angles(1.0), angles(0.0), rtol=0, atol=1e-12)
    # S against an independent integration of the slipping foot's motion
    S, bound = displacement_oracle(model, angles)
    assert abs(res.S - S) <= bound + 1e-10 * L, (res.S, S, bound)


def _check_energy(model: Model, angles, res) -> None:
    """The energy balance per cycle, W+ and the cost of transport."""
    r = model.robot
    Mg, L = r.M * r.g, r.L
    torque_scale = r.MgL + r.k
    # energy per cycle: W_in = Delta V + dissipation, Delta V = 0 (periodic), W+ >= W_in
    e = res.energy
    scale = max(abs(e["input_work"]), e["dissipation"], e["gross_work"], 1e-12 * r.MgL, 1e-300)
    assert e["gross_work"] >= abs(e["input_work"]) * (1 - 1e-12)
    assert abs(e["balance_residual"]) <= 1e-9, e
    assert e["balance_residual"] == pytest.approx(
        (e["input_work"] - e["potential_change"] - e["dissipation"]) / scale, rel=1e-9, abs=1e-15)
    assert abs(e["potential_change"]) <= 1e-12 * torque_scale
    assert e["dissipation"] >= 0
    assert np.all(res.W_plus_joint >= -1e-12 * scale)
    assert res.W_plus == pytest.approx(float(np.sum(res.W_plus_joint)), rel=1e-12, abs=1e-300)
    assert res.W_plus >= e["input_work"] - 1e-9 * scale
    diss, err = dissipation_oracle(model, angles)
    assert e["dissipation"] == pytest.approx(diss, rel=1e-9, abs=10 * err + 1e-12 * r.M * r.g * r.L)
    # cost of transport
    if abs(res.S) > 1e-12 * L:
        assert res.CoT_plus == pytest.approx(res.W_plus / (Mg * abs(res.S)), rel=1e-12)
    else:
        assert res.CoT_plus == math.inf


EVENT_KINDS = ("slip_reversal", "slip_switch", "slip_to_stick", "slip_onset_1", "slip_onset_2",
               "slip_onset_both")
FAILURE_KINDS = {Status.LIFT_OFF: ("lift_off_1", "lift_off_2"),
                 Status.FEET_CROSSED: ("feet_crossed",),
                 Status.JOINT_ON_GROUND: ("joint_1_on_ground", "joint_2_on_ground")}


def check_failure(model: Model, angles, res) -> None:
    r = model.robot
    status = Status(res.status)
    assert not res.success and status in FAILURE_KINDS
    assert res.message.startswith(STATUS_MESSAGES[status]) and "phase" in res.message
    assert "\n" not in res.message
    tf = res.failure_t
    assert tf is not None and 0 < tf <= 1 and math.isfinite(tf)
    assert res.failure_mode in {m.label for m in Mode}
    kind = res.events[-1].kind
    assert kind in FAILURE_KINDS[status] and res.events[-1].t == tf
    json.dumps(res.summary(), allow_nan=False)  # a failure's summary is valid JSON too
    # the reported failure is real: its guard vanishes at the failure phase ...
    kin = model.kinematics(angles(tf))
    sc = guard_scales(r)
    if status == Status.LIFT_OFF:
        i = kind[-1]
        assert abs(kin[f"fn{i}"]) <= 1e-8 * sc["fn1"], kin[f"fn{i}"]
    elif status == Status.JOINT_ON_GROUND:
        i = kind.split("_")[1]
        assert abs(kin[f"zj{i}"]) <= 1e-8 * r.L, kin[f"zj{i}"]
    else:
        assert abs(kin["d"]) <= 1e-6 * r.L, kin["d"]
    # ... and it is the first one: the configuration is valid at every phase before it
    before = np.linspace(0.0, tf, FINE + 1)[:-1]
    before = before[before < tf - 1e-6]
    assert np.all(valid_config(model.kinematics(angles(before))))


def check_outcome(model: Model, angles, res) -> str:
    """Check a result (None: rejected input) and return its outcome name."""
    if res is None:
        return "rejected"
    note(repr(res))
    if res.success:
        check_success(model, angles, res)
    else:
        check_failure(model, angles, res)
    event(f"status: {res.status_name}")
    return res.status_name
