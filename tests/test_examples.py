"""The examples gallery: every script in examples/ runs headless and writes its outputs.

A script that is not listed in :data:`OUTPUTS` fails the test (add it with the files it must write),
so no example goes untested.  The default suite runs the scripts once, in the documentation's build
(tests/test_docs.py, whose gallery executes them and checks their outputs with
:func:`check_outputs`); :func:`test_example_runs` runs each in a fresh process, by hand (heavy
tier).
"""
import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
EXAMPLES = REPO / "examples"
#: script -> files it writes into its output directory
OUTPUTS = {
    "01_simulate_one_gait.py": ["gait.png"],
    "02_gravity_conventions.py": ["gravity_conventions.png"],
    "03_design_map.py": ["design_map.png", "design_map.csv"],
    "04_friction_band.py": ["friction_band.png"],
    "05_optimise_and_replay.py": ["optimise_and_replay.png"],
    "06_custom_waveform.py": ["custom_waveform.png"],
    "07_study_to_pandas.py": ["study.png", "study.csv", "sweep/results.csv"],
    "08_fit_pressure_robot.py": ["amplitude/fit.png", "amplitude/fit.json", "k_and_map/fit.png",
                                 "k_and_map/fit.json"],
    "09_past_a_fold.py": ["past_a_fold.png"],
    "10_user_objective.py": ["user_objective.png"],
    "11_lumped_models.py": ["lumped_models.png", "symmetric/fit.json", "asymmetric/fit.json"],
}
SCRIPTS = sorted(p.name for p in EXAMPLES.glob("*.py") if not p.name.startswith("_"))
TIMEOUT_S = 300


def test_every_example_is_covered():
    assert SCRIPTS == sorted(OUTPUTS), \
        (f"examples without a test entry: {set(SCRIPTS) - set(OUTPUTS)}; "
         f"entries without a script: {set(OUTPUTS) - set(SCRIPTS)}")
    for name in SCRIPTS:  # each says what it shows
        doc = ast.get_docstring(ast.parse((EXAMPLES / name).read_text(encoding="utf-8")))
        assert doc and len(doc.split()) >= 30 and "Run:" in doc, name


def check_outputs(name: str, out: Path) -> None:
    """The example ``name`` wrote every file of :data:`OUTPUTS` into ``out``, PNG files as PNG, and
    left no temporary file."""
    for f in OUTPUTS[name]:
        path = out / f
        assert path.is_file() and path.stat().st_size > 1000, path
        if f.endswith(".png"):
            assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", path
    leftovers = list(out.rglob("*.tmp"))
    assert not leftovers, leftovers  # written atomically, nothing left over


@pytest.mark.slow
@pytest.mark.heavy   # the docs build (tests/test_docs.py) runs every example in the default suite
@pytest.mark.parametrize("name", sorted(OUTPUTS))
def test_example_runs(name, tmp_path):
    out = tmp_path / "out"
    # the quick budget (examples/_common.py): the full runs (08: about 4 min of CPU) are by hand
    env = dict(os.environ, MPLBACKEND="Agg", OCP_CRAWL_EXAMPLES_QUICK="1",
               PYTHONPATH=os.pathsep.join(
        p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p))
    proc = subprocess.run([sys.executable, str(EXAMPLES / name), str(out)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=TIMEOUT_S)
    assert proc.returncode == 0, (proc.stdout[-3000:], proc.stderr[-3000:])
    check_outputs(name, out)
