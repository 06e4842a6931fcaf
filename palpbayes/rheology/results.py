"""Viscoelastic fits of many traces into a results folder: one table a user opens in pandas.

``DIR/rheology.csv`` has one row per trace: the relaxation model, the fitted segments, every
parameter's posterior median and central 90 % interval in columns named
``<parameter>[_lo|_hi]_<unit>`` (moduli as E* [Pa], and as E with ``nu``), whether the model
check passed (``model_ok``), the short codes of what was flagged (``flag_codes``, ``;``
separated; :data:`palpbayes.flagcodes.RHEOLOGY_CODES`), ``flag_level`` and the flags in words
(``notes``), the number of block means and the fit time, the stretch of the retract cut as
an adhesive pull-off (``adhesion_cut_from_s``, ``adhesion_cut_to_s`` [s] on the trace's time
axis; NaN when nothing was cut: :mod:`~palpbayes.rheology.adhesion`),
the posterior ``engine`` (``grid``, or ``emcee`` with its ``rhat_max``, ``ess_min`` and
``converged``).
With ``nu`` and the specimen's thickness known, ``E_compression_pa`` (``_lo``, ``_hi``) is the
Young's modulus a compression test of that height at ``compression_speed_mm_min`` would report
(:func:`~palpbayes.rheology.compression.compression_moduli`: the ground truth's rule), to set
beside the Instron.  A trace that cannot be fitted (no contact, a missing segment) keeps its row
with the reason in ``error``.  The table is written atomically, once, after the last trace;
every fit is also stored as ``rheology/<trace_id>_<rheology>.nc`` (:mod:`~palpbayes.rheology.
store`: its draws and bands, what the report draws), and a previous run's table and stored fits
are removed first.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import InputError, PalpbayesError
from ..flagcodes import RHEOLOGY_CODES, listed_flag_columns
from ..io.atomic import write_csv_atomic
from ..outputs import RHEOLOGY_TABLE, rheology_fit_path
from ..trace import IndentationTrace
from .compression import PAPER_COMPRESSION_SPEED
from .cycle import DEFAULT_SEGMENTS
from .fit import RheologyFit, fit_rheology
from .peer import PEERS, peer_compatible
from .store import clear_rheology_outputs, save_rheology_fit

__all__ = ["RHEOLOGY_TABLE", "summary_row", "fit_traces", "UNIT_SUFFIXES"]

#: Column-name suffix of each parameter unit in ``rheology.csv`` (a parameter in Pa ends in
#: ``_pa``; other units fall back to their lower-case spelling).
UNIT_SUFFIXES = {"Pa": "pa", "s": "s", "m": "m", "N": "n", "-": "", "N·s/m": "n_s_per_m",
                 "N/m": "n_per_m"}


def _column(parameter: str, unit: str, part: str = "") -> str:
    name = parameter.replace("*", "_star")
    suffix = UNIT_SUFFIXES.get(unit, unit.lower())
    return "_".join(p for p in (name, part, suffix) if p)


def summary_row(trace: IndentationTrace, fit: RheologyFit,
                compression_speed: float = PAPER_COMPRESSION_SPEED) -> dict:
    """The table row of one fitted trace (module docstring).

    Parameters
    ----------
    trace
        The fitted recording (its id, source and thickness [m]).
    fit
        Its :func:`~palpbayes.rheology.fit_rheology` result.
    compression_speed
        [m/s] Cross-head speed of the compression test the modulus is read for.

    Returns
    -------
    dict
        Column name -> value.
    """
    row: dict = {"trace_id": trace.trace_id, "source": trace.source or "",
                 "rheology": fit.rheology, "segments": ",".join(fit.data.segments),
                 "t0_s": fit.t0, "nu": np.nan if fit.nu is None else fit.nu}
    for _, r in fit.table().iterrows():
        row[_column(r["parameter"], r["unit"])] = r["median"]
        row[_column(r["parameter"], r["unit"], "lo")] = r["lo"]
        row[_column(r["parameter"], r["unit"], "hi")] = r["hi"]
    if fit.nu is not None and trace.thickness is not None:
        med, lo, hi = fit.compression_modulus(trace.thickness, compression_speed)
        row.update(E_compression_pa=med, E_compression_lo_pa=lo, E_compression_hi_pa=hi,
                   compression_speed_mm_min=compression_speed * 6e4,
                   compression_height_m=trace.thickness)
    row["engine"] = "grid" if fit.sampler is None else "emcee"
    if fit.sampler is not None:
        row.update(rhat_max=max(fit.sampler.rhat.values()),
                   ess_min=min(fit.sampler.ess.values()), converged=fit.sampler.converged)
    row.update(model_ok=fit.model_ok, **listed_flag_columns(list(fit.flags), RHEOLOGY_CODES),
               n_points=fit.data.n_points,
               block=fit.data.block, seconds=round(fit.seconds, 3), error="")
    cut = fit.adhesion_cut
    row.update(adhesion_cut_from_s=np.nan if cut is None else cut.t_start,
               adhesion_cut_to_s=np.nan if cut is None else cut.t_end)
    return row


def _error_row(trace_id: str, source: str, rheology: str, exc: Exception) -> dict:
    what = str(exc) if isinstance(exc, PalpbayesError) else (
        f"the fit failed numerically ({type(exc).__name__}: {exc}); report this record")
    return {"trace_id": trace_id, "source": source, "rheology": rheology, "model_ok": False,
            "error": what}


def fit_traces(traces: Iterable[IndentationTrace | tuple[str, str, Callable[[], IndentationTrace]]],
               rheology: str | Sequence[str], out: str | os.PathLike, *,
               segments=DEFAULT_SEGMENTS, t0: float = 1.0, nu: float | None = None,
               seed: int = 0, compression_speed: float = PAPER_COMPRESSION_SPEED,
               drag: bool | None = None, baseline: str = "constant", engine: str = "grid",
               adhesion: str = "keep", peer: str | None = None,
               progress: bool | None = None,
               total: int | None = None,
               on_fit: Callable[[IndentationTrace, RheologyFit], None] | None = None
               ) -> pd.DataFrame:
    """Fit every trace with :func:`~palpbayes.rheology.fit_rheology` and write
    ``out/rheology.csv`` (module docstring); returns the table.

    ``rheology`` is one model or several (``("power-law", "sls")``): with several, every
    trace gets a row per model and :func:`~palpbayes.rheology.choice.compare_rheology`'s columns
    (``elpd_loo``, ``elpd_loo_se``, ``p_loo``, ``pareto_k_max``, ``elpd_diff``,
    ``elpd_diff_se``, ``preferred``).  ``traces`` holds traces, or (trace_id, source, load)
    with ``load()`` reading the trace (a manifest's rows: a file that cannot be read keeps its
    row too).  ``seed`` + the trace's position seeds its draws (the same table every run);
    ``nu`` gives way to the trace's own ``metadata["nu"]`` (a manifest's ``nu`` column).
    Errors of one trace and model (:class:`~palpbayes.errors.PalpbayesError`, or a linear
    algebra failure) go into that row's ``error``; the other models of the trace keep theirs.
    ``compression_speed`` [m/s] is the compression test's (module docstring).

    Parameters
    ----------
    traces
        Traces, or (trace_id, source, load) triples.
    rheology
        ``"power-law"``, ``"sls"`` or several of them.
    out
        Results folder (created).
    segments, t0, nu, seed, compression_speed
        As above; ``segments`` as :func:`~palpbayes.rheology.fit_rheology` takes them.
    drag, baseline, engine, adhesion
        A viscous drag term (None: when the retract is fitted), the baseline model
        (``"constant"`` or ``"linear"``), the posterior engine (``"grid"`` or ``"emcee"``) and
        what to do with an adhesive pull-off on the retract (``"keep"`` or ``"cut"``), as
        :func:`~palpbayes.rheology.fit_rheology` takes them.
    peer
        ``"pyfmrheo"``: read every trace as PyFMRheo's notebook does
        (:func:`~palpbayes.rheology.peer.pyfmrheo_compatible`: straight ramps, its drag fixed;
        its segments, drag and t0 replace the ones above), for comparing with the peer's
        numbers; each row's ``peer_compatible`` says so.  None (default): the recording.
    progress, total
        A progress bar (None: only on a terminal) and its length.
    on_fit
        Called with (trace, fit) for every successful fit, after its row (e.g.
        :meth:`palpbayes.rheology.campaign.SpeedPools.add`: pooling without keeping the fits).

    Returns
    -------
    pandas.DataFrame
        The table written to ``out/rheology.csv``.
    """
    from ..progress import progress_bar
    from .choice import compare_rheology

    models = (rheology,) if isinstance(rheology, str) else tuple(rheology)
    if peer is not None and peer not in PEERS:
        raise InputError(f"peer {peer!r}: palpbayes can read a trace as {', '.join(PEERS)} does")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    clear_rheology_outputs(out)  # the table and stored fits of a previous run (--force)
    rows = []
    bar = progress_bar(total, progress, desc=f"{'/'.join(models)} fits")
    try:
        for i, item in enumerate(traces):
            if isinstance(item, IndentationTrace):
                trace_id, source, load = item.trace_id, item.source or "", (lambda t=item: t)
            else:
                trace_id, source, load = item
            try:
                trace = load()
            except PalpbayesError as exc:
                rows.extend(_error_row(trace_id, source, m, exc) for m in models)
                bar.update(1)
                continue
            trace_nu = (trace.metadata or {}).get("nu", nu)
            fits, new = {}, []
            options = {"segments": segments, "t0": t0, "drag": drag}
            if peer is not None:
                try:
                    trace, options = peer_compatible(trace, peer)
                except PalpbayesError as exc:
                    rows.extend(_error_row(trace_id, source, m, exc) for m in models)
                    bar.update(1)
                    continue
            for m in models:  # one model failing keeps the others' rows
                try:
                    fits[m] = fit_rheology(trace, m, nu=trace_nu, baseline=baseline,
                                           engine=engine, adhesion=adhesion, rng=seed + i,
                                           **options)
                    row = summary_row(trace, fits[m], compression_speed)
                    if peer is not None:
                        row["peer_compatible"] = peer
                    save_rheology_fit(fits[m], rheology_fit_path(out, trace.trace_id, m),
                                      trace=trace)  # the report's draws and bands
                    new.append(row)
                except (PalpbayesError, np.linalg.LinAlgError) as exc:
                    fits.pop(m, None)
                    new.append(_error_row(trace_id, source, m, exc))
            if len(fits) > 1:
                choice = compare_rheology(fits).set_index("rheology")
                for r in new:
                    if r["rheology"] in choice.index:
                        r.update(choice.loc[r["rheology"]].to_dict())
            rows.extend(new)
            if on_fit is not None:
                for fit in fits.values():
                    on_fit(trace, fit)
            bar.update(1)
    finally:
        bar.close()
    table = pd.DataFrame(rows)
    write_csv_atomic(table, out / RHEOLOGY_TABLE, index=False)
    return table
