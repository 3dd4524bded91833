"""Parameter sweeps: grids, executors (serial, process pool, Dask), the journal store and SweepResult."""
from ocp_crawl.sweep.executors import default_jobs
from ocp_crawl.sweep.grid import check_some_point_valid, grid_from_specs, normalize_grid, parse_grid
from ocp_crawl.sweep.journal import JOURNAL_FILE, RESULTS_FILE, SETTINGS_FILE, SUMMARY_FILE
from ocp_crawl.sweep.result import SUCCESS, SweepResult
from ocp_crawl.sweep.run import run_sweep
from ocp_crawl.sweep.settings import SweepError, SweepFailed, SweepSettings

__all__ = ["JOURNAL_FILE", "RESULTS_FILE", "SETTINGS_FILE", "SUCCESS", "SUMMARY_FILE", "SweepError", "SweepFailed",
           "SweepResult", "SweepSettings", "check_some_point_valid", "default_jobs", "grid_from_specs",
           "normalize_grid", "parse_grid", "run_sweep"]
