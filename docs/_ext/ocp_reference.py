"""Reference pages written from the code's own tables, at the start of every build.

* ``reference/problem_files.md``: every key of a problem file, from
  :func:`ocp_crawl.problem.schema_markdown` (the schema ``SECTIONS``);
* ``reference/cli.md``: every command of ``ocp-crawl`` with its usage and each argument's help,
  from the parser of :func:`ocp_crawl.cli.app.build_parser`;
* ``reference/statuses.md``: every :class:`ocp_crawl.Status` with its text from
  :data:`ocp_crawl.STATUS_MESSAGES`;
* ``reference/api.rst`` and ``reference/api/<package>.rst``: the Python API, one page for
  ``ocp_crawl`` and one for each subpackage that declares public names (``__all__``).  A package's
  page has an autosummary table of its names (linking to the entries below it), then the autodoc
  entry of each (a class with its members); every object is documented once, under its first public
  name (the top-level package first), and the later packages list it as *also here*.

  One page per package, not one per name: a theme's navigation (furo's sidebar) is the whole
  toctree, rendered again for every page, so that ~200 per-name pages made the build quadratic.

The pages are generated, not written by hand, and git-ignored; a page is rewritten only when its
text changes, so that an unchanged page is not read again by an incremental build, and a page in
``reference/api/`` that no package makes any more is removed.
"""
from __future__ import annotations

import argparse
import importlib
import inspect
import pkgutil
from pathlib import Path

#: generated page -> the function that writes its text
PAGES = {}


def page(name: str):
    """Register a function returning the text of the generated page ``reference/<name>``."""
    def wrap(fn):
        PAGES[name] = fn
        return fn
    return wrap


def md_escape(text: str) -> str:
    """Plain text (a help string) as Markdown that shows it unchanged, in a table cell too."""
    text = " ".join(str(text).split())
    return "".join("\\" + c if c in "\\`*_[]<>|$#~{}" else c for c in text)


def md_cell(text: str) -> str:
    """Markdown (code spans allowed) inside a table cell: bars escaped."""
    return " ".join(str(text).split()).replace("|", "\\|")


@page("problem_files.md")
def problem_files_page() -> str:
    from ocp_crawl.problem import schema_markdown
    return "\n".join([
        "(reference-problem-files)=",
        "# Problem-file keys",
        "",
        "Every key a problem file may set, as `[section]` and `key = value` in TOML, and as",
        "`section.key=value` in `--set` and `--grid`: its type, unit, whether it is required",
        "or its default, the values it accepts and what it means.  Generated from the schema of",
        "{py:mod}`ocp_crawl.problem` ({py:func}`~ocp_crawl.problem.schema_markdown`).",
        "",
        schema_markdown(),
        "",
    ])


def subcommands(parser: argparse.ArgumentParser) -> dict[str, tuple[argparse.ArgumentParser, str]]:
    """The subcommands of ``parser`` in their order: name -> (parser, one-line help)."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help or "" for a in action._choices_actions}
            return {name: (sub, helps.get(name, "")) for name, sub in action.choices.items()}
    return {}


def _arguments(parser: argparse.ArgumentParser) -> list[str]:
    """The argument tables of ``parser``: one per argument group (as ``--help`` groups them)."""
    formatter = parser._get_formatter()
    lines = []
    for group in parser._action_groups:
        actions = [a for a in group._group_actions
                   if a.help != argparse.SUPPRESS and not isinstance(a, argparse._SubParsersAction)]
        if not actions:
            continue
        lines += ["", f"**{md_escape(group.title)}**", "", "| argument | meaning |", "|---|---|"]
        for action in actions:
            invocation = formatter._format_action_invocation(action)
            meaning = formatter._expand_help(action) if action.help else ""
            lines.append(f"| {md_cell(f'`{invocation}`')} | {md_cell(md_escape(meaning))} |")
    return lines


def _usage(parser: argparse.ArgumentParser) -> list[str]:
    return ["", "```text", parser.format_usage().strip(), "```"]


@page("cli.md")
def cli_page() -> str:
    from ocp_crawl.cli.app import build_parser   # the package registers the commands
    parser = build_parser()
    commands = subcommands(parser)
    lines = ["(reference-cli)=", f"# Command line: `{parser.prog}`", "",
             f"`{parser.prog}` (also `python -m ocp_crawl`): {md_escape(parser.description)}",
             "Every command and option below is generated from the parser itself; "
             f"`{parser.prog} COMMAND --help` prints the same.", ""]
    lines += [f"- [`{parser.prog} {name}`](#reference-cli-{name}): {md_escape(short)}"
              for name, (sub, short) in commands.items()]
    lines += _usage(parser) + _arguments(parser) + ["", md_escape(parser.epilog or "")]
    for name, (sub, short) in commands.items():
        lines += ["", f"(reference-cli-{name})=", f"## `{parser.prog} {name}`", "",
                  md_escape(sub.description or short)]
        lines += _usage(sub) + _arguments(sub)
        if sub.epilog:
            lines += ["", md_escape(sub.epilog)]
    return "\n".join(lines) + "\n"


@page("statuses.md")
def statuses_page() -> str:
    from ocp_crawl.status import STATUS_MESSAGES, Status
    lines = ["(reference-statuses)=", "# Statuses", "",
             "Every result of a simulation, an optimisation or a sweep row carries one status",
             "({py:class}`ocp_crawl.Status`); `success` is the only success.  JSON and CSV files",
             "write a status as its label, the lower-case name.  Generated from",
             "{py:data}`ocp_crawl.STATUS_MESSAGES`, whose text starts the result's `message`.", "",
             "| label | member | code | meaning |", "|---|---|---|---|"]
    for status in Status:
        lines.append(f"| `{status.label}` | `Status.{status.name}` | {int(status)} "
                     f"| {md_cell(md_escape(STATUS_MESSAGES[status]))} |")
    return "\n".join(lines) + "\n"


def public_packages() -> list[str]:
    """``ocp_crawl`` and its subpackages that declare public names (``__all__``), in name order."""
    import ocp_crawl
    names = ["ocp_crawl"]
    modules = pkgutil.iter_modules(ocp_crawl.__path__, "ocp_crawl.")
    for info in sorted(modules, key=lambda m: m.name):
        if info.ispkg and getattr(importlib.import_module(info.name), "__all__", None):
            names.append(info.name)
    return names


def _identity(package: str, name: str, obj) -> tuple:
    """What makes two public names the same object: a class's or function's qualified name, else
    the defining module (from the lazy-export table) and the name."""
    module, qualname = getattr(obj, "__module__", None), getattr(obj, "__qualname__", None)
    if isinstance(module, str) and isinstance(qualname, str):
        return module, qualname
    exports = getattr(importlib.import_module(package), "_EXPORTS", {})
    return exports.get(name, package), name


def _first_line(package: str) -> str:
    doc = (importlib.import_module(package).__doc__ or "").strip()
    return doc.split("\n\n")[0].replace("\n", " ")


#: the directory of the packages' API pages, relative to ``reference/``
API_DIR = "api"


def _directive(obj) -> list[str]:
    """The autodoc directive (and options) documenting ``obj``: a class with its members and bases,
    a data object without its value."""
    if inspect.isclass(obj) and issubclass(obj, BaseException):
        return ["autoexception"]
    if inspect.isclass(obj):
        return ["autoclass", ":members:", ":show-inheritance:"]
    if inspect.isroutine(obj):
        return ["autofunction"]
    return ["autodata", ":no-value:"]


def api_entries() -> dict[str, tuple[list[str], list[tuple[str, str]]]]:
    """Each public package -> (the names it documents, in the order of its ``__all__``; the names
    documented by an earlier package, as (name, the full name documenting it))."""
    seen: dict[tuple, str] = {}
    out = {}
    for package in public_packages():
        mod = importlib.import_module(package)
        new, again = [], []
        for name in mod.__all__:
            if name.startswith("__"):
                continue
            key = _identity(package, name, getattr(mod, name))
            if key in seen:
                again.append((name, seen[key]))
            else:
                seen[key] = f"{package}.{name}"
                new.append(name)
        out[package] = (new, again)
    return out


def _api_package_page(package: str, new: list[str], again: list[tuple[str, str]]) -> str:
    mod = importlib.import_module(package)
    title = f"``{package}``"
    lines = [f".. _reference-api-{package}:", "", title, "=" * len(title), "",
             f".. py:module:: {package}", "", _first_line(package), "",
             f".. currentmodule:: {package}", ""]
    if new:
        lines += [".. autosummary::", "   :nosignatures:", ""]
        lines += [f"   {name}" for name in new] + [""]
    if again:
        lines += ["Also here: " + ", ".join(f":py:obj:`{name} <{full}>`" for name, full in again)
                  + ".", ""]
    for name in new:
        directive, *options = _directive(getattr(mod, name))
        lines += [f".. {directive}:: {name}"] + [f"   {o}" for o in options] + [""]
    return "\n".join(lines)


def api_pages() -> dict[str, str]:
    """The Python API's pages, relative to ``reference/``: ``api.rst`` (the overview and its
    toctree) and ``api/<package>.rst`` for each public package."""
    entries = api_entries()
    title = "Python API"
    lines = [".. _reference-api:", "", title, "=" * len(title), "",
             "The public names of the package and of each subpackage (their ``__all__``),",
             "generated from the code: a page per package, with a table of its names and then",
             "the documentation of each.  An object re-exported by several packages is documented",
             "once, under its first name here; the later packages list it as *also here*.", "",
             ".. toctree::", "   :hidden:", ""]
    lines += [f"   {API_DIR}/{package}" for package in entries] + [""]
    for package, (new, again) in entries.items():
        count = f"{len(new)} names" + (f", {len(again)} also here" if again else "")
        lines.append(f"* :doc:`{package} <{API_DIR}/{package}>` ({count}): "
                     f"{_first_line(package)}")
    pages = {"api.rst": "\n".join(lines) + "\n"}
    for package, (new, again) in entries.items():
        pages[f"{API_DIR}/{package}.rst"] = _api_package_page(package, new, again)
    return pages


def all_pages() -> dict[str, str]:
    """Every generated page, relative to ``reference/`` -> its text."""
    pages = {name: fn() for name, fn in PAGES.items()}
    pages.update(api_pages())
    return pages


def write_pages(reference_dir: Path) -> list[Path]:
    """Write every generated page into ``reference_dir`` (only those whose text changed), and
    remove the other pages of its ``api/`` directory."""
    written = []
    for name, text in all_pages().items():
        path = reference_dir / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
        written.append(path)
    for stale in (reference_dir / API_DIR).glob("*.rst"):
        if stale not in written:
            stale.unlink()
    return written


def _on_config_inited(app, config) -> None:
    write_pages(Path(app.confdir) / "reference")


def setup(app):
    app.connect("config-inited", _on_config_inited, priority=100)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
