"""One table of IPOPT return statuses, and real (not mocked) IPOPT failures of the MPCC step, the
MPCC time-stepping, the CLI and the gait OCP, each reported through that table."""
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from ocp_crawl import CallableSignal, Model, Robot, Status
from ocp_crawl.sim.event import HybridStepper
from ocp_crawl.nlp.ipopt import (FAILURE_KINDS, IPOPT_RETURN_STATUS, SolverOutcome, call_ipopt,
                                 ipopt_status)
from ocp_crawl.ocp import GaitOCP, GaitSolver, OCPSettings, optimize_gait
from ocp_crawl.sim.mpcc import MPCCOptions, MPCCStep
from ocp_crawl.sim.step import RESULT_FIELDS, StepState
from ocp_crawl.sim.oracle import solve_step_enumerate
from ocp_crawl.sim.timestepping import simulate_mpcc

from conftest import paper_torque

PACKAGE = Path(__file__).resolve().parents[1] / "ocp_crawl"

#: Every value of IPOPT's ``enum ApplicationReturnStatus`` (IPOPT 3.14), transcribed from IPOPT's
#: documentation: https://coin-or.github.io/Ipopt/IpReturnCodes__inc_8h.html
#: (src/Interfaces/IpReturnCodes_inc.h); CasADi reports them by these names in
#: ``solver.stats()['return_status']``.
IPOPT_DOCUMENTED = {
    "Solve_Succeeded": 0, "Solved_To_Acceptable_Level": 1, "Infeasible_Problem_Detected": 2,
    "Search_Direction_Becomes_Too_Small": 3, "Diverging_Iterates": 4, "User_Requested_Stop": 5,
    "Feasible_Point_Found": 6, "Maximum_Iterations_Exceeded": -1, "Restoration_Failed": -2,
    "Error_In_Step_Computation": -3, "Maximum_CpuTime_Exceeded": -4,
    "Maximum_WallTime_Exceeded": -5,
    "Not_Enough_Degrees_Of_Freedom": -10, "Invalid_Problem_Definition": -11, "Invalid_Option": -12,
    "Invalid_Number_Detected": -13, "Unrecoverable_Exception": -100,
    "NonIpopt_Exception_Thrown": -101, "Insufficient_Memory": -102, "Internal_Error": -199,
}
#: IPOPT's own documentation counts these as solutions (codes 0, 1 and 6, "Optimal Solution Found",
#: "Solved To Acceptable Level", "Feasible point for square problem found")
IPOPT_SOLUTIONS = {"Solve_Succeeded", "Solved_To_Acceptable_Level", "Feasible_Point_Found"}


# ---------------------------------------------------------------------------------------- the table
def test_table_covers_every_documented_ipopt_status():
    missing = set(IPOPT_DOCUMENTED) - set(IPOPT_RETURN_STATUS)
    assert not missing, f"IPOPT statuses missing from the table: {sorted(missing)}"
    for status in IPOPT_DOCUMENTED:
        out = ipopt_status(status)
        assert out.status == status and out.source == "ipopt"
        assert out.usable is (status in IPOPT_SOLUTIONS), status
        assert out.kind in (("success", "acceptable") if out.usable
                            else tuple(FAILURE_KINDS)), status


def test_every_table_entry_is_complete():
    assert len(IPOPT_RETURN_STATUS) >= len(IPOPT_DOCUMENTED)
    for name, out in IPOPT_RETURN_STATUS.items():
        assert isinstance(out, SolverOutcome) and out.status == name
        assert isinstance(out.usable, bool) and len(out.message) > 10 and "\n" not in out.message
        assert out.kind in ("success", "acceptable", *FAILURE_KINDS), name
        assert out.usable == (out.kind in ("success", "acceptable")), name
        # entries that are not IPOPT's are marked as CasADi's or this package's
        assert out.source in (("ipopt",) if name in IPOPT_DOCUMENTED
                              else ("casadi", "ocp_crawl")), name
        assert name in out.describe() and out.message in out.describe()
    # CasADi's own: its name for an unknown IPOPT code, and an exception raised by the solver call
    assert (ipopt_status("Unknown").usable is False
            and ipopt_status("Solver_Exception").usable is False)
    assert ipopt_status("Infeasible_Problem_Detected").kind == "infeasible"


@pytest.mark.parametrize("status", ["Some_New_Status", "", "solve_succeeded", None, 3])
def test_a_status_not_in_the_table_is_a_documented_failure(status):
    out = ipopt_status(status)
    assert out.usable is False and out.kind == "unknown" and out.kind in FAILURE_KINDS
    assert repr(str(status)) in out.message and "not in the table" in out.message


def test_solvers_read_outcomes_only_through_the_table():
    """No module but nlp/ipopt.py calls nlpsol or reads solver stats, and no module compares status
    strings."""
    statuses = "|".join(IPOPT_DOCUMENTED)
    for path in sorted(PACKAGE.rglob("*.py")):
        src = path.read_text()
        if path.relative_to(PACKAGE).as_posix() == "nlp/ipopt.py":
            # one nlpsol (build_ipopt) and one stats() (call_ipopt)
            assert len(re.findall(r"cs\.nlpsol\(", src)) == 1 and len(re.findall(r"\.stats\(\)",
                                                                                 src)) == 1
            continue
        # no solver built or its stats (e.g. stats()["success"]) read elsewhere, no status compared
        # by hand
        assert not re.search(r"\bnlpsol\(|\.stats\(\)|return_status\s*[!=]=", src), path
        assert not re.search(rf"[\"']({statuses})[\"']",
                             src), f"{path.name} compares an IPOPT status string"


# ---------------------------------------------------------------------------------------- MPCC step
def released(model, torque) -> StepState:
    start = HybridStepper(model, torque).initial_state(0.0)
    return StepState(start.x[:2], 0.0, float(model.kinematics(start.x[:2])["d"]), 0.0)


def assert_failed_step(res, status):
    """A failed step: the table's status and meaning in the message, no number that could pass for a
    solution."""
    assert not res.success and res.status == status, res.message
    out = ipopt_status(res.status)
    assert not out.usable and status in res.message and out.message in res.message
    assert np.all(np.isnan(res.phi)) and all(math.isnan(getattr(res, f)) for f in RESULT_FIELDS)
    assert res.w is None and res.homotopy and not res.homotopy[-1].accepted


@pytest.mark.parametrize("ipopt,status", [
    ({"max_iter": 1}, "Maximum_Iterations_Exceeded"),
    ({"max_cpu_time": 1e-9}, "Maximum_CpuTime_Exceeded"),
    ({"max_wall_time": 1e-9}, "Maximum_WallTime_Exceeded"),
], ids=["max_iter", "cpu_time", "wall_time"])
def test_step_resource_limits_are_failures(paper_robot, ipopt, status):
    model = Model(paper_robot)
    torque = paper_torque(paper_robot)
    res = MPCCStep(model, MPCCOptions(ipopt=ipopt)).solve(released(model, torque), torque(0.01))
    assert_failed_step(res, status)
    assert ipopt_status(status).kind == "limit"
    # every attempt ran into the same limit: cold start, non-monotone sigma, and both of the
    # fallback formulation
    assert res.attempts == 4 and {s.attempt for s in res.homotopy} == {0, 1, 2, 3}
    assert ({s.return_status for s in res.homotopy} == {status}
            and "fallback l1_penalty" in res.message)
    # the same step without the limit is solved
    assert MPCCStep(model).solve(released(model, torque), torque(0.01)).success


def test_step_that_would_lift_a_foot_is_infeasible():
    """A torque that pulls foot 2 off the ground: IPOPT reports infeasibility, and the
    mode-enumeration oracle confirms that every contact-mode equilibrium has a normal force <= 0."""
    robot = Robot.paper().with_stiffness_ratio(10.0)
    model = Model(robot, gravity="physical")
    torque = paper_torque(robot, A=60)
    state = released(model, torque)
    res = MPCCStep(model).solve(state, torque(0.7))
    assert_failed_step(res, "Infeasible_Problem_Detected")
    oracle = solve_step_enumerate(model, state, torque(0.7))
    assert not oracle.success and oracle.extra["lift_off"] and np.all(np.isnan(oracle.phi))
    assert ipopt_status(oracle.status).kind == "no_solution"


def test_unavailable_linear_solver_is_invalid_option(paper_robot):
    """IPOPT accepts the option name but cannot load the HSL solver at solve time:
    Invalid_Option."""
    model = Model(paper_robot)
    torque = paper_torque(paper_robot)
    res = MPCCStep(model, MPCCOptions(ipopt={"linear_solver": "ma86"}, max_retries=0)).solve(
        released(model, torque), torque(0.01))
    if res.success:
        pytest.skip("an HSL library is installed: ma86 is available")
    assert_failed_step(res, "Invalid_Option")


def test_nan_reaches_ipopt_as_invalid_number(paper_robot):
    """A NaN parameter (here the scaled torque) in the real step NLP: IPOPT stops with
    Invalid_Number_Detected, which the table and the step's call wrapper mark as unusable."""
    model = Model(paper_robot)
    torque = paper_torque(paper_robot)
    step = MPCCStep(model)
    state = released(model, torque)
    tau = np.asarray(torque(0.01), float)
    P = step._params(state, tau, 1e-2)
    P[2] = np.nan
    w0 = step.initial_guess(state, tau)
    lbx, ubx, lbg, ubg = step._bounds(1e-2)
    call = call_ipopt(step._solver_cold, w0.size, step.ng, x0=w0, p=P, lbx=lbx, ubx=ubx, lbg=lbg,
                      ubg=ubg)
    assert call.status == "Invalid_Number_Detected" and not call.usable
    assert call.outcome.kind == "invalid_number" and "NaN" in call.describe()
    sol = step._call(step._solver_cold, w0, None, None, P, lbx, ubx, lbg, ubg)
    assert sol.status == "Invalid_Number_Detected" and sol.accepted is False


def test_casadi_exception_is_caught_and_reported(paper_robot):
    """CasADi raising from the solver call (here an input of the wrong shape) becomes
    Solver_Exception."""
    step = MPCCStep(Model(paper_robot))
    call = call_ipopt(step._solver_cold, 12, step.ng, x0=np.zeros(13), p=np.zeros(0))
    assert call.status == "Solver_Exception" and not call.usable and call.outcome.source == "casadi"
    assert "x0" in call.detail and call.detail in call.describe() and "\n" not in call.describe()


def test_non_finite_step_inputs_are_bad_input(paper_robot):
    """The step's own inputs are checked before IPOPT: one-line ValueErrors naming the value."""
    model = Model(paper_robot)
    torque = paper_torque(paper_robot)
    step = MPCCStep(model)
    with pytest.raises(ValueError, match=r"tau must be 2 finite.*nan"):
        step.solve(released(model, torque), [np.nan, 0.0])
    with pytest.raises(ValueError, match=r"StepState.x1 must be a finite.*inf"):
        StepState([1.0, 1.0], np.inf, 0.1)


def test_failed_warm_start_is_not_used(paper_robot):
    model = Model(paper_robot)
    torque = paper_torque(paper_robot)
    state = released(model, torque)
    failed = MPCCStep(model,
                      MPCCOptions(ipopt={"max_iter": 1}, max_retries=0)).solve(state, torque(0.01))
    res = MPCCStep(model).solve(state, torque(0.02), warm_start=failed)
    assert res.success and "cold start" in res.message, res.message


@pytest.mark.parametrize("ipopt,exc,match", [
    ({"no_such_option": 1}, ValueError,
     r"MPCCOptions.ipopt = \{'no_such_option': 1\}: .*No such IPOPT option"),
    ({"max_iter": -3}, ValueError, r"MPCCOptions.ipopt = \{'max_iter': -3\}: IPOPT rejected"),
    ({"max_iter": "many"}, ValueError,
     r"MPCCOptions.ipopt = \{'max_iter': 'many'\}: IPOPT rejected"),
    ({"tol": float("nan")}, ValueError, r"MPCCOptions.ipopt\['tol'\] must be finite, got nan"),
    ({"tol": True}, TypeError,
     r"MPCCOptions.ipopt\['tol'\] must be a number or a string, got True"),
    ({"tol": [1e-8]}, TypeError, r"MPCCOptions.ipopt\['tol'\] must be a number or a string"),
    ({1: 2}, TypeError, r"MPCCOptions.ipopt: IPOPT option names must be strings, got 1"),
], ids=["unknown", "range", "type", "nan", "bool", "list", "key"])
def test_bad_ipopt_options_are_one_line_errors(paper_robot, ipopt, exc, match):
    with pytest.raises(exc, match=match) as info:
        MPCCStep(Model(paper_robot), MPCCOptions(ipopt=ipopt))
    assert "\n" not in str(info.value)
    # the OCP's options: the same checks (in OCPSettings, or when its solver is built)
    with pytest.raises(exc, match=match.replace("MPCCOptions", "OCPSettings")) as info:
        GaitSolver(GaitOCP(Robot.paper(), "physical", OCPSettings(nodes=8, ipopt=ipopt)))
    assert "\n" not in str(info.value)


# ---------------------------------------------------------------------------------------- MPCC
# time-stepping
@pytest.mark.slow
def test_time_stepping_failure_keeps_the_steps_done_so_far(paper_robot):
    """A step IPOPT cannot solve in mid-cycle (a torque jump to 1000 N m at phase 0.5):
    SOLVER_FAILURE naming the step, its phase and the IPOPT status; the steps before it are those of
    an undisturbed run."""
    model = Model(paper_robot)
    torque = paper_torque(paper_robot)
    N = 40
    jump = CallableSignal(lambda t: torque(t) if t % 1 < 0.5 else np.array([1e3, 0.0]))
    res = simulate_mpcc(model, jump, steps=N)
    assert res.status == Status.SOLVER_FAILURE and not res.success, res.message
    assert res.nsteps == N // 2 and res.failure_t == pytest.approx(0.5, abs=1e-12)
    m = re.search(r"IPOPT return status (\w+)", res.message)
    assert m and not ipopt_status(m.group(1)).usable and m.group(1) in IPOPT_DOCUMENTED
    assert f"step {N // 2} (t = 0.500000 cycles: cycle 1, phase 0.500000)" in res.message
    assert ipopt_status(m.group(1)).message in res.message
    ref = simulate_mpcc(model, torque, steps=N, cycles=1)
    assert ref.success
    # samples t = 0 .. (N/2 - 1)/N and the events located before (switch-exact steps)
    k = int(np.count_nonzero(ref.t < 0.5 - 1e-12))
    assert res.t.size == k and res.t[-1] == pytest.approx((N // 2 - 1) / N)
    np.testing.assert_allclose(res.t, ref.t[:k], rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.phi, ref.phi[:, :k], rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.x1, ref.x1[:k], rtol=0, atol=1e-15)
    assert math.isnan(res.S) and math.isnan(res.W_plus) and math.isnan(res.CoT_plus)


def test_time_stepping_with_a_non_finite_torque_is_a_status(paper_robot):
    model = Model(paper_robot)
    torque = paper_torque(paper_robot)
    N = 40
    bad = CallableSignal(lambda t: torque(t) if t % 1 < 0.5 else np.array([np.nan, 0.0]))
    res = simulate_mpcc(model, bad, steps=N)
    assert res.status == Status.SOLVER_FAILURE and res.nsteps == N // 2, res.message
    assert "torque input is not finite" in res.message and "step 20 " in res.message
    assert np.all(np.isfinite(res.phi))


def test_time_stepping_without_a_start_is_no_start():
    """As the event-driven stepper: no released equilibrium at t = 0 is status NO_START, not an
    exception."""
    robot = Robot.paper()
    model = Model(robot)
    torque = paper_torque(robot, gamma=2.0, A=1.0)  # joints folded flat: no stance on both feet
    with pytest.raises(ValueError):
        HybridStepper(model, torque).initial_state(0.0)
    res = simulate_mpcc(model, torque, steps=40)
    assert res.status == Status.NO_START and not res.success and res.t.size == 0
    assert res.message.startswith("no equilibrium to start from")


def test_cli_simulate_mpcc_solver_failure_exits_1(monkeypatch, capsys):
    """IPOPT's real failure through the CLI (iteration limit 0 in the step solver's defaults): exit
    code 1, the IPOPT status on stderr in one line, no traceback."""
    import ocp_crawl.nlp.ipopt as nlp_ipopt
    from ocp_crawl.cli.app import main

    monkeypatch.setitem(nlp_ipopt.STEP_IPOPT, "max_iter", 0)
    problem = PACKAGE.parent / "problems" / "paper_gait.toml"
    code = main(["simulate", str(problem), "--solver", "mpcc", "--steps", "40", "--json"])
    captured = capsys.readouterr()
    assert code == 1
    data = json.loads(captured.out)
    assert (data["status"] == int(Status.SOLVER_FAILURE) and data["success"] is False
            and data["S"] is None)
    assert "Maximum_Iterations_Exceeded" in data["message"]
    err = captured.err.strip().splitlines()
    assert (len(err) == 1 and "Maximum_Iterations_Exceeded" in err[0]
            and "Traceback" not in captured.err)


# ---------------------------------------------------------------------------------------- gait OCP
#: a small OCP (few nodes, one start; multi-start: test_multistart): each solve a few seconds
SMALL = dict(objective="max_speed", nodes=16, harmonic_psi=4, harmonic_A=1, starts=1,
             baselines="harmonic", baseline_samples=0, baseline_starts=1, baseline_evaluations=40)


def assert_failed_ocp(res, status, ocp_status=Status.SOLVER_FAILURE):
    assert not res.success and res.status == ocp_status, res.message
    out = ipopt_status(status)
    assert status in res.message and out.message in res.message
    assert res.homotopy and all(h.return_status == status and not h.accepted for h in res.homotopy)
    assert res.failed_stage and "homotopy stage 1/" in res.failed_stage
    # nothing is presented as an optimum: no profile, no S, no replay; the summary is strict JSON
    assert res.tau.size == 0 and res.S_ocp == [] and res.replay == [] and math.isnan(res.value_ocp)
    json.dumps(res.summary(), allow_nan=False)


@pytest.mark.parametrize("ipopt,status", [
    ({"max_iter": 1}, "Maximum_Iterations_Exceeded"),
    ({"max_cpu_time": 1e-9}, "Maximum_CpuTime_Exceeded"),
    ({"max_wall_time": 1e-9}, "Maximum_WallTime_Exceeded"),
], ids=["max_iter", "cpu_time", "wall_time"])
def test_ocp_resource_limits_are_solver_failures(ipopt, status):
    res = optimize_gait(Robot.paper(), "physical", OCPSettings(ipopt=ipopt, **SMALL))
    assert_failed_ocp(res, status)
    # each homotopy start failed at its first stage
    assert len(res.homotopy) == len(res.settings.sigma0)


@pytest.mark.slow
def test_ocp_infeasible_speed_requirement_is_infeasible():
    res = optimize_gait(Robot.paper(), "physical",
                        OCPSettings(**dict(SMALL, objective="min_cot", speed_min=5.0)))
    assert_failed_ocp(res, "Infeasible_Problem_Detected", Status.INFEASIBLE)
    assert res.message.startswith("infeasible: IPOPT Infeasible_Problem_Detected")


def test_ocp_nan_in_the_initial_guess_is_invalid_number(monkeypatch):
    """A NaN in the NLP's starting point (one node's angle): IPOPT's Invalid_Number_Detected,
    reported as a solver failure, never as an optimum."""
    original = GaitOCP.initial_guess

    def with_nan(self, signal, period, **kw):
        x = original(self, signal, period, **kw)
        x[self._slices["w_0"].start] = np.nan
        return x
    monkeypatch.setattr(GaitOCP, "initial_guess", with_nan)
    res = optimize_gait(Robot.paper(), "physical", OCPSettings(**SMALL))
    assert_failed_ocp(res, "Invalid_Number_Detected")


@pytest.mark.slow
def test_ocp_success_names_its_final_status():
    res = optimize_gait(Robot.paper(), "physical", OCPSettings(**SMALL), replay=False)
    assert res.status == Status.SUCCESS and res.success, res.message
    m = re.search(r"final IPOPT status (\w+)", res.message)
    assert m and ipopt_status(m.group(1)).usable
    assert all(h.accepted == ipopt_status(h.return_status).usable for h in res.homotopy)
    assert np.all(np.isfinite(res.tau)) and all(math.isfinite(s) for s in res.S_ocp)


@pytest.mark.parametrize("gamma, A", [(150.0, 40.0), (30.0, 40.0), (100.0, 85.0)])
def test_ocp_envelope_outside_0_180_is_rejected(gamma, A):
    with pytest.raises(ValueError, match="envelope gamma"):
        OCPSettings(gamma_deg=gamma, A_max_deg=A)


# ---------------------------------------------------------------------------------------- BLAS
# threads
BLAS_PROBE = """
import ctypes, os, casadi as cs
from ocp_crawl.nlp.ipopt import build_ipopt
from ocp_crawl.nlp.process import CASADI_OPENBLAS
x = cs.SX.sym("x")
build_ipopt("probe", {"x": x, "f": (x - 1) ** 2}, {"ipopt.print_level": 0, "print_time": False},
            "probe", {})
print(ctypes.CDLL(CASADI_OPENBLAS, mode=os.RTLD_NOLOAD).openblas_get_num_threads())
"""


@pytest.mark.skipif(not (Path(__import__("casadi").__file__).parent
                         / "libcasadi-tp-openblas.so.0").is_file(),
                    reason="CasADi's wheel on this platform bundles no libcasadi-tp-openblas.so.0")
@pytest.mark.parametrize("env,threads",
                         [({}, 1), ({"OPENBLAS_NUM_THREADS": "2"}, 2),
                          ({"OMP_NUM_THREADS": "2"}, 2)])
def test_ipopt_runs_casadis_blas_on_one_thread_unless_the_user_says_otherwise(env, threads):
    """In a fresh process: once a solver is built, the OpenBLAS instance that MUMPS uses runs one
    thread (the default would be one per core); a user's thread count is respected (OpenBLAS caps it
    at the CPUs available)."""
    import os
    import subprocess
    import sys
    from ocp_crawl.nlp.process import BLAS_THREAD_VARIABLES
    base = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES}
    proc = subprocess.run([sys.executable, "-c", BLAS_PROBE], env=dict(base, **env),
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert int(proc.stdout.split()[-1]) == min(threads, len(os.sched_getaffinity(0)))
