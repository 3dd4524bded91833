"""Shared problem factories for the tests (the paper's robot and gaits)."""
import compileall
import os
import re
from pathlib import Path

#: the package's sources, compiled to bytecode once by the first pytest process (the controller
#: of pytest-xdist's workers, or the only process): with PYTHONDONTWRITEBYTECODE set (as in CI's
#: environment) no process writes it, and each of the suite's processes (the workers, every
#: ``ocp-crawl`` subprocess and worker pool, the documentation's build) would compile the package
#: again; stale files are never read (their source's time and size are checked on import)
PACKAGE = Path(__file__).resolve().parents[1] / "ocp_crawl"
if "PYTEST_XDIST_WORKER" not in os.environ:
    compileall.compile_dir(PACKAGE, quiet=1)

import matplotlib
import pytest

matplotlib.use("Agg")

from ocp_crawl import Harmonic, Model, ReferenceTorque, Robot  # noqa: E402
from ocp_crawl.ocp import OCPSettings, optimize_gait  # noqa: E402
from ocp_crawl.model import compiled  # noqa: E402

# the line "compiling ... into the cache" depends on the state of the cache, not on the code
# under test: the checks of stderr in this process do not see it (test_warmup.py checks it)
compiled.ANNOUNCE_BUILDS = False

#: why a heavy test is skipped: the default suite stays within its time budget (docs/benchmarks.md,
#: "The test suite")
HEAVY_REASON = ("a convergence, dense-grid or fuzz run: by hand, "
                "OCP_CRAWL_HEAVY=1 python -m pytest -q -m heavy")


def pytest_collection_modifyitems(config, items):
    """Tests marked ``heavy`` run only with OCP_CRAWL_HEAVY set."""
    if os.environ.get("OCP_CRAWL_HEAVY"):
        return
    for item in items:
        if "heavy" in item.keywords:
            item.add_marker(pytest.mark.skip(reason=HEAVY_REASON))


PAPER_DATA = os.path.join(os.path.dirname(__file__), os.pardir, "ocp_crawl", "data", "paper")


def _cells(line: str) -> int:
    """Cells of a markdown table row (escaped bars stay inside their cell)."""
    return len(re.split(r"(?<!\\)\|", line.strip())) - 2


def markdown_table_shapes(text: str) -> list[tuple[int, list[int]]]:
    """(header cells, [cells of each row]) of every markdown table in ``text``."""
    lines = text.splitlines()
    out = []
    for i, line in enumerate(lines[:-1]):
        if line.startswith("|") and re.fullmatch(r"\|(---\|)+", lines[i + 1]):
            rows = []
            for row in lines[i + 1:]:
                if not row.startswith("|"):
                    break
                rows.append(_cells(row))
            out.append((_cells(line), rows))
    return out


def paper_torque(robot: Robot, gamma=90.0, A=30.0, psi=45.0, **per_joint):
    """Harmonic torque input tau = k (phi_ref - pi) of the paper's eq. (tau)."""
    return ReferenceTorque(Harmonic.from_degrees(gamma, A, psi, **per_joint), robot.k)


def shared_tmp(tmp_path_factory) -> Path:
    """A temporary directory of this test run that every pytest-xdist worker shares (the parent of
    the workers' base directories; without xdist the base directory itself)."""
    base = tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


@pytest.fixture
def paper_robot():
    return Robot.paper()


@pytest.fixture(params=["physical", "paper"])
def gravity(request):
    return request.param


@pytest.fixture
def make_torque():
    return paper_torque


@pytest.fixture
def model_of():
    def build(robot=None, gravity="physical", **robot_changes):
        robot = ((robot or Robot.paper()).replace(**robot_changes) if robot_changes
                 else (robot or Robot.paper()))
        return Model(robot, gravity=gravity)
    return build


def computed_once(tmp_path_factory, name: str, compute):
    """``compute()`` once in this test run, shared by the pytest-xdist workers through a pickle in
    :func:`shared_tmp` (the first worker to take the lock computes it, the others read it)."""
    import fcntl
    import pickle

    shared = shared_tmp(tmp_path_factory)
    record = shared / f"{name}.pickle"
    with open(shared / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not record.is_file():
            record.write_bytes(pickle.dumps(compute()))
        return pickle.loads(record.read_bytes())


@pytest.fixture(scope="session")
def cli_optimize_run(tmp_path_factory):
    """One ``ocp-crawl optimize problems/ocp_max_speed.toml --json --progress --out DIR`` at N = 20
    (a cheap search of every waveform family), shared by the tests of its JSON, progress bar and
    output files, and by the worker processes of pytest-xdist: (exit code, stdout, stderr, the --out
    directory, N)."""
    import contextlib
    import io

    from ocp_crawl.cli.app import main

    nodes = 20
    problem = Path(__file__).resolve().parents[1] / "problems" / "ocp_max_speed.toml"
    out = shared_tmp(tmp_path_factory) / "cli_optimize" / "opt"

    def run():
        out.parent.mkdir(exist_ok=True)
        stdout, stderr = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
            code = main(["optimize", str(problem), "--set", f"ocp.nodes={nodes}", "--set",
                         "ocp.harmonic_psi=8", "--set", "ocp.baseline_samples=8", "--set",
                         "ocp.baseline_starts=1", "--set", "ocp.baseline_evaluations=40",
                         "--json", "--out", str(out), "--progress"])
        return code, stdout.getvalue(), stderr.getvalue()

    code, stdout, stderr = computed_once(tmp_path_factory, "cli_optimize", run)
    return code, stdout, stderr, out, nodes


#: max_speed at N = 16 from a short search of the harmonic family (:func:`coarse_max_speed`)
COARSE = OCPSettings(objective="max_speed", nodes=16, starts=1, harmonic_psi=8, harmonic_A=2,
                     baselines="harmonic", baseline_samples=0, baseline_starts=1,
                     baseline_evaluations=40)


@pytest.fixture(scope="session")
def coarse_max_speed(tmp_path_factory):
    """One optimisation of the paper's robot with :data:`COARSE`, shared by the tests that read
    it (a figure, the tightened NLP, a user objective's comparison) and by the xdist workers."""
    return computed_once(tmp_path_factory, "coarse_max_speed",
                         lambda: optimize_gait(Robot.paper(), "physical", COARSE, jobs=1))
