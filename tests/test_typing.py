"""Type checking of the public API: mypy on the modules that define the re-exported names.

The checked set is ``[tool.mypy] files`` in pyproject.toml (the configuration, flags and the
modules whose errors are still ignored are there); one test checks that it covers every name of
the packages' ``_EXPORTS`` tables (io/lazy.py), the other runs mypy on it.
"""
import ast
import functools
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PKG = ROOT / "ocp_crawl"


def _mypy_config() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["mypy"]


def _module_file(module: str) -> Path:
    path = ROOT.joinpath(*module.split("."))
    return path / "__init__.py" if path.is_dir() else path.with_suffix(".py")


@functools.cache
def _parsed(path: Path) -> ast.Module:
    return ast.parse(path.read_text(encoding="utf-8"))


def _defining_file(module: str, name: str) -> Path:
    """The file that defines ``module.name``, following ``from X import name`` and the lazy
    ``_EXPORTS`` of a package."""
    path = _module_file(module)
    for node in _parsed(path).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            if node.name == name:
                return path
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names = {n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)}
            if name in names and "_EXPORTS" not in names:
                return path
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if any((a.asname or a.name) == name for a in node.names):
                return _defining_file(node.module, name)
    exports = _exports(path)
    if name in exports:
        return _defining_file(exports[name], name)
    raise AssertionError(f"{module}.{name}: not found in {path.relative_to(ROOT)}")


def _exports(init: Path) -> dict[str, str]:
    """The ``_EXPORTS`` table of a package's ``__init__.py`` (public name -> module), {} if none."""
    for node in _parsed(init).body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "_EXPORTS"
                                                for t in node.targets):
            out: dict[str, str] = {}
            for key, value in zip(node.value.keys, node.value.values):
                if key is None:  # **{name: "module" for name in (...)}
                    assert isinstance(value, ast.DictComp), ast.unparse(value)
                    names = ast.literal_eval(value.generators[0].iter)
                    out.update(dict.fromkeys(names, ast.literal_eval(value.value)))
                else:
                    out[ast.literal_eval(key)] = ast.literal_eval(value)
            return out
    return {}


def test_the_mypy_files_cover_the_public_api():
    """Every package ``__init__.py`` and the module defining each name of its ``_EXPORTS`` table
    are in ``[tool.mypy] files`` (a name added to a table, from a new module, is checked too)."""
    checked = {ROOT / f for f in _mypy_config()["files"]}
    missing = set()
    for init in sorted(PKG.rglob("__init__.py")):
        if "data" in init.relative_to(PKG).parts:
            continue
        if init not in checked:
            missing.add(f"{init.relative_to(ROOT)} (a package's front door)")
        package = ".".join(init.parent.relative_to(ROOT).parts)
        for name, module in _exports(init).items():
            path = _defining_file(module, name)
            if path not in checked:
                missing.add(f"{path.relative_to(ROOT)} (defines {package}.{name})")
    assert not missing, ("add to [tool.mypy] files in pyproject.toml:\n  "
                         + "\n  ".join(sorted(missing)))


@pytest.mark.slow
def test_mypy_finds_nothing_in_the_public_api(request, tmp_path):
    """``python -m mypy`` with the project's configuration ([tool.mypy] in pyproject.toml) finds
    no error in the public API's modules."""
    pytest.importorskip("mypy")
    cache = getattr(request.config, "cache", None)
    # mypy's incremental cache under .pytest_cache (ignored by git): a run after a first one
    # re-checks only what changed
    cache_dir = cache.mkdir("mypy") if cache is not None else tmp_path / "mypy_cache"
    proc = subprocess.run([sys.executable, "-m", "mypy", "--config-file", "pyproject.toml",
                           "--cache-dir", str(cache_dir), "--no-pretty", "--no-color-output"],
                          cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, f"mypy failed ({proc.returncode}):\n{proc.stdout}{proc.stderr}"
