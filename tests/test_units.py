"""The formatting layer (ocp_crawl.io.units): text numbers read back to the SI values they stand
for, and every command's text output uses it (S in mm, W+ in mJ, CoT+ to 3 significant digits, times
in s)."""
import json
import math
import re
from pathlib import Path

import pytest

from ocp_crawl.cli.app import main
from ocp_crawl.io import units
from ocp_crawl.studies.text import dec, num, rel, table

from conftest import markdown_table_shapes

PAPER = Path(__file__).resolve().parent.parent / "problems" / "paper_gait.toml"


@pytest.mark.parametrize("S", [-0.0558381, 0.0123456, 1e-7, -4.9999e-7, 0.0, 12.5])
def test_distance_reads_back_in_mm(S):
    text = units.distance(S)
    m = re.fullmatch(r"(-?\d+\.\d{3}) mm", text)
    assert m, text
    # three decimals of mm: the text is S [m] x 1000 to half a micrometre
    assert float(m.group(1)) == pytest.approx(1e3 * S, abs=5e-4 + 1e-12)
    assert not text.startswith("-0.000"), text


@pytest.mark.parametrize("W", [0.579376, 1.2e-5, 3.0])
def test_work_reads_back_in_mJ(W):
    m = re.fullmatch(r"(-?\d+\.\d{3}) mJ", units.work(W))
    assert m and float(m.group(1)) == pytest.approx(1e3 * W, abs=5e-4)


@pytest.mark.parametrize("x", [20.3456, 0.5, 1234.5, 0.0123456, 99.96, 2.0])
def test_cot_has_three_significant_digits(x):
    text = units.cot(x)
    digits = re.sub(r"e[+-]\d+$", "", text).replace(".", "").lstrip("0")
    assert len(digits) == 3, text
    assert float(text) == pytest.approx(x, rel=5e-3)


@pytest.mark.parametrize("fn", [units.distance, units.work, units.cot, units.seconds, units.ratio,
                                units.scientific, lambda x: units.fixed(x, 2)])
@pytest.mark.parametrize("missing", [None, math.nan, "n/a"])
def test_missing_numbers_are_a_dash(fn, missing):
    assert fn(missing) == units.MISSING


def test_zero_never_prints_negative():
    assert units.fixed(-1e-9, 2) == "0.00"
    assert units.fixed(-0.0, 3, 1e3) == "0.000"
    assert dec(-0.0) == "0.00" and dec(-4e-3) == "0.00" and dec(-6e-3) == "-0.01"
    assert num(-1e-9, ".2f") == "0.00" and num(-0.5, ".2f") == "-0.50"
    assert num(-1e-5, "+.1%") == "+0.0%"
    assert rel(38.5401, 38.55) == "+0.0%"


def test_seconds_and_ratio():
    assert units.seconds(4.109812) == "4.1 s"
    assert float(units.seconds(0.0415).split()[0]) == pytest.approx(0.0415, rel=1e-2)
    assert units.ratio(0.2986984) == "+29.9 %"
    assert units.ratio(-0.016200) == "-1.62 %"


def test_markdown_table_with_bars_keeps_its_shape():
    text = table(["stiffness", "median |rel. diff.|", "max |S(psi) + S(-psi)|"],
                 [["large", "|x|", "a|b"]])
    (header, rows), = markdown_table_shapes(text)
    assert header == 3 and rows == [3, 3]
    assert text.startswith("\n"), "a table needs a blank line before it"


def test_simulate_text_agrees_with_its_json(capsys):
    """The text summary shows the JSON's SI numbers in mm, mJ and 3 significant digits."""
    assert main(["simulate", str(PAPER), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert main(["simulate", str(PAPER)]) == 0
    out = capsys.readouterr().out
    S = float(re.search(r"^S\s+(-?[\d.]+) mm per cycle", out, re.M).group(1))
    W = float(re.search(r"^W\+\s+(-?[\d.]+) mJ per cycle", out, re.M).group(1))
    cot = re.search(r"^CoT\+\s+(\S+)$", out, re.M).group(1)
    assert S == pytest.approx(1e3 * data["S"], abs=5e-4)
    assert W == pytest.approx(1e3 * data["W_plus"], abs=5e-4)
    assert cot == units.cot(data["CoT_plus"]) and float(cot) == pytest.approx(data["CoT_plus"],
                                                                              rel=5e-3)
