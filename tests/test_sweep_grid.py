"""Sweep grids: ``--grid`` specifications (the count and step forms) parsed or rejected, grids of
several keys, the bound on a grid's size (the sweeps themselves: test_sweep.py)."""
import math

import numpy as np
import pytest

from ocp_crawl.problem import ProblemError
from ocp_crawl.sweep import grid_from_specs, normalize_grid, parse_grid


# --------------------------------------------------------------------------------------------
# grids
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("spec, key, values", [
    ("gait.psi_deg=0:180:37", "gait.psi_deg", np.linspace(0, 180, 37)),
    ("gait.gamma_deg = 60:120:3", "gait.gamma_deg", [60.0, 90.0, 120.0]),
    ("robot.k=0.05,0.1,0.2", "robot.k", [0.05, 0.1, 0.2]),
    ("robot.mu=0.4", "robot.mu", [0.4]),
    ("gait.A_deg=30:30:1", "gait.A_deg", [30.0]),
    ("gait.psi_deg=-45:45:3", "gait.psi_deg", [-45.0, 0.0, 45.0]),
    ("simulation.max_cycles=4:8:3", "simulation.max_cycles", [4, 6, 8]),
    ("model.gravity=physical,paper", "model.gravity", ["physical", "paper"]),
    ('model.gravity="paper"', "model.gravity", ["paper"]),
    ("gait.drive=torque,angles", "gait.drive", ["torque", "angles"]),
    ("gait.psi_deg=0:180:num=5", "gait.psi_deg", [0.0, 45.0, 90.0, 135.0, 180.0]),
    ("simulation.max_cycles=4:8:step=2", "simulation.max_cycles", [4, 6, 8]),
    ("gait.psi_deg=180:0:step=-45", "gait.psi_deg", [180.0, 135.0, 90.0, 45.0, 0.0]),
    ("gait.A_deg=30:30:step=5", "gait.A_deg", [30.0]),
])
def test_parse_grid(spec, key, values):
    name, arr = parse_grid(spec)
    assert name == key
    assert arr.ndim == 1 and list(arr) == list(values)
    if key == "simulation.max_cycles":
        assert arr.dtype.kind == "i"
    elif key.startswith("model") or key == "gait.drive":
        assert arr.dtype.kind == "U"
    else:
        assert arr.dtype == np.float64


@pytest.mark.parametrize("spec, match", [
    ("gait.psi_deg", "expected SECTION.KEY=START:STOP:NUM"),
    ("psi_deg=0:180:3", "must be SECTION.KEY"),
    ("gait.psi=0:180:3", "did you mean gait.psi_deg"),
    ("gaitt.psi_deg=0:180:3", "unknown section \\[gaitt\\]; did you mean gait"),
    ("gait.psi_deg=", "no values"),
    ("gait.psi_deg=0:180", "START:STOP:step=STEP, got 2 fields"),
    ("gait.psi_deg=0:180:step=7",
     "STEP = 7 does not divide STOP - START = 180; the last value would be 175"),
    ("gait.psi_deg=0:180:step=-5", "goes away from STOP; use step=5"),
    ("gait.psi_deg=0:180:step=0", "finite non-zero"),
    ("gait.psi_deg=0:180:step=x", "STEP must be a number"),
    ("gait.psi_deg=0:180:stp=5", "the third field is NUM, num=NUM or step=STEP"),
    ("gait.psi_deg=0:180:step=0.001", "gives 180001 values, more than the 20000"),
    ("gait.psi_deg=0:180:3:4", "got 4 fields"),
    ("gait.psi_deg=a:180:3", "START and STOP must be numbers"),
    ("gait.psi_deg=0:180:2.5", "NUM must be an integer >= 1"),
    ("gait.psi_deg=0:180:0", "NUM must be an integer >= 1, got 0"),
    ("gait.psi_deg=0:180:1", "NUM = 1 gives one value"),
    ("gait.psi_deg=0:nan:3", "must be finite"),
    ("gait.psi_deg=1,,2", "empty value"),
    ("gait.psi_deg=1,x", "'x' is not a number"),
    ("gait.psi_deg=1,1", "appears twice"),
    ("gait.psi_deg=0:0:3", "appears twice"),
    ("robot.k=true", "takes numbers"),
    ("model.gravity=physical,phys", "must be one of"),
    ("model.gravity=1", "takes strings"),
    ("simulation.max_cycles=4:6:4", "takes integers"),
])
def test_parse_grid_rejects(spec, match):
    with pytest.raises(ProblemError, match=match) as info:
        parse_grid(spec)
    assert "\n" not in str(info.value)
    assert "--grid" in str(info.value)


@pytest.mark.parametrize("start, stop, step",
                         [(0, 180, 5), (0.3, 0.5, 0.05), (-45, 45, 7.5), (1, 2, 0.1),
                                                (180, 0, -10)])
def test_step_form_is_the_arange_of_numpy_with_stop_included(start, stop, step):
    """START:STOP:step=STEP gives start, start + step, ... up to STOP, as numpy.arange would with
    the end included (the count form START:STOP:NUM keeps meaning NUM values)."""
    _, values = parse_grid(f"gait.psi_deg={start}:{stop}:step={step}")
    ref = np.arange(start, stop + step / 2, step)
    assert values.shape == ref.shape
    np.testing.assert_allclose(values, ref, rtol=0, atol=1e-12 * max(abs(start), abs(stop)))
    assert values[0] == start and values[-1] == stop
    _, counted = parse_grid(f"gait.psi_deg={start}:{stop}:{len(ref)}")
    np.testing.assert_array_equal(values, counted)


def test_grids_of_several_keys():
    grid = grid_from_specs(["gait.psi_deg=0:90:3", "robot.k=0.1,0.2"])
    assert list(grid) == ["gait.psi_deg", "robot.k"]
    with pytest.raises(ProblemError, match="already a grid key"):
        grid_from_specs(["robot.k=0.1", "robot.k=0.2"])
    with pytest.raises(ProblemError, match="alternatives"):
        normalize_grid({"robot.mu": [0.3], "robot.mu1": [0.3]})
    with pytest.raises(ProblemError, match="1-D"):
        normalize_grid({"robot.k": [[0.1, 0.2]]})
    with pytest.raises(ProblemError, match="at least one key"):
        normalize_grid({})
    assert list(normalize_grid({"robot.k": 0.1})["robot.k"]) == [0.1]


# ------------------------------------------------------------------------------------------ grid
# size
def test_grid_size_is_bounded():
    """A grid of MAX_GRID_POINTS points is fine; one more, in one axis or in the product, is bad
    input naming the keys and the limit (checked through the API too, not only on the command
    line)."""
    from ocp_crawl.sweep import normalize_grid, parse_grid
    from ocp_crawl.sweep.grid import MAX_GRID_POINTS

    name, values = parse_grid(f"gait.psi_deg=-180:180:{MAX_GRID_POINTS}")
    assert len(values) == MAX_GRID_POINTS
    with pytest.raises(ProblemError,
                       match=f"NUM = {MAX_GRID_POINTS + 1} is more than the {MAX_GRID_POINTS} "
                             "points"):
        parse_grid(f"gait.psi_deg=-180:180:{MAX_GRID_POINTS + 1}")
    side = math.isqrt(MAX_GRID_POINTS) + 1
    grid = {"gait.psi_deg": np.linspace(0, 180, side), "gait.gamma_deg": np.linspace(60, 120, side)}
    with pytest.raises(ProblemError,
                       match=rf"the grid has {side * side} points, {side} \(gait.psi_deg\) "
                             rf"x {side} \(gait.gamma_deg\): more than the {MAX_GRID_POINTS}"):
        normalize_grid(grid)
    with pytest.raises(ProblemError, match="START and STOP must be finite, got STOP = inf"):
        parse_grid("gait.psi_deg=0:inf:3")


@pytest.mark.parametrize("spec, values", [
    ("robot.mu=0.05:0.5:10", [0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5]),
    ("gait.psi_deg=0:0.3:4", [0.0, 0.1, 0.2, 0.3]),
    ("gait.psi_deg=0:0.3:step=0.1", [0.0, 0.1, 0.2, 0.3]),
    ("gait.psi_deg=-0.3:0:step=0.1", [-0.3, -0.2, -0.1, 0.0]),
    ("robot.k=0.1:0.2:step=0.05", [0.1, 0.15, 0.2]),
    ("gait.psi_deg=0:1:4", [0.0, 1 / 3, 2 / 3, 1.0]),
])
def test_range_values_are_the_decimals_they_stand_for(spec, values):
    """A range's values are the floats of their decimals (0.15, not numpy.linspace's
    0.15000000000000002), shown as such; a value without a short decimal is the nearest float."""
    from ocp_crawl.sweep.grid import axis_text, value_text

    _, got = parse_grid(spec)
    assert got.tolist() == values
    assert all(len(repr(v)) <= 6 or v in (1 / 3, 2 / 3) for v in got.tolist())
    text = axis_text(got.tolist())
    assert "0000" not in text and "9999" not in text
    assert value_text(0.1 + 0.2) == "0.3" and value_text(0.049999999999999996) == "0.05"
    assert value_text(45.0) == "45" and value_text(3) == "3"
    assert value_text(0.123456789) == "0.123456789"
