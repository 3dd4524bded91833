"""Lazy re-exports (PEP 562): a package's public names are imported from their modules on first use.

The package ``__init__`` files re-export their folder's public names this way, so that
``import ocp_crawl`` (or ``ocp_crawl.sweep``, ...) costs nothing until a name is used: numpy,
CasADi, scipy and matplotlib are imported by the modules that need them, when one of their names is
first asked for.  Start-up time matters for short commands and for every worker process of a sweep.
"""
from __future__ import annotations

import importlib
import sys
from typing import Any, Callable, Mapping


def lazy_exports(package: str, exports: Mapping[str, str]) -> tuple[Callable[[str], Any],
                                                                    Callable[[], list[str]]]:
    """The module-level ``__getattr__`` and ``__dir__`` of a package with lazy public names.

    Parameters
    ----------
    package : str
        The package's dotted name (its ``__name__``).
    exports : mapping of str to str
        Public name -> dotted name of the module that defines it.

    Returns
    -------
    (__getattr__, __dir__) : to assign at the package's top level.  A name, once imported, is stored
    on the package, so that later look-ups are plain attribute reads.
    """
    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(exports))

    return __getattr__, __dir__
