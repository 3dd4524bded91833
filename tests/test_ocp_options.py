"""IPOPT's options and log from a problem file and the command line: ``[ocp.ipopt]`` reaches every solve,
``--verbose`` shows IPOPT's own iteration log."""
import json

from ocp_crawl.cli import main

#: a cheap problem: 12 nodes, the harmonic family's coarse scan only
CHEAP = ["--set", "ocp.nodes=12", "--set", "ocp.baselines=harmonic", "--set", "ocp.baseline_samples=0",
         "--set", "ocp.harmonic_psi=8"]


def _file(tmp_path, extra: str):
    from pathlib import Path
    text = (Path(__file__).resolve().parents[1] / "problems" / "ocp_max_speed.toml").read_text()
    path = tmp_path / "x.toml"
    path.write_text(text + extra)
    return path


def test_ipopt_options_of_the_file_reach_the_solver(tmp_path, capsys):
    """max_iter = 5 in [ocp.ipopt]: the first stage stops at IPOPT's iteration limit, and says so."""
    code = main(["optimize", str(_file(tmp_path, "\n[ocp.ipopt]\nmax_iter = 5\n")), "--json", *CHEAP])
    out = json.loads(capsys.readouterr().out)
    assert code == 1 and out["status"] == "solver_failure"
    assert "Maximum_Iterations_Exceeded" in out["message"]
    assert out["homotopy"][0]["iterations"] == 5


def test_verbose_prints_ipopts_log(tmp_path, capfd):
    """--verbose: IPOPT's banner and iteration table on stdout, then the summary."""
    code = main(["optimize", str(_file(tmp_path, "")), "--verbose", *CHEAP])
    out = capfd.readouterr().out
    assert code == 0, out[-2000:]
    assert "This is Ipopt version" in out and "iter    objective" in out
    assert "status      success" in out
