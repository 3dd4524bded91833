"""Calls through a CasADi function's buffer (model/buffered.py) give the plain call's numbers.

Checked on the n-link chain's functions the simulators call that way (dense and sparse outputs,
mapped over columns, one output and two), at random points; symbolic inputs and calls from
another thread go through the plain call.
"""
import threading

import casadi as cs
import numpy as np
import pytest

from ocp_crawl.model.buffered import Buffered
from ocp_crawl.model.chain_statics import chain_symbolic


def _plain(fun, args):
    out = fun(*args)
    return [np.asarray(o) for o in (out if isinstance(out, (list, tuple)) else [out])]


def _random_args(fun, rng):
    return [rng.uniform(0.5, 2.5, (fun.size1_in(i), fun.size2_in(i))) for i in range(fun.n_in())]


@pytest.mark.parametrize("n", [3, 5])
@pytest.mark.parametrize("name", ["system", "evaluate", "kin", "ddot2"])
def test_buffered_call_equals_the_plain_call(n, name):
    fun = getattr(chain_symbolic(n), name)
    rng = np.random.default_rng(n)
    b = Buffered(fun)
    for _ in range(3):
        args = _random_args(fun, rng)
        out = b(*args)
        outs = out if isinstance(out, tuple) else (out,)
        for got, want in zip(outs, _plain(fun, args), strict=True):
            assert got.shape == want.shape
            np.testing.assert_array_equal(got, want)


def test_a_sparse_output_is_returned_dense():
    x = cs.SX.sym("x", 3)
    fun = cs.Function("diag", [x], [cs.diag(cs.sin(x)), x[0] * x[2]])
    assert not fun.sparsity_out(0).is_dense()
    got = Buffered(fun)(np.array([0.3, 0.5, 0.7]))
    np.testing.assert_array_equal(got[0], np.diag(np.sin([0.3, 0.5, 0.7])))
    assert got[1].shape == (1, 1) and got[1][0, 0] == 0.3 * 0.7


def test_mapped_columns_and_shared_inputs():
    fun = chain_symbolic(4).system
    mapped = fun.map("system_cols8", "serial", 8, [2, 3], [])
    rng = np.random.default_rng(1)
    args = [rng.uniform(0.5, 2.5, (4, 8)), rng.uniform(-0.1, 0.1, (3, 8)),
            np.array([0.0, 1.0, 1.0, 0.0]), rng.uniform(0.1, 1.0, fun.size1_in(3))]
    for got, want in zip(Buffered(mapped)(*args), _plain(mapped, args), strict=True):
        np.testing.assert_array_equal(got, want)


def test_symbolic_inputs_and_other_threads_take_the_plain_call(monkeypatch):
    fun = chain_symbolic(3).kin
    b = Buffered(fun)
    phi, p = cs.MX.sym("phi", 2), cs.MX.sym("p", fun.size1_in(1))
    assert isinstance(b(phi, p), cs.MX)
    args = _random_args(fun, np.random.default_rng(2))
    want = _plain(fun, args)[0]

    def no_buffer():
        raise AssertionError("the buffer was used")

    monkeypatch.setattr(b, "_eval", no_buffer)
    seen = []
    thread = threading.Thread(target=lambda: seen.append(b(*args)))
    thread.start()
    thread.join()
    np.testing.assert_array_equal(seen[0], want)
    with pytest.raises(AssertionError, match="the buffer was used"):
        b(*args)


def test_results_are_new_arrays_and_a_wrongly_shaped_input_is_refused():
    """A result is not overwritten by the next call; a matrix in another shape with the same
    number of entries (transposed) is refused as by the plain call, not read column-major."""
    x = cs.SX.sym("x", 2, 3)
    fun = cs.Function("twice", [x], [2 * x])
    b = Buffered(fun)
    a = np.arange(6.0).reshape(2, 3)
    first = b(a)
    second = b(a + 1)
    np.testing.assert_array_equal(first, 2 * a)
    np.testing.assert_array_equal(second, 2 * (a + 1))
    with pytest.raises(RuntimeError):
        b(a.T)
    with pytest.raises(RuntimeError):  # a wrong size, as in the plain call
        b(np.ones(7))
