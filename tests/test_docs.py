"""The documentation site (docs/): it builds, and its reference pages cover the code's tables.

The build is Sphinx with warnings as errors, offline, on a copy of docs/ (nothing is written into
the work tree).  Its examples gallery runs every example script, the one place the default suite
runs them: their outputs are checked here as tests/test_examples.py would.  The reference pages are
generated from the code (docs/_ext/ocp_reference.py): every problem-file key, command, option and
status must appear in them, in the generated Markdown (quick) and in the built HTML (the build).
"""
import argparse
import html
import importlib.util
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from test_examples import OUTPUTS, check_outputs

REPO = Path(__file__).resolve().parent.parent
DOCS = REPO / "docs"
BUILD_TIMEOUT_S = 1800
#: what the build generates in the docs' own directory: never copied into the test's build
GENERATED = ("_build", "_gallery_src", "gallery", "api", "sg_execution_times.rst", "__pycache__")


def _reference_module():
    path = DOCS / "_ext" / "ocp_reference.py"
    spec = importlib.util.spec_from_file_location("ocp_reference", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def schema_keys() -> list[str]:
    from ocp_crawl.problem import SECTIONS
    return [f"{section.name}.{key.name}" for section in SECTIONS for key in section.keys]


def commands() -> dict[str, list[str]]:
    """Each command of ``ocp-crawl`` -> its option strings (positionals by their metavar)."""
    from ocp_crawl.cli.app import COMMANDS, build_parser   # the package registers the commands
    subs = _reference_module().subcommands(build_parser())
    assert list(subs) == list(COMMANDS)
    out = {}
    for name, (parser, _) in subs.items():
        out[name] = []
        for action in parser._actions:
            if action.option_strings:
                out[name] += action.option_strings
            elif not isinstance(action, argparse._SubParsersAction):
                out[name].append(action.metavar or action.dest)
    return out


def statuses() -> list[tuple[str, str]]:
    from ocp_crawl import STATUS_MESSAGES, Status
    assert set(STATUS_MESSAGES) == set(Status)
    return [(s.label, f"Status.{s.name}") for s in Status]


def has(text: str, word: str) -> bool:
    """``word`` in ``text`` as a whole (not part of a longer name or option)."""
    return re.search(rf"(?<![\w.-]){re.escape(word)}(?![\w-])", text) is not None


def sections(text: str, marker: str) -> dict[str, str]:
    """The parts of ``text`` that follow each ``marker + NAME``, by NAME."""
    parts = re.split(rf"{re.escape(marker)}([\w-]+)", text)
    return dict(zip(parts[1::2], parts[2::2]))


def check_reference(problem_files: str, cli: str, status_page: str, cli_marker: str) -> None:
    """Every schema key, command, option and status in the reference pages' text."""
    missing = [k for k in schema_keys() if not has(problem_files, k)]
    assert not missing, f"problem-file keys missing: {missing}"
    by_command = sections(cli, cli_marker)
    for name, options in commands().items():
        assert name in by_command, f"no section of the command {name}"
        assert has(by_command[name], f"ocp-crawl {name}"), name
        missing = [o for o in options if not has(by_command[name], o)]
        assert not missing, f"options of {name} missing: {missing}"
    missing = [s for s in statuses() if not (has(status_page, s[0]) and has(status_page, s[1]))]
    assert not missing, f"statuses missing: {missing}"


def test_generated_reference_covers_the_code():
    ref = _reference_module()
    check_reference(ref.problem_files_page(), ref.cli_page(), ref.statuses_page(),
                    "(reference-cli-")
    api = ref.api_page()
    import ocp_crawl
    assert all(has(api, name) for name in ocp_crawl.__all__ if not name.startswith("__"))


def html_text(path: Path) -> str:
    """The text of an HTML page, tags as spaces, element ids kept as ``#id=NAME`` markers."""
    page = path.read_text(encoding="utf-8")
    page = re.sub(r"<(?:section|span|div)[^>]*\bid=\"([^\"]+)\"[^>]*>", r" #id=\1 ", page)
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", page)).split())


def build(tmp: Path) -> tuple[subprocess.CompletedProcess, Path, Path]:
    """docs/ copied into ``tmp`` and built: (the process, the HTML, the examples' outputs)."""
    src, out_html, examples = tmp / "src", tmp / "html", tmp / "examples"
    shutil.copytree(DOCS, src, ignore=shutil.ignore_patterns(*GENERATED))
    env = dict(os.environ, MPLBACKEND="Agg", OCP_CRAWL_EXAMPLES_QUICK="1",
               OCP_CRAWL_EXAMPLES_OUT=str(examples), PYTHONPATH=os.pathsep.join(
                   p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p))
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html",
                           str(src), str(out_html)], cwd=tmp, env=env, capture_output=True,
                          text=True, timeout=BUILD_TIMEOUT_S)
    return proc, out_html, examples


@pytest.mark.slow
def test_docs_build(tmp_path):
    """One build (several minutes: it runs the examples), checked as a whole."""
    proc, out_html, examples = build(tmp_path)
    assert proc.returncode == 0, (proc.stdout[-3000:], proc.stderr[-6000:])
    for page in ("index", "getting_started", "guide/model", "gallery/index"):
        assert (out_html / f"{page}.html").is_file(), page

    # the reference pages, generated from the code's tables
    ref = out_html / "reference"
    check_reference(html_text(ref / "problem_files.html"), html_text(ref / "cli.html"),
                    html_text(ref / "statuses.html"), "#id=reference-cli-")
    # the Python API: a page for every public name of the package, with its docstring
    import ocp_crawl
    for name in ocp_crawl.__all__:
        if not name.startswith("__"):
            assert (ref / "api" / f"ocp_crawl.{name}.html").is_file(), name
    assert "Total mass [kg]" in html_text(ref / "api" / "ocp_crawl.Robot.html")

    # the gallery ran every example: its outputs, and its figures on its page
    for name in sorted(OUTPUTS):
        stem = Path(name).stem
        check_outputs(name, examples / stem)
        page = out_html / "gallery" / f"{stem}.html"
        assert page.is_file(), page
        figures = [f for f in OUTPUTS[name] if f.endswith(".png")]
        shown = re.findall(rf"images/sphx_glr_{re.escape(stem)}_\d+\.png", page.read_text())
        assert len(set(shown)) == len(figures), (name, shown)
