"""IPOPT's options and log from a problem file and the command line: ``[ocp.ipopt]`` reaches every
solve, ``--verbose`` shows IPOPT's own iteration log."""
import json

import pytest

from ocp_crawl.cli import main

#: a cheap problem: 12 nodes, the harmonic family's coarse scan and one short local search (these
#: tests check options, logs and --start, not the baseline: the default search took 3/4 of the
#: time), solved by the homotopy (its stages' log)
CHEAP = ["--set", "ocp.nodes=12", "--set", "ocp.baselines=harmonic",
         "--set", "ocp.start_solve=homotopy",
         "--set", "ocp.baseline_samples=0", "--set", "ocp.harmonic_psi=8",
         "--set", "ocp.baseline_starts=1", "--set", "ocp.baseline_evaluations=40"]


def _file(tmp_path, extra: str):
    from pathlib import Path
    text = (Path(__file__).resolve().parents[1] / "problems" / "ocp_max_speed.toml").read_text()
    path = tmp_path / "x.toml"
    path.write_text(text + extra)
    return path


@pytest.mark.slow
def test_ipopt_options_of_the_file_reach_the_solver(tmp_path, capsys):
    """max_iter = 5 in [ocp.ipopt]: the first stage stops at IPOPT's iteration limit, and says
    so."""
    code = main(["optimize", str(_file(tmp_path, "\n[ocp.ipopt]\nmax_iter = 5\n")), "--json",
                 *CHEAP])
    out = json.loads(capsys.readouterr().out)
    assert code == 1 and out["status"] == "solver_failure"
    assert "Maximum_Iterations_Exceeded" in out["message"]
    assert out["homotopy"][0]["iterations"] == 5


@pytest.mark.slow
def test_verbose_log_and_the_optimum_as_the_next_start(tmp_path, capfd):
    """--verbose: IPOPT's banner and iteration table on stdout, then the summary.  That run's
    replay file as --start DIR/optimal_gait.toml: the first start is that gait, labelled so, and the
    optimum reached from it is at least as good by replay as the one it started from."""
    ocp = str(_file(tmp_path, ""))
    code = main(["optimize", ocp, "--verbose", "--out", str(tmp_path / "first"), *CHEAP])
    out = capfd.readouterr().out
    assert code == 0, out[-2000:]
    assert "This is Ipopt version" in out and "iter    objective" in out
    assert "status      success" in out

    first = json.loads((tmp_path / "first" / "summary.json").read_text())
    code = main(["optimize", ocp, "--json", "--start",
                 str(tmp_path / "first" / "optimal_gait.toml"), *CHEAP])
    again = json.loads(capfd.readouterr().out)
    assert code == 0 and again["starts"][0]["label"] == "given start"
    assert again["starts"][0]["T_start"] == first["T_ocp"]
    value, before = again["objective_value_replay"], first["objective_value_replay"]
    assert value >= before * (1 - first["replay_tol"])


@pytest.mark.slow
def test_the_nlp_exported_to_a_solver_of_ones_own():
    """GaitOCP.export: CasADi's nlpsol input and the relaxation's bounds; IPOPT called directly on
    it from the simulated guess of the harmonic baseline's family member reaches a point whose
    objective and constraints the transcription's own functions confirm."""
    import casadi as cs
    import numpy as np

    from ocp_crawl import Robot
    from ocp_crawl.ocp import GaitOCP, OCPSettings
    from ocp_crawl.ocp.family import WaveParams

    s = OCPSettings(nodes=12, direction=-1)
    ocp = GaitOCP(Robot.paper(), "physical", s)
    member = WaveParams(90.0, 90.0, 25.0, 25.0, 30.0)
    x0 = ocp.initial_guess(member.torque(Robot.paper().k), member.period(s))
    out = ocp.export(sigma=1e-4)
    solver = cs.nlpsol("mine", "ipopt", out["nlp"], {"ipopt.print_level": 0, "print_time": False})
    sol = solver(x0=x0, lbx=out["lbx"], ubx=out["ubx"], lbg=out["lbg"], ubg=out["ubg"])
    assert solver.stats()["success"]
    x = np.asarray(sol["x"]).ravel()
    g = np.asarray(cs.Function("g", [out["nlp"]["x"]], [out["nlp"]["g"]])(x)).ravel()
    assert np.all(g >= out["lbg"] - 1e-6) and np.all(g <= out["ubg"] + 1e-6)
    assert float(sol["f"]) == ocp.objective(x) < ocp.objective(x0)
    assert ocp.unpack(x)["scen"][0]["v"] > 0
