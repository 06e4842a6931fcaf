"""How much indentation did each trace need?  Every recorded trace of a results folder
replayed through the online estimator (:mod:`palpbayes.online`) with a precision target.

:func:`indentation_study` gives one row per trace with a readable file (material, tip and
:func:`palpbayes.online.needed_indentation`'s columns: where a ±:data:`REPLAY_TARGET` rule
stopped, the depth and force then and at the end of the recording); ``palpbayes compare``
writes it as ``indentation.csv`` and the report reads that table.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..bayes.noisemodels import exact_noise
from ..errors import PalpbayesError
from ..io.manifest import load_trace
from ..online import StoppingRule, needed_indentation
from .fitjob import FitOptions, trace_model

__all__ = ["REPLAY_TARGET", "REPLAY_CHUNK", "indentation_study", "online_noise"]

#: Relative half-width of the 90 % interval of E at which the replay stops (±2 %).
REPLAY_TARGET = 0.02
#: Samples per online update of the replay.
REPLAY_CHUNK = 100


def online_noise(options: dict) -> str:
    """The campaign's noise model when the online estimator has it (gaussian, ar1), else
    gaussian (Student-t noise is emcee's alone)."""
    return exact_noise(str(options.get("noise", "gaussian")))


def indentation_study(traces: pd.DataFrame | None, settings: dict,
                      target: float = REPLAY_TARGET) -> pd.DataFrame:
    """Per trace with a readable file: where a ±``target`` rule would have stopped.

    Parameters
    ----------
    traces
        ``traces.csv`` of a results folder (the manifest's rows, ``file`` among them).
    settings
        ``settings.json`` as a dict: the fit options (``options_fields``: nu, layer, bonding,
        noise) and the trace reader's options (``read_options``).
    target
        Relative half-width of the 90 % interval of E (statistical) to reach.

    Returns
    -------
    pandas.DataFrame
        ``material``, ``tip`` and :func:`palpbayes.online.needed_indentation`'s columns; empty
        when no trace file can be read (a results folder moved without its traces).
    """
    if traces is None or "file" not in traces:
        return pd.DataFrame()
    opts = dict(settings.get("options_fields") or {})
    rows, models, meta = [], [], []
    for _, row in traces.iterrows():
        try:  # the model the fit used (tip, the row's or the run's nu, layer)
            trace = load_trace(row, **settings.get("read_options", {}))
            model = trace_model(trace, FitOptions(
                nu=opts.get("nu"), layer=opts.get("layer", "off"),
                bonding=opts.get("bonding", "unknown")), depth=np.nan)
            if not model.is_concrete:  # the online estimator takes one shape function
                model = (model.variant(base="bonded") if model.thickness is not None
                         else model.half_space())
        except (PalpbayesError, OSError):
            continue
        rows.append(trace)
        models.append(model)
        meta.append({"material": str(row.get("material", "")), "tip": trace.tip.kind})
    if not rows:
        return pd.DataFrame()
    study = needed_indentation(rows, models, StoppingRule(target=target),
                               chunk=REPLAY_CHUNK, noise=online_noise(opts))
    return pd.concat([pd.DataFrame(meta), study], axis=1)
