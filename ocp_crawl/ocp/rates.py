"""Peak joint rates and foot sliding speeds of a replayed gait: what the joints and feet actually
do.

The bandwidth ``max_rate_deg_s`` bounds the reference angles' rate; the joint angles themselves move
faster or slower (springs, gravity, slips).  :func:`replay_peaks` measures, over the steady cycle of
an event-driven replay, the peak actual joint rate |d phi_i/dt| [deg/s] of each joint and the peak
sliding speed |d x_i/dt| [m/s] of each foot.  Between the breakpoints (the input's kinks at the
nodes k/N, the replay's contact events, and at least :data:`MIN_PIECES` equal pieces per cycle) the
motion is smooth (one contact mode, a smooth input), so the replay is sampled again at PIECE_DEGREE
+ 1 Chebyshev-Lobatto phases of every piece (``simulate_torque(..., t_eval=)``), each piece's
samples are interpolated by a polynomial, and its derivative's largest magnitude on the piece (at
its ends or where the second derivative vanishes) is the piece's peak: spectrally accurate on smooth
pieces, one-sided at the jumps of the rates (the slip switches, the kinks of the input).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ocp_crawl.ocp.plant import as_plant

#: degree of each smooth piece's interpolating polynomial (PIECE_DEGREE + 1 samples per piece)
PIECE_DEGREE = 8
#: a piece shorter than this [cycles] is sampled at its ends only (its mean rate: the samples'
#: round-off, divided by a short length, would swamp a higher derivative); one shorter than
#: TINY_PIECE is left out
SHORT_PIECE = 1e-4
TINY_PIECE = 1e-9
#: the fewest pieces per cycle (an input without kinks, e.g. a harmonic gait, is cut into this many)
MIN_PIECES = 64
#: relative tolerance of the judge's check of max_joint_rate_deg_s on the replay's peak rate.  The
#: transcription bounds the mean rate over each interval, and over each sub-step to
#: SUBSTEP_RATE_SLACK (0.5 %) looser (:func:`~ocp_crawl.ocp.substeps.joint_rate_rows`); inside a
#: sub-step (one contact mode, the torque linear in time) the rate changes smoothly, so the peak
#: exceeds the bounded mean by O(1/N) more.  Measured on max_speed at the bound 180 deg/s: 0.63 %
#: above it at N = 20, 0.57 % at N = 50
JOINT_RATE_RTOL = 0.01


@dataclass(frozen=True)
class Peaks:
    """Peak actual rates of a replayed steady cycle (NaN where not measured)."""

    joint_rate_deg_s: tuple = (math.nan, math.nan)
    """largest |d phi_i/dt| of each joint [deg/s]"""
    slip_speed_m_s: tuple = (math.nan, math.nan)
    """largest sliding speed |d x_i/dt| of feet 1 and 2 [m/s] (0 for a foot that never slips)"""


def breakpoints(res, nodes: int | None = None) -> np.ndarray:
    """Phases [cycles, in [0, 1] of the steady cycle] where the motion may be non-smooth: the nodes
    k/N of the input's kinks (``nodes``; None: an input without kinks), the steady cycle's events of
    the replay ``res``, and MIN_PIECES equal pieces; sorted, without pieces shorter than
    TINY_PIECE."""
    grid = [np.linspace(0.0, 1.0, MIN_PIECES + 1)]
    if nodes:
        grid.append(np.arange(nodes + 1) / nodes)
    grid.append(np.clip([e.t - res.t0 for e in res.steady_events()], 0.0, 1.0))
    t = np.unique(np.concatenate(grid))
    keep = np.r_[True, np.diff(t) >= TINY_PIECE]
    t = t[keep]
    t[-1] = 1.0
    return t


def piece_phases(breaks: np.ndarray) -> tuple[np.ndarray, list[slice]]:
    """The sample phases of every piece between consecutive ``breaks`` (Chebyshev-Lobatto, the ends
    included; only the ends on a piece shorter than SHORT_PIECE) and each piece's slice of them."""
    unit = 0.5 * (1.0 - np.cos(np.pi * np.arange(PIECE_DEGREE + 1) / PIECE_DEGREE))
    phases, slices, start = [], [], 0
    for a, b in zip(breaks[:-1], breaks[1:]):
        pts = np.array([a, b]) if b - a < SHORT_PIECE else a + (b - a) * unit
        pts[-1] = b
        phases.append(pts)
        slices.append(slice(start, start + pts.size))
        start += pts.size
    return np.concatenate(phases), slices


def piece_peak(t: np.ndarray, y: np.ndarray) -> float:
    """Largest |dy/dt| on one smooth piece from its samples y at the phases t (the piece's ends
    t[0], t[-1]): the derivative of the interpolating polynomial at the ends and where its second
    derivative vanishes; the secant's slope for two samples."""
    if t.size == 2:
        return abs(float(y[1] - y[0])) / float(t[1] - t[0])
    p = np.polynomial.Chebyshev.fit(t, y, t.size - 1, domain=[t[0], t[-1]])
    dp = p.deriv()
    roots = dp.deriv().roots()
    real = roots[np.abs(roots.imag) <= 1e-9 * (t[-1] - t[0])].real
    inside = real[(real > t[0]) & (real < t[-1])]
    return float(np.max(np.abs(dp(np.r_[t[0], t[-1], inside]))))


def peak_rate(t: np.ndarray, y: np.ndarray, slices: list[slice]) -> float:
    """The largest |dy/dt| [unit of y per cycle] over the pieces (``slices`` of the samples t,
    y)."""
    return max(piece_peak(t[s], y[s]) for s in slices)


def replay_peaks(model, signal, T: float, res, nodes: int | None = None) -> Peaks:
    """Peak joint rates [deg/s] and foot sliding speeds [m/s] of the successful replay ``res`` of
    ``signal`` (the torque input, phases in cycles) at the period T [s]: the replay sampled again on
    its pieces (module docstring).  ``model``: a three-link Model, a ChainModel or a
    :class:`~ocp_crawl.ocp.plant.Plant` (a rate per joint).  ``nodes``: the input's kinks at k/N
    (the linear interpolant of N nodes), None for a smooth input.  NaNs if the dense replay fails or
    T is not positive."""
    nan = Peaks((math.nan,) * np.shape(signal(0.0))[0])   # a NaN per joint
    if not res.success or not T > 0:
        return nan
    te, slices = piece_phases(breakpoints(res, nodes))
    dense = as_plant(model).simulate(signal, t_eval=te)
    if not dense.success or dense.t.size != te.size:
        return nan
    rates = [math.degrees(peak_rate(te, row, slices)) / T for row in dense.phi]
    speeds = [peak_rate(te, x, slices) / T for x in (dense.x1, dense.x2)]
    return Peaks(tuple(rates), tuple(speeds))


def signal_peaks(model, signal, T: float, nodes: int | None = None) -> Peaks:
    """:func:`replay_peaks` of ``signal`` at the period T [s], replayed here first (e.g. the
    harmonic baseline)."""
    return replay_peaks(model, signal, T, as_plant(model).simulate(signal), nodes)
