"""Parameter sweeps: grids, executors (serial, process pool, Dask), the journal store and SweepResult."""
from ocp_crawl.sweep.core import SweepError, SweepFailed, SweepResult, SweepSettings, parse_grid, run_sweep

__all__ = ["SweepError", "SweepFailed", "SweepResult", "SweepSettings", "parse_grid", "run_sweep"]
