"""Scale invariance and the stiff limit.

The quasistatic crawler has one time-free force scale M g and one length scale L: with the body
ratio beta, the friction coefficients and the nondimensional stiffness k/(M g L) fixed, multiplying
M, L and g by any factors (and k by their product) must leave every nondimensional output unchanged:
S/L, CoT+, W+/(M g L), the event phases, the angles and f_t/(M g).  Checked to 1e-7 for several
gaits, both gravity conventions, the failures too (same status at the same phase), and the MPCC
solver.

Stiff limit: as k/(M g L) -> infinity the joints hold their reference angles, so the torque-driven
gait tends to the prescribed-angle gait (``gait.drive = "angles"``).  The angles then deviate from
the reference by O(M g L/k), so S(k) - S_angles = C L (M g L/k) + o(1/k): the test measures the
order of convergence over k/(M g L) = 1e2..1e8 and checks that every run succeeds.
"""
import math

import numpy as np
import pytest

from ocp_crawl import paper_problem, run_problem

#: factors (M, L, g) spanning 1e-3..1e3 in each, and a generic one
FACTORS = [(1e-3, 1e3, 1.0), (1e3, 1e-3, 1e-3), (1e3, 1e3, 1e3), (1e-3, 1e-3, 1e-3),
           (1.0, 1e-3, 1e3), (37.0, 0.02, 0.3)]
#: gaits (problem keys) of the invariance test: the paper's, a forward one, a wide-gamma one,
#: per-joint values with unequal friction, and the paper's gait prescribed (angles drive)
GAITS = {
    "paper": {},
    "forward": {"gait.gamma_deg": 70.0, "gait.A_deg": 40.0, "gait.psi_deg": -100.0},
    "wide": {"gait.gamma_deg": 110.0, "gait.A_deg": 20.0, "gait.psi_deg": 150.0},
    "per_joint": {"gait.gamma1_deg": 95.0, "gait.gamma2_deg": 80.0, "gait.A1_deg": 30.0,
                  "gait.A2_deg": 20.0, "gait.psi_deg": 60.0, "robot.mu1": 0.3, "robot.mu2": 0.5},
    "low_stiffness": {"robot.k": 0.03},
    "angles": {"gait.drive": "angles"},
}
TOL = 1e-7
#: output phases of the compared samples (fixed: the default grid adds the event phases, and two
#: events at one phase may be apart by round-off, adding a sample)
T_EVAL = np.linspace(0.0, 1.0, 201)


def scaled(problem, fM: float, fL: float, fg: float):
    """The problem with M, L, g multiplied by fM, fL, fg and k by fM fL fg (k/(M g L) unchanged)."""
    r = problem.robot
    return problem.with_values({"robot.M": r.M * fM, "robot.L": r.L * fL, "robot.g": r.g * fg,
                                "robot.k": r.k * fM * fL * fg})


def nondimensional(problem, res) -> dict:
    """The nondimensional outputs of a result: status, failure phase, S/L, CoT+, W+/(M g L), events,
    samples."""
    r = problem.robot
    # events as a set with their phases (two events at one phase, e.g. the reversal of d' and the
    # switch of the slipping foot of a mirror-symmetric gait, come in an order that round-off
    # decides)
    events = sorted((e.kind, e.mode_before, e.mode_after, e.t) for e in res.events)
    out = {"status": res.status_name, "failure_t": res.failure_t, "events": [e[:3] for e in events],
           "event_t": np.array([e[3] for e in events])}
    if res.success:
        out.update(S=res.S / r.L, CoT=res.CoT_plus, W=res.W_plus / r.MgL, phi=res.phi,
                   ft=res.f_t / (r.M * r.g), t=res.t, balance=res.energy["balance_residual"])
    return out


def assert_same(a: dict, b: dict, tol: float) -> None:
    assert a["status"] == b["status"] and a["events"] == b["events"]
    assert a["event_t"] == pytest.approx(b["event_t"], rel=0, abs=tol)
    if a["failure_t"] is not None:
        assert a["failure_t"] == pytest.approx(b["failure_t"], rel=0, abs=tol)
    if a["status"] != "success":
        return
    for name in ("S", "CoT", "W"):
        assert a[name] == pytest.approx(b[name], rel=tol, abs=1e-12), name
    assert a["t"] == pytest.approx(b["t"], rel=0, abs=tol)
    assert np.max(np.abs(a["phi"] - b["phi"])) <= tol
    assert np.max(np.abs(a["ft"] - b["ft"])) <= tol
    assert abs(a["balance"] - b["balance"]) <= tol


@pytest.mark.parametrize("gravity", ["physical", "paper"])
@pytest.mark.parametrize("gait", list(GAITS))
def test_rescaled_robot_gives_the_same_nondimensional_gait(gait, gravity):
    base = paper_problem().with_values({"model.gravity": gravity, **GAITS[gait]})
    ref = nondimensional(base, run_problem(base, T_EVAL))
    for f in FACTORS:
        p = scaled(base, *f)
        assert p.robot.k / p.robot.MgL == pytest.approx(base.robot.k / base.robot.MgL, rel=1e-14)
        assert_same(nondimensional(p, run_problem(p, T_EVAL)), ref, TOL)


def test_rescaling_covers_success_and_failure():
    """The invariance test above sees both outcomes (a failure must scale too: same status, same
    phase)."""
    statuses = {run_problem(paper_problem().with_values({"model.gravity": "physical",
                                                         **GAITS[g]})).status_name
                for g in GAITS}
    assert "success" in statuses and len(statuses) >= 2


@pytest.mark.slow
@pytest.mark.parametrize("gravity", ["physical", "paper"])
def test_rescaled_robot_mpcc(gravity):
    """The MPCC time-stepping (40 steps per cycle) is scale invariant too, to its solver
    tolerance."""
    base = paper_problem(["simulation.solver=mpcc", "simulation.steps=40",
                          f"model.gravity={gravity}"])
    ref = nondimensional(base, run_problem(base, T_EVAL))
    assert ref["status"] == "success"
    for f in FACTORS[:3]:
        p = scaled(base, *f)
        assert_same(nondimensional(p, run_problem(p, T_EVAL)), ref, TOL)


# ------------------------------------------------------------------------------------- stiff limit
STIFF_GAITS = {
    "paper": {},
    "forward": {"gait.gamma_deg": 80.0, "gait.A_deg": 35.0, "gait.psi_deg": -60.0},
    "wide": {"gait.gamma_deg": 110.0, "gait.A_deg": 20.0, "gait.psi_deg": 150.0},
}
RATIOS = 10.0 ** np.arange(2, 9)


def stiff_errors(problem) -> tuple[float, np.ndarray]:
    """(S_angles/L, (S(k) - S_angles)/L for k/(M g L) in RATIOS); every run must succeed."""
    r = problem.robot
    ang = run_problem(problem.with_values({"gait.drive": "angles"}))
    assert ang.success, ang.message
    err = []
    for ratio in RATIOS:
        res = run_problem(problem.with_values({"robot.k": ratio * r.MgL}))
        assert res.success, (ratio, res.message)
        err.append((res.S - ang.S) / r.L)
    return ang.S / r.L, np.array(err)


def test_paper_gait_stiff_limit_is_the_prescribed_gait():
    """k/(M g L) up to 1e8 (it failed with no_consistent_mode from 1e6): S -> -55.811 mm, the angles
    drive."""
    problem = paper_problem()
    s_ang, err = stiff_errors(problem)
    assert s_ang * problem.robot.L == pytest.approx(-55.811e-3, abs=5e-7)
    # k = 1e8 M g L: within 1e-8 mm of the prescribed gait
    assert abs(err[-1]) * problem.robot.L < 1e-11


@pytest.mark.parametrize("gravity", ["physical", "paper"])
@pytest.mark.parametrize("gait", list(STIFF_GAITS))
def test_stiff_limit_converges_at_first_order(gait, gravity):
    """(S(k) - S_angles)/L = C M g L/k + O((M g L/k)^2): the order measured between decades 1e2..1e6
    is 1 (to 1 %), and the scaled error (S(k) - S_angles)/L * k/(M g L) settles to C: within 1e-4 of
    C from 1e4 on, up to the round-off of S (~1e-13 L, which the factor k/(M g L) magnifies at 1e7,
    1e8)."""
    _, err = stiff_errors(paper_problem().with_values({"model.gravity": gravity,
                                                       **STIFF_GAITS[gait]}))
    assert np.all(err != 0.0)
    order = -np.diff(np.log10(np.abs(err[:5])))  # decades 1e2..1e6, well above round-off
    assert np.all(np.abs(order - 1.0) < 0.01), order
    C = err * RATIOS
    assert np.all(np.abs(C[2:] - C[4]) <= 1e-4 * abs(C[4]) + 1e-13 * RATIOS[2:]), C
    assert math.copysign(1.0, C[0]) == math.copysign(1.0, C[-1])
