"""Open an AFM file with afmformats: its curves, every library error wrapped, the last file kept.

:func:`load_afm_curves` is what :mod:`palpbayes.io.afm` (curves to traces) and
:mod:`palpbayes.maps.afm_source` (a force map's positions) read a file with.  The last file
read stays loaded in the process while its size and modification time are unchanged, so the
Dask workers of ``palpbayes map``, which read a force map's curves one at a time, parse its
headers once (afmformats loads the data columns lazily and keeps at most 100 of them).
"""

from __future__ import annotations

import functools
import logging
import os
from pathlib import Path

from ..errors import DataFileError
from .extras import import_extra
from .tabular import check_file

__all__ = ["AFM_SUFFIXES", "load_afm_curves"]

#: File suffixes read through afmformats (its .txt/.csv/.tab/.zip formats are not claimed:
#: palpbayes reads those as its own tables).
AFM_SUFFIXES = (".jpk-force", ".jpk-force-map", ".jpk-qi-data", ".jpk-qi-series", ".ibw",
                ".h5")

#: afmformats logs a traceback before re-raising a loader's error; palpbayes reports it once.
logging.getLogger("afmformats").addHandler(logging.NullHandler())


def load_afm_curves(path: str | os.PathLike, meta_override: dict | None = None
                    ) -> tuple[list, str]:
    """afmformats' curves of a file and its name for messages, every library error wrapped;
    ``meta_override`` (afmformats metadata, SI units) fills what the file lacks.  The last file
    read stays loaded (per process, while its size and time are unchanged; afmformats loads
    the data lazily and keeps at most 100 columns): a map's curves read one at a time parse
    the file's headers once."""
    path = Path(path)
    import_extra("afm", f"reading {path.suffix or path.name} files")
    check_file(path, str(path))
    st = path.stat()
    over = tuple(sorted((meta_override or {}).items()))
    return list(_load(str(path), (st.st_mtime_ns, st.st_size), over)), str(path)


@functools.lru_cache(maxsize=1)
def _load(source: str, stamp: tuple, override: tuple) -> tuple:
    """The curves of `source`; `stamp` (mtime, size) is only part of the cache key."""
    import afmformats

    try:
        curves = afmformats.load_data(Path(source), meta_override=dict(override))
    except (KeyboardInterrupt, SystemExit, GeneratorExit):
        raise
    except BaseException as exc:  # afmformats' own errors derive from BaseException
        fix = ("check that the file is complete and of the kind its name says; afmformats "
               f"reads {', '.join(AFM_SUFFIXES)} and AFM Workshop zips")
        if type(exc).__name__ == "MissingMetaDataError":  # e.g. AFM Workshop: k, sensitivity
            fix = ("give what the file lacks (palpbayes fit, replay or map: "
                   "--spring-constant N/m, --sensitivity m/V; read_afm: meta_override)")
        raise DataFileError(source, f"afmformats cannot read it ({type(exc).__name__}: "
                            f"{exc})".replace("\n", " "), fix) from None
    if not curves:
        raise DataFileError(source, "holds no curves", "check the file")
    return tuple(curves)
