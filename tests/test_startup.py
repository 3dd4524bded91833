"""Start-up time: heavy libraries are imported where they are used, not by ``import ocp_crawl`` or
the CLI.

Every short command and every sweep worker pays the package's import time (scipy and
matplotlib imported eagerly cost ~0.4 s of a ~0.7 s start-up).  Each check runs in a fresh
interpreter and reads its ``sys.modules``.
"""
import importlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

#: imported only by the code that needs them (splines and root finding; figures; clusters; progress
#: bars)
HEAVY = ("scipy", "matplotlib", "dask", "distributed", "tqdm", "pandas")

PACKAGES = ["ocp_crawl", "ocp_crawl.model", "ocp_crawl.nlp", "ocp_crawl.sim", "ocp_crawl.ocp",
            "ocp_crawl.problem",
            "ocp_crawl.viz", "ocp_crawl.sweep", "ocp_crawl.fit", "ocp_crawl.studies"]


def _modules_after(code: str) -> set[str]:
    """Top-level names of the modules imported by a fresh interpreter running ``code``."""
    env = dict(os.environ,
               PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    script = (code
              + "\nimport json, sys\nprint(json.dumps(sorted({m.split('.')[0] for m in "
                "sys.modules})))")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env,
                          cwd=ROOT, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return set(json.loads(proc.stdout.splitlines()[-1]))


def test_import_ocp_crawl_imports_no_library():
    """The front door re-exports lazily: not even numpy or CasADi until a name is used."""
    loaded = _modules_after("import ocp_crawl")
    assert not loaded & {*HEAVY, "numpy", "casadi"}, sorted(loaded & {*HEAVY, "numpy", "casadi"})


def test_cli_parser_imports_no_heavy_library():
    """The parser of every command (what ``ocp-crawl --version`` and ``--help`` build) needs none of
    them."""
    loaded = _modules_after("import ocp_crawl.cli\nfrom ocp_crawl.cli.app import "
                            "build_parser\nbuild_parser()\nfrom ocp_crawl import Robot, simulate, "
                            "load_problem, run_problem")
    assert not loaded & set(HEAVY), sorted(loaded & set(HEAVY))


def test_simulate_command_imports_no_figures_cluster_or_progress():
    """``ocp-crawl simulate --json`` runs a gait: no matplotlib, Dask, tqdm or pandas on its way."""
    code = ("import contextlib, io\nfrom ocp_crawl.cli import main\nwith "
            "contextlib.redirect_stdout(io.StringIO()):\n    assert main(['simulate', "
            "'problems/paper_gait.toml', '--json']) == 0")
    loaded = _modules_after(code)
    assert not loaded & (set(HEAVY) - {"scipy"}), sorted(loaded & set(HEAVY))


@pytest.mark.parametrize("package", PACKAGES)
def test_every_lazy_export_resolves(package):
    """Each name of a package's ``__all__`` is importable from it and is the object its module
    defines."""
    mod = importlib.import_module(package)
    for name in mod.__all__:
        value = getattr(mod, name)
        home = mod._EXPORTS.get(name, package)
        assert value is getattr(importlib.import_module(home), name), f"{package}.{name}"
        assert name in dir(mod)
    with pytest.raises(AttributeError, match="no_such_name"):
        getattr(mod, "no_such_name")
