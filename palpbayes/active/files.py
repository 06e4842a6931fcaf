"""The files of a search state, and reading a map folder as one.

A search-state folder (``palpbayes next DIR --init``, then one row per press from
``palpbayes follow --map DIR`` or from the user's own loop)::

    DIR/
      search.json   the specimen: footprint, keep-out zones, minimum spacing [m], the tip's
                    contact radius and the block thickness [m], the tip and the depth, the
                    limits of a press (optional: the allowed depths as fractions of the
                    thickness, the largest force [N]; :func:`read_limits`), optionally
                    "background": "correlated" (the posterior's model), and with a choice
                    of depths "press_depths_m", "contact_radii_m" and "press_overhead_s"
                    (:class:`~palpbayes.active.depth.PressDepths`)
      presses.csv   one row per press: x_m, y_m, logE_mean, logE_sd (the press's
                    posterior of log(E/Pa)), depth_m [m] when the search chooses depths, and
                    after each press p_lump (P(lump) after it)

An output folder of ``palpbayes map`` (``points.csv`` and ``settings.json``) is read as a
state too: its points with a fit are the presses, its lattice the footprint.  Files are
written whole (:mod:`palpbayes.io.atomic`); what is read is parsed as numbers and JSON only.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import DataFileError, InputError
from ..io.atomic import write_csv_atomic, write_text_atomic
from .depth import PressDepths
from .safety import PressLimits
from .search import PRESS_COLUMNS, SearchState

__all__ = ["SEARCH_FILE", "PRESSES_FILE", "init_state", "read_state", "append_press",
           "read_limits"]

SEARCH_FILE = "search.json"
PRESSES_FILE = "presses.csv"
#: search.json keys -> SearchState fields (numbers in SI units).
_FIELDS = {"min_spacing_m": "min_spacing", "candidate_step_m": "candidate_step",
           "resolution_m": "resolution", "min_excess": "min_excess",
           "max_ratio": "max_ratio", "prior_lump": "prior_lump"}


def init_state(folder: str | os.PathLike, *, footprint, contact_radius: float,
               thickness: float, keep_out=(), overwrite: bool = False, **extra) -> SearchState:
    """Create a search-state folder with no press yet (``extra``: ``min_spacing_m``, ...,
    as in :data:`_FIELDS`, and free-form records such as ``tip`` and ``depth_m``).

    Raises
    ------
    OutputExistsError
        The folder already holds a state and ``overwrite`` is False.
    """
    from ..errors import OutputExistsError

    out = Path(folder)
    if (out / SEARCH_FILE).exists() and not overwrite:
        raise OutputExistsError(f"{out / SEARCH_FILE} exists: give another folder, or "
                                "--force to start the search again")
    rec = {"footprint_m": [float(v) for v in footprint], "contact_radius_m": contact_radius,
           "thickness_m": thickness, "keep_out_m": [list(map(float, z)) for z in keep_out],
           **extra}
    state = _from_record(rec, pd.DataFrame(columns=PRESS_COLUMNS), out / SEARCH_FILE)
    _ = state.hyp  # the lump grid for this specimen can be built (a block thick enough)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(json.dumps(rec, indent=2, allow_nan=False) + "\n", out / SEARCH_FILE)
    write_csv_atomic(pd.DataFrame(columns=[*PRESS_COLUMNS, "p_lump"]), out / PRESSES_FILE,
                     index=False)
    return state


def _from_record(rec: dict, presses: pd.DataFrame, path: Path, **overrides) -> SearchState:
    try:
        fp = tuple(float(v) for v in rec["footprint_m"])
        a, H = float(rec["contact_radius_m"]), float(rec["thickness_m"])
        keep = tuple(tuple(float(v) for v in z) for z in rec.get("keep_out_m", ()))
        kw = {f: float(rec[k]) for k, f in _FIELDS.items() if rec.get(k) is not None}
        if rec.get("background") is not None:
            kw["background"] = str(rec["background"])
        depths = None
        if rec.get("press_depths_m"):
            more = {} if rec.get("press_overhead_s") is None else {
                "overhead": float(rec["press_overhead_s"])}
            depths = (tuple(float(v) for v in rec["press_depths_m"]),
                      tuple(float(v) for v in rec["contact_radii_m"]), more)
    except (KeyError, TypeError, ValueError) as exc:
        raise DataFileError(path, f"is not a search state ({type(exc).__name__}: {exc})",
                            "create one with 'palpbayes next DIR --init'") from None
    if len(fp) != 4 or not all(map(math.isfinite, (*fp, a, H))):
        raise DataFileError(path, "footprint_m needs 4 finite numbers x0, x1, y0, y1 [m]")
    kw.update(footprint=fp, contact_radius=a, thickness=H, keep_out=keep)
    kw.update({k: v for k, v in overrides.items() if v is not None})
    try:
        if depths is not None:
            kw["press_depths"] = PressDepths(depths[0], depths[1], **depths[2])
        return SearchState(presses, **kw)
    except InputError as exc:
        raise DataFileError(path, str(exc)) from None


def read_limits(folder: str | os.PathLike) -> PressLimits:
    """The limits of a press recorded in a state folder's ``search.json``: ``depths``
    (fractions of the thickness), ``max_force_n`` [N] and ``depth_m`` [m], each optional (a
    state written before they existed has none: no limit); a map folder has none either.

    Raises
    ------
    DataFileError
        ``search.json`` is not readable, or a limit in it is not a number of its kind.
    """
    path = Path(folder) / SEARCH_FILE
    if not path.is_file():
        return PressLimits()
    try:
        rec = json.loads(path.read_text(encoding="utf-8"))
        depths = tuple(float(v) for v in (rec.get("depths") or ()))
        F, d = rec.get("max_force_n"), rec.get("depth_m")
        return PressLimits(depths=depths, max_force=None if F is None else float(F),
                           depth=None if d is None else float(d))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, AttributeError, TypeError,
            ValueError, InputError) as exc:
        raise DataFileError(path, f"has no readable limits ({exc})",
                            "create the state again with 'palpbayes next DIR --init'") from None


def _read_table(path: Path) -> pd.DataFrame:
    """A CSV with the press columns (:data:`PRESS_COLUMNS`), or an error naming the file."""
    try:
        df = pd.read_csv(path)
    except (OSError, ValueError, pd.errors.ParserError) as exc:
        raise DataFileError(path, f"not readable ({exc})") from None
    missing = [c for c in PRESS_COLUMNS if c not in df.columns]
    if missing:
        raise DataFileError(path, f"no column {', '.join(missing)}",
                            "a press needs " + ", ".join(PRESS_COLUMNS))
    return df


def _read_presses(path: Path) -> pd.DataFrame:
    df = _read_table(path)
    for c in PRESS_COLUMNS:
        v = pd.to_numeric(df[c], errors="coerce")
        vals = v.to_numpy(dtype=float)
        bad = ~np.isfinite(vals) | ((vals <= 0) if c == "logE_sd" else False)
        if bad.any():
            j = int(np.flatnonzero(bad)[0])
            what = "a finite number > 0" if c == "logE_sd" else "a finite number"
            raise DataFileError(path, f"row {j + 2}, column {c}: {df[c].iloc[j]!r} is not "
                                f"{what}", "remove the press or give its value")
        df[c] = v.astype(float)
    if "depth_m" in df.columns:  # empty: the reference depth
        v = pd.to_numeric(df["depth_m"], errors="coerce")
        bad = v.isna() & df["depth_m"].notna()
        if bad.any():
            j = int(np.flatnonzero(bad.to_numpy())[0])
            raise DataFileError(path, f"row {j + 2}, column depth_m: {df['depth_m'].iloc[j]!r} "
                                "is not a number [m]", "give the press's depth or leave it "
                                "empty")
        df["depth_m"] = v.astype(float)
    return df


def read_state(folder: str | os.PathLike, **overrides) -> SearchState:
    """The search state of a state folder or a ``palpbayes map`` output folder (module
    docstring); ``overrides`` replace :class:`SearchState` fields (None: keep).

    Raises
    ------
    DataFileError
        Neither kind of folder, or a file that cannot be read (the message names it).
    """
    d = Path(folder)
    if (d / SEARCH_FILE).is_file():
        try:
            rec = json.loads((d / SEARCH_FILE).read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise DataFileError(d / SEARCH_FILE, f"not readable JSON ({exc})") from None
        if not isinstance(rec, dict):
            raise DataFileError(d / SEARCH_FILE, "is not a search state (a JSON object)")
        presses = (_read_presses(d / PRESSES_FILE) if (d / PRESSES_FILE).is_file()
                   else pd.DataFrame(columns=PRESS_COLUMNS))
        return _from_record(rec, presses, d / SEARCH_FILE, **overrides)
    if (d / "points.csv").is_file() and (d / "settings.json").is_file():
        return _from_map(d, **overrides)
    raise DataFileError(d, "holds no search state (search.json) and no map (points.csv with "
                        "settings.json)", "create a state with 'palpbayes next DIR --init', "
                        "or give the --out folder of 'palpbayes map'")


def _from_map(d: Path, **overrides) -> SearchState:
    try:
        s = json.loads((d / "settings.json").read_text(encoding="utf-8"))
        lat = s["lattice"]
        x0, y0, step = float(lat["x0_m"]), float(lat["y0_m"]), float(lat["step_m"])
        fp = (x0, x0 + (int(lat["nx"]) - 1) * step, y0, y0 + (int(lat["ny"]) - 1) * step)
        a = float(s["contact_radius_m"])
        H = s.get("thickness_m")
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError,
            ValueError) as exc:
        raise DataFileError(d / "settings.json", f"is not a map's settings ({exc})") from None
    if H is None and overrides.get("thickness") is None:
        raise DataFileError(d / "settings.json", "has no block thickness",
                            "give --thickness M")
    points = _read_points(d / "points.csv")
    rec = {"footprint_m": fp, "contact_radius_m": a,
           "thickness_m": overrides.pop("thickness", None) or H}
    return _from_record(rec, points, d / "settings.json", **overrides)


def _read_points(path: Path) -> pd.DataFrame:
    v = _read_table(path)[PRESS_COLUMNS].apply(pd.to_numeric, errors="coerce")
    ok = np.isfinite(v.to_numpy(dtype=float)).all(axis=1) & (v["logE_sd"] > 0).to_numpy()
    return v[ok].reset_index(drop=True)  # points without a fit are not presses


def append_press(folder: str | os.PathLike, state: SearchState, x: float, y: float,
                 mean: float, sd: float, **extra) -> SearchState:
    """Add one press to the state and rewrite ``presses.csv`` whole; return the new state."""
    new = state.with_press(x, y, mean, sd, **extra)
    write_csv_atomic(new.presses, Path(folder) / PRESSES_FILE, index=False)
    return new
