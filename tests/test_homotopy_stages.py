"""The homotopy's stage solvers: every stage but the last is solved to a looser tolerance (it only
leads to the next one), the last stage and the polish to the tight one; checked on a relaxed
complementarity problem with a closed-form solution and on the gait OCP against the same solve
without loose stages."""
import math

import casadi as cs
import numpy as np
import pytest

from ocp_crawl import Robot
from ocp_crawl.model.inputs import Harmonic, ReferenceTorque
from ocp_crawl.nlp.homotopy import Homotopy, Solve, Start, schedule
from ocp_crawl.nlp.ipopt import OCP_IPOPT, OCP_WARM_IPOPT, call_ipopt, ipopt_solvers
from ocp_crawl.ocp import OCPSettings
from ocp_crawl.ocp.solver import GaitSolver
from ocp_crawl.ocp.transcription import GaitOCP

#: min (x - 1)^2 + (y - 1/2)^2 subject to x y <= sigma, x, y >= 0: for small sigma the solution is
#: x = 1 + O(sigma), y = sigma / x (the constraint active), whose KKT system gives x exactly below
TARGET = (1.0, 0.5)


def _relaxed_pair():
    z = cs.SX.sym("z", 2)
    return {"x": z, "f": (z[0] - TARGET[0]) ** 2 + (z[1] - TARGET[1]) ** 2, "g": z[0] * z[1]}


def _exact(sigma: float) -> tuple[float, float]:
    """The solution of the relaxed problem: y = sigma / x and stationarity along the curve,
    (x - 1) - (y - 1/2) sigma / x^2 = 0, solved by Newton's method (independent of IPOPT)."""
    x = 1.0
    for _ in range(50):
        y = sigma / x
        r = (x - TARGET[0]) - (y - TARGET[1]) * sigma / x**2
        dr = 1.0 + sigma**2 / x**4 + 2 * (y - TARGET[1]) * sigma / x**3
        x -= r / dr
    return x, sigma / x


def _homotopy(stage_tol):
    solvers = ipopt_solvers("pair", _relaxed_pair(), OCP_IPOPT, OCP_WARM_IPOPT, {}, "test",
                            stage_tol=stage_tol)
    used = []

    def call(solver, start: Start, data: dict) -> Solve:
        used.append(solver.name())
        args = dict(data, x0=start.x)
        if start.warm:
            args.update(lam_x0=start.lam_x, lam_g0=start.lam_g)
        return Solve.of(call_ipopt(solver, 2, 1, **args), comp=0.0)

    return solvers, Homotopy.of(solvers, call), used


def _data(sigma):
    return {"lbx": [0.0, 0.0], "ubx": [math.inf, math.inf], "lbg": [-math.inf], "ubg": [sigma]}


def test_intermediate_stages_use_the_stage_solvers_and_the_last_is_tight():
    solvers, hom, used = _homotopy(1e-3)
    sigmas = schedule(1e-1, 0.1, 1e-4)
    run = hom.relax(sigmas, Start(np.array([0.5, 0.5])), _data)
    assert run.ok and len(used) == len(sigmas) == 4
    assert used == ["pair_stage_cold", "pair_stage_warm", "pair_stage_warm", "pair_warm"]
    # the last stage is solved to the tight tolerance: its point is the closed-form solution at
    # sigma_min
    assert run.last.x == pytest.approx(_exact(1e-4), abs=1e-9)
    # a homotopy from a warm start (multipliers given) uses the warm stage solver first
    _, hom2, used2 = _homotopy(1e-3)
    hom2.relax(sigmas[2:], run.last.start(), _data)
    assert used2 == ["pair_stage_warm", "pair_warm"]


def test_loose_stage_is_loose():
    """The stage solver stops earlier than the tight one on the same stage (the test can fail: if
    the option were not passed, both would run to the same tolerance)."""
    solvers, hom, _ = _homotopy(1e-2)
    x0 = np.array([0.9, 0.2])  # on the branch of the solution x near 1
    loose = call_ipopt(solvers.stage_cold, 2, 1, x0=x0, **_data(1e-3))
    tight = call_ipopt(solvers.cold, 2, 1, x0=x0, **_data(1e-3))
    assert loose.usable and tight.usable and loose.iterations < tight.iterations
    assert tight.x == pytest.approx(_exact(1e-3), abs=1e-9)
    assert np.max(np.abs(loose.x - _exact(1e-3))) > 1e-9


@pytest.mark.parametrize("stage_tol", [None, 1e-12])
def test_no_stage_tolerance_means_the_same_solvers(stage_tol):
    """Without a stage tolerance looser than the solvers' own, the stage solvers are the cold and
    warm ones."""
    solvers, hom, used = _homotopy(stage_tol)
    assert solvers.stage_cold is solvers.cold and solvers.stage_warm is solvers.warm
    hom.relax(schedule(1e-1, 0.1, 1e-3), Start(np.array([0.5, 0.5])), _data)
    assert used == ["pair_cold", "pair_warm", "pair_warm"]


@pytest.mark.heavy
def test_gait_ocp_optimum_does_not_depend_on_the_stage_tolerance():
    """max_speed at N = 20: the loose first stage (default stage_tol) reaches the optimum of the
    homotopy with every stage solved to 1e-10, and its first stage takes fewer IPOPT iterations.
    "The optimum" to the spread of neighbouring branches: both end complementary, possibly on
    branches whose contact modes differ in a sub-step or two (measured: sub-steps 32 and 36, speeds
    1.2e-6 apart), far below replay_tol."""
    robot = Robot.paper()
    sig = ReferenceTorque(Harmonic.from_degrees(90.0, 30.0, 45.0), robot.k)
    out = {}
    for tol in (OCPSettings().stage_tol, 1e-10):
        st = OCPSettings(objective="max_speed", nodes=20, starts=1, stage_tol=tol)
        ocp = GaitOCP(robot, "physical", st)
        x0 = ocp.initial_guess(sig, st.min_period(30.0, 30.0))
        x, hist, failed, _ = GaitSolver(ocp).solve(x0)
        assert failed is None
        out[tol] = (ocp.unpack(x)["scen"][0]["v"], hist[0].iterations)
    (v_loose, it_loose), (v_tight, it_tight) = out.values()
    assert v_loose == pytest.approx(v_tight, rel=1e-5)
    assert it_loose < it_tight


def test_loose_last_stage_then_tighten():
    """With ``loose_last`` every stage uses the stage solvers, so the last point is only near the
    solution; ``tighten`` solves that stage again with the tight warm solver, to the closed-form
    solution."""
    solvers, hom, used = _homotopy(1e-3)
    sigmas = schedule(1e-1, 0.1, 1e-3)
    run = hom.relax(sigmas, Start(np.array([0.5, 0.5])), _data, loose_last=True)
    assert run.ok and used == ["pair_stage_cold", "pair_stage_warm", "pair_stage_warm"]
    # loose: not the solution to the tight tolerance
    assert np.max(np.abs(run.last.x - _exact(1e-3))) > 1e-9
    sol = hom.tighten(run.last, sigmas[-1], _data(sigmas[-1]))
    assert (used[-1] == "pair_warm" and hom.records[-1].kind == "homotopy"
            and hom.records[-1].sigma == sigmas[-1])
    assert sol.x == pytest.approx(_exact(1e-3), abs=1e-9)


@pytest.mark.slow
def test_gait_ocp_loose_last_stage_from_an_optimum_stays_there(monkeypatch):
    """max_speed at N = 16: from the optimum's own profile (as the convergence run's warm solves
    start), the solve with ``loose_last`` returns to the same optimum; and when the polish from the
    loose last stage fails (here: no candidate offered), that stage is solved again tightly and
    polished."""
    from ocp_crawl.ocp.judge import replay_signal

    robot = Robot.paper()
    sig = ReferenceTorque(Harmonic.from_degrees(90.0, 30.0, 45.0), robot.k)
    st = OCPSettings(objective="max_speed", nodes=16, starts=1)
    ocp = GaitOCP(robot, "physical", st)
    x, _, failed, _ = GaitSolver(ocp).solve(ocp.initial_guess(sig, st.min_period(30.0, 30.0)))
    assert failed is None
    best = ocp.unpack(x)
    near = replay_signal(np.arange(16) / 16, best["tau"])
    loose = GaitOCP(robot, "physical",
                    OCPSettings(objective="max_speed", nodes=16, starts=1, loose_last=True,
                                stage_tol=st.sigma_min))
    x, hist, failed, _ = GaitSolver(loose).solve(loose.initial_guess(near, best["T"]))
    kinds = [h.kind for h in hist]
    assert failed is None and kinds[:3] == ["homotopy", "homotopy",
                                            "polish"] and "homotopy" not in kinds[3:]
    assert hist[-1].accepted
    # the same local optimum (others differ by percents); 1e-5: the polishes end at IPOPT's
    # acceptable level
    assert loose.unpack(x)["scen"][0]["v"] == pytest.approx(best["scen"][0]["v"], rel=1e-5)
    calls = []
    candidates = GaitSolver._polish_candidates
    monkeypatch.setattr(GaitSolver, "_polish_candidates",
                        lambda self, x: [] if not calls.append(1) and len(calls) == 1
                        else candidates(self, x))
    x, hist, failed, _ = GaitSolver(loose).solve(loose.initial_guess(near, best["T"]))
    kinds = [h.kind for h in hist]
    assert failed is None and kinds[:4] == ["homotopy", "homotopy", "homotopy", "polish"]
    assert hist[2].sigma == st.sigma_min and hist[-1].accepted and "homotopy" not in kinds[4:]
    assert loose.unpack(x)["scen"][0]["v"] == pytest.approx(best["scen"][0]["v"], rel=1e-5)


def test_loose_pairs_at_other_tolerances_are_built_once_and_named_validly():
    """``Solvers.loose(tol)``: a working (cold, warm) pair per tolerance, kept; the tight pair when
    tol is not looser than the solvers' own; and a homotopy with ``loose_at`` uses the pair of each
    stage's sigma."""
    solvers, base, used = _homotopy(1e-3)
    a, b = solvers.loose(1e-5), solvers.loose(1e-6)
    assert a is solvers.loose(1e-5) and a != b and solvers.loose(1e-12) == (solvers.cold,
                                                                            solvers.warm)
    assert solvers.loose(1e-3) == (solvers.stage_cold, solvers.stage_warm)
    # a sigma from repeated products (1e-9 = 1e-3 0.1^6 carries rounding noise): the same pair, or
    # the tight one
    assert (solvers.loose(1e-5 * (1 + 1e-15)) is a
            and solvers.loose(1e-10 * (1 + 1e-15)) == (solvers.cold, solvers.warm))
    hom = Homotopy.of(solvers, base.call, loose_at=lambda sigma: solvers.loose(sigma / 10))
    run = hom.relax(schedule(1e-3, 0.1, 1e-5), Start(np.array([0.5, 0.5])), _data)
    assert run.ok and used == [solvers.loose(1e-4)[0].name(), a[1].name(), "pair_warm"]
    assert len(set(used)) == 3 and run.last.x == pytest.approx(_exact(1e-5), abs=1e-9)


@pytest.mark.heavy
def test_deep_homotopy_ends_complementary_without_a_polish():
    """max_speed at N = 20 down to sigma = 1e-11 (stages to a tenth of their sigma): the last point
    is within comp_tol, so no polish runs, and it is the optimum that the default path reaches
    through its polish."""
    robot = Robot.paper()
    sig = ReferenceTorque(Harmonic.from_degrees(90.0, 30.0, 45.0), robot.k)
    v = {}
    for deep in (False, True):
        extra = dict(sigma0=1e-3, sigma_factor=0.1, sigma_min=1e-11,
                     stage_tol_ratio=0.1) if deep else {}
        st = OCPSettings(objective="max_speed", nodes=20, starts=1, **extra)
        ocp = GaitOCP(robot, "physical", st)
        x0 = ocp.initial_guess(sig, st.min_period(30.0, 30.0))
        x, hist, failed, _ = GaitSolver(ocp).solve(x0)
        assert failed is None and hist[-1].accepted
        assert (hist[-1].kind == "homotopy") == deep and (hist[-1].sigma == 1e-11) == deep
        sc = ocp.unpack(x)["scen"][0]
        assert sc["comp"] <= st.comp_tol
        v[deep] = sc["v"]
    assert v[True] == pytest.approx(v[False], rel=1e-5)


def test_polish_uses_the_tight_warm_solver():
    solvers, hom, used = _homotopy(1e-3)
    run = hom.relax(schedule(1e-1, 0.1, 1e-3), Start(np.array([0.5, 0.5])), _data)
    # the tightened NLP: y on its branch (y = 0), x free
    pol = hom.polish(run.last,
                     [dict(_data(0.0), ubx=[math.inf, 0.0],
                           x0=np.minimum(run.last.x, [math.inf, 0.0]))],
                     lambda p: True)
    assert used[-1] == "pair_warm" and pol is not None
    # the exact solution of the unrelaxed problem
    assert pol.x == pytest.approx([TARGET[0], 0.0], abs=1e-9)


@pytest.mark.parametrize("user_tol,loose", [(1e-3, False), (1e-4, False), (1e-6, True)])
def test_user_tolerance_at_or_above_the_stage_tolerance_means_no_loose_stages(user_tol, loose):
    solvers = ipopt_solvers("pair", _relaxed_pair(), OCP_IPOPT, OCP_WARM_IPOPT, {"tol": user_tol},
                            "test", stage_tol=1e-4)
    assert (solvers.stage_cold is not solvers.cold) == loose
    assert (solvers.stage_warm is not solvers.warm) == loose


class _Fake:
    """A stand-in solver: the homotopy only hands it to ``call``."""

    def __init__(self, name):
        self.name = name


def _fake_call(used):
    def call(solver, start, data):
        used.append(solver.name)
        return Solve(np.zeros(2), np.zeros(2), np.zeros(1), "Solve_Succeeded", True, 1, comp=0.0)
    return call


@pytest.mark.parametrize("stage_solvers", [False, True])
def test_done_ends_the_homotopy_only_without_stage_solvers(stage_solvers):
    """``done`` true after every stage: without stage solvers (the MPCC step) the homotopy ends
    after its first stage, as before; with them a loose stage never ends it (its point is not an
    answer)."""
    used = []
    extra = (_Fake("stage_cold"), _Fake("stage_warm")) if stage_solvers else (None, None)
    hom = Homotopy(_Fake("cold"), _Fake("warm"), _fake_call(used), [], *extra)
    run = hom.relax((1e-2, 1e-3, 1e-4), Start(np.zeros(2)), lambda s: {}, done=lambda sol: True)
    assert run.ok
    assert used == (["stage_cold", "stage_warm", "warm"] if stage_solvers else ["cold"])
