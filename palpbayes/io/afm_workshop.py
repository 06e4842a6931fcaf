"""Recognise an AFM Workshop force map: a zip of the instrument's per-curve CSV files.

AFM Workshop instruments write one CSV per curve of a force map (a header starting
``Force-Distance Curve`` with ``Mode: Mapping``, ``Point``, ``X, um``, ``Y, um``, then
``Extend Z-Sense(nm),Extend T-B(V),...``); afmformats reads a zip of them as one map
(``afmformats.formats.fmt_workshop.ws_map``).  palpbayes reads other ``.zip`` files as its own
tables, so a zip is an AFM file only when its first CSV starts with that header.

The files record the deflection in volts and neither the sensitivity [m/V] nor the spring
constant [N/m] (unless their header has ``Light Lever Gain`` and ``Force Constant``): pass them
as ``meta_override={"sensitivity": ..., "spring constant": ...}`` to
:func:`palpbayes.io.afm.read_afm` (``palpbayes map`` and ``fit``: ``--sensitivity``,
``--spring-constant``).
"""

from __future__ import annotations

import os
import zipfile
from pathlib import Path

__all__ = ["WORKSHOP_HEADER", "is_afm_workshop_zip"]

#: First line of every AFM Workshop force-curve CSV.
WORKSHOP_HEADER = "Force-Distance Curve"


def is_afm_workshop_zip(path: str | os.PathLike) -> bool:
    """True when ``path`` is a ``.zip`` whose first ``.csv`` member (in name order) starts
    with :data:`WORKSHOP_HEADER`; False for anything else, unreadable files included."""
    path = Path(path)
    if path.suffix.lower() != ".zip" or not path.is_file():
        return False
    try:
        with zipfile.ZipFile(path) as arc:
            names = sorted(n for n in arc.namelist() if n.lower().endswith(".csv"))
            if not names:
                return False
            with arc.open(names[0]) as fd:
                head = fd.read(200).decode("utf-8", errors="replace")
    except (OSError, zipfile.BadZipFile):
        return False
    return head.lstrip("\ufeff").startswith(WORKSHOP_HEADER)
