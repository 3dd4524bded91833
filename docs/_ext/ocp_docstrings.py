"""The package's docstrings as the API reference shows them: numpy sections, plain text elsewhere.

The docstrings are numpy style (Parameters, Returns, Attributes sections) with reST roles and
inline literals, and read as plain text too.  Before autodoc renders one:

* a data object that has no documentation of its own (autodoc would show its type's, e.g.
  ``dict``'s, or nothing, e.g. for a ``mappingproxy``) gets the ``#:`` comment above its assignment
  in the module that defines it (found through the packages' lazy-export tables), or nothing;
* the numpy sections become field lists (:class:`sphinx.ext.napoleon.NumpyDocstring`, numpy style
  only); prose after a section's entries, an unindented paragraph after a blank line, stays prose
  (under a Notes heading) instead of being read as more entries;
* attribute, property and data docstrings stay prose: napoleon alone would read their first line
  as ``type: description`` (this is why ``sphinx.ext.napoleon`` is not loaded as an extension);
* ``|x|`` (an absolute value) stays text: a bar outside inline literals and roles is escaped,
  since reST would read a substitution; a line starting like ``(a) ...`` is not an enumerated list.
"""
from __future__ import annotations

import importlib
import re
import sys

from sphinx.ext.napoleon import Config
from sphinx.ext.napoleon.docstring import NumpyDocstring

#: napoleon, numpy style; an Attributes section is a list as Parameters are (not one directive per
#: attribute, which would document the dataclass fields a second time beside autodoc's members)
NAPOLEON = Config(napoleon_google_docstring=False, napoleon_numpy_docstring=True,
                  napoleon_use_param=True, napoleon_use_rtype=False,
                  napoleon_custom_sections=[("Attributes", "params_style")])
#: numpy sections made of entries (name : type, then an indented description)
FIELD_SECTIONS = {"Parameters", "Other Parameters", "Returns", "Yields", "Receives", "Raises",
                  "Warns", "Attributes", "Methods"}
PROSE_KINDS = {"attribute", "property", "data"}

_UNDERLINE = re.compile(r"-{3,}")
_LITERAL = re.compile(r"``.+?``|(?::[\w:.+-]+:)?`[^`]+`")
_BAR = re.compile(r"(?<!\\)\|")
_ENUMERATOR = re.compile(r"^(\s*)\((\w)\)(\s)")
_TYPE_FIELD = re.compile(r"^\s*:(type|rtype|vartype)\b")


def _entry_like(line: str) -> bool:
    """Whether an unindented line in a field section reads as an entry: ``name : type`` or a
    short name or type (``list of str``), not a sentence."""
    return " : " in line or len(line.split()) <= 4


def prose_after_sections(lines: list[str]) -> list[str]:
    """``lines`` with a Notes heading before prose that follows a field section's entries."""
    out, in_fields = [], False
    for i, line in enumerate(lines):
        following = lines[i + 1] if i + 1 < len(lines) else ""
        if line.strip() and _UNDERLINE.fullmatch(following.strip()):
            in_fields = line.strip() in FIELD_SECTIONS
        elif (in_fields and line and not line[0].isspace() and i and not lines[i - 1].strip()
              and not _UNDERLINE.fullmatch(line.strip()) and not _entry_like(line)):
            out += ["Notes", "-----", ""]
            in_fields = False
        out.append(line)
    return out


def plain_text(line: str) -> str:
    """Bars outside literals escaped, a leading ``(a)`` not an enumerator."""
    if _TYPE_FIELD.match(line):
        return line
    pieces, pos = [], 0
    for m in _LITERAL.finditer(line):
        pieces += [_BAR.sub(r"\\|", line[pos:m.start()]), m[0]]
        pos = m.end()
    pieces.append(_BAR.sub(r"\\|", line[pos:]))
    return _ENUMERATOR.sub(r"\1\\(\2)\3", "".join(pieces))


def _defining_module(name: str) -> tuple[str, str] | None:
    """(module, attribute) where the public data object ``name`` is assigned."""
    package, _, attr = name.rpartition(".")
    try:
        module = importlib.import_module(package)
    except ImportError:
        return None
    while attr in getattr(module, "_EXPORTS", {}):
        module = importlib.import_module(module._EXPORTS[attr])
    return module.__name__, attr


def _attr_comment(module: str, attr: str) -> list[str]:
    from sphinx.pycode import ModuleAnalyzer
    try:
        docs = ModuleAnalyzer.for_module(module).find_attr_docs()
    except Exception:   # no source to analyse
        return []
    return list(docs.get(("", attr), []))


def comment_doc(name: str) -> list[str]:
    """The ``#:`` comment documenting the data object ``name`` where it is defined, or []: in the
    module its package's lazy exports name, or else in the package's imported submodule that holds
    the same object (a package that imports the name from a submodule)."""
    found = _defining_module(name)
    if found is None:
        return []
    lines = _attr_comment(*found)
    if lines:
        return lines
    module, attr = found
    obj = getattr(importlib.import_module(module), attr, None)
    for sub in sorted(m for m in sys.modules if m.startswith(module + ".")):
        if getattr(sys.modules[sub], attr, None) is obj and (lines := _attr_comment(sub, attr)):
            return lines
    return []


def _is_type_doc(obj, lines: list[str]) -> bool:
    doc = type(obj).__doc__
    first = next((line.strip() for line in lines if line.strip()), None)
    return bool(doc and first and doc.strip().splitlines()[0].strip() == first)


def process_docstring(app, what, name, obj, options, lines: list[str]) -> None:
    """autodoc-process-docstring: see the module's docstring."""
    if what == "data" and (not any(line.strip() for line in lines) or _is_type_doc(obj, lines)):
        lines[:] = comment_doc(name)
    if what not in PROSE_KINDS:
        lines[:] = NumpyDocstring(prose_after_sections(list(lines)), NAPOLEON, app, what, name,
                                  obj, options).lines()
    lines[:] = [plain_text(line) for line in lines]


def setup(app):
    app.setup_extension("sphinx.ext.autodoc")
    app.connect("autodoc-process-docstring", process_docstring)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
