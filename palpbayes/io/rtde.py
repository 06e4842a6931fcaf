"""Read Universal Robots RTDE recordings and joint-angle traces (docs/design.md §2, §5).

Two inputs end up here:

* **RTDE recordings** (:func:`read_rtde`): the CSV written by UR's RTDE client library
  (``examples/record.py``, space-separated by default) or by ur_rtde's
  ``RTDEReceiveInterface.startFileRecording`` (comma-separated).  Vector fields are expanded to
  one column per component, ``<field>_<i>``:

  =========================  ====================================================  ============
  column                     meaning                                               unit
  =========================  ====================================================  ============
  ``timestamp``              controller time                                       [s]
  ``actual_q_0..5``          joint positions                                       [rad]
  ``actual_TCP_pose_0..5``   TCP position x, y, z and orientation (axis-angle)     [m], [rad]
  ``actual_TCP_force_0..5``  wrench at the TCP in the base frame Fx..Fz, Tx..Tz    [N], [N m]
  =========================  ====================================================  ============

  The tip height z comes either from forward kinematics of ``actual_q`` plus the sensor and
  tip length (``z_source="q"``, the paper's method) or from ``actual_TCP_pose_2``
  (``z_source="tcp"``, which already contains the TCP offset configured on the robot).

* **Joint traces** (:func:`read_joint_trace`, :func:`trace_from_joint_frame`): the canonical
  trace CSV with ``time_s, q0_rad … q5_rad, force_n`` columns instead of ``z_m``.

Force sign
----------
UR documents ``actual_TCP_force`` as the generalised external force at the TCP, expressed in the
base frame.  Whether pressing down on a specimen shows up as +Fz or -Fz depends on the
controller generation, the sensor (built-in e-Series sensor, CB3 current-based estimate, or an
add-on sensor feeding the field) and its zeroing, and reports disagree.  The compressive force is
therefore ``force_sign × actual_TCP_force_{force_axis}``; the default ``force_sign="auto"``
chooses the sign that makes the force grow as the tip goes down (the physics of pressing, not a
guess about the controller), and the chosen sign is stored in ``trace.metadata["force_sign"]``.
Pass ``force_sign=+1`` or ``-1`` to fix it; with ``check=True`` (default) a trace whose force is
then negative at the deepest indentation is rejected with the advice to flip it.
"""

from __future__ import annotations

import os
from dataclasses import fields
from pathlib import Path
from typing import Literal

import numpy as np
import pandas as pd

from ..contact import Tip
from ..errors import DataFileError, InputError
from ..kinematics import UR3E, DHParameters, _as_offset, tip_z
from ..trace import IndentationTrace
from .tabular import check_force_sign, check_plausible, numeric_column, sniff_delimiter
from .units import FORCE_UNITS, TIME_UNITS, force_factor, time_factor

__all__ = [
    "read_rtde",
    "read_joint_trace",
    "trace_from_joint_frame",
    "rotvec_to_matrix",
    "RTDE_TIME_COLUMN",
    "RTDE_Q_COLUMNS",
    "RTDE_TCP_POSE_COLUMNS",
    "RTDE_TCP_FORCE_COLUMNS",
]

#: [s] Controller timestamp column.
RTDE_TIME_COLUMN = "timestamp"
#: [rad] Joint positions (RTDE output field ``actual_q``).
RTDE_Q_COLUMNS = tuple(f"actual_q_{i}" for i in range(6))
#: [m, m, m, rad, rad, rad] TCP pose, axis-angle orientation (field ``actual_TCP_pose``).
RTDE_TCP_POSE_COLUMNS = tuple(f"actual_TCP_pose_{i}" for i in range(6))
#: [N, N, N, N m, N m, N m] TCP wrench in the base frame (field ``actual_TCP_force``).
RTDE_TCP_FORCE_COLUMNS = tuple(f"actual_TCP_force_{i}" for i in range(6))

_ANGLE_UNITS = {"rad": 1.0, "deg": np.pi / 180.0}
_TRACE_FIELDS = {f.name for f in fields(IndentationTrace)} - {"time", "z", "force", "source"}


# ---------------------------------------------------------------------------------- helpers
def rotvec_to_matrix(rotvec: np.ndarray) -> np.ndarray:
    """Rotation matrices from axis-angle vectors (UR's rx, ry, rz), vectorised.

    Parameters
    ----------
    rotvec
        [rad] Shape (N, 3): rotation axis times angle.

    Returns
    -------
    ndarray
        Shape (N, 3, 3), by Rodrigues' formula R = I + sin(θ)·K + (1 − cos θ)·K².
    """
    r = np.asarray(rotvec, dtype=float).reshape(-1, 3)
    theta = np.linalg.norm(r, axis=1)
    safe = np.where(theta > 0.0, theta, 1.0)
    k = r / safe[:, None]
    K = np.zeros((r.shape[0], 3, 3))
    K[:, 0, 1], K[:, 0, 2] = -k[:, 2], k[:, 1]
    K[:, 1, 0], K[:, 1, 2] = k[:, 2], -k[:, 0]
    K[:, 2, 0], K[:, 2, 1] = -k[:, 1], k[:, 0]
    s = np.sin(theta)[:, None, None]
    c = (1.0 - np.cos(theta))[:, None, None]
    return np.eye(3) + s * K + c * (K @ K)


def _read_table(path: str | os.PathLike, delimiter: str | None) -> tuple[pd.DataFrame, str]:
    """Read a delimited text file into a DataFrame; sniff the separator when None."""
    path = Path(path)
    source = str(path)
    if not path.is_file():
        raise DataFileError(source, "file not found", "check the path")
    if path.stat().st_size == 0:
        raise DataFileError(source, "file is empty", "check that the recording was saved")
    try:
        sep = delimiter if delimiter is not None else sniff_delimiter(path)
        df = pd.read_csv(path, sep=sep, comment="#", skipinitialspace=True,
                         engine="c", encoding="utf-8")
    except UnicodeDecodeError:
        raise DataFileError(
            source, "not a text file (a binary RTDE recording?)",
            "record without --binary, or convert the file to CSV first",
        ) from None
    except pd.errors.EmptyDataError:
        raise DataFileError(source, "file is empty", "check that the recording was saved") from None
    except pd.errors.ParserError as exc:
        raise DataFileError(
            source, f"not a readable CSV ({exc})".replace("\n", " "),
            "check that every row has the same number of columns",
        ) from None
    df.columns = [str(c).strip() for c in df.columns]
    return df, source


def _require(df: pd.DataFrame, columns: list[str], source: str, fix: str) -> None:
    missing = [c for c in columns if c not in df.columns]
    if missing:
        shown = ", ".join(missing)
        have = ", ".join(map(str, df.columns[:12])) + (" …" if df.shape[1] > 12 else "")
        raise DataFileError(
            source,
            f"missing column{'s' if len(missing) > 1 else ''} {shown}; the file has {have}",
            fix,
        )


def _auto_sign(z: np.ndarray, raw_force: np.ndarray) -> float:
    """+1 or -1: the sign making the force larger at the deepest point than at the start."""
    end = int(np.argmin(z)) + 1
    f = raw_force[:end] if end >= 3 else raw_force
    head = np.median(f[: max(1, f.size // 10)])
    tail = np.median(f[int(0.9 * f.size):])
    return 1.0 if tail >= head else -1.0


def _split_metadata(metadata: dict, extra: dict) -> tuple[dict, dict]:
    """Split keyword metadata into IndentationTrace fields and the free-form dict."""
    reserved = {"time", "z", "force", "source"} & set(metadata)
    if reserved:
        raise InputError(f"metadata may not set {sorted(reserved)}; they come from the file")
    kwargs = {k: v for k, v in metadata.items() if k in _TRACE_FIELDS and k != "metadata"}
    free = dict(metadata.get("metadata") or {})
    free.update({k: v for k, v in metadata.items() if k not in _TRACE_FIELDS})
    free.update(extra)
    return kwargs, free


def _validate_sign(force_sign: float | str, allow_auto: bool) -> float | str:
    if allow_auto and isinstance(force_sign, str):
        if force_sign.lower() == "auto":
            return "auto"
        raise InputError(f"force_sign must be +1, -1 or 'auto', got {force_sign!r}")
    if force_sign not in (1, -1):
        allowed = "+1, -1 or 'auto'" if allow_auto else "+1 or -1"
        raise InputError(f"force_sign must be {allowed}, got {force_sign!r}")
    return float(force_sign)


# ---------------------------------------------------------------------------------- RTDE
def read_rtde(
    path: str | os.PathLike,
    *,
    tool_offset: float | tuple[float, float, float] = 0.0,
    dh: DHParameters = UR3E,
    z_source: Literal["q", "tcp"] = "q",
    force_sign: float | Literal["auto"] = "auto",
    force_axis: int = 2,
    tip: Tip | None = None,
    trace_id: str | None = None,
    check: bool = True,
    delimiter: str | None = None,
    **metadata,
) -> IndentationTrace:
    """Read a UR RTDE recording into an :class:`~palpbayes.trace.IndentationTrace` (SI units).

    Parameters
    ----------
    path
        CSV written by the RTDE client library's ``record.py`` (space-separated) or by
        ur_rtde's ``startFileRecording`` (comma-separated); semicolons also work.
    tool_offset
        [m] With ``z_source="q"``: tip position in the flange frame, a scalar being the length
        of force sensor + tip along the flange z axis (or a length-3 vector).  With
        ``z_source="tcp"``: an *additional* offset in the TCP frame, for a tip not included in
        the TCP configured on the robot (default 0).
    dh
        DH table of the arm (default :data:`~palpbayes.kinematics.UR3E`).
    z_source
        ``"q"``: z from forward kinematics of ``actual_q_0..5`` (the paper's method).
        ``"tcp"``: z from ``actual_TCP_pose_2`` (and the orientation ``_3..5`` if an offset is
        given).
    force_sign
        Multiplier (+1 or -1) turning ``actual_TCP_force_{force_axis}`` into the compressive
        force, positive when pressing; ``"auto"`` picks the sign that makes the force larger
        at the deepest point than at the start.  Default ``"auto"`` (see the module notes: the
        sign UR reports when pressing down differs between setups — check your first trace;
        the sign chosen is in ``trace.metadata["force_sign"]``).
    force_axis
        Component of ``actual_TCP_force`` (base frame) along the indentation: 0, 1 or 2
        (default 2, vertical indentation).
    tip
        The indenter, stored in the trace.
    trace_id
        Identifier; default the file name without extension.
    check
        Reject implausible traces (force negative at the deepest point, z span or |force| out
        of range; see :func:`palpbayes.io.tabular.check_plausible`).
    delimiter
        Column separator; None (default) sniffs it from the header line.
    **metadata
        ``specimen``, ``material``, ``thickness`` [m], ``repetition``, ``rest_time`` [s] go to
        the trace; anything else into ``trace.metadata``.

    Returns
    -------
    IndentationTrace
        time [s] relative to the first timestamp, z [m] up in the base frame, force [N].
        ``metadata`` records the robot, z source, tool offset, force column and sign and the
        first controller timestamp ``t0_s``.

    Raises
    ------
    DataFileError
        Missing file, missing columns (the message names them and the RTDE field to record),
        non-numeric or NaN cells (with the data row), fewer than 3 rows, time not strictly
        increasing, implausible sign or units.
    InputError
        Invalid options.
    """
    if z_source not in ("q", "tcp"):
        raise InputError(f"z_source must be 'q' or 'tcp', got {z_source!r}")
    sign = _validate_sign(force_sign, allow_auto=True)
    if force_axis not in (0, 1, 2):
        raise InputError(f"force_axis must be 0, 1 or 2 (Fx, Fy, Fz), got {force_axis!r}")
    offset = _as_offset(tool_offset)

    df, source = _read_table(path, delimiter)
    force_col = RTDE_TCP_FORCE_COLUMNS[force_axis]
    _require(df, [RTDE_TIME_COLUMN], source,
             "record the RTDE output 'timestamp' (first field of the recipe)")
    _require(df, [force_col], source,
             "record the RTDE output field 'actual_TCP_force' (VECTOR6D): add it to the "
             "recipe of record.py or to the variables of ur_rtde's startFileRecording")
    if z_source == "q":
        _require(df, list(RTDE_Q_COLUMNS), source,
                 "record the RTDE output field 'actual_q' (VECTOR6D), or read z from the TCP "
                 "pose with z_source='tcp'")
    else:
        needed = [RTDE_TCP_POSE_COLUMNS[2]]
        if np.any(offset != 0.0):
            needed += list(RTDE_TCP_POSE_COLUMNS[3:])
        _require(df, needed, source,
                 "record the RTDE output field 'actual_TCP_pose' (VECTOR6D), or compute z "
                 "from the joints with z_source='q'")
    if df.shape[0] < 3:
        raise DataFileError(source, f"only {df.shape[0]} data row(s); a trace needs at least 3",
                            "check that the file holds the whole recording")

    t = numeric_column(df, RTDE_TIME_COLUMN, source)
    raw_force = numeric_column(df, force_col, source)
    if z_source == "q":
        q = np.column_stack([numeric_column(df, c, source) for c in RTDE_Q_COLUMNS])
        z = tip_z(q, dh, offset)
    else:
        z = numeric_column(df, RTDE_TCP_POSE_COLUMNS[2], source)
        if np.any(offset != 0.0):
            rv = np.column_stack([numeric_column(df, c, source)
                                  for c in RTDE_TCP_POSE_COLUMNS[3:]])
            z = z + rotvec_to_matrix(rv)[:, 2, :] @ offset
    if sign == "auto":
        sign = _auto_sign(z, raw_force)

    kwargs, free = _split_metadata(metadata, {
        "reader": "rtde",
        "robot": dh.name,
        "z_source": z_source,
        "tool_offset_m": offset.tolist(),
        "force_column": force_col,
        "force_sign": sign,
        "t0_s": float(t[0]),
    })
    trace = IndentationTrace(
        time=t - t[0],
        z=z,
        force=sign * raw_force,
        tip=tip,
        trace_id=trace_id if trace_id is not None else Path(path).stem,
        source=source,
        metadata=free,
        **kwargs,
    )
    if check:
        check_force_sign(source, trace,
                          f"flip the sign: pass force_sign={-sign:+g} (or force_sign='auto')")
        check_plausible(trace)
    return trace


# ---------------------------------------------------------------------------------- joints
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
    sign = _validate_sign(force_sign, allow_auto=False)
    offset = _as_offset(tool_offset)
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

    kwargs, free = _split_metadata(metadata, {
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
    df, source = _read_table(path, delimiter)
    metadata.setdefault("trace_id", Path(path).stem)
    return trace_from_joint_frame(df, source, dh, tool_offset, units=units,
                                  force_sign=force_sign, check=check, tip=tip, **metadata)
