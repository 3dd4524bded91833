"""A wheel install works as a new user meets it: build the wheel, install it into a fresh virtual
environment, run the README's quick start (``ocp-crawl init``, ``ocp-crawl simulate problems/...``,
an example script).

The wheel is built from a copy of the files a build reads (pyproject.toml, README.md, LICENSE,
ocp_crawl/), so that nothing is written into the checkout, with pip's ordinary isolated build (as
CI's ``pip install -e .``).  The new environment gets its dependencies (numpy, scipy, casadi,
matplotlib, tqdm) from the running one through a ``.pth`` file, which keeps the test fast; the
``ocp_crawl`` that runs is the installed wheel's, which the test asserts.
"""
import fcntl
import json
import os
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from ocp_crawl import load_problem, run_problem
from ocp_crawl.problem.shipped import SHIPPED_FOLDERS, shipped_files

from conftest import shared_tmp

REPO = Path(__file__).resolve().parent.parent
#: what a build reads
SOURCES = ("pyproject.toml", "README.md", "LICENSE", "ocp_crawl")
DEPENDENCIES = ("numpy", "scipy", "casadi", "matplotlib", "tqdm")
TIMEOUT_S = 600


def _run(argv, cwd, env=None, check=True):
    proc = subprocess.run([str(a) for a in argv], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=TIMEOUT_S)
    if check:
        assert proc.returncode == 0, (argv, proc.returncode, proc.stdout[-3000:],
                                      proc.stderr[-3000:])
    return proc


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel built from a copy of the sources, once for every pytest-xdist worker (the first to
    take the lock builds it)."""
    shared = shared_tmp(tmp_path_factory)
    with open(shared / "wheel.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        wheels = list((shared / "wheel" / "dist").glob("ocp_crawl-*.whl"))
        if not wheels:
            wheels = [_build_wheel(shared / "wheel")]
    assert len(wheels) == 1, wheels
    return wheels[0]


def _build_wheel(root: Path) -> Path:
    src = root / "src"
    src.mkdir(parents=True)
    for name in SOURCES:
        if (REPO / name).is_dir():
            shutil.copytree(REPO / name, src / name,
                            ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        else:
            shutil.copy2(REPO / name, src / name)
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--disable-pip-version-check", "-w",
          root / "dist", f"{src}{os.sep}"], cwd=root)
    wheels = list((root / "dist").glob("ocp_crawl-*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


@pytest.fixture(scope="module")
def venv(wheel, tmp_path_factory) -> Path:
    """A fresh virtual environment with the wheel installed by pip (dependencies borrowed through a
    .pth file)."""
    env_dir = tmp_path_factory.mktemp("venv") / "venv"
    # without a pip of its own (ensurepip's copy is most of venv's time): the running pip installs
    # the wheel into it, as its own would (pip >= 22.3 has --python)
    own_pip = _pip_version() < (22, 3)
    _run([sys.executable, "-m", "venv", *([] if own_pip else ["--without-pip"]), env_dir],
         cwd=env_dir.parent)
    python = env_dir / ("Scripts" if os.name == "nt" else "bin") / "python"
    pip = [python, "-m", "pip"] if own_pip else [sys.executable, "-m", "pip", "--python", python]
    _run([*pip, "install", "--no-deps", "--no-index", "--disable-pip-version-check", wheel],
         cwd=env_dir.parent)
    site = Path(_run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                     cwd=env_dir.parent).stdout.strip())
    dirs = {str(Path(__import__(name).__file__).resolve().parents[1]) for name in DEPENDENCIES}
    (site / "_ocp_crawl_test_dependencies.pth").write_text("\n".join(sorted(dirs)) + "\n")
    return env_dir


def _pip_version() -> tuple[int, ...]:
    """The running pip's version, its numeric leading parts."""
    from importlib.metadata import version

    return tuple(int(p) for p in re.findall(r"\d+", version("pip"))[:2])


def _clean_env() -> dict:
    """The environment without anything that would put the checkout on the path."""
    dropped = ("PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP", "OCP_CRAWL_PAPER_DATA")
    env = {k: v for k, v in os.environ.items() if k not in dropped}
    env["MPLBACKEND"] = "Agg"
    return env


def _bin(venv: Path, name: str) -> Path:
    return venv / ("Scripts" if os.name == "nt" else "bin") / name


@pytest.mark.slow
def test_wheel_holds_the_data_files(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    shipped = {f"ocp_crawl/data/{folder}/{n}"
               for folder in SHIPPED_FOLDERS for n in shipped_files(folder)}
    paper = {f"ocp_crawl/data/paper/{p.name}"
             for p in (REPO / "ocp_crawl" / "data" / "paper").iterdir() if p.is_file()}
    assert shipped and paper
    assert shipped <= names, shipped - names
    assert paper <= names, paper - names
    assert "ocp_crawl/py.typed" in names
    licenses = [n for n in names
                if re.fullmatch(r"ocp_crawl-[^/]+\.dist-info/(licenses/)?LICENSE", n)]
    assert licenses, sorted(n for n in names if "dist-info" in n)
    with zipfile.ZipFile(wheel) as z:
        assert z.read(licenses[0]) == (REPO / "LICENSE").read_bytes()
        for name in shipped:  # byte for byte as in the package
            assert z.read(name) == (REPO / name).read_bytes(), name
    # no test or checkout file slipped in
    assert not [n for n in names if n.startswith(("tests/", "problems/", "scripts/", "examples/"))]


@pytest.mark.slow
def test_quick_start_from_a_wheel_install(venv, tmp_path):
    env = _clean_env()
    work = tmp_path / "new_user"
    work.mkdir()
    where = _run([_bin(venv, "python"), "-c", "import ocp_crawl; print(ocp_crawl.__file__)"],
                 cwd=work, env=env)
    assert Path(where.stdout.strip()).resolve().is_relative_to(venv.resolve()), where.stdout
    # the paper's data are found in the installed package
    _run([_bin(venv, "python"), "-c",
          "from ocp_crawl.io.paper_data import paper_data_dir, read_paper_csv; "
          "assert paper_data_dir().is_relative_to(__import__('sys').prefix); "
          "assert len(read_paper_csv('fig_cot_vs_amplitude.csv')) > 0"], cwd=work, env=env)

    init = _run([_bin(venv, "ocp-crawl"), "init", "--json"], cwd=work, env=env)
    written = json.loads(init.stdout)["files"]
    assert written == [f"{folder}/{n}" for folder in SHIPPED_FOLDERS for n in shipped_files(folder)]
    for name in written:
        assert (work / name).read_bytes() == (REPO / name).read_bytes(), name
    again = _run([_bin(venv, "ocp-crawl"), "init"], cwd=work, env=env, check=False)
    assert again.returncode == 2 and "--force" in again.stderr, again

    sim = _run([_bin(venv, "ocp-crawl"), "simulate", "problems/paper_gait.toml", "--json"],
               cwd=work, env=env)
    report = json.loads(sim.stdout)
    assert report["success"] and report["problem_file"] == "problems/paper_gait.toml"
    # the installed code computes what the checkout computes
    here = run_problem(load_problem(REPO / "problems" / "paper_gait.toml"))
    assert report["S"] == pytest.approx(here.S, rel=1e-9, abs=0)
    assert report["S"] < 0  # the paper gait crawls towards foot 1

    fresh = tmp_path / "readme"  # the README's quick start, as written, in an empty directory
    fresh.mkdir()
    # the venv's ocp-crawl and python
    path = dict(env, PATH=f"{_bin(venv, '')}{os.pathsep}{env.get('PATH', '')}")
    for line in _readme_quick_start():
        proc = _run(line.split(), cwd=fresh, env=path, check=False)
        assert proc.returncode == 0, (line, proc.stdout[-2000:], proc.stderr[-2000:])


def _readme_quick_start() -> list[str]:
    """The `ocp-crawl ...` and `python examples/...` lines of the README's quick start after 'From a
    wheel'."""
    text = (REPO / "README.md").read_text(encoding="utf-8")
    block = re.search(r"From a wheel.*?```\n(.*?)```", text, re.S)
    assert block, "README: no 'From a wheel' block"
    lines = [re.sub(r"\s+#.*", "", ln).strip() for ln in block.group(1).splitlines()]
    lines = [ln for ln in lines if ln.startswith(("ocp-crawl ", "python examples/"))]
    assert lines[0].startswith("ocp-crawl init") and any("simulate" in ln for ln in lines), lines
    assert any(ln.startswith("python examples/") for ln in lines), lines
    return lines
