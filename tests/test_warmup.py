"""``ocp-crawl warmup`` prebuilds every compiled function of the package into the cache.

Checked in a temporary cache (``OCP_CRAWL_CACHE``): warm-up builds each function once, a second
warm-up finds them all cached, and simulations afterwards compile nothing more (so warm-up missed
none of the functions they use).  Every ``FastFunction(...)`` of the package must be made by a
builder registered with ``compiled_function``, or warm-up would not know it.
"""
import ast
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PKG = ROOT / "ocp_crawl"


def _cli(args, cache: Path, **env_extra) -> subprocess.CompletedProcess:
    env = dict(os.environ, OCP_CRAWL_CACHE=str(cache), **env_extra)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    env.pop("OCP_CRAWL_NO_COMPILE", None)
    return subprocess.run([sys.executable, "-m", "ocp_crawl", *args], capture_output=True, text=True, env=env,
                          cwd=ROOT, timeout=300)


def test_warmup_builds_every_function_once_and_simulations_compile_nothing_more(tmp_path):
    cache = tmp_path / "cache"
    first = _cli(["warmup", "--json"], cache)
    assert first.returncode == 0, first.stderr
    built = json.loads(first.stdout)
    assert built["cache"] == str(cache)
    assert built["built"] == len(built["functions"]) >= 5 and built["cached"] == built["not compiled"] == 0
    libraries = {Path(f["library"]) for f in built["functions"]}
    assert len(libraries) == len(built["functions"]) and all(lib.parent == cache for lib in libraries)
    assert set(cache.glob("*.so")) == libraries

    again = json.loads(_cli(["warmup", "--json"], cache).stdout)
    assert again["cached"] == len(again["functions"]) and again["built"] == 0
    assert {Path(f["library"]) for f in again["functions"]} == libraries

    # the torque drive (event stepper, sampled stability) and the angles drive after warm-up: no new library
    for extra in ([], ["--set", "gait.drive=angles"]):
        run = _cli(["simulate", "problems/paper_gait.toml", "--json", *extra], cache)
        assert run.returncode == 0, run.stderr
    assert set(cache.glob("*.so")) == libraries


def test_warmup_text_names_the_cache_and_each_function(tmp_path):
    cache = tmp_path / "c"
    out = _cli(["warmup"], cache)
    assert out.returncode == 0, out.stderr
    assert f"compiled-library cache {cache}" in out.stdout
    assert "ocp_crawl_newton " in out.stdout and "built" in out.stdout


def test_warmup_without_a_compiler_is_a_failure_with_one_line(tmp_path):
    out = _cli(["warmup"], tmp_path / "c", PATH="", CC="")
    assert out.returncode == 1
    assert out.stderr.count("\n") == 1 and "no working C compiler" in out.stderr
    assert not list(tmp_path.rglob("*.so"))


def _decorators(node: ast.FunctionDef) -> set[str]:
    names = set()
    for d in node.decorator_list:
        d = d.func if isinstance(d, ast.Call) else d
        names.add(d.attr if isinstance(d, ast.Attribute) else getattr(d, "id", ""))
    return names


def test_every_fast_function_is_made_by_a_registered_builder():
    """A FastFunction made outside a ``@compiled_function`` builder would be compiled on first use only."""
    unregistered, found = [], 0
    for path in PKG.rglob("*.py"):
        if path.name == "compiled.py" and path.parent.name == "model":
            continue  # the class itself
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            makes = any(isinstance(c, ast.Call) and getattr(c.func, "id", getattr(c.func, "attr", None)) == "FastFunction"
                        for c in ast.walk(node))
            if makes:
                found += 1
                if "compiled_function" not in _decorators(node):
                    unregistered.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name}")
    assert found >= 5
    assert not unregistered, "FastFunction made outside a @compiled_function builder: " + ", ".join(unregistered)
