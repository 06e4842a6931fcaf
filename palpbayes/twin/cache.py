"""The twin's tables and compression factors on disk, under a key of their inputs.

A table costs about a second of finite elements, a compression factor ~0.15 s, and a fit
needs ten of the one and five of the other in every process; each is stored as a ``.npz``
file (arrays only, read with ``allow_pickle=False``: nothing is unpickled) named by the
SHA-256 of its key,
the key itself stored inside and compared on reading (a file whose key differs, or that cannot
be read, is rebuilt).  Files are written atomically.

The folder is ``$PALPBAYES_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/palpbayes``, else
``~/.cache/palpbayes``; ``PALPBAYES_CACHE_DIR=off`` keeps the tables in memory only.

A source checkout also ships the tables its example campaign needs (:data:`SHIPPED_DIR`,
``data/twin-cache``, written by ``python tools/ship_twin_cache.py``): a file the cache folder
lacks is read from there, read-only, under the same key (a key of other inputs, code or library
versions finds nothing and the table is solved as before).  ``PALPBAYES_SHIPPED_TABLES=off``
ignores them (the test suite does, so that it solves what it tests).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
import sys
import zipfile
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_path

__all__ = ["cache_dir", "load_arrays", "save_arrays", "key_text", "code_stamp", "package_stamp",
           "SHIPPED_DIR", "shipped_dir"]

#: Subfolder of the cache for the twin's tables; its number changes with the solver.
_SUBDIR = "twin-v1"
#: The tables shipped with the source checkout (the example campaign's), read-only.
SHIPPED_DIR = Path(__file__).resolve().parents[2] / "data" / "twin-cache" / _SUBDIR


def shipped_dir() -> Path | None:
    """:data:`SHIPPED_DIR` when it is there and not switched off
    (``PALPBAYES_SHIPPED_TABLES=off``), else None."""
    if os.environ.get("PALPBAYES_SHIPPED_TABLES", "").strip().lower() in ("off", "0", "no"):
        return None
    return SHIPPED_DIR if SHIPPED_DIR.is_dir() else None


def cache_dir() -> Path | None:
    """The folder of the twin's tables, or None when disk caching is off."""
    env = os.environ.get("PALPBAYES_CACHE_DIR")
    if env is not None and env.strip().lower() in ("off", "none", "0", ""):
        return None
    if env:
        root = Path(env)
    else:
        xdg = os.environ.get("XDG_CACHE_HOME")
        root = (Path(xdg) if xdg else Path.home() / ".cache") / "palpbayes"
    return root / _SUBDIR


def key_text(key: dict) -> str:
    """The canonical text of a key (sorted JSON, floats to 12 significant digits)."""
    def norm(v):
        if isinstance(v, float):
            return float(f"{v:.12g}")
        return v
    return json.dumps({k: norm(v) for k, v in key.items()}, sort_keys=True)


def _name(key: dict) -> str:
    digest = hashlib.sha256(key_text(key).encode()).hexdigest()[:32]
    return f"{key.get('kind', 'table')}-{digest}.npz"


def _file(key: dict) -> Path | None:
    folder = cache_dir()
    return None if folder is None else folder / _name(key)


def _read(path: Path, key: dict) -> dict[str, np.ndarray] | None:
    try:
        with np.load(path, allow_pickle=False) as data:
            if str(data["key"]) != key_text(key):
                return None
            return {k: data[k] for k in data.files if k != "key"}
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError):
        return None


def load_arrays(key: dict) -> dict[str, np.ndarray] | None:
    """The arrays stored under ``key`` in the cache folder, else among the shipped tables
    (:func:`shipped_dir`), or None (absent, unreadable or another key)."""
    for folder in (cache_dir(), shipped_dir()):
        if folder is not None and (folder / _name(key)).is_file():
            found = _read(folder / _name(key), key)
            if found is not None:
                return found
    return None


def save_arrays(key: dict, arrays: dict[str, np.ndarray]) -> Path | None:
    """Store ``arrays`` under ``key`` (atomic); the path, or None when caching is off or
    the folder cannot be written (the table is then kept in memory only)."""
    path = _file(key)
    if path is None:
        return None
    with contextlib.suppress(OSError):
        with atomic_path(path, suffix=".npz") as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, key=np.array(key_text(key)), **arrays)
        return path
    return None


@functools.lru_cache(maxsize=16)
def code_stamp(modules: tuple[str, ...], extra: str = "") -> str:
    """A digest of the source files of the (imported) ``modules``, numpy's and scipy's versions
    and ``extra``: what an array derived by that code is valid for.  "" when a source cannot
    be read (a stamp that nothing stored matches)."""
    import scipy

    h = hashlib.sha256(f"{np.__version__} {scipy.__version__} {extra}".encode())
    for name in modules:
        try:
            h.update(Path(sys.modules[name].__file__).read_bytes())
        except (KeyError, OSError, TypeError):
            return ""
    return h.hexdigest()[:32]


@functools.lru_cache(maxsize=1)
def package_stamp() -> str:
    """A digest of every source and compiled file of the palpbayes package with numpy's,
    scipy's and pandas' versions: what a result of the whole package (the gap table) is valid
    for.  "" when a file cannot be read."""
    import pandas
    import scipy

    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256(f"{np.__version__} {scipy.__version__} {pandas.__version__}".encode())
    try:
        for f in sorted(root.rglob("*")):
            if f.suffix in (".py", ".pyx", ".so", ".pyd") and "__pycache__" not in f.parts:
                h.update(f.relative_to(root).as_posix().encode())
                h.update(f.read_bytes())
    except OSError:
        return ""
    return h.hexdigest()[:32]
