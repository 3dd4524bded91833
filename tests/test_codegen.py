"""The compiled step kernel (nlp/codegen.py) against the SX kernel it was generated from.

Checked through ``map`` as an NLP uses it: values, the Jacobian and the Hessian of a random weighted
sum of the outputs (what IPOPT's exact Hessian of the Lagrangian evaluates) agree to 1e-12 relative
at random points, with the same sparsity; the derivatives of the mapped kernel that IPOPT's solver
builds run compiled code only; an NLP solved by IPOPT has the same iterates (iterations, optimum)
with either; without a C compiler the kernel itself comes back with a warning.
"""
import casadi as cs
import numpy as np
import pytest

from ocp_crawl.model import compiled
from ocp_crawl.model.statics import NP, Model, Robot
from ocp_crawl.model.step_equations import NW, step_equations
from ocp_crawl.nlp.codegen import compiled_kernel, kernel_library

N = 7  # nodes of the map (the kernel does not depend on N)

needs_cc = pytest.mark.skipif(compiled._compiler() is None, reason="no C compiler")


@pytest.fixture(scope="module")
def kernel():
    """The OCP's per-step kernel: step equations and lifting, complementarity products, of
    (phi_prev, w, tau_hat, p) (as the transcription builds it)."""
    phi_prev, w, th, p = (cs.SX.sym("phi_prev", 2), cs.SX.sym("w", NW), cs.SX.sym("tau_hat", 2),
                          cs.SX.sym("p", NP))
    g_eq, g_lift, sv, cv = step_equations(phi_prev, w, th, p)
    return cs.Function("test_kernel", [phi_prev, w, th, p], [cs.vertcat(g_eq, g_lift), sv * cv])


@pytest.fixture(scope="module")
def built(kernel, tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("OCP_CRAWL_CACHE", str(tmp_path_factory.mktemp("cache")))
    mp.delenv("OCP_CRAWL_NO_COMPILE", raising=False)
    try:
        yield kernel_library(kernel)
    finally:
        mp.undo()


def _mapped(fun):
    """x (all inputs but p, stacked) -> (outputs stacked, their Jacobian, Hessian of lam . outputs),
    p and lam parameters, through fun.map(N)."""
    syms = [cs.MX.sym(f"a{i}", fun.size1_in(i), N) for i in range(4)]
    x = cs.vertcat(*[cs.vec(s) for s in syms[:3]])
    y = cs.vertcat(*[cs.vec(o) for o in fun.map(N)(*syms)])
    lam = cs.MX.sym("lam", y.numel())
    H, _ = cs.hessian(cs.dot(lam, y), x)
    return cs.Function("mapped", [x, cs.vec(syms[3]), lam], [y, cs.jacobian(y, x), H])


def _random_point(rng, model):
    x = np.concatenate([rng.uniform(1.0, 2.2, (2, N)).ravel(order="F"),
                        rng.uniform(-1.0, 2.0, (NW, N)).ravel(order="F"),
                        rng.uniform(-0.5, 0.5, (2, N)).ravel(order="F")])
    return x, np.tile(model.p, N)


@pytest.mark.slow
@needs_cc
def test_compiled_kernel_values_jacobian_and_hessian_equal_the_sx_kernel(kernel, built):
    assert built.compiled and built.function.class_name() == "External"
    ref, fast = _mapped(kernel), _mapped(built.function)
    for k in range(3):  # same structure: no lost nonzero, no dense block
        assert fast.sparsity_out(k) == ref.sparsity_out(k)
    rng = np.random.default_rng(13)
    model = Model(Robot.paper(mu1=0.33, mu2=0.45))
    for _ in range(10):
        x, p = _random_point(rng, model)
        lam = rng.standard_normal(ref.size1_out(0))
        for a, b in zip(ref(x, p, lam), fast(x, p, lam)):
            a, b = np.asarray(a.nonzeros()), np.asarray(b.nonzeros())
            assert np.max(np.abs(a)) > 0
            np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12 * np.max(np.abs(a)))


@needs_cc
def test_ipopt_derivatives_of_the_mapped_kernel_run_compiled_code(built):
    syms = [cs.MX.sym(f"a{i}", built.fun.size1_in(i), N) for i in range(4)]
    x = cs.vertcat(*[cs.vec(s) for s in syms[:3]])
    g = cs.vertcat(*[cs.vec(o) for o in built.function.map(N)(*syms)])
    solver = cs.nlpsol("s", "ipopt", {"x": x, "p": cs.vec(syms[3]), "f": cs.sumsqr(x), "g": g},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes"})
    for name in ("nlp_g", "nlp_jac_g", "nlp_hess_l"):
        kinds = {f.class_name() for f in solver.get_function(name).find_functions()
                 if "test_kernel" in f.name()}
        assert "External" in kinds and "SXFunction" not in kinds, (name, kinds)


def _solve(fun, model):
    """A small NLP through fun.map(N): N independent steps of the paper robot (the step equations as
    constraints, the complementarity products relaxed to <= 1e-3), torques near a sine, the slip of
    foot 1 rewarded; (stats, x, f)."""
    syms = [cs.MX.sym(f"a{i}", fun.size1_in(i), N) for i in range(3)]
    eqs, comp = fun.map(N)(*syms, cs.repmat(cs.DM(model.p), 1, N))
    x = cs.vertcat(*[cs.vec(s) for s in syms])
    tau = cs.vec(syms[2])
    f = (cs.sumsqr(tau - 0.2 * np.sin(np.linspace(0, 2 * np.pi, 2 * N)))
         - 0.05 * cs.sum2(syms[1][4, :] - syms[1][5, :]))
    solver = cs.nlpsol("s", "ipopt", {"x": x, "f": f, "g": cs.vertcat(cs.vec(eqs), cs.vec(comp))},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
                        "ipopt.tol": 1e-10})
    lbw = np.r_[0.0, 0.0, -np.inf, -np.inf, np.zeros(8)]
    lbx = np.r_[np.zeros(2 * N), np.tile(lbw, N), np.full(2 * N, -1.0)]
    x0 = np.r_[np.full(2 * N, 1.6),
               np.tile(np.r_[1.6, 1.6, 0.0, 0.0, np.zeros(4), np.full(4, 0.3)], N), np.zeros(2 * N)]
    sol = solver(x0=x0, lbx=lbx,
                 ubx=np.r_[np.full(2 * N, np.pi), np.full(NW * N, np.inf), np.ones(2 * N)],
                 lbg=np.r_[np.zeros(8 * N), np.full(4 * N, -np.inf)],
                 ubg=np.r_[np.zeros(8 * N), np.full(4 * N, 1e-3)])
    return solver.stats(), np.asarray(sol["x"]).ravel(), float(sol["f"])


@needs_cc
def test_an_nlp_solved_with_the_compiled_kernel_has_the_same_iterates(kernel, built):
    model = Model(Robot.paper())
    st_ref, x_ref, f_ref = _solve(kernel, model)
    st, x, f = _solve(built.function, model)
    assert st_ref["return_status"] == st["return_status"] == "Solve_Succeeded"
    assert st["iter_count"] == st_ref["iter_count"]
    assert f == pytest.approx(f_ref, rel=1e-9)
    np.testing.assert_allclose(x, x_ref, rtol=0, atol=1e-7 * np.max(np.abs(x_ref)))


def test_without_a_compiler_the_kernel_itself_comes_back_with_a_warning(kernel, monkeypatch,
                                                                        tmp_path):
    monkeypatch.setenv("OCP_CRAWL_CACHE", str(tmp_path))
    monkeypatch.delenv("OCP_CRAWL_NO_COMPILE", raising=False)
    monkeypatch.setenv("PATH", "")
    monkeypatch.delenv("CC", raising=False)
    with pytest.warns(RuntimeWarning, match="test_kernel is not compiled .*same results"):
        fun = compiled_kernel(kernel)
    assert fun is kernel and not list(tmp_path.iterdir())


def test_compilation_disabled_on_purpose_is_silent(kernel, monkeypatch, recwarn):
    monkeypatch.setenv("OCP_CRAWL_NO_COMPILE", "1")
    assert compiled_kernel(kernel) is kernel and not recwarn.list
    with pytest.raises(TypeError, match="casadi.Function"):
        compiled_kernel("kernel")
