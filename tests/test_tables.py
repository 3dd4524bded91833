"""The one CSV convention (ocp_crawl/io/tables.py): units in the header, SI conversion, errors
naming file and line, full-precision round trip."""
import math

import numpy as np
import pytest

from ocp_crawl.io.tables import TableError, read_table, split_header, write_table


def _write(tmp_path, text, name="t.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_units_convert_to_si_and_comments_are_skipped(tmp_path):
    p = _write(tmp_path,
               "# measured 2026-11-23\nphase [-],phi1 [deg],tau1 [N "
               "mm]\n0,90,1000\n\n0.5,180,-250\n")
    t = read_table(p, {"phase": "dimensionless", "phi1": "angle", "tau1": "torque"})
    np.testing.assert_allclose(t["phi1"], [math.pi / 2, math.pi])
    np.testing.assert_allclose(t["tau1"], [1.0, -0.25])
    assert t.units == {"phase": "-", "phi1": "deg", "tau1": "N mm"}
    assert list(t.lines) == [3, 5]


def test_round_trip_keeps_every_bit(tmp_path):
    rng = np.random.default_rng(3)
    x, y = rng.random(7), rng.standard_normal(7) * 1e-3
    p = write_table(tmp_path / "w.csv", [("phase", "-", x), ("tau1", "N m", y)],
                    comments=["from a test"])
    t = read_table(p, {"phase": "dimensionless", "tau1": "torque"})
    assert np.array_equal(t["phase"], x) and np.array_equal(t["tau1"], y)


@pytest.mark.parametrize("text, where, words", [
    ("phase,tau1 [N m]\n0,1\n", ":1:", "has no unit"),
    ("phase [-],tau1 [deg]\n0,1\n", ":1:", "not a torque unit"),
    ("phase [-]\n0\n", ":1:", "missing column(s) 'tau1'"),
    ("phase [-],tau1 [N m],x [m]\n0,1,2\n", ":1:", "unknown column(s) 'x'"),
    ("phase [-],tau1 [N m]\n0,1\n0.5,abc\n", ":3:", "'abc' is not a number"),
    ("phase [-],tau1 [N m]\n0,1\n0.5,nan\n", ":3:", "not a finite number"),
    ("phase [-],tau1 [N m]\n0,1\n0.5\n", ":3:", "1 cells where the header has 2"),
    ("phase [-],phase [-],tau1 [N m]\n0,0,1\n", ":1:", "appears twice"),
    ("# only a comment\n", "t.csv:", "no header row"),
])
def test_bad_tables_name_file_and_line(tmp_path, text, where, words):
    p = _write(tmp_path, text)
    with pytest.raises(TableError) as info:
        read_table(p, {"phase": "dimensionless", "tau1": "torque"})
    msg = str(info.value)
    assert "\n" not in msg and str(p) in msg and where in msg and words in msg


def test_too_few_rows_and_missing_file(tmp_path):
    p = _write(tmp_path, "phase [-],tau1 [N m]\n0,1\n")
    with pytest.raises(TableError, match="1 data row"):
        read_table(p, {"phase": "dimensionless", "tau1": "torque"}, min_rows=3)
    with pytest.raises(TableError, match="nope.csv"):
        read_table(tmp_path / "nope.csv", {"phase": "dimensionless"})


def test_split_header():
    assert split_header(" tau1 [ N  m ] ") == ("tau1", "N m")
    assert split_header("tau1") is None and split_header("[deg]") is None
