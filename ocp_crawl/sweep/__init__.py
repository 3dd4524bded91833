"""Parameter sweeps: grids, executors (serial, process pool, Dask), the journal store and
SweepResult."""
from ocp_crawl.io.lazy import lazy_exports

#: public name -> the module that defines it (imported on first use: start-up time, see io/lazy.py)
_EXPORTS = {
    "JOURNAL_FILE": "ocp_crawl.sweep.journal", "RESULTS_FILE": "ocp_crawl.sweep.journal",
    "SETTINGS_FILE": "ocp_crawl.sweep.journal", "SUMMARY_FILE": "ocp_crawl.sweep.journal",
    "SUCCESS": "ocp_crawl.sweep.result", "SweepResult": "ocp_crawl.sweep.result",
    "SweepError": "ocp_crawl.sweep.settings", "SweepFailed": "ocp_crawl.sweep.settings",
    "SweepSettings": "ocp_crawl.sweep.settings",
    "check_some_point_valid": "ocp_crawl.sweep.grid", "grid_from_specs": "ocp_crawl.sweep.grid",
    "normalize_grid": "ocp_crawl.sweep.grid", "parse_grid": "ocp_crawl.sweep.grid",
    "default_jobs": "ocp_crawl.workers",
    "run_sweep": "ocp_crawl.sweep.run",
}

__all__ = [
    "JOURNAL_FILE", "RESULTS_FILE", "SETTINGS_FILE", "SUCCESS", "SUMMARY_FILE", "SweepError",
    "SweepFailed",
    "SweepResult", "SweepSettings", "check_some_point_valid", "default_jobs", "grid_from_specs",
    "normalize_grid", "parse_grid", "run_sweep",
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
