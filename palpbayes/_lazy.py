"""Lazy public names of a package (PEP 562): each imported from its submodule on first use, so
that importing the package (and the command line's parser) does not load every submodule
and what they import (scipy.signal, arviz, ...)."""

from __future__ import annotations

import importlib
import importlib.util
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


def lazy_modules(package: str, api_modules: tuple[str, ...]
                 ) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package`` whose public names are the ``__all__`` of
    its submodules ``api_modules`` (``__all__`` itself is computed on first use, importing
    them all); a submodule's own name imports only that submodule.  A name exported by two of
    them is an ImportError."""
    module = importlib.import_module(package)

    def public_names() -> dict[str, str]:
        owner: dict[str, str] = {}
        for sub in api_modules:
            for name in importlib.import_module(f"{package}.{sub}").__all__:
                if name in owner:
                    raise ImportError(f"{package}: {name!r} is exported by both "
                                      f"{owner[name]} and {sub}; export it from one module")
                owner[name] = sub
        return owner

    def __getattr__(name: str) -> object:
        if name == "__all__":
            return list(public_names())
        if name.startswith("__"):  # e.g. __wrapped__, looked up by tools: never a public name
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        if importlib.util.find_spec(f"{package}.{name}") is not None:
            # a submodule (``from palpbayes.campaign import run``): import only that one
            return importlib.import_module(f"{package}.{name}")
        sub = public_names().get(name)
        if sub is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{sub}"), name)
        setattr(module, name, value)  # later look-ups skip __getattr__
        return value

    def __dir__() -> list[str]:
        return sorted({*vars(module), *public_names()})

    return __getattr__, __dir__
