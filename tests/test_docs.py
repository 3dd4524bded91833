"""The documentation site (docs/): it builds, and its reference pages cover the code's tables.

The build is Sphinx with warnings as errors, offline, on a copy of docs/ (nothing is written into
the work tree).  Its examples gallery runs every example script, the one place the default suite
runs them: their outputs are checked here as tests/test_examples.py would.  The reference pages are
generated from the code (docs/_ext/ocp_reference.py): every problem-file key, command, option and
status must appear in them, in the generated Markdown (quick) and in the built HTML (the build);
every public name of every public package must have its entry, with its docstring, on its package's
API page (or, re-exported, link to the entry of its first name).
"""
import argparse
import html
import importlib
import importlib.util
import inspect
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


def _ext_module(name: str):
    """The documentation's extension ``docs/_ext/<name>.py``, imported."""
    if name in sys.modules:
        return sys.modules[name]
    path = DOCS / "_ext" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module      # imported once
    spec.loader.exec_module(module)
    return module


def _reference_module():
    return _ext_module("ocp_reference")


def public_names(package: str) -> list[str]:
    return [n for n in importlib.import_module(package).__all__ if not n.startswith("__")]


def summary_words(package: str, name: str) -> list[str]:
    """The first words of the docstring of ``package.name`` (the ``#:`` comment of a data object,
    as the reference shows it), without the markup of its roles and literals."""
    obj = getattr(importlib.import_module(package), name)
    if inspect.isclass(obj) or inspect.isroutine(obj):
        doc = inspect.getdoc(obj) or ""
    else:
        doc = "\n".join(_ext_module("ocp_docstrings").comment_doc(f"{package}.{name}"))
    line = doc.strip().split("\n")[0]
    def role(m: re.Match) -> str:   # what a role shows: its title, or the target (~: last part)
        title, _, target = m[1].partition("<")
        return title if target else title.rpartition(".")[2] if title[0] == "~" else title
    line = re.sub(r":[\w:.+-]+:`([^`]+)`", role, line)
    return re.findall(r"[A-Za-z]{3,}", line.replace("`", " "))[:6]


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
    # the Python API: an overview linking a page per public package; on each, an autodoc entry of
    # every name it documents first (all of the top-level package's), the others listed as also here
    pages = ref.api_pages()
    packages = ref.public_packages()
    assert packages[0] == "ocp_crawl" and len(packages) > 1
    entry = re.compile(r"^\.\. auto(?:class|exception|function|data):: (\w+)$", re.MULTILINE)
    documented = {}
    for package in packages:
        assert has(pages["api.rst"], f"api/{package}"), package
        page = pages[f"api/{package}.rst"]
        assert f".. py:module:: {package}" in page
        names = entry.findall(page)
        documented.update((f"{package}.{name}", package) for name in names)
        undocumented = [name for name in names if not summary_words(package, name)]
        assert not undocumented, f"{package}: no docstring or #: comment for {undocumented}"
        for name in public_names(package):
            if name in names:
                continue
            also = re.search(rf":py:obj:`{re.escape(name)} <([\w.]+)>`", page)
            assert also and also[1] in documented, f"{package}.{name} neither documented nor linked"
    assert set(entry.findall(pages["api/ocp_crawl.rst"])) == set(public_names("ocp_crawl"))


def html_text(path: Path) -> str:
    """The text of an HTML page, tags as spaces, element ids kept as ``#id=NAME`` markers."""
    page = path.read_text(encoding="utf-8")
    page = re.sub(r"<(?:section|span|div|dt)[^>]*\bid=\"([^\"]+)\"[^>]*>", r" #id=\1 ", page)
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", page)).split())


def by_id(text: str) -> dict[str, str]:
    """The parts of an :func:`html_text` that follow each element id (up to the next), by id."""
    parts = re.split(r"#id=(\S+)", text)
    return dict(zip(parts[1::2], parts[2::2]))


def check_api(api: Path) -> None:
    """The built API pages: every public name of every public package has its entry (its id), with
    the first words of its docstring, on its package's page, or that page links to the entry of its
    first name."""
    ref = _reference_module()
    pages = {p: api / f"{p}.html" for p in ref.public_packages()}
    texts = {p: by_id(html_text(path)) for p, path in pages.items() if path.is_file()}
    assert set(texts) == set(pages), f"API pages missing: {set(pages) - set(texts)}"
    ids = {i for parts in texts.values() for i in parts}
    for package, parts in texts.items():
        links = set(re.findall(r'href="[\w.]*#([\w.]+)"', pages[package].read_text("utf-8")))
        for name in public_names(package):
            full = f"{package}.{name}"
            if full in parts:
                missing = [w for w in summary_words(package, name)
                           if not re.search(rf"(?<![A-Za-z]){w}(?![A-Za-z])", parts[full])]
                assert not missing, (full, missing, parts[full][:300])
            else:
                assert any(i.endswith(f".{name}") and i in ids for i in links), full
    assert set(public_names("ocp_crawl")) <= {i.partition(".")[2] for i in texts["ocp_crawl"]}


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
    # the Python API: a page per public package, an entry with its docstring for every public name
    assert (ref / "api.html").is_file()
    check_api(ref / "api")
    robot = by_id(html_text(ref / "api" / "ocp_crawl.html"))["ocp_crawl.Robot"]
    assert "Total mass [kg]" in robot

    # the gallery ran every example: its outputs, and its figures on its page
    for name in sorted(OUTPUTS):
        stem = Path(name).stem
        check_outputs(name, examples / stem)
        page = out_html / "gallery" / f"{stem}.html"
        assert page.is_file(), page
        figures = [f for f in OUTPUTS[name] if f.endswith(".png")]
        shown = re.findall(rf"images/sphx_glr_{re.escape(stem)}_\d+\.png", page.read_text())
        assert len(set(shown)) == len(figures), (name, shown)
