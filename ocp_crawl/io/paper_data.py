"""The numbers behind the paper's published curves, shipped with the package
(``ocp_crawl/data/paper``)."""
from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np

#: environment variable naming the directory of the paper's data files
PAPER_DATA_ENV = "OCP_CRAWL_PAPER_DATA"


def paper_data_dir() -> Path:
    """Directory of the paper's data files: ``$OCP_CRAWL_PAPER_DATA``, else the copy shipped in the
    package."""
    env = os.environ.get(PAPER_DATA_ENV)
    return Path(env) if env else Path(__file__).resolve().parent.parent / "data" / "paper"


def read_paper_csv(name: str, data_dir: str | Path | None = None) -> dict[str, np.ndarray]:
    """Columns of one of the paper's data files (``<paper_data_dir>/<name>``) as float arrays."""
    path = Path(data_dir or paper_data_dir()) / name
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except OSError as exc:
        raise FileNotFoundError(f"paper data file {path}: {exc.strerror or exc}") from None
    header, body = rows[0], [r for r in rows[1:] if r]
    return {h: np.array([float(r[j]) for r in body]) for j, h in enumerate(header)}
