"""workers.overlap: a task in a forked process while this one does something else."""
import json
import multiprocessing
import os
import subprocess
import sys
import textwrap
import threading

from ocp_crawl import workers
from ocp_crawl.workers import overlap


def _fresh(code: str) -> dict:
    """Run ``code`` (which prints one JSON object) in a fresh interpreter: no other thread runs there, so fork is used
    (in this one, an earlier test may have left a thread running, e.g. Dask's offload thread)."""
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=120)
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
        print(json.dumps({"method": mp_context().get_start_method(), "parent": os.getpid(), "other": other,
                          "child": result["pid"], "big": result["big"] == list(range(100_000)), "got": got}))
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

        def raising(exc):
            def task(send):
                raise exc
            try:
                overlap(task, lambda: None, lambda m: None)
            except Exception as caught:
                return [type(caught).__name__, str(caught)]

        parent, got = os.getpid(), []

        def dying(send):
            if os.getpid() != parent:
                os._exit(3)  # killed, out of memory, ...
            send("here")
            return "done here"

        print(json.dumps({"plain": raising(ValueError("boom")), "odd": raising(Unpicklable("odd")),
                          "died": overlap(dying, lambda: 7, got.append), "got": got}))
        """)
    assert out["plain"] == ["ValueError", "boom"]
    assert out["odd"] == ["RuntimeError", "Unpicklable: odd"]
    assert out["died"] == ["done here", 7] and out["got"] == ["here"]


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
