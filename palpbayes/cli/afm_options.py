"""The calibration an AFM file may lack, as options: ``--spring-constant``, ``--sensitivity``
and ``--sample-rate`` (AFM Workshop zips record none of them), defined once for ``fit``,
``replay`` (through :func:`palpbayes.cli.options.add_trace_options`) and ``map``, and read
back as afmformats' ``meta_override`` (SI units)."""

from __future__ import annotations

import argparse
import math

from ..errors import InputError
from ..io.recording import AFM_META_KEYS

__all__ = ["AFM_META_OPTIONS", "add_afm_meta_options", "afm_meta_from_args"]

#: Option -> (argparse attribute, afmformats metadata key) of the calibration an AFM file may
#: lack (AFM Workshop: no spring constant, sensitivity nor time column).
AFM_META_OPTIONS = {"--" + attr.replace("_", "-"): (attr, key)
                    for attr, key in AFM_META_KEYS.items()}


def add_afm_meta_options(g) -> None:
    """``--spring-constant``, ``--sensitivity`` and ``--sample-rate`` on the argument group
    ``g`` (read back by :func:`afm_meta_from_args`; ``fit``, ``replay``, ``map``)."""
    g.add_argument("--spring-constant", type=float, metavar="N_PER_M",
                   help="cantilever spring constant [N/m], for AFM files that lack it (AFM "
                        "Workshop)")
    g.add_argument("--sensitivity", type=float, metavar="M_PER_V",
                   help="deflection sensitivity [m/V], for AFM files that lack it (AFM "
                        "Workshop)")
    g.add_argument("--sample-rate", type=float, metavar="HZ",
                   help="sample rate of the approach [Hz], for AFM files without a time "
                        "column (AFM Workshop; an elastic fit does not depend on it)")


def afm_meta_from_args(args: argparse.Namespace) -> dict:
    """The afmformats metadata the AFM file lacks, from :func:`add_afm_meta_options`'s options
    (SI units; only those given, each checked positive): ``read_afm``'s ``meta_override``."""
    meta = {}
    for option, (attr, key) in AFM_META_OPTIONS.items():
        value = getattr(args, attr, None)
        if value is None:
            continue
        if not (math.isfinite(value) and value > 0):
            raise InputError(f"{option} {value!r} must be a positive number")
        meta[key] = float(value)
    return meta
