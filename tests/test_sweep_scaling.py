"""What makes a sweep scale: compiled functions built once per process, not per point; points
sent to the workers in chunks; the journal fsync'd about once a second, not per row."""
import os
from pathlib import Path

import numpy as np
import pytest

from ocp_crawl.model import compiled
from ocp_crawl.sweep import executors, journal, run_sweep
from ocp_crawl.sweep.journal import SweepStore

REPO = Path(__file__).resolve().parent.parent
PAPER = REPO / "problems" / "paper_gait.toml"
GRID = {"gait.psi_deg": list(np.linspace(0.0, 180.0, 8))}


def _rows(res):
    return [{k: v for k, v in r.items() if k != "message"} for r in res.rows]


@pytest.fixture
def constructions(tmp_path, monkeypatch):
    """Log the pid of every FastFunction built from now on (fresh builders: their per-process caches
    cleared)."""
    log = tmp_path / "built.log"
    init = compiled.FastFunction.__init__

    def logged(self, fun):
        with open(log, "a") as fh:
            fh.write(f"{os.getpid()}\n")
        init(self, fun)

    monkeypatch.setattr(compiled.FastFunction, "__init__", logged)
    for builder in compiled.BUILDERS.values():
        builder.cache_clear()

    def by_pid() -> dict[int, int]:
        pids = [int(line) for line in log.read_text().split()] if log.exists() else []
        return {pid: pids.count(pid) for pid in set(pids)}
    return by_pid


def test_compiled_functions_are_built_once_per_process_not_per_point(constructions):
    run_sweep(PAPER, GRID, jobs=1)
    serial = constructions()
    assert list(serial) == [os.getpid()]
    n_functions = serial[os.getpid()]
    assert 1 <= n_functions <= len(compiled.BUILDERS)  # 8 points, each function built once

    for builder in compiled.BUILDERS.values():
        builder.cache_clear()
    forked = executors.mp_context().get_start_method() == "fork"
    res = run_sweep(PAPER, GRID, jobs=2)
    parallel = constructions()
    # forked workers inherit the parent's functions (it runs the first points); without fork (a
    # thread of an earlier test still running) the parent runs no point but may build what its own
    # checks of the problem use (at most once each), and the workers, which do not inherit the
    # logging either, build their own (once each)
    parent = parallel[os.getpid()] - n_functions
    assert parent == n_functions if forked else 0 <= parent <= n_functions
    workers = {pid: n for pid, n in parallel.items() if pid != os.getpid()}
    assert not workers if forked else all(n <= n_functions for n in workers.values())
    assert res.counts().get("success", 0) >= 6


def test_points_go_to_the_workers_in_chunks_with_the_same_rows(monkeypatch):
    sizes = []
    chunks = executors._chunks

    def recorded(tasks, size):
        sizes.append(size)
        return chunks(tasks, size)

    monkeypatch.setattr(executors, "_chunks", recorded)
    monkeypatch.setattr(executors, "CHUNK_SECONDS", 100.0)  # as if every point took a microsecond
    monkeypatch.setattr(executors, "CHUNKS_PER_WORKER", 1)
    chunked = run_sweep(PAPER, GRID, jobs=2)
    first_here = 2 if executors.mp_context().get_start_method() == "fork" else 0
    assert sizes == [(len(GRID["gait.psi_deg"]) - first_here) // 2]
    assert _rows(chunked) == _rows(run_sweep(PAPER, GRID, jobs=1))


def test_chunk_size():
    # ~3 ms points: 16 per chunk (50 ms), unless there would be fewer than CHUNKS_PER_WORKER chunks
    # per worker
    assert executors.chunk_size(1147, 2, 0.003) == 16
    assert executors.chunk_size(40, 2, 0.003) == 40 // (2 * executors.CHUNKS_PER_WORKER)
    # a point longer than a chunk's time: one per chunk
    assert executors.chunk_size(1147, 2, 0.5) == 1
    assert executors.chunk_size(1, 4, 0.0) == 1


def test_journal_is_fsynced_about_once_a_second_not_per_row(tmp_path, monkeypatch):
    syncs = []
    sync = SweepStore._sync

    def counted(self):
        syncs.append(self.journal_path)
        sync(self)

    monkeypatch.setattr(SweepStore, "_sync", counted)
    res = run_sweep(PAPER, GRID, out_dir=tmp_path / "a", jobs=1)
    # the header, then at most one per FSYNC_SECONDS while the 8 rows come (none at the end:
    # results.csv is written)
    assert 1 <= len(syncs) <= 2 + res.elapsed / journal.FSYNC_SECONDS
    syncs.clear()
    monkeypatch.setattr(journal, "FSYNC_SECONDS", 0.0)
    run_sweep(PAPER, GRID, out_dir=tmp_path / "b", jobs=1)
    # the counter sees every fsync: header and each row
    assert len(syncs) == 1 + len(GRID["gait.psi_deg"])


def test_an_interrupted_sweep_syncs_its_journal_on_the_way_out(tmp_path, monkeypatch):
    synced = []
    sync, append = SweepStore._sync, SweepStore.append

    def counted(self):
        synced.append(self.journal_path.read_text().count("\n"))
        sync(self)

    def interrupted_at_the_fourth(self, settings, index, row):
        if sum(1 for _ in open(self.journal_path)) == 4:
            raise KeyboardInterrupt
        append(self, settings, index, row)

    monkeypatch.setattr(SweepStore, "_sync", counted)
    monkeypatch.setattr(SweepStore, "append", interrupted_at_the_fourth)
    # no fsync while the rows come: only the one at the end
    monkeypatch.setattr(journal, "FSYNC_SECONDS", 1e9)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(PAPER, GRID, out_dir=tmp_path / "s", jobs=1)
    assert synced[-1] == 4  # the header and three rows are on disk
