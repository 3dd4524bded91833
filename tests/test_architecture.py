"""The house rules of the package layout (ARCHITECTURE.md), checked on the source itself.

* Import floors: a module imports only from its own floor or lower ones, never upwards, and
  module-level imports form no cycle.
* Size: no module over 500 lines, no function over 80 lines.
"""
import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parent.parent / "ocp_crawl"

#: floors from the bottom; one floor per subpackage (or floor-0 module)
FLOORS = ["version", "status", "checks", "io", "model", "nlp", "sim", "ocp", "problem", "viz",
          "sweep", "fit", "studies", "cli"]
FLOOR = {name: i for i, name in enumerate(FLOORS)}
FLOOR["status"] = FLOOR["checks"] = FLOOR["io"] = FLOOR["version"] = FLOOR["workers"] = 0
TOP = {"__init__", "__main__"}  # the package's front door may import anything

MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 80


def _modules():
    # ocp_crawl/data/ holds shipped files (the examples gallery's scripts, written out by `ocp-crawl
    # init`), not modules
    return sorted(p for p in PKG.rglob("*.py") if p.relative_to(PKG).parts[0] != "data")


def _dotted(path: Path) -> str:
    parts = path.relative_to(PKG.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, top_level_only: bool = False) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    nodes = tree.body if top_level_only else ast.walk(tree)
    out = []
    for node in nodes:
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module == "ocp_crawl":
                out += [f"ocp_crawl.{a.name}" for a in node.names]
            elif node.module.startswith("ocp_crawl."):
                out.append(node.module)
        elif isinstance(node, ast.ImportFrom) and node.level:
            raise AssertionError(f"{path}: relative import; use absolute imports (ocp_crawl....)")
        elif isinstance(node, ast.Import):
            out += [a.name for a in node.names if a.name.startswith("ocp_crawl.")]
    return out


def _floor(dotted: str) -> int | None:
    parts = dotted.split(".")
    if len(parts) < 2 or parts[1] in TOP:
        return None
    # a name of the front door (``from ocp_crawl import __version__``)
    if parts[1].startswith("__"):
        return len(FLOORS)
    return FLOOR[parts[1]]


def test_every_subpackage_has_a_floor():
    for path in _modules():
        parts = _dotted(path).split(".")
        if len(parts) > 1 and parts[1] not in TOP:
            assert parts[1] in FLOOR, f"{path}: {parts[1]} has no floor in ARCHITECTURE.md / FLOORS"


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(PKG)))
def test_no_upward_import(path):
    me = _floor(_dotted(path))
    if me is None:
        return
    for target in _imports(path):
        floor = _floor(target)
        assert floor is None or floor <= me, (
            f"{_dotted(path)} (floor {FLOORS[me]}) imports {target} "
            f"""({FLOORS[floor] if floor < len(FLOORS)
                  else 'the front door, which imports every floor'}): upward import""")


def test_no_import_cycle():
    graph = {_dotted(p): {t for t in _imports(p, top_level_only=True)} for p in _modules()}
    names = set(graph)
    graph = {k: {t if t in names else t.rsplit(".", 1)[0] for t in v} & names
             for k, v in graph.items()}
    state: dict[str, int] = {}

    def visit(node, stack):
        state[node] = 1
        for nxt in sorted(graph[node]):
            if nxt == node or nxt in ("ocp_crawl",):
                continue
            if state.get(nxt) == 1:
                raise AssertionError("import cycle: "
                                     + " -> ".join(stack[stack.index(nxt):] + [nxt]))
            if nxt not in state:
                visit(nxt, stack + [nxt])
        state[node] = 2

    for node in sorted(graph):
        if node not in state and node != "ocp_crawl":
            visit(node, [node])


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(PKG)))
def test_module_and_function_size(path):
    text = path.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= MAX_MODULE_LINES, f"{path}: {len(text.splitlines())} lines"
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            n = node.end_lineno - node.lineno + 1
            assert n <= MAX_FUNCTION_LINES, f"{path}:{node.lineno} {node.name} has {n} lines"


def test_ruff_finds_nothing():
    """ruff with the project's configuration (pyproject.toml: pyflakes' errors, syntax errors) on
    the package, the tests, the scripts and the docs' extensions."""
    import shutil
    import subprocess

    ruff = shutil.which("ruff")
    if ruff is None:
        pytest.skip("ruff is not installed (pip install -e .[test])")
    proc = subprocess.run([ruff, "check", "ocp_crawl", "tests", "scripts", "docs/_ext"],
                          cwd=PKG.parent, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
