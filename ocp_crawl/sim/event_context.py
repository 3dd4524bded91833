"""What every part of the event-driven stepper reads and none of them writes:
:class:`StepperContext`.

The model, the input, the options, the compiled functions and the numbers derived from them once
(the round-off level of the scaled guards, the accepted residual of a mode solve, the largest
continuation step, the input's knots).  The parts of :class:`~ocp_crawl.sim.event.HybridStepper`
(the solves, the guards, the checks, event location, the choice of a mode, the output) each take it
at construction.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from ocp_crawl.model.inputs import PeriodicSignal, as_signal, input_knots
from ocp_crawl.model.stability import fast_step
from ocp_crawl.model.statics import Model, fast_ddot2, fast_newton, symbolic
from ocp_crawl.sim.event_kinks import linear_pieces, step_limit
from ocp_crawl.sim.event_state import torque_pair

if TYPE_CHECKING:
    from ocp_crawl.sim.event import HybridOptions


@dataclass(frozen=True, eq=False)
class StepperContext:
    """The fixed inputs of one stepper (build with :meth:`build`)."""

    model: Model
    torque: PeriodicSignal
    """the input: joint torques tau(t) [N m] of the phase t [cycles]"""
    torque_at: Callable
    """t -> (tau(t), tau'(t)) of :func:`~ocp_crawl.sim.event_state.torque_pair` (``values``: as one
    list)"""
    opt: HybridOptions
    sym: Any
    """the symbolic mode system and fold system (:func:`~ocp_crawl.model.statics.symbolic`)"""
    newton: Any
    """compiled Newton solve of a mode (:func:`~ocp_crawl.model.statics.fast_newton`)"""
    step_fn: Any
    """compiled Newton solve with the stability numbers and d'' coefficients
    (:func:`~ocp_crawl.model.stability.fast_step`)"""
    ddot2: Any
    """compiled d'' coefficients of a solved state (:func:`~ocp_crawl.model.statics.fast_ddot2`)"""
    p: Any
    """the model's parameter vector"""
    p_list: list
    """the parameter vector as a list of floats (the tail of every compiled solve's input)"""
    Mg: float
    """weight M g [N]"""
    L: float
    """link length [m]"""
    mu: tuple[float, float]
    """friction coefficients (mu1, mu2)"""
    noise: float
    """round-off level of the scaled guards: the mode equations are scaled by M g L, so the
    conditioning (and the noise in f_t) grows with k/(M g L)"""
    res_tol: float
    """accepted residual of a mode solve: ``residual_tol``, or 10 noise when the stiffness makes the
    round-off floor of the scaled joint balance (about 1e-16 k/(M g L)) reach it (stiff limit)"""
    breakpoints: np.ndarray
    """phases where a sampled input's derivative may have a kink (its knots): quadrature panel
    edges"""
    max_step: float
    """largest continuation step [cycles]: ``max_step``, shortened for a fast input
    (:func:`~ocp_crawl.sim.event_kinks.step_limit`) unless it is linear between its knots"""

    @classmethod
    def build(cls, model: Model, torque, opt: HybridOptions) -> StepperContext:
        """The context of ``model`` driven by ``torque`` (a signal or a callable) with the options
        ``opt``."""
        signal = as_signal(torque)
        robot = model.robot
        noise = 1e-13 * (1.0 + robot.k / robot.MgL)
        breakpoints = input_knots(signal)
        max_step = opt.max_step
        if opt.resolve_input and not linear_pieces(signal, breakpoints):
            max_step = min(max_step, max(step_limit(signal), max_step / 64))
        return cls(model=model, torque=signal, torque_at=torque_pair(signal), opt=opt,
                   sym=symbolic(), newton=fast_newton(), step_fn=fast_step(), ddot2=fast_ddot2(),
                   p=model.p, p_list=np.asarray(model.p, float).ravel().tolist(),
                   Mg=robot.M * robot.g, L=robot.L, mu=(robot.mu1, robot.mu2), noise=noise,
                   res_tol=max(opt.residual_tol, 10 * noise), breakpoints=breakpoints,
                   max_step=max_step)
