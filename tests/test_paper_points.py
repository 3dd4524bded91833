"""Every published point of the paper's simulated figures, at the published abscissae.

CoT+ against the amplitude (Fig. CoT) in the paper's convention within 2 % at every published point;
where CoT+ is ill-conditioned (more than 5 % change per degree, measured here by a central
difference) an amplitude within 0.2 deg of the published one may give the published value instead.
The pressure-driven robot (Fig. exp) with the paper's form (ref) of the input.  Each point is one
run of about 20 ms.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from ocp_crawl.io.paper_data import read_paper_csv
from ocp_crawl.model.pressure import FLAT_REST_DEG, PAPER_FORM_AMPLITUDE_BAR, PressureWaveform
from ocp_crawl.problem import run_problem
from ocp_crawl.studies.common import COT_K_RATIOS, PAPER_ROBOT, base_problem
from ocp_crawl.studies.paper_points import LOW_K_PAPER_PSI_DEG, PaperCurve, PaperPoints, markdown
from ocp_crawl.studies.pressure import (PSI_CURVE_AMPLITUDE_BAR, evaluate_fit, paper_grids,
                                        simulate_pressure)
from ocp_crawl.model.statics import Model

COLUMNS = ("CoT_plus_large_k", "CoT_plus_realistic_k", "CoT_plus_low_k")


def _cot(k_ratio: float, A: float, psi: float = 45.0) -> float:
    r = run_problem(base_problem("paper",
                                 {"robot.k": k_ratio * PAPER_ROBOT.MgL, "gait.A_deg": float(A),
                                  "gait.psi_deg": float(psi)}))
    return r.CoT_plus if r.success else math.nan


def _published(i: int):
    data = read_paper_csv("fig_cot_vs_amplitude.csv")
    keep = np.isfinite(data[COLUMNS[i]])
    return data["A_deg"][keep], data[COLUMNS[i]][keep]


def _point_ok(k_ratio: float, A: float, paper: float, psi: float = 45.0) -> str | None:
    """None if the published point is matched (gait with phase difference ``psi`` [deg]), else why
    not."""
    ours = _cot(k_ratio, A, psi)
    if abs(ours / paper - 1) <= 0.02:
        return None
    h = 0.1
    slope = abs(_cot(k_ratio, A + h, psi) - _cot(k_ratio, A - h, psi)) / (2 * h * ours)
    if not slope > 0.05:
        return f"A {A:.2f}: {ours / paper - 1:+.2%} (well-conditioned, {slope:.1%}/deg)"
    # ill-conditioned: some amplitude within 0.2 deg must give the published value
    edges = np.linspace(A - 0.2, A + 0.2, 5)
    vals = [_cot(k_ratio, a, psi) - paper for a in edges]
    for a, b, fa, fb in zip(edges[:-1], edges[1:], vals[:-1], vals[1:]):
        if fa * fb <= 0:
            root = brentq(lambda x: _cot(k_ratio, x, psi) - paper, a, b, xtol=1e-4)
            assert abs(root - A) <= 0.2
            return None
    return (f"A {A:.2f}: {ours / paper - 1:+.2%} (ill-conditioned, {slope:.1%}/deg, "
            "no amplitude within 0.2 deg)")


@pytest.mark.parametrize("i", [0, 1], ids=["large_k", "realistic_k"])
def test_cot_within_2pc_at_every_published_point(i):
    A, paper = _published(i)
    bad = [why for a, p in zip(A, paper) if (why := _point_ok(COT_K_RATIOS[i], a, p))]
    assert not bad, bad


@pytest.mark.xfail(strict=True,
                   reason="the paper's low-stiffness curve was computed with psi = 42 deg, "
                          "not the 45 deg of its other curves (test_low_k_curve_is_psi_42); "
                          "at 45 deg ours is 2..6 % above it at 12 well- or ill-conditioned "
                          "points, see paper_points.FINDINGS")
def test_cot_low_k_within_2pc_at_every_published_point():
    A, paper = _published(2)
    bad = [why for a, p in zip(A, paper) if (why := _point_ok(COT_K_RATIOS[2], a, p))]
    assert not bad, bad


def test_low_k_first_point_ill_conditioned_and_matched():
    """The first published low-stiffness point (A = 11.59 deg, +8 %) sits where CoT+ changes by ~45
    %/deg: an amplitude within 0.2 deg gives the published value."""
    A, paper = _published(2)
    assert _point_ok(COT_K_RATIOS[2], A[0], paper[0]) is None


@pytest.mark.slow
def test_low_k_curve_is_psi_42():
    """The paper's low-stiffness curve is the gait with phase difference 42 deg (not stated in the
    paper; its other two curves are at 45 deg): every published point within 2 % or, the first
    (ill-conditioned), matched within 0.2 deg; the 32 others within 1 %, while at 45 deg they are up
    to +6 %; and 42 deg is the best fit to 0.5 deg (the rms error over the 32 points is larger at
    41.5 and at 42.5 deg)."""
    A, paper = _published(2)
    bad = [why for a, p in zip(A, paper)
           if (why := _point_ok(COT_K_RATIOS[2], a, p, LOW_K_PAPER_PSI_DEG))]
    assert not bad, bad

    def rel(psi):
        return np.array([_cot(COT_K_RATIOS[2], a, psi) / p - 1 for a, p in zip(A[1:], paper[1:])])

    best = rel(LOW_K_PAPER_PSI_DEG)
    assert np.max(np.abs(best)) < 0.01
    assert np.max(rel(45.0)) > 0.05
    rms = [np.sqrt(np.mean(rel(psi) ** 2)) for psi in (LOW_K_PAPER_PSI_DEG - 0.5,
                                                       LOW_K_PAPER_PSI_DEG + 0.5)]
    assert np.sqrt(np.mean(best ** 2)) < min(rms)


def test_realistic_bias_is_the_stiffness_ratio():
    """The +0.9 % bias of the realistic curve disappears with k/(M g L) = 2.717 (0.84 % below Table
    I's): then every point is within 0.3 %, as the k = 5 curve is with its stated stiffness."""
    A, paper = _published(1)
    rel = np.array([_cot(2.7166, a) / p - 1 for a, p in zip(A, paper)])
    rel_table = np.array([_cot(COT_K_RATIOS[1], a) / p - 1 for a, p in zip(A[::8], paper[::8])])
    assert np.max(np.abs(rel)) < 0.003
    assert np.all(rel_table > 0.003)


def test_paper_form_p0_curve():
    """The paper's form (ref) read literally (nominal p0, amplitude 0.4 bar, flat rest) reproduces
    the paper's simulated p0 curve (RMS <= 0.03 in S/S(1.7 bar) at its 27 points) in the paper's
    convention, not in the physical one (the paper's figures use its printed sign)."""
    p0, _ = paper_grids()
    paper = evaluate_fit(FLAT_REST_DEG, "paper", p0_bar=p0, psi_deg=[45.0],
                         amplitude_p0_bar=PAPER_FORM_AMPLITUDE_BAR,
                         amplitude_psi_bar=PAPER_FORM_AMPLITUDE_BAR)
    assert paper.rms_p0 <= 0.03
    assert np.max(np.abs(paper.err_p0[p0 <= 1.7])) < 0.005
    physical = evaluate_fit(FLAT_REST_DEG, "physical", p0_bar=p0[p0 <= 1.7], psi_deg=[45.0],
                            amplitude_p0_bar=PAPER_FORM_AMPLITUDE_BAR,
                            amplitude_psi_bar=PAPER_FORM_AMPLITUDE_BAR)
    assert physical.rms_p0 > 0.03


@pytest.mark.slow
def test_stored_psi_amplitude_is_the_fit():
    """The stored amplitude of the psi curve is the minimum of its RMS error on the paper's 49
    points (paper's convention), which the 1 deg point bounds below by 0.334/7."""
    _, psi = paper_grids()

    def rms(amp):
        return evaluate_fit(FLAT_REST_DEG, "paper", [1.7], psi, PAPER_FORM_AMPLITUDE_BAR,
                            amp).rms_psi

    best = rms(PSI_CURVE_AMPLITUDE_BAR)
    assert 0.334 / 7 <= best < 0.06
    assert best < rms(PSI_CURVE_AMPLITUDE_BAR - 0.1) and best < rms(PSI_CURVE_AMPLITUDE_BAR + 0.1)


def test_paper_psi_curve_first_point_not_reachable():
    """Why the psi curve is not matched at psi = 1 deg (published 0.33 of the maximum): with the
    form (ref) at p0 = 1.7 bar the robot does not move at all there, for every pressure amplitude up
    to p0, while it moves at 8.3 deg (so the RMS over the 49 points is at least 0.334/7 = 0.048)."""
    model = Model(gravity="paper")
    for amp in (0.4, 1.0, 1.7):
        stuck = simulate_pressure(model, 1.7, 1.0, FLAT_REST_DEG, amplitude_bar=amp)
        moving = simulate_pressure(model, 1.7, 8.3, FLAT_REST_DEG, amplitude_bar=amp)
        assert stuck.success and moving.success
        assert abs(stuck.S) < 1e-3 * abs(moving.S)


def test_paper_form_waveform():
    w = PressureWaveform(1.7, math.radians(40.0), 0.4)
    t = np.linspace(0, 1, 2001)
    p = w(t)
    assert np.allclose(p.mean(axis=1), 1.7, atol=1e-3) and np.allclose(p.max(axis=1), 2.1,
                                                                       atol=1e-5)
    h = 1e-6
    assert np.allclose(w.derivative(0.3), (w(0.3 + h) - w(0.3 - h)) / (2 * h), rtol=1e-6)
    with pytest.raises(ValueError, match="amplitude"):
        PressureWaveform(0.3, 0.0, 0.4)


def test_paper_curve_summary_and_markdown():
    """Median and worst over the points that have a value; a missing value counts as missing and
    beyond 2 %; every table row of the report section has as many cells as its header."""
    c = PaperCurve("cot_low", "CoT+ low k", "A [deg]", np.array([10.0, 20.0, 30.0]),
                   np.array([2.0, 2.0, 2.0]),
                   np.array([2.02, 1.9, np.nan]), ("success", "success", "fold"))
    assert c.median == pytest.approx(0.03) and c.worst == (pytest.approx(-0.05), 20.0)
    assert c.missing == 1 and c.beyond(0.02) == 2
    text = markdown({"paper": PaperPoints("paper", (c,), {})})
    rows = [ln for ln in text.splitlines() if ln.startswith("|")]
    assert len({ln.count("|") for ln in rows}) == 1 and "-5.00%" in text and "20 deg" in text
