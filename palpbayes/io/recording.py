"""One entry point for every recording palpbayes reads: the reader is chosen from the path.

=====================================  ============================================  ==========
path                                   reader                                        traces
=====================================  ============================================  ==========
rosbag2 folder, ``.mcap``, ``.db3``    :func:`palpbayes.io.rosbag.read_bag`          one
``.jpk-force``, ``.jpk-force-map``,    :func:`palpbayes.io.afm.read_afm`             one per
``.jpk-qi-*``, ``.ibw``, ``.h5``                                                     curve
a table whose header names the UR      :func:`palpbayes.io.rtde.read_rtde`           one
RTDE fields (``timestamp``,
``actual_TCP_force_*``, ``actual_q_*``
or ``actual_TCP_pose_2``)
anything else (CSV, text)              :func:`palpbayes.io.trace_csv.read_trace`     one
=====================================  ============================================  ==========

Each reader's module documents its units and sign conventions.  Instron exports keep their
own reader (:mod:`palpbayes.io.instron`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Literal

from ..contact import Tip
from ..errors import InputError
from ..trace import IndentationTrace
from .afm import is_afm_file, read_afm
from .bagfile import is_bag
from .rosbag import read_bag
from .rtde import default_z_source, is_rtde, read_rtde
from .trace_csv import read_trace

__all__ = ["AFM_META_KEYS", "recording_kind", "read_recording", "READER_OPTIONS", "KIND_NAMES"]

#: Reader options each kind of recording accepts (besides ``tip`` and trace metadata).
READER_OPTIONS = {
    "bag": {"force_topic", "pose_topic", "force_axis", "force_sign", "time_offset",
            "tool_offset", "dh", "max_gap", "check"},
    "afm": {"curves", "force_sign", "z_sign", "check", "segments", "meta_override"},
    "rtde": {"tool_offset", "dh", "z_source", "force_sign", "force_axis", "check",
             "delimiter"},
    "table": {"columns", "units", "force_sign", "z_sign", "check", "delimiter"},
}
#: The calibration an AFM file may lack, by Python name -> afmformats' metadata key (SI): the
#: ``meta_override`` of :func:`~palpbayes.io.afm.read_afm` (``--spring-constant``,
#: ``--sensitivity``, ``--sample-rate``).
AFM_META_KEYS = {"spring_constant": "spring constant", "sensitivity": "sensitivity",
                 "sample_rate": "rate approach"}
#: How messages name each kind.
KIND_NAMES = {"bag": "a ROS 2 bag", "afm": "an AFM file", "rtde": "a UR RTDE log",
              "table": "a trace CSV"}
#: An RTDE log's force component by the axis names the bags' option takes.
_AXES = {"x": 0, "y": 1, "z": 2}


def recording_kind(path: str | os.PathLike) -> Literal["bag", "afm", "rtde", "table"]:
    """``"bag"`` (rosbag2 folder or storage file; any folder goes to the bag reader, which says
    what a folder without ``metadata.yaml`` is missing), ``"afm"`` (a suffix afmformats reads
    and palpbayes does not), ``"rtde"`` (a table with the UR RTDE fields,
    :func:`~palpbayes.io.rtde.is_rtde`) or ``"table"`` (everything else: CSV and text
    tables)."""
    if is_bag(path) or Path(path).is_dir():
        return "bag"
    if is_afm_file(path):
        return "afm"
    if is_rtde(path):
        return "rtde"
    return "table"


def read_recording(path: str | os.PathLike, *, tip: Tip | None = None,
                   **options) -> list[IndentationTrace]:
    """Read a recording with the reader its path calls for; a list of traces (SI units).

    Parameters
    ----------
    path
        Trace CSV, UR RTDE log, ROS 2 bag (folder, ``.mcap``, ``.db3``) or AFM file.
    tip
        The indenter, stored in every trace.
    **options
        Reader options (:data:`READER_OPTIONS` of the kind) and trace metadata (``material``,
        ``thickness``, ``trace_id`` ...).

    Raises
    ------
    InputError
        An option that belongs to another kind of recording (the message names both).
    DataFileError, MissingExtraError
        From the reader.
    """
    kind = recording_kind(path)
    others = set().union(*READER_OPTIONS.values()) - READER_OPTIONS[kind]
    wrong = sorted(k for k in options if k in others and options[k] is not None)
    if wrong:
        owners = sorted(KIND_NAMES[k] for k, v in READER_OPTIONS.items() if wrong[0] in v)
        raise InputError(f"{Path(path)} is {KIND_NAMES[kind]}: option {wrong[0]!r} applies to "
                         f"{' and '.join(owners)} only")
    options = {k: v for k, v in options.items() if v is not None or k not in others}
    if kind == "bag":
        return [read_bag(path, tip=tip, **options)]
    if kind == "afm":
        return read_afm(path, tip=tip, **options)
    if kind == "rtde":
        if isinstance(options.get("force_axis"), str):
            options["force_axis"] = _AXES[options["force_axis"]]
        if options.get("z_source") is None:  # the joints when recorded, else the TCP pose
            options["z_source"] = default_z_source(path)
        return [read_rtde(path, tip=tip, **options)]
    return [read_trace(path, tip=tip, **options)]
