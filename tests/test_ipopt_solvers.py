"""The IPOPT solvers of an NLP are built on first use and share one set of derivative functions; a
solve serves large blocks from the heap and restores glibc's defaults afterwards."""
from __future__ import annotations

import ctypes

import casadi as cs
import numpy as np
import pytest

from ocp_crawl.nlp import ipopt as nlp_ipopt
from ocp_crawl.nlp import process as nlp_process
from ocp_crawl.nlp.ipopt import OCP_IPOPT, OCP_WARM_IPOPT, LazySolver, call_ipopt, ipopt_solvers
from ocp_crawl.nlp.process import heap_allocations


def _nlp():
    x = cs.SX.sym("x", 2)
    return {"x": x, "f": (x[0] - 1) ** 2 + (x[1] - 2) ** 2, "g": x[0] + x[1]}


def _solvers(monkeypatch, stage_tol=1e-4, user=None):
    built = []
    real = nlp_ipopt.build_ipopt

    def counting(name, nlp, options, owner, user_options):
        built.append((name, sorted(k for k in options if k in nlp_ipopt.DERIVATIVES)))
        return real(name, nlp, options, owner, user_options)

    monkeypatch.setattr(nlp_ipopt, "build_ipopt", counting)
    solvers = ipopt_solvers("t", _nlp(), OCP_IPOPT, OCP_WARM_IPOPT, user or {}, "owner",
                            stage_tol=stage_tol)
    return solvers, built


def test_solvers_are_built_on_first_use_and_share_the_first_ones_derivatives(monkeypatch):
    solvers, built = _solvers(monkeypatch)
    assert [name for name, _ in built] == ["t_options"]  # only the option check so far
    assert all(isinstance(s, LazySolver) and not s.built for s in solvers[:4])
    call = call_ipopt(solvers.stage_warm, 2, 1, x0=np.zeros(2), lbg=3.0, ubg=3.0)
    assert call.usable and np.allclose(call.x, [1.0, 2.0], atol=1e-6)
    # the first: own derivatives
    assert [name for name, _ in built[1:]] == ["t_stage_warm"] and built[1][1] == []
    assert solvers.stage_warm.built and not solvers.cold.built and not solvers.warm.built
    call = call_ipopt(solvers.cold, 2, 1, x0=np.zeros(2), lbg=3.0, ubg=3.0)
    assert call.usable and np.allclose(call.x, [1.0, 2.0], atol=1e-6)
    # reuses the first one's derivative functions
    assert built[2] == ("t_cold", sorted(nlp_ipopt.DERIVATIVES))
    # the same objects before and after the build (the homotopy compares solvers by identity)
    assert solvers.loose(1e-4) == (solvers.stage_cold, solvers.stage_warm)
    assert solvers.loose(1e-12) == (solvers.cold, solvers.warm)
    assert solvers.cold.name() == "t_cold" and len(built) == 3


@pytest.mark.parametrize("user, warm_strategy",
                         [({}, "monotone"), ({"mu_strategy": "adaptive"}, "adaptive")])
def test_warm_over_sets_the_warm_solvers_options_under_the_users(monkeypatch, user, warm_strategy):
    """``warm_over`` (OCPSettings.warm_barrier) overrides the defaults in every warm-started solver,
    tight and loose, not in the cold ones; the user's options override it."""
    built = {}
    real = nlp_ipopt.build_ipopt

    def recording(name, nlp, options, owner, user_options):
        built[name] = options["ipopt"]
        return real(name, nlp, options, owner, user_options)

    monkeypatch.setattr(nlp_ipopt, "build_ipopt", recording)
    solvers = ipopt_solvers("t", _nlp(), OCP_IPOPT, OCP_WARM_IPOPT, user, "owner", stage_tol=1e-4,
                            warm_over={"mu_strategy": "monotone"})
    for solver in (*solvers[:4], *solvers.loose(1e-6)):
        solver.function()
    assert sorted(built) == ["t_cold", "t_options", "t_stage_cold", "t_stage_cold_loose2",
                             "t_stage_warm", "t_stage_warm_loose2", "t_warm"]
    for name, options in built.items():
        cold = "cold" in name
        assert options["mu_strategy"] == (OCP_IPOPT["mu_strategy"] if cold else warm_strategy), name
        # the warm start's own options: mu_init 1e-6
        assert ("mu_init" in options) == (not cold), name
    assert built["t_stage_warm_loose2"]["tol"] == built["t_stage_cold_loose2"]["tol"] == 1e-6
    assert built["t_warm"]["tol"] == OCP_IPOPT["tol"] and built["t_stage_warm"]["tol"] == 1e-4


def test_bad_options_fail_at_once_naming_the_owner(monkeypatch):
    with pytest.raises(ValueError, match="owner = .*IPOPT rejected the options"):
        _solvers(monkeypatch, user={"no_such_option": 1})


class _FakeMallopt:
    def __init__(self):
        self.calls = []

    def __call__(self, param, value):
        self.calls.append((param, value))
        return 1


def test_heap_allocations_set_and_restore_glibcs_parameters(monkeypatch):
    fake = _FakeMallopt()
    monkeypatch.setattr(nlp_process, "_mallopt", [fake])
    during = [(nlp_process._M_MMAP_MAX, 0), (nlp_process._M_TRIM_THRESHOLD, nlp_process.HEAP_KEEP)]
    with pytest.raises(RuntimeError):
        with heap_allocations():
            with heap_allocations():  # nested: acts once, at the outermost
                assert fake.calls == during
            assert fake.calls == during
            raise RuntimeError("a failed solve")
    assert fake.calls[2:] == list(nlp_process._BETWEEN_SOLVES.items())  # set after an exception too
    assert nlp_process._heap_depth == [0]


@pytest.mark.parametrize("env, found",
                         [({"GLIBC_TUNABLES": "glibc.malloc.trim_threshold=0"}, False),
                          ({"MALLOC_MMAP_MAX_": "0"}, False),
                          ({"GLIBC_TUNABLES": "glibc.pthread.rseq=0"}, True), ({}, True)])
def test_heap_allocations_leave_a_users_malloc_settings_alone(monkeypatch, env, found):
    for var in (*nlp_process.MALLOC_VARIABLES, "GLIBC_TUNABLES"):
        monkeypatch.delenv(var, raising=False)
    for var, value in env.items():
        monkeypatch.setenv(var, value)
    monkeypatch.setattr(nlp_process, "_mallopt", [])
    fun = nlp_process._find_mallopt()
    if not found:
        assert fun is None
    elif not hasattr(ctypes.CDLL(None), "mallopt"):
        pytest.skip("no mallopt in this C library")
    else:
        assert fun is not None
