"""workers.overlap: a task in a forked process while this one does something else."""
import json
import multiprocessing
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import pytest

from ocp_crawl import workers
from ocp_crawl.workers import overlap


def _fresh(code: str) -> dict:
    """Run ``code`` (which prints one JSON object) in a fresh interpreter: no other thread runs
    there, so fork is used (in this one, an earlier test may have left a thread running, e.g. Dask's
    offload thread)."""
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def test_the_task_runs_in_a_fork_and_its_messages_arrive_in_order():
    out = _fresh("""
        import json, os
        from ocp_crawl.workers import mp_context, overlap
        got = []

        def task(send):
            for i in range(50):
                send((i, os.getpid()))
            return {"pid": os.getpid(), "big": list(range(100_000))}  # larger than a pipe's buffer

        result, other = overlap(task, lambda: os.getpid(), got.append)
        print(json.dumps({"method": mp_context().get_start_method(), "parent": os.getpid(),
                          "other": other, "child": result["pid"],
                          "big": result["big"] == list(range(100_000)), "got": got}))
        """)
    assert out["method"] == "fork" and out["other"] == out["parent"] != out["child"] and out["big"]
    assert out["got"] == [[i, out["child"]] for i in range(50)]


class Unpicklable(Exception):
    def __reduce__(self):
        raise TypeError("no pickling")


def test_an_exception_of_the_task_is_raised_here_and_a_dead_child_leaves_the_task_here():
    out = _fresh("""
        import json, os
        from ocp_crawl.workers import overlap

        class Unpicklable(Exception):
            def __reduce__(self):
                raise TypeError("no pickling")

        class Unbuildable(Exception):  # pickles, but cannot be rebuilt from its args
            def __init__(self, a, b):
                super().__init__(f"{a} {b}")

        def raising(exc):
            def task(send):
                raise exc
            try:
                overlap(task, lambda: None, lambda m: None)
            except Exception as caught:
                return [type(caught).__name__, str(caught)]

        parent, got = os.getpid(), []

        def dying(send):
            send(["first", os.getpid()])
            if os.getpid() != parent:
                os._exit(3)  # killed, out of memory, ...
            send(["second", os.getpid()])
            return "done here"

        print(json.dumps({"plain": raising(ValueError("boom")), "odd": raising(Unpicklable("odd")),
                          "unbuildable": raising(Unbuildable("x", "y")), "parent": parent,
                          "died": overlap(dying, lambda: 7, got.append), "got": got}))
        """)
    assert out["plain"] == ["ValueError", "boom"]
    assert out["odd"] == ["RuntimeError", "Unpicklable: odd"]
    assert out["unbuildable"] == ["RuntimeError", "Unbuildable: x y"]
    # the child's message, then the rest of the task here (its first message not forwarded twice)
    assert out["died"] == ["done here", 7]
    assert ([m[0] for m in out["got"]] == ["first", "second"]
            and out["got"][0][1] != out["parent"] == out["got"][1][1])


def test_the_child_ends_when_its_parent_is_killed():
    proc = subprocess.Popen([sys.executable, "-c", textwrap.dedent("""
        import os, sys, time
        from ocp_crawl.workers import overlap

        def task(send):
            send(os.getpid())
            time.sleep(60)

        overlap(task, lambda: None, lambda pid: (print(pid, flush=True), time.sleep(60)))
        """)], stdout=subprocess.PIPE, text=True)
    child = int(proc.stdout.readline())
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    for _ in range(100):
        try:
            os.kill(child, 0)
        except ProcessLookupError:
            break
        time.sleep(0.05)
    else:
        os.kill(child, signal.SIGKILL)
        pytest.fail("the child outlived its killed parent")


def test_without_fork_the_task_runs_here_after_meanwhile(monkeypatch):
    monkeypatch.setattr(workers, "mp_context", lambda: multiprocessing.get_context("spawn"))
    order = []

    def task(send):
        send(os.getpid())
        order.append("task")
        return 1

    got = []
    assert overlap(task, lambda: order.append("meanwhile"), got.append) == (1, None)
    assert order == ["meanwhile", "task"] and got == [os.getpid()]


def test_fork_is_not_used_while_other_threads_run():
    stop = threading.Event()
    thread = threading.Thread(target=stop.wait)
    thread.start()
    try:
        assert workers.mp_context().get_start_method() != "fork"
        assert overlap(lambda send: os.getpid(), lambda: None, lambda m: None)[0] == os.getpid()
    finally:
        stop.set()
        thread.join()


def _group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    return True


def _rows(journal) -> int:
    try:
        return max(journal.read_bytes().count(b"\n") - 1, 0)
    except FileNotFoundError:
        return 0


@pytest.mark.slow
@pytest.mark.parametrize("whole_group", [False, True], ids=["main_process_only", "process_group"])
def test_a_killed_sweep_leaves_no_worker_and_resumes_to_the_same_file(tmp_path, whole_group):
    """SIGKILL to the sweep's main process alone (a timeout, an out-of-memory kill) or to its whole
    group, after a few rows: within seconds no process of the run is left (a worker holding the
    directory's lock would refuse --resume), and --resume ends on the bytes of an uninterrupted
    run."""
    from pathlib import Path

    paper = Path(__file__).resolve().parent.parent / "problems" / "paper_gait.toml"
    grid = ["--grid", "gait.psi_deg=0:180:20", "--grid", "gait.gamma_deg=85:95:2"]
    base = [sys.executable, "-m", "ocp_crawl", "sweep", str(paper), *grid,
            "--set", "simulation.max_step=0.002", "--jobs", "2", "--no-progress"]
    out = tmp_path / "killed"
    # no pipes: a worker that outlived the kill would hold them open and block the wait here
    proc = subprocess.Popen(base + ["--out", str(out)], cwd=tmp_path, start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while (time.monotonic() < deadline and proc.poll() is None
           and _rows(out / "results.partial.csv") < 3):
        time.sleep(0.005)
    if whole_group:
        os.killpg(proc.pid, signal.SIGKILL)
    else:
        os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the sweep ended before it could be killed"
    deadline = time.monotonic() + 10
    while _group_alive(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    if _group_alive(proc.pid):
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail("a worker outlived its killed sweep by 10 s")
    assert not (out / "results.csv").exists()
    resumed = subprocess.run(base + ["--out", str(out), "--resume"], cwd=tmp_path,
                             capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    ref = subprocess.run(base + ["--out", str(tmp_path / "ref")], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300)
    assert ref.returncode == 0, ref.stderr
    assert (out / "results.csv").read_bytes() == (tmp_path / "ref" / "results.csv").read_bytes()
