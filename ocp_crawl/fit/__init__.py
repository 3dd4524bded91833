"""Calibration from measurements: fit problem keys and the pressure actuator's constants to measured
data.

``read_measurements`` (files of the CSV convention), ``resolve_parameters`` (what to fit, bounds),
``fit_measurements`` (weighted least squares on simulations, uncertainties, identifiability),
``fit_report`` / ``write_fit`` (text, JSON, the fitted problem file, the figure).
"""
from ocp_crawl.io.lazy import lazy_exports

#: public name -> the module that defines it (imported on first use: start-up time, see io/lazy.py)
_EXPORTS = {
    "Measurements": "ocp_crawl.fit.data", "read_measurements": "ocp_crawl.fit.data",
    "Parameter": "ocp_crawl.fit.params", "fittable_names": "ocp_crawl.fit.params",
    "resolve_parameters": "ocp_crawl.fit.params",
    "Direction": "ocp_crawl.fit.solve", "FileFit": "ocp_crawl.fit.solve",
    "FitResult": "ocp_crawl.fit.solve",
    "fit_measurements": "ocp_crawl.fit.solve", "uncertainty": "ocp_crawl.fit.solve",
    "fit_report": "ocp_crawl.fit.report", "write_fit": "ocp_crawl.fit.report",
}

__all__ = ["Direction", "FileFit", "FitResult", "Measurements", "Parameter", "fit_measurements",
           "fit_report",
           "fittable_names", "read_measurements", "resolve_parameters", "uncertainty", "write_fit"]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
