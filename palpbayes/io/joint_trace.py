"""Read joint-angle traces: time, the six joint angles and force, z by forward kinematics.

The canonical trace CSV with ``time_s, q0_rad … q5_rad, force_n`` columns instead of ``z_m``
(:func:`read_joint_trace`), or such a table already parsed (:func:`trace_from_joint_frame`, also
used by :func:`palpbayes.io.trace_csv.read_trace` when a file has joint columns and no z).  The
tip height is that of :func:`palpbayes.kinematics.tip_z` for the arm's DH table and the sensor +
tip offset (docs/design.md §2, §5).  UR RTDE recordings are read by :mod:`palpbayes.io.rtde`.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from ..contact import Tip
from ..errors import DataFileError, InputError
from ..kinematics import UR3E, DHParameters, as_offset, tip_z
from ..trace import IndentationTrace
from .tabular import (
    check_plausible,
    numeric_column,
    read_table,
    split_trace_metadata,
    validate_force_sign,
)
from .units import FORCE_UNITS, TIME_UNITS, force_factor, time_factor

__all__ = ["read_joint_trace", "trace_from_joint_frame"]

_ANGLE_UNITS = {"rad": 1.0, "deg": np.pi / 180.0}


def _find(df: pd.DataFrame, stem: str, table: dict[str, float], unit: str | None,
          default_unit: str, source: str, fix: str) -> tuple[str, str]:
    """Column ``<stem>_<unit>`` or ``<stem>`` (case-insensitive) and its unit."""
    lower = {c.lower(): c for c in df.columns}
    for u in table:
        name = f"{stem}_{u}".lower()
        if name in lower:
            return lower[name], unit or u
    if stem.lower() in lower:
        return lower[stem.lower()], unit or default_unit
    have = ", ".join(map(str, df.columns)) or "no columns"
    raise DataFileError(source, f"missing column '{stem}_{default_unit.lower()}'; the file has "
                        f"{have}", fix)


def trace_from_joint_frame(
    df: pd.DataFrame,
    source: str,
    dh: DHParameters = UR3E,
    tool_offset: float | tuple[float, float, float] = 0.0,
    *,
    units: dict[str, str] | None = None,
    force_sign: float = 1.0,
    check: bool = True,
    **metadata,
) -> IndentationTrace:
    """Build a trace from a table of time, joint angles and force (z by forward kinematics).

    Parameters
    ----------
    df
        Table with columns ``time_s``, ``q0_rad`` … ``q5_rad`` and ``force_n``.  Other units
        are recognised from the suffix (``time_ms``, ``q0_deg``, ``force_mn``) or given in
        ``units``; names match case-insensitively.
    source
        File name (or description) used in error messages.
    dh
        DH table of the arm (default :data:`~palpbayes.kinematics.UR3E`).
    tool_offset
        [m] Sensor + tip length along the flange z axis, or a length-3 vector in the flange
        frame.
    units
        Unit overrides by quantity: ``time`` (s, ms, us, min), ``q`` (rad, deg), ``force``
        (N, mN, uN/µN, nN, pN, kN).
    force_sign
        +1 or -1, multiplies the force column (+1: the file already has compression positive).
    check
        Reject implausible traces (see :func:`palpbayes.io.tabular.check_plausible`).
    **metadata
        Trace fields (``tip``, ``trace_id``, ``specimen``, ``material``, ``thickness``,
        ``repetition``, ``rest_time``); anything else goes into ``trace.metadata``.

    Returns
    -------
    IndentationTrace
        time [s] as in the file, z [m] of the tip in the base frame, force [N].

    Raises
    ------
    DataFileError
        Missing column, non-numeric or NaN cell (with its data row), fewer than 3 rows, time
        not strictly increasing, implausible sign or units.
    InputError
        Invalid options (unknown unit or quantity, bad sign or offset).
    """
    units = dict(units or {})
    unknown = set(units) - {"time", "q", "force"}
    if unknown:
        raise InputError(f"unknown quantity {sorted(unknown)} in units; use time, q and force")
    sign = validate_force_sign(force_sign, allow_auto=False)
    offset = as_offset(tool_offset)
    if df.shape[0] == 0:
        raise DataFileError(source, "no data rows (header only or empty)",
                            "check that the recording was saved")
    df = df.rename(columns=lambda c: str(c).strip())
    fix_q = "a joint trace needs columns time_s, q0_rad … q5_rad, force_n"
    time_col, time_unit = _find(df, "time", TIME_UNITS, units.get("time"), "s", source, fix_q)
    force_col, force_unit = _find(df, "force", FORCE_UNITS, units.get("force"), "N", source,
                                  fix_q)
    q_cols = [_find(df, f"q{i}", _ANGLE_UNITS, units.get("q"), "rad", source, fix_q)
              for i in range(6)]
    try:
        t_factor = time_factor(time_unit)
        f_factor = force_factor(force_unit)
        q_factors = []
        for col, u in q_cols:
            if u.lower() not in _ANGLE_UNITS:
                raise InputError(f"column {col!r}: unknown angle unit {u!r}; use rad or deg")
            q_factors.append(_ANGLE_UNITS[u.lower()])
    except InputError as exc:
        raise DataFileError(source, str(exc)) from None
    q = np.column_stack([numeric_column(df, col, source) * fac
                         for (col, _), fac in zip(q_cols, q_factors, strict=True)])
    t = numeric_column(df, time_col, source) * t_factor
    force = sign * f_factor * numeric_column(df, force_col, source)
    z = tip_z(q, dh, offset)

    kwargs, free = split_trace_metadata(metadata, {
        "reader": "joint_trace",
        "robot": dh.name,
        "z_source": "q",
        "tool_offset_m": offset.tolist(),
    })
    trace = IndentationTrace(time=t, z=z, force=force, source=source, metadata=free, **kwargs)
    if check:
        check_plausible(trace)
    return trace


def read_joint_trace(
    path: str | os.PathLike,
    *,
    dh: DHParameters = UR3E,
    tool_offset: float | tuple[float, float, float] = 0.0,
    units: dict[str, str] | None = None,
    force_sign: float = 1.0,
    tip: Tip | None = None,
    check: bool = True,
    delimiter: str | None = ",",
    **metadata,
) -> IndentationTrace:
    """Read a canonical joint-angle trace CSV (``time_s, q0_rad … q5_rad, force_n``).

    Parameters
    ----------
    path
        CSV file; lines starting with ``#`` are comments.
    dh, tool_offset, units, force_sign, check
        See :func:`trace_from_joint_frame`.
    tip
        The indenter, stored in the trace.
    delimiter
        Column separator (default comma); None sniffs it
        (:func:`~palpbayes.io.tabular.sniff_delimiter`).
    **metadata
        Stored on the trace; ``trace_id`` defaults to the file name without extension.

    Returns
    -------
    IndentationTrace
        z [m] of the tip from forward kinematics, force [N], time [s].

    Raises
    ------
    DataFileError
        See :func:`trace_from_joint_frame`; also a missing or unreadable file.
    """
    df, source = read_table(path, delimiter)
    metadata.setdefault("trace_id", Path(path).stem)
    return trace_from_joint_frame(df, source, dh, tool_offset, units=units,
                                  force_sign=force_sign, check=check, tip=tip, **metadata)
