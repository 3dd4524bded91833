"""Co-design: the NLP with design variables is the fixed robot's NLP at every design (checked
against the NLP built for that robot), its stability rows against the reduced stiffness computed
apart, the bounds and the uniform body as errors naming the bound (the command's one-line
refusals: tests/_bad_input_rows.py), and the command end to end (the chosen design's optimum
replays, beats the given robot's optimal gait and every scanned design's harmonic gait, and its
optimal_gait.toml reproduces it)."""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from ocp_crawl import Robot
from ocp_crawl.cli import main
from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_stability import reduced_stiffness_matrix
from ocp_crawl.ocp.chain_search import ChainWave
from ocp_crawl.ocp.codesign import design_points
from ocp_crawl.ocp.design import Design
from ocp_crawl.ocp.plant import Plant
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.transcription import GaitOCP
from ocp_crawl.problem import load_problem

ROBOT = Robot.paper()
THREE = Chain.from_robot(ROBOT)
#: a four-link chain of unequal links, uniform (masses proportional to the lengths)
FOUR = Chain(lengths=(0.03, 0.035, 0.025, 0.03), masses=(0.012, 0.014, 0.010, 0.012),
             stiffness=(0.15, 0.3, 0.2), mu=(0.4, 0.35))
FILE = Path(__file__).resolve().parents[1] / "problems" / "codesign_stiffness.toml"


def _common_rows(a: GaitOCP, b: GaitOCP, x_a: np.ndarray, x_b: np.ndarray) -> float:
    """The largest difference of the constraint blocks both NLPs have, at x_a and x_b."""
    ga, gb = (np.asarray(o._g(x)).ravel() for o, x in ((a, x_a), (b, x_b)))
    return max(float(np.max(np.abs(ga[a.slices[k]] - gb[sl]), initial=0.0))
               for k, sl in b.slices.items() if k.startswith("g_") and k in a.slices)


@pytest.mark.parametrize("chain, design, centres", [
    (THREE, Design(stiffness=[(0.02, 2.0)]), None),
    (FOUR, Design(stiffness=[(0.05, 1.0)], lengths=[(0.01, 0.06)]), (90.0, 170.0, 90.0)),
])
def test_the_design_nlp_is_the_fixed_robots_nlp_at_every_design(chain, design, centres):
    """At a design other than the robot's, the NLP with design variables equals the NLP built for
    the robot of that design (its numbers, not expressions; its torque rates weighed as the
    co-design NLP weighs them): objective, every common constraint block (the stability rows
    among them), and the envelope's rows at the torque bounds of that robot."""
    settings = OCPSettings(nodes=8, A_max_deg=25.0, gamma_deg=100.0, gamma_joints_deg=centres)
    cd = GaitOCP(chain, "physical", settings, design=design, stability=0.05)
    values = cd.design.initial(chain) * np.linspace(0.8, 1.3, len(cd.design.names(chain)))
    if design.lengths:   # the total length kept
        n = chain.n
        values[-n:] *= chain.L / values[-n:].sum()
    other = cd.design.chain_of(chain, values)
    fixed = GaitOCP(other, "physical", settings, stability=0.05,
                    rate_weights=np.array(chain.stiffness) / other.stiffness)
    x_f = fixed.initial_guess(ChainWave(20.0, 30.0, "harmonic").torque(settings, other), 0.4)
    x_c = np.zeros(cd.nx)
    for k, sl in fixed.slices.items():
        if not k.startswith("g_"):
            x_c[cd.slices[k]] = x_f[sl]
    x_c[cd.slices["design"]] = values / cd.design.initial(chain)
    assert cd.objective(x_c) == pytest.approx(fixed.objective(x_f), rel=1e-12)
    assert _common_rows(cd, fixed, x_c, x_f) < 1e-12
    assert "g_stability_0" in cd.slices and "g_stability_0" in fixed.slices
    # the envelope as rows: zero exactly where the fixed robot's torque sits at its bound
    g = np.asarray(cd._g(x_c)).ravel()
    tau = x_f[fixed.slices["tau"]]
    assert np.allclose(g[cd.slices["g_tau_low"]], tau - fixed.lbx[fixed.slices["tau"]],
                       atol=1e-12)
    assert np.allclose(g[cd.slices["g_tau_high"]], fixed.ubx[fixed.slices["tau"]] - tau,
                       atol=1e-12)
    np.testing.assert_allclose(cd.design_values(x_c), values, rtol=1e-15)


@pytest.mark.parametrize("chain", [THREE.replace(stiffness=(0.03, 0.02)), FOUR])
def test_the_stability_rows_change_sign_at_the_reduced_stiffness(chain):
    """The NLP's stability rows at a configuration are all >= 0 exactly when kappa_min is at most
    the smallest eigenvalue of the stick-stick reduced stiffness over M g L, computed apart
    (:func:`~ocp_crawl.model.chain_stability.reduced_stiffness_matrix`: an orthonormal tangent
    basis, numpy's eigenvalues)."""
    plant = Plant(chain)
    rng = np.random.default_rng(3)
    centre = np.full(2, np.pi / 2) if chain.n == 3 else np.array([1.6, 2.9, 1.6])
    for _ in range(4):
        phi = centre + rng.uniform(-0.25, 0.25, chain.n_joints)
        ft_hat = rng.uniform(-0.2, 0.2)
        K = reduced_stiffness_matrix(plant.model, phi, ft_hat * chain.M * chain.g) / chain.MgL
        kappa = float(np.linalg.eigvalsh(K)[0])
        for k_min, holds in ((0.0, True), (0.999 * kappa, True), (1.001 * kappa, False)):
            rows = np.asarray(plant.stability_function(phi, ft_hat, plant.p, k_min)).ravel()
            assert bool(np.all(rows >= 0)) == holds, (kappa, k_min, rows)


def test_a_design_keeps_the_totals_and_a_uniform_body():
    """Free lengths keep the total length and mass, the masses proportional to the lengths; the
    scan's designs lie inside the bounds with the robot's own first."""
    d = Design(stiffness=[(0.05, 1.0)], lengths=[(0.01, 0.06)]).checked(FOUR)
    assert d.names(FOUR) == ["stiffness[0]", "stiffness[1]", "stiffness[2]", "lengths[0]",
                             "lengths[1]", "lengths[2]", "lengths[3]"]
    pts = design_points(FOUR, d, 6)
    np.testing.assert_array_equal(pts[0], d.initial(FOUR))
    lo, hi = d.limits()
    for p in pts:
        assert np.all(p >= lo) and np.all(p <= hi)
        c = d.chain_of(FOUR, p)
        assert sum(c.lengths) == pytest.approx(FOUR.L, rel=1e-14)
        assert sum(c.masses) == pytest.approx(FOUR.M, rel=1e-14)
        np.testing.assert_allclose(np.array(c.masses) / c.lengths, FOUR.M / FOUR.L, rtol=1e-12)
    assert len(pts) == 6


@pytest.mark.parametrize("design, error", [
    (Design(stiffness=[(0.2, 1.0)]), r"stiffness\[0\]: the robot's 0.15 is outside"),
    (Design(stiffness=[(0.1, 1.0), (0.1, 1.0)]), r"stiffness must give 3 \(low, high\) pairs"),
    (Design(stiffness=[(1.0, 0.1)]), r"stiffness\[0\]: low 1.0 is above high 0.1"),
])
def test_bad_bounds_name_the_bound(design, error):
    with pytest.raises(ValueError, match=error):
        design.checked(FOUR)


def test_free_lengths_need_a_uniform_body():
    lumpy = FOUR.replace(masses=(0.02, 0.014, 0.010, 0.012))
    with pytest.raises(ValueError, match="needs a uniform body"):
        Design(lengths=[(0.01, 0.06)]).checked(lumpy)
    with pytest.raises(ValueError, match="a design is a chain's"):
        GaitOCP(ROBOT, design=Design(stiffness=[(0.02, 2.0)]))


def test_codesign_end_to_end(tmp_path, capsys):
    """The shipped file at N = 10 with two scanned designs (coarse harmonic searches) and one round
    of the local search: success;
    the co-design NLP's value equals the replay at the chosen design (the fixed robot's NLP on
    the optimum's branches);
    better than the given robot's optimal gait and every scanned design's harmonic gait; the
    written optimal_gait.toml, a chain with the chosen stiffnesses, simulates to the replay's S."""
    out = tmp_path / "out"
    # (at N = 12 the co-design NLP's optimum slips at a friction tie, and its replay fails)
    code = main(["codesign", str(FILE), "--set", "ocp.nodes=10", "--set", "design.scan=2",
                 "--set", "ocp.harmonic_A=1", "--set", "ocp.harmonic_psi=6",
                 "--set", "ocp.baseline_evaluations=10", "--set", "design.search_rounds=1",
                 "--jobs", "2", "--json",
                 "--out", str(out)])
    data = json.loads(capsys.readouterr().out)
    assert code == 0, data["message"]
    assert data["status"] == "success"
    # the judge's fixed NLP on the optimum's branches stops where IPOPT's tolerance lets it
    assert data["value_replay"] == pytest.approx(data["value_nlp"], rel=1e-5)
    assert data["value_replay"] > data["given"]["objective_value_replay"]
    assert all(data["value_replay"] > d["value"] for d in data["scan"])
    lo, hi = np.array(data["low"]), np.array(data["high"])
    assert np.all(np.array(data["chosen"]) >= lo) and np.all(np.array(data["chosen"]) <= hi)
    gait = load_problem(out / "optimal_gait.toml")
    assert list(gait.robot.stiffness) == pytest.approx(data["chosen"], rel=1e-15)
    summary = json.loads((out / "summary.json").read_text())
    assert main(["simulate", str(out / "optimal_gait.toml"), "--json"]) == 0
    sim = json.loads(capsys.readouterr().out)
    assert sim["S"] == pytest.approx(summary["S_replay"], rel=1e-9)
    assert (out / "codesign.png").stat().st_size > 0
    # the chosen design's optimum under a friction asymmetry: its own problem file at mu1/mu2 moved
    low, mid, high = summary["friction_asymmetry"]["S_m"][0]
    assert mid == summary["S_replay"]
    mu = math.sqrt(gait.robot.mu1 * gait.robot.mu2)
    for f, S in ((0.995, low), (1.005, high)):
        assert main(["simulate", str(out / "optimal_gait.toml"), "--json",
                     "--set", f"robot.mu1={mu * math.sqrt(f)!r}",
                     "--set", f"robot.mu2={mu / math.sqrt(f)!r}"]) == 0
        assert json.loads(capsys.readouterr().out)["S"] == pytest.approx(S, rel=1e-9)


@pytest.mark.heavy
def test_the_codesign_optimum_beats_a_grid_of_fixed_designs():
    """The shipped file (N = 20, four scanned designs): the co-design optimum by replay against a
    grid of fixed robots around the chosen design, each with the plain OCP's optimum (``optimize``'s
    NLP without the design's rows and weights, its homotopy from the co-design profile with each
    joint's reference angles kept, judged by replay): none is better (minutes)."""
    from ocp_crawl.ocp.judge import replay_signal
    from ocp_crawl.ocp.solve import solve_from
    from ocp_crawl.ocp.solver import GaitSolver
    from ocp_crawl.problem import codesign_problem, ocp_settings
    from ocp_crawl.ocp.plant import Plant

    problem = load_problem(FILE, ["design.scan=4"])
    res = codesign_problem(problem, jobs=2)
    assert res.success, res.message
    settings = ocp_settings(problem)
    tau, T = res.result.tau, res.result.T_ocp
    phase = np.arange(settings.nodes) / settings.nodes
    k = np.array(res.chosen)
    grid = []
    for a in (0.7, 0.85, 1.0):
        for b in (0.8, 1.0, 1.25):
            trial = np.clip(k * (a, b), res.low, res.high)
            chain = res.robot.replace(stiffness=tuple(trial))
            scaled = tau * (trial / k)[:, None]
            r = solve_from(GaitSolver(GaitOCP(chain, problem.gravity, settings)),
                           [Plant(c, problem.gravity) for c in settings.scenarios(chain)],
                           replay_signal(phase, scaled), T)
            if r.success:
                grid.append(r.value_replay)
    assert len(grid) >= 7
    # at the chosen design the plain OCP's regularisation differs from the co-design NLP's (its
    # torque rates unweighted): the same optimum to about 1e-6
    assert max(grid) <= res.value_replay * (1 + 1e-5)
