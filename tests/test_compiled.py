"""The compiled fast path and CasADi's own evaluation give the same numbers."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from ocp_crawl import Model, Robot
from ocp_crawl.model.statics import fast_newton, fast_newton_batch, solve_many, symbolic
from ocp_crawl.sim.event_state import mode_q
from ocp_crawl.sim.result import Mode

SCRIPT = """
import json
from ocp_crawl import *
from ocp_crawl.model.statics import fast_newton
m = Model(Robot.paper(mu1=0.36, mu2=0.41))
r = simulate_torque(m, ReferenceTorque(Harmonic.from_degrees(90, 30, 60), m.robot.k))
print(json.dumps({"compiled": fast_newton().compiled, "S": r.S, "W": r.W_plus,
                  "ev": [e.t for e in r.events]}))
"""


def run(env_extra):
    env = dict(os.environ, **env_extra)
    out = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, env=env,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


@pytest.mark.slow
def test_fallback_without_compiler_gives_identical_results():
    fast = run({})
    slow = run({"OCP_CRAWL_NO_COMPILE": "1"})
    assert slow["compiled"] is False
    assert slow["S"] == pytest.approx(fast["S"], rel=1e-12)
    assert slow["W"] == pytest.approx(fast["W"], rel=1e-12)
    np.testing.assert_allclose(slow["ev"], fast["ev"], rtol=0, atol=1e-12)


def test_fast_newton_equals_casadi_function():
    model = Model(Robot.paper())
    rng = np.random.default_rng(3)
    f = fast_newton()
    sym = symbolic().newton
    for _ in range(20):
        x0 = np.array([*rng.uniform(1.2, 2.0, 2), rng.uniform(-0.3, 0.3)])
        tau = rng.uniform(-0.3, -0.1, 2)
        dtau = rng.uniform(-1, 1, 2)
        q = mode_q(Mode(int(rng.integers(0, 5))), 0.06)
        xa, aa = f(x0, tau, dtau, q, model.p)
        xb, ab = sym(x0, tau, dtau, q, model.p)
        np.testing.assert_allclose(xa, np.asarray(xb).ravel(), rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(aa, np.asarray(ab).ravel(), rtol=1e-12, atol=1e-12)


def test_batched_solve_equals_single_solves():
    model = Model(Robot.paper())
    rng = np.random.default_rng(4)
    n = 70  # more than one batch, with padding
    x0 = np.vstack([rng.uniform(1.3, 1.9, (2, n)), rng.uniform(-0.2, 0.2, (1, n))])
    tau = rng.uniform(-0.3, -0.1, (2, n))
    dtau = rng.uniform(-1, 1, (2, n))
    q = mode_q(Mode.SLIP2_NEG)
    xs, aux = solve_many(x0, tau, dtau, q, model.p)
    f = fast_newton()
    for j in (0, 33, 64, 69):
        xj, aj = f(x0[:, j], tau[:, j], dtau[:, j], q, model.p)
        np.testing.assert_allclose(xs[:, j], xj, rtol=0, atol=1e-14)
        np.testing.assert_allclose(aux[:, j], aj, rtol=1e-13, atol=1e-14)
    assert fast_newton_batch().n_in[0] == 3 * 64
