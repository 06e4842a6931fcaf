"""Lazy public names of a package (PEP 562): each imported from its submodule on first use, so
that importing the package (and the command line's parser) does not load every submodule
and what they import (scipy.signal, arviz, ...)."""

from __future__ import annotations

import importlib
from collections.abc import Callable


def lazy_exports(package: str, table: dict[str, str]
                 ) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package`` whose public names are the keys of
    ``table`` (name -> the submodule defining it); a name once looked up is stored in the
    package's namespace, so later look-ups skip ``__getattr__``."""
    module = importlib.import_module(package)

    def __getattr__(name: str) -> object:
        try:
            sub = table[name]
        except KeyError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        value = getattr(importlib.import_module(f"{package}.{sub}"), name)
        setattr(module, name, value)
        return value

    def __dir__() -> list[str]:
        return sorted({*vars(module), *table})

    return __getattr__, __dir__
