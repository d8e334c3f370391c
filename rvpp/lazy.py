"""Names of a module imported on first use (a module's ``__getattr__``, PEP 562).

``rvpp``, ``rvpp.backtest``, ``rvpp.studies`` and ``rvpp.service`` offer names from modules
that import the solver stack; importing them on first use keeps ``import rvpp`` and the command
line's start light. It imports nothing of rvpp itself, so any layer may use it.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from importlib import import_module


def lazy_names(module: str, where: Mapping[str, str], anchor: str | None = None
               ) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``module``: its name ``n`` is the attribute ``n`` of the
    module ``where[n]`` (a relative name, from ``anchor``, by default ``module`` itself), or that
    module's submodule ``n``, imported when first asked for and then kept in ``module``."""
    own, base = sys.modules[module], anchor or module

    def __getattr__(name: str) -> object:
        if name not in where:
            raise AttributeError(f"module {module!r} has no attribute {name!r}")
        source = import_module(where[name], base)
        value = getattr(source, name) if hasattr(source, name) else import_module(f"{source.__name__}.{name}")
        setattr(own, name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(own)) | set(where))

    return __getattr__, __dir__
