"""The robot: named parameters, kinematics and statics, contact modes, step equations, input
signals; planar chains of n links (``Chain``: their statics, stability and joint-angle inputs)."""
from ocp_crawl.io.lazy import lazy_exports

#: public name -> the module that defines it (imported on first use: start-up time, see io/lazy.py)
_EXPORTS = {
    "Model": "ocp_crawl.model.statics", "Robot": "ocp_crawl.model.statics",
    "CallableSignal": "ocp_crawl.model.inputs", "FourierSeries": "ocp_crawl.model.inputs",
    "Harmonic": "ocp_crawl.model.inputs", "PeriodicLinear": "ocp_crawl.model.sampled",
    "PeriodicPchip": "ocp_crawl.model.sampled", "PeriodicSignal": "ocp_crawl.model.inputs",
    "PeriodicSpline": "ocp_crawl.model.sampled", "ReferenceTorque": "ocp_crawl.model.inputs",
    "Pulse": "ocp_crawl.model.pulse", "TorqueReference": "ocp_crawl.model.inputs",
    "as_signal": "ocp_crawl.model.inputs",
    "Chain": "ocp_crawl.model.chain", "ChainModel": "ocp_crawl.model.chain_model",
    "JointFourier": "ocp_crawl.model.chain_inputs", "JointSamples": "ocp_crawl.model.chain_inputs",
    "ChainReferenceTorque": "ocp_crawl.model.chain_inputs",
    "JointLinear": "ocp_crawl.model.sampled", "JointPchip": "ocp_crawl.model.sampled",
    "JointSpline": "ocp_crawl.model.sampled", "JointPulse": "ocp_crawl.model.pulse",
}

__all__ = [
    "Model", "Robot", "CallableSignal", "FourierSeries", "Harmonic", "PeriodicLinear",
    "PeriodicPchip",
    "PeriodicSignal", "PeriodicSpline", "Pulse", "ReferenceTorque", "TorqueReference", "as_signal",
    "Chain", "ChainModel", "ChainReferenceTorque", "JointFourier", "JointSamples", "JointLinear",
    "JointPchip", "JointSpline", "JointPulse",
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
