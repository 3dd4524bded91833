"""Numeric calls of CasADi functions through their buffers (``Function.buffer``).

A CasADi ``Function`` called from Python converts each argument into a ``DM`` and each result back;
for the small SX functions of the n-link chain that conversion is most of the call (the five-link
mode system: about 90 us a call, 22 us through :class:`Buffered`, 11 us of them the evaluation).
:class:`Buffered` copies the inputs into arrays the function reads in place and returns its outputs
as new dense arrays, the same numbers as the plain call.  The functions themselves stay ``Function``
objects (the chain's MPCC builds expressions from them); only numeric hot loops call them through a
:class:`Buffered`.
"""
from __future__ import annotations

import threading

import casadi as cs
import numpy as np


class Buffered:
    """``fun`` evaluated through its buffer: ``Buffered(fun)(*inputs)`` returns what
    ``fun(*inputs)`` returns, as dense float arrays of the outputs' shapes (one array for one
    output, else a tuple).

    Inputs are numbers or arrays of each input's number of entries (column-major, as CasADi reads
    a matrix).  A buffer belongs to the thread that made it: a call from another thread, or with
    symbolic or wrongly sized inputs, goes through the plain call."""

    def __init__(self, fun: cs.Function):
        self.fun = fun
        self._thread = threading.get_ident()
        self._buf, self._eval = fun.buffer()
        n_in, n_out = fun.n_in(), fun.n_out()
        self._in = [np.zeros(fun.nnz_in(i)) for i in range(n_in)]
        self._shapes_in = [(fun.size1_in(i), fun.size2_in(i)) for i in range(n_in)]
        self._dense_in = all(fun.sparsity_in(i).is_dense() for i in range(n_in))
        self._out = [np.zeros(fun.nnz_out(i)) for i in range(n_out)]
        for i, a in enumerate(self._in):
            self._buf.set_arg(i, memoryview(a))
        for i, a in enumerate(self._out):
            self._buf.set_res(i, memoryview(a))
        self._shapes = [(fun.size1_out(i), fun.size2_out(i)) for i in range(n_out)]
        # the (rows, columns) of a sparse output's entries; None for a dense one
        self._entries = [None if fun.sparsity_out(i).is_dense()
                         else fun.sparsity_out(i).get_triplet() for i in range(n_out)]

    def __call__(self, *inputs):
        if (threading.get_ident() != self._thread or not self._dense_in
                or len(inputs) != len(self._in)):
            return self._plain(inputs)
        for buf, shape, x in zip(self._in, self._shapes_in, inputs):
            if isinstance(x, (cs.SX, cs.MX)):
                return self._plain(inputs)
            a = np.asarray(x, float)
            # a matrix is read column-major in its own shape only: any other shape (a transposed
            # matrix of as many entries) is the plain call's to accept or refuse
            if a.size != buf.size or a.ndim > 2 or (a.ndim == 2 and a.shape != shape):
                return self._plain(inputs)
            buf[:] = a.ravel(order="F")
        self._eval()
        if self._buf.ret() != 0:
            raise FloatingPointError(f"{self.fun.name()}: evaluation failed")
        outs = []
        for out, shape, entries in zip(self._out, self._shapes, self._entries):
            if entries is None:
                outs.append(out.reshape(shape, order="F").copy())
            else:
                dense = np.zeros(shape)
                dense[entries[0], entries[1]] = out
                outs.append(dense)
        return outs[0] if len(outs) == 1 else tuple(outs)

    def _plain(self, inputs):
        out = self.fun(*inputs)
        if any(isinstance(x, (cs.SX, cs.MX)) for x in inputs):
            return out
        if isinstance(out, (list, tuple)):
            return tuple(np.asarray(o, float) for o in out)
        return np.asarray(out, float)
