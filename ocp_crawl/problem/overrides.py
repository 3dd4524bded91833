"""Setting keys of a problem: ``SECTION.KEY`` names, ``--set`` text, typed values, and reading TOML
files.

Values set in code (:func:`set_values`, ``Problem.with_values``) are typed: no text round trip.
Only the command line's ``--set SECTION.KEY=VALUE`` is text, parsed here as one TOML value.
Values are validated later, when the problem is built.
"""
from __future__ import annotations

import re
import sys
import tomllib
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
import tomli_w

from ocp_crawl.io.files import read_bounded
from ocp_crawl.problem.messages import format_value, suggest
from ocp_crawl.problem.keys import TYPE_WORDS, ProblemError
from ocp_crawl.problem.schema import SCHEMA, removed_key

#: an entry's index as written after an array key: a count from 0, no leading zeros (one spelling
#: per entry), at most 9 digits
INDEX = r"\[(?:0|[1-9][0-9]{0,8})\]"
_KEY_RE = re.compile(rf"^\s*([A-Za-z0-9_-]+)\.([A-Za-z0-9_-]+)({INDEX})?\s*$")
_ENTRY_RE = re.compile(rf"^([A-Za-z0-9_-]+)({INDEX})$")


def entry(name: str) -> tuple[str, int | None]:
    """The key and the index of an entry name: ``("stiffness", 1)`` of ``"stiffness[1]"`` (entry 1,
    counted from 0, of an array key); ``(name, None)`` of a plain key."""
    m = _ENTRY_RE.match(name)
    return (m[1], int(m[2][1:-1])) if m else (name, None)


def entry_value(sec: Mapping[str, Any], name: str, missing: Any = None) -> Any:
    """The value of key or entry ``name`` in the section ``sec``, ``missing`` if it has none."""
    base, index = entry(name)
    value = sec.get(base, missing)
    if index is None or value is missing:
        return value
    return value[index] if isinstance(value, (list, tuple)) and index < len(value) else missing


def split_key(dotted: str, where: str) -> tuple[str, str]:
    """``"SECTION.KEY"`` (or ``"SECTION.KEY[i]"``, entry i of an array key) as (section, key) of the
    schema (the key with its ``[i]``), or ProblemError naming ``where``."""
    m = _KEY_RE.match(dotted) if isinstance(dotted, str) else None
    if not m:
        shown = format_value(dotted.strip()) if isinstance(dotted, str) else repr(dotted)
        raise ProblemError(f"{where} is invalid: the key {shown} must be SECTION.KEY, e.g. "
                           "robot.k=0.05 (or an array's entry SECTION.KEY[i], e.g. "
                           "robot.stiffness[1]=0.2)")
    section, name, index = m.groups()
    if section not in SCHEMA:
        hint = suggest(section, list(SCHEMA))
        raise ProblemError(f"{where} is invalid: unknown section [{section}]; {hint}valid "
                           f"sections: {', '.join(SCHEMA)}")
    keys = SCHEMA[section].key_map
    if name not in keys:
        removed = removed_key(section, name)
        if removed is not None:
            raise ProblemError(f"{where} is invalid: {removed}")
        hint = suggest(name, list(keys))
        raise ProblemError(f"{where} is invalid: unknown key {name} in [{section}]; {hint}valid "
                           f"keys: {', '.join(keys)}")
    if index is not None and keys[name].type is not list:
        raise ProblemError(f"{where} is invalid: {section}.{name}{index} names an entry, and "
                           f"{section}.{name} is {TYPE_WORDS[keys[name].type]}, not an array of "
                           "numbers")
    return section, name + (index or "")


def parse_override(text: str, source: str = "--set") -> tuple[str, str, Any]:
    """Parse ``SECTION.KEY=VALUE`` (VALUE a TOML value; a bare word is accepted for string keys).

    Returns (section, key, value); bad text raises ProblemError naming ``source`` and the text.
    """
    if not isinstance(text, str):
        raise ProblemError(f"{source}: --set {text!r} is invalid: expected SECTION.KEY=VALUE, e.g. "
                           "robot.k=0.05")
    where = f"{source}: --set {format_value(text)}"
    if "=" not in text:
        raise ProblemError(f"{where} is invalid: expected SECTION.KEY=VALUE, e.g. robot.k=0.05")
    lhs, rhs = text.split("=", 1)
    section, name = split_key(lhs, where)
    base, index = entry(name)
    key = SCHEMA[section].key_map[base]
    rhs = rhs.strip()
    if not rhs or "\n" in rhs or "\r" in rhs:
        if index is not None:
            example: Any = 1.0
        elif key.default is not None:
            example = key.default
        else:
            example = (key.choices or (1.0,))[0]
        raise ProblemError(f"{where} is invalid: the value must be one TOML value, e.g. "
                           f"{section}.{name}={format_value(example)}")
    try:
        parsed = toml_loads(f"v = {rhs}", f"{where} is invalid")
        if set(parsed) != {"v"}:
            raise tomllib.TOMLDecodeError("more than one value")
        value = parsed["v"]
    except tomllib.TOMLDecodeError:
        if key.type is not str:
            expected = TYPE_WORDS[key.type if index is None else float]
            raise ProblemError(f"{where} is invalid: {format_value(rhs)} is not a TOML value; "
                               f"expected {expected} ({key.what})") from None
        value = rhs
    return section, name, value


def set_values(data: Mapping[str, Any], items: Iterable[tuple[str, str, Any]],
               source: str = "<dict>" ) -> tuple[dict[str, Any], set[tuple[str, str]]]:
    """Copy of ``data`` with typed values set, in order: ``items`` are (section, key, value)
    triples.

    Setting one of two alternative keys (``mu`` and ``mu1``/``mu2``, ``file`` and ``phase``) removes
    the other (and the keys that need it: inline samples with their phases); ``mu1`` or ``mu2`` on a
    robot given one ``mu`` keeps the other foot at mu.  Setting a selector (``gait.waveform``,
    ``ocp.objective``) removes the keys of ``data`` that belong to other variants than its last
    value; keys set here stay, for the validation to refuse.  An item that undoes an earlier item
    (the same key to another value, its alternative) is a ProblemError naming both.  Returns the new
    data and the set keys.  Values are validated later, when the problem is built.
    """
    out = {k: dict(v) if isinstance(v, Mapping) else v for k, v in data.items()}
    done: dict[tuple[str, str], Any] = {}
    for section, name, value in items:
        sec = out.setdefault(section, {})
        if not isinstance(sec, dict):
            raise ProblemError(f"{source}: {section}.{name} cannot be set: {section} is not a "
                               "section in the file")
        value = value.item() if isinstance(value, np.generic) else value
        if (section, name) in done and done[section, name] != value:
            raise ProblemError(f"{source}: {section}.{name} is set twice, to "
                               f"{format_value(done[section, name])} and to {format_value(value)}: "
                               "give it once")
        schema = SCHEMA[section]
        _check_entries(done, section, name, value, source)
        base, index = entry(name)
        if index is not None:   # one entry of an array the problem gives
            sec[base] = _with_entry(sec.get(base), index, value, f"{section}.{name}", source)
            done[section, name] = value
            continue
        if section == "robot" and name in ("mu1", "mu2") and "mu" in sec:
            # one foot's friction changed on a robot given one mu: the other foot keeps mu
            sec.setdefault("mu1" if name == "mu2" else "mu2", sec["mu"])
            done.pop((section, "mu"), None)   # carried, not lost
        alternatives = set(schema.key_map[name].exclusive_with) | {k.name for k in schema.keys
                                                                   if name in k.exclusive_with}
        _drop(sec, schema, {k for k in alternatives if k in sec}, done,
              f"{section}.{name} = {format_value(value)}", source)
        sec[name] = value
        done[section, name] = value
    for section in {s for s, n in done if n == SCHEMA[s].selector}:
        schema, sec = SCHEMA[section], out[section]
        variant = sec[schema.selector]
        _drop(sec, schema,
              {k.name for k in schema.keys if k.name in sec and (section, k.name) not in done
               and not schema.applies(k, variant)}, done, "", source)
    # (an entry set is its array's key set, as the messages name it)
    return out, set(done) | {(section, entry(name)[0]) for section, name in done}


def _check_entries(done: Mapping[tuple[str, str], Any], section: str, name: str, value: Any,
                   source: str) -> None:
    """ProblemError when ``name`` = ``value`` and an earlier item disagree on an array's entry: an
    entry of an array given whole before it, or a whole array that changes an entry given before
    it."""
    base, index = entry(name)
    for (sec, earlier), before in done.items():
        if sec != section or entry(earlier)[0] != base or earlier == name:
            continue
        if index is not None and entry(earlier)[1] is None:
            same = entry_value({base: before}, name, value) == value
        elif index is None and entry(earlier)[1] is not None:
            same = entry_value({base: value}, earlier, before) == before
        else:
            continue
        if not same:
            raise ProblemError(f"{source}: {section}.{name} = {format_value(value)} changes "
                               f"{section}.{earlier} = {format_value(before)} given before it: "
                               "give one of them")


def _with_entry(values: Any, index: int, value: Any, name: str, source: str) -> list:
    """A copy of the array ``values`` with entry ``index`` set to ``value``; ProblemError naming
    ``name`` when the problem gives no array with that entry."""
    if not isinstance(values, (list, tuple)):
        raise ProblemError(f"{source}: {name} = {format_value(value)} sets an entry of an array "
                           "the problem does not give: give the whole array")
    if index >= len(values):
        raise ProblemError(f"{source}: {name} = {format_value(value)} is invalid: the array has "
                           f"{len(values)} entries, indices 0 to {len(values) - 1}")
    out = list(values)
    out[index] = value
    return out


def _drop(sec: dict, schema, names: set[str], done: Mapping[tuple[str, str], Any], by: str,
          source: str) -> None:
    """Remove the keys ``names`` of ``sec`` and those that need one of them (``requires``); a key
    that an earlier item set is a ProblemError (``by`` undoes it)."""
    names = names | {k.name for k in schema.keys if k.name in sec and set(k.requires) & names}
    for name in sorted(names):
        if (schema.name, name) in done:
            raise ProblemError(f"{source}: {by} drops {schema.name}.{name} = "
                               f"{format_value(done[schema.name, name])} given before it (they are "
                               "alternatives): give one of them")
        sec.pop(name, None)


def first_loss(data: Mapping[str, Any], first: Sequence[tuple[str, str, Any]],
               then: Sequence[tuple[str, str, Any]] ) -> tuple[int, str] | None:
    """Which of the values set by ``first`` the later ``then`` overrides silently undo: the index in
    ``then`` of the first (section, key, value) that changes or removes one (a key set again to
    another value, an alternative key, another waveform or objective dropping it), with that key as
    ``"section.key"``; None if none does.  Keys are checked in the order of ``first``.

    A removed key whose value the same item carried to a key it added is kept: ``robot.mu`` then
    ``robot.mu1`` leaves foot 2 at mu (``mu2``), as :func:`set_values` promises.
    """
    base, _ = set_values(data, first)
    kept = list(dict.fromkeys((section, name) for section, name, _ in first))
    current = base
    for i, item in enumerate(then):
        before = current
        current, _ = set_values(current, [item])
        for section, name in kept:
            gone = object()
            was, sec = entry_value(base[section], name), current.get(section, {})
            if entry_value(sec, name, gone) == was:
                continue
            added = set(sec) - set(before.get(section, {})) - {item[1]}
            if entry_value(sec, name, gone) is gone and any(sec[n] == was for n in added):
                continue
            return i, f"{section}.{name}"
    return None


def apply_overrides(data: Mapping[str, Any], overrides: Sequence[str], source: str = "<dict>"
                    ) -> tuple[dict[str, Any], set[tuple[str, str]]]:
    """Copy of ``data`` with ``SECTION.KEY=VALUE`` overrides (text, as ``--set``) applied; also
    returns the overridden keys."""
    if isinstance(overrides, str):
        overrides = [overrides]
    items = [parse_override(text, source) for text in overrides]
    for (section, _, _), text in zip(items, overrides):
        if not isinstance(data.get(section, {}), Mapping):
            raise ProblemError(f"{source}: --set {format_value(text)} is invalid: {section} is not "
                               "a section in the file")
    return set_values(data, items, source)


#: largest problem file read [bytes]: problem files are a few hundred bytes; a path such as
#: /dev/zero must not hang
MAX_PROBLEM_BYTES = 1 << 20


def toml_loads(text: str, where: str) -> dict[str, Any]:
    """``tomllib.loads``, nesting deeper than Python's recursion limit (arrays of arrays ...) a
    ProblemError naming ``where`` instead of a RecursionError."""
    try:
        return tomllib.loads(text)
    except RecursionError:
        raise ProblemError(f"{where}: malformed TOML: arrays or tables nested too deeply (problem "
                           "values are numbers and strings)") from None
    except tomllib.TOMLDecodeError:
        raise
    # an integer longer than Python's limit of digits (sys.get_int_max_str_digits)
    except ValueError:
        raise ProblemError(f"{where}: malformed TOML: an integer of more than "
                           f"{sys.get_int_max_str_digits()} digits (no problem value needs one; "
                           "write large numbers as floats, e.g. 1e308)") from None


def read_bytes(path: Path, limit: int = MAX_PROBLEM_BYTES) -> bytes:
    """The bytes of a problem file, at most ``limit`` (a larger file, or an endless one such as
    /dev/zero, is a ProblemError naming the file and the limit)."""
    try:
        raw = read_bounded(path, limit)
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise ProblemError(f"{path}: cannot read the problem file: {reason}") from None
    if len(raw) > limit:
        raise ProblemError(f"{path}: cannot read the problem file: larger than {limit} bytes "
                           f"({limit / 2**20:g} MiB), the limit of a problem file (problem files "
                           "are a few hundred bytes)")
    return raw


def read_toml(path: str | Path) -> dict[str, Any]:
    """Read a TOML file (at most :data:`MAX_PROBLEM_BYTES`); unreadable or oversized files and
    malformed TOML raise ProblemError (with the offending line)."""
    path = Path(path)
    raw = read_bytes(path)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ProblemError(f"{path}: cannot read the problem file: not UTF-8 text (byte "
                           f"{exc.start})") from None
    try:
        return toml_loads(text, str(path))
    except tomllib.TOMLDecodeError as exc:
        msg = str(exc)
        m = re.search(r"line (\d+)", msg)
        line = ""
        if m:
            lines = text.splitlines()
            n = int(m.group(1))
            if 1 <= n <= len(lines):
                line = f": {format_value(lines[n - 1].strip())}"
        raise ProblemError(f"{path}: malformed TOML: {msg}{line}") from None


def toml_string(text: str) -> str:
    """``text`` as a TOML string value (tomli-w's quoting: quotes, backslashes and control
    characters escaped), e.g. for an override ``gait.file=<path>``."""
    return tomli_w.dumps({"v": text}).split("=", 1)[1].strip()


def _plain_value(value: Any) -> Any:
    """``value`` with numpy scalars and tuples as the Python types tomli-w writes."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_plain_value(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): _plain_value(v) for k, v in value.items()}
    return value


def toml_text(sections: Mapping[str, Mapping[str, Any]], comments: Sequence[str] = ()) -> str:
    """A problem file's text: ``# comments``, then the ``[section]`` tables of ``sections`` written
    by tomli-w (floats with full precision, strings quoted); :func:`read_toml` reads the same values
    back."""
    head = "".join(f"# {c}\n" for c in comments)
    body = tomli_w.dumps(_plain_value(sections))
    return head + ("\n" if head and body else "") + body
