"""Read Universal Robots RTDE recordings into a tip trace (docs/design.md §2, §5).

:func:`read_rtde` reads the CSV written by UR's RTDE client library (``examples/record.py``,
space-separated by default) or by ur_rtde's ``RTDEReceiveInterface.startFileRecording``
(comma-separated).  Vector fields are expanded to one column per component, ``<field>_<i>``:

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

Joint-angle traces (``time_s, q0_rad … q5_rad, force_n``) are read by
:mod:`palpbayes.io.joint_trace`.

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
from pathlib import Path
from typing import Literal

import numpy as np
import pandas as pd

from ..contact import Tip
from ..errors import DataFileError, InputError
from ..kinematics import UR3E, DHParameters, as_offset, tip_z
from ..trace import IndentationTrace
from .tabular import (
    WHITESPACE,
    _header_line,
    auto_force_sign,
    check_force_sign,
    check_plausible,
    numeric_column,
    read_table,
    sniff_delimiter,
    split_trace_metadata,
    validate_force_sign,
)

__all__ = [
    "read_rtde",
    "is_rtde",
    "default_z_source",
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


def _header_names(path: Path) -> set[str]:
    header, sep = _header_line(path), sniff_delimiter(path)
    return {n.strip() for n in (header.split() if sep == WHITESPACE else header.split(sep))}


def default_z_source(path: str | os.PathLike) -> Literal["q", "tcp"]:
    """``"q"`` when the log records the joints (the paper's method), else ``"tcp"``."""
    return "q" if set(RTDE_Q_COLUMNS) <= _header_names(Path(path)) else "tcp"


def is_rtde(path: str | os.PathLike) -> bool:
    """True when ``path`` is a text table whose header names the RTDE ``timestamp``, a
    component of ``actual_TCP_force`` and the joints or the TCP pose: what
    :func:`palpbayes.io.recording.recording_kind` reads with :func:`read_rtde`."""
    p = Path(path)
    if not p.is_file():
        return False
    try:
        names = _header_names(p)
    except (OSError, UnicodeDecodeError):
        return False
    return (RTDE_TIME_COLUMN in names and bool(names & set(RTDE_TCP_FORCE_COLUMNS))
            and (set(RTDE_Q_COLUMNS) <= names or RTDE_TCP_POSE_COLUMNS[2] in names))


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


# ---------------------------------------------------------------------------------- RTDE
# Many parameters: a UR RTDE log's columns, axis, sign, tool geometry and kinematics: each a reader
# option of `palpbayes fit`.
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
    sign = validate_force_sign(force_sign, allow_auto=True)
    if force_axis not in (0, 1, 2):
        raise InputError(f"force_axis must be 0, 1 or 2 (Fx, Fy, Fz), got {force_axis!r}")
    offset = as_offset(tool_offset)

    df, source = read_table(path, delimiter)
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
        sign = auto_force_sign(z, raw_force)

    kwargs, free = split_trace_metadata(metadata, {
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
