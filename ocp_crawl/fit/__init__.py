"""Calibration from measurements: fit problem keys and the pressure actuator's constants to measured data.

``read_measurements`` (files of the CSV convention), ``resolve_parameters`` (what to fit, bounds),
``fit_measurements`` (weighted least squares on simulations, uncertainties, identifiability),
``fit_report`` / ``write_fit`` (text, JSON, the fitted problem file, the figure).
"""
from ocp_crawl.fit.data import Measurements, read_measurements
from ocp_crawl.fit.params import Parameter, fittable_names, resolve_parameters
from ocp_crawl.fit.solve import Direction, FileFit, FitResult, fit_measurements, uncertainty

__all__ = ["Direction", "FileFit", "FitResult", "Measurements", "Parameter", "fit_measurements", "fittable_names",
           "read_measurements", "resolve_parameters", "uncertainty"]
