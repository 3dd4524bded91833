"""The robot: named parameters, kinematics and statics, contact modes, step equations, input signals."""
from ocp_crawl.model.statics import Model, Robot
from ocp_crawl.model.inputs import (CallableSignal, FourierSeries, Harmonic, PeriodicLinear, PeriodicPchip,
                                    PeriodicSignal, PeriodicSpline, Pulse, ReferenceTorque, TorqueReference, as_signal)

__all__ = ["Model", "Robot", "CallableSignal", "FourierSeries", "Harmonic", "PeriodicLinear", "PeriodicPchip",
           "PeriodicSignal", "PeriodicSpline", "Pulse", "ReferenceTorque", "TorqueReference", "as_signal"]
