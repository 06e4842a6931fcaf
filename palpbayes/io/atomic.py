"""Atomic output: write to a temporary file in the target folder, then ``os.replace``.

A reader never sees half a file, and an interrupted run leaves either the old file or none.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import stat
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

import pandas as pd

__all__ = ["atomic_path", "write_csv_atomic", "write_text_atomic"]


def _process_umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


#: The umask at import (read once: changing it is not thread-safe).
_UMASK = _process_umask()


def _final_mode(path: Path) -> int:
    """Permissions for the finished file: those of the file it replaces, else 0o666 & ~umask.

    (``mkstemp`` creates its file with 0o600, which would otherwise leak into the result.)
    """
    try:
        return stat.S_IMODE(path.stat().st_mode)
    except OSError:
        return 0o666 & ~_UMASK


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it onto ``path``.

    On an exception the temporary file is removed and ``path`` is left untouched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix or ".tmp",
                               dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.chmod(tmp_path, _final_mode(path))
        os.replace(tmp_path, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


def write_csv_atomic(df: pd.DataFrame, path: str | os.PathLike, **to_csv_kwargs) -> Path:
    """Write ``df`` as CSV (no index unless asked) atomically; return the path."""
    to_csv_kwargs.setdefault("index", False)
    with atomic_path(path) as tmp:
        df.to_csv(tmp, **to_csv_kwargs)
    return Path(path)


def write_text_atomic(text: str, path: str | os.PathLike) -> Path:
    """Write ``text`` (UTF-8) atomically; return the path."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_with(writer: Callable[[Path], None], path: str | os.PathLike,
               suffix: str | None = None) -> Path:
    """Call ``writer(tmp_path)`` and move the result onto ``path`` atomically."""
    with atomic_path(path, suffix=suffix) as tmp:
        writer(tmp)
    return Path(path)


__all__.append("write_with")


def write_netcdf_atomic(idata, path: str | os.PathLike) -> Path:
    """Write an arviz InferenceData with the h5netcdf engine atomically; return the path."""
    return write_with(lambda tmp: idata.to_netcdf(str(tmp), engine="h5netcdf"), path,
                      suffix=".nc")


__all__.append("write_netcdf_atomic")


@contextlib.contextmanager
def staged_folder(out: str | os.PathLike, prefix: str = ".partial-") -> Iterator[Path]:
    """Yield a new, empty staging folder inside ``out`` (created if need be) for a group of
    files written together; on success move each file written there onto ``out`` (keeping the
    permissions of the file it replaces, as :func:`atomic_path` does) and remove the folder.

    On an exception the folder is removed and ``out``'s files are left as they were: the group
    is written all or nothing, up to the final renames (one per file, within one folder).
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=prefix, dir=out))
    try:
        yield stage
        for f in sorted(stage.iterdir()):
            os.chmod(f, _final_mode(out / f.name))
            os.replace(f, out / f.name)
        stage.rmdir()
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise


__all__.append("staged_folder")
