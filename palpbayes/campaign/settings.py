"""``settings.json``: the record of how a results folder was fitted.

The record holds the palpbayes version, the fit options (their ``repr``, compared on
``--resume``, and their fields), the seed, the source manifest and the reader options
(:func:`settings_record`).  :func:`read_settings` reads it back.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING

from .. import __version__, outputs
from .. import errors as _errors

if TYPE_CHECKING:
    from .fitjob import FitOptions

__all__ = ["options_record", "read_settings", "settings_record"]


def options_record(options: FitOptions) -> dict:
    """JSON-able record of the options (progress display removed: it changes no result)."""
    opts = options.with_progress(None)
    return {"repr": repr(opts), "fields": json.loads(json.dumps(asdict(opts), default=str))}


def read_settings(out_dir: str | os.PathLike) -> dict:
    """``settings.json`` of a results folder as a dict ({} when absent)."""
    path = Path(out_dir) / outputs.SETTINGS
    if not path.is_file():
        return {}
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise _errors.DataFileError(path, f"not valid JSON ({exc})",
                                    "delete it and rerun with --force") from None


def settings_record(options: FitOptions, source: Path | None, out: Path, n: int,
                    read_options: dict | None = None) -> dict:
    """The ``settings.json`` record of a run: version, options, source, seed, read options.

    ``source`` is the manifest (None for a list of traces), ``out`` the results folder and
    ``n`` the number of traces.
    """
    camp = None if source is None else source.parent
    rec = options_record(options)
    return {
        "palpbayes_version": __version__,
        "options": rec["repr"],
        "options_fields": rec["fields"],
        "method": options.method,
        "seed": int(options.seed),
        "source": None if source is None else str(source),
        "campaign_dir": None if camp is None else str(camp),
        "campaign_dir_relative": None if camp is None else os.path.relpath(camp, out.resolve()),
        "n_traces": n,
        "read_options": json.loads(json.dumps(read_options or {}, sort_keys=True, default=str)),
    }
