"""``ocp-crawl warmup`` prebuilds every compiled function of the package into the cache.

Checked in a temporary cache (``OCP_CRAWL_CACHE``): warm-up builds each function once, a second
warm-up finds them all cached, a run that finds libraries missing says that it compiles, and
simulations afterwards compile nothing more (so warm-up missed none of the functions they use).
Every ``FastFunction(...)`` of the package must be made by a builder registered with
``compiled_function``, or warm-up would not know it.
"""
import ast
import errno
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import ocp_crawl.sweep.warmup as warmup_module
from ocp_crawl.model import compiled

ROOT = Path(__file__).resolve().parent.parent
PKG = ROOT / "ocp_crawl"


def _cli(args, cache: Path, **env_extra) -> subprocess.CompletedProcess:
    env = dict(os.environ, OCP_CRAWL_CACHE=str(cache), **env_extra)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    env.pop("OCP_CRAWL_NO_COMPILE", None)
    return subprocess.run([sys.executable, "-m", "ocp_crawl", *args], capture_output=True,
                          text=True, env=env, cwd=ROOT, timeout=300)


@pytest.mark.slow
def test_warmup_builds_every_function_once_and_simulations_compile_nothing_more(tmp_path):
    cache = tmp_path / "cache"
    first = _cli(["warmup", "--json"], cache)
    assert first.returncode == 0, first.stderr
    built = json.loads(first.stdout)
    assert built["cache"] == str(cache)
    assert (built["built"] == len(built["functions"]) >= 5
            and built["cached"] == built["not compiled"] == 0)
    libraries = {Path(f["library"]) for f in built["functions"]}
    assert (len(libraries) == len(built["functions"])
            and all(lib.parent == cache for lib in libraries))
    assert set(cache.glob("*.so")) == libraries

    again = json.loads(_cli(["warmup", "--json"], cache).stdout)
    assert again["cached"] == len(again["functions"]) and again["built"] == 0
    assert {Path(f["library"]) for f in again["functions"]} == libraries

    # a run that finds libraries missing says on stderr, in one line however many it builds, that
    # it compiles, stdout stays the JSON alone; a run on the filled cache says nothing
    newton = next(lib for lib in libraries if lib.name.startswith("ocp_crawl_newton_")
                  and not lib.name.startswith("ocp_crawl_newton_batch"))
    step = next(lib for lib in libraries if lib.name.startswith("ocp_crawl_step_"))
    newton.unlink()
    step.unlink()
    compiling = _cli(["simulate", "problems/paper_gait.toml", "--json"], cache)
    assert compiling.returncode == 0, compiling.stderr
    assert json.loads(compiling.stdout)["success"] is True
    assert compiling.stderr == (f"ocp-crawl: compiling the model's C functions into {cache} (not "
                                "in the cache yet; once per machine)\n")
    # the torque drive (event stepper, sampled stability) and the angles drive after warm-up: no new
    # library
    for extra in ([], ["--set", "gait.drive=angles"]):
        run = _cli(["simulate", "problems/paper_gait.toml", "--json", *extra], cache)
        assert run.returncode == 0 and run.stderr == "", run.stderr
        if not extra:
            assert json.loads(run.stdout) == json.loads(compiling.stdout)
    assert set(cache.glob("*.so")) == libraries

    # the text: the cache and a line for each function, a library taken out of the cache is built
    # again, the others are cached
    newton.unlink()
    text = _cli(["warmup"], cache)
    assert text.returncode == 0, text.stderr
    assert f"compiled-library cache {cache}" in text.stdout
    lines = {line.split()[1]: line.split()[0] for line in text.stdout.splitlines()[1:-1]}
    assert lines == {f["function"]: ("built" if f["function"] == "ocp_crawl_newton" else "cached")
                     for f in built["functions"]}, text.stdout
    assert newton.is_file()


def test_warmup_without_a_compiler_is_a_failure_with_one_line(tmp_path):
    out = _cli(["warmup"], tmp_path / "c", PATH="", CC="")
    assert out.returncode == 1
    assert out.stderr.count("\n") == 1 and "no working C compiler" in out.stderr
    assert not list(tmp_path.rglob("*.so"))


def _bad_caches(tmp_path: Path) -> dict[str, tuple[Path, str]]:
    """Cache paths that cannot be a cache directory, each with the reason its message must give."""
    afile = tmp_path / "afile"
    afile.write_text("x")
    readonly = tmp_path / "readonly"
    readonly.mkdir(mode=0o555)
    return {"regular file": (afile, "not a directory (it is a regular file)"),
            "device": (Path(os.devnull), "not a directory (it is a character device)"),
            "under a file": (afile / "sub",
                             f"not a directory ({afile} in its path is a regular file)"),
            "name too long": (tmp_path / ("a" * 300), "name too long"),
            "read-only directory": (readonly, "not writable"),
            "under a read-only directory": (readonly / "sub", "not writable")}


def _deny_writes(monkeypatch, created: Path | None) -> None:
    """What the system says to a user other than root: no access, and no ``created`` directory."""
    monkeypatch.setattr(os, "access", lambda path, mode: False)
    mkdir = Path.mkdir

    def denied(self, *args, **kwargs):
        if self == created:
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(self))
        return mkdir(self, *args, **kwargs)
    monkeypatch.setattr(Path, "mkdir", denied)


@pytest.mark.parametrize("case",
                         ["regular file", "device", "under a file", "name too long",
                          "read-only directory", "under a read-only directory"])
def test_warmup_refuses_a_cache_that_is_not_a_writable_directory(tmp_path, monkeypatch, case):
    """Checked before anything is built: the message names OCP_CRAWL_CACHE, the path and the real
    reason (not the "no working C compiler" of a build that failed in the unusable directory)."""
    cache, reason = _bad_caches(tmp_path)[case]
    if "read-only" in case and os.access(cache.parent if "under" in case else cache, os.W_OK):
        _deny_writes(monkeypatch, cache if "under" in case else None)  # root writes anywhere
    monkeypatch.setenv("OCP_CRAWL_CACHE", str(cache))
    monkeypatch.delenv("OCP_CRAWL_NO_COMPILE", raising=False)
    built = []
    monkeypatch.setattr(warmup_module, "_register_all", lambda: None)
    monkeypatch.setattr(warmup_module, "BUILDERS", {"x": lambda: built.append(1)})
    with pytest.raises(getattr(compiled, "CacheError", ())) as info:
        warmup_module.warmup()
    message = str(info.value)
    assert (message.startswith(f"OCP_CRAWL_CACHE={cache}: ") and reason in message
            and "\n" not in message)
    assert not built


def test_cli_warmup_with_an_unusable_cache_is_one_line_naming_the_variable(tmp_path):
    (tmp_path / "afile").write_text("x")
    out = _cli(["warmup"], tmp_path / "afile")
    assert out.stderr.count("\n") == 1 and "Traceback" not in out.stderr
    assert f"OCP_CRAWL_CACHE={tmp_path / 'afile'}: not a directory" in out.stderr
    assert "C compiler" not in out.stderr and not out.stdout


def test_cli_warmup_with_an_unusable_cache_is_bad_input(tmp_path):
    (tmp_path / "afile").write_text("x")
    out = _cli(["warmup"], tmp_path / "afile")
    assert out.returncode == 2 and out.stderr.startswith("ocp-crawl: error: "
                                                         "OCP_CRAWL_CACHE="), out.stderr


def _decorators(node: ast.FunctionDef) -> set[str]:
    names = set()
    for d in node.decorator_list:
        d = d.func if isinstance(d, ast.Call) else d
        names.add(d.attr if isinstance(d, ast.Attribute) else getattr(d, "id", ""))
    return names


@pytest.mark.slow
def test_every_fast_function_is_made_by_a_registered_builder():
    """A FastFunction made outside a ``@compiled_function`` builder would be compiled on first use
    only."""
    unregistered, found = [], 0
    for path in PKG.rglob("*.py"):
        if path.name == "compiled.py" and path.parent.name == "model":
            continue  # the class itself
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            makes = any(isinstance(c, ast.Call)
                        and getattr(c.func, "id", getattr(c.func, "attr", None)) == "FastFunction"
                        for c in ast.walk(node))
            if makes:
                found += 1
                if "compiled_function" not in _decorators(node):
                    unregistered.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name}")
    assert found >= 5
    assert not unregistered, ("FastFunction made outside a @compiled_function builder: "
                              + ", ".join(unregistered))


def _gcc_out_of_space(args, **kwargs):
    return subprocess.CompletedProcess(args, 1, "", "/usr/bin/ld: final link failed: No space "
                                       "left on device\ncollect2: error: "
                                       "ld returned 1 exit status\n")


def _no_space_for_the_directory(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device", str(kwargs.get("dir", "?")) + "/.x.tmp")


@pytest.mark.parametrize("where", ["compiler", "directory"])
def test_warmup_on_a_full_disk_says_so_not_no_compiler(where, tmp_path, monkeypatch, capsys):
    """A cache the disk cannot take (the compiler's output, or the build directory) is a full
    disk, named by the cache's file, not "no working C compiler"."""
    from ocp_crawl.cli.app import main
    cache = tmp_path / "c"
    monkeypatch.setenv("OCP_CRAWL_CACHE", str(cache))
    monkeypatch.delenv("OCP_CRAWL_NO_COMPILE", raising=False)
    if where == "compiler":
        monkeypatch.setattr(compiled.subprocess, "run", _gcc_out_of_space)
    else:
        monkeypatch.setattr(compiled.tempfile, "TemporaryDirectory", _no_space_for_the_directory)
    assert main(["warmup", "--json"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no working C compiler" not in err, err
    start = f"ocp-crawl: error: cannot write the compiled-library cache: {cache}/"
    assert err.startswith(start), err
    assert ".so: No space left on device" in err
