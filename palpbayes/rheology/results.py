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

import math
import os
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ..arguments import check_seed
from ..contact import check_nu
from ..errors import InputError, PalpbayesError
from ..flagcodes import RHEOLOGY_CODES, listed_flag_columns
from ..io.atomic import write_csv_atomic
from ..outputs import RHEOLOGY_TABLE, rheology_fit_path
from ..trace import IndentationTrace
from .compression import PAPER_COMPRESSION_SPEED
from .cycle import check_segments
from .fit import ADHESION, BASELINES, ENGINES, RheologyFit, fit_rheology
from .peer import PEERS, peer_compatible
from .posterior import RHEOLOGIES
from .store import clear_rheology_outputs, save_rheology_fit

__all__ = ["RHEOLOGY_TABLE", "RheologyOptions", "rheology_options", "summary_row", "fit_traces",
           "UNIT_SUFFIXES"]

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


@dataclass(frozen=True)
class RheologyOptions:
    """What a viscoelastic run is asked to do, checked (:func:`rheology_options`).

    Attributes
    ----------
    rheology
        The models fitted to every trace (``"power-law"``, ``"sls"``, ``"elastic"``; several
        are compared by PSIS-LOO).
    segments
        The fitted segments, comma-separated (``approach,hold`` unless chosen).
    t0
        [s] Reference time of the power law.
    nu
        Poisson's ratio (None: a manifest row's, else moduli as E* only).
    drag
        A viscous drag term (None: when the retract is fitted).
    baseline, engine, adhesion
        ``"constant"|"linear"``, ``"grid"|"exact"|"emcee"``, ``"keep"|"cut"``
        (:func:`palpbayes.rheology.fit.fit_rheology`).
    peer
        Read every trace as this peer does (``"pyfmrheo"``), or None.
    compression_speed_mm_min
        [mm/min] Cross-head speed of the compression test set beside the fit.
    seed
        Seed of the draws (+ the trace's position).
    """

    rheology: tuple[str, ...] = ("power-law",)
    segments: str = "approach,hold"
    t0: float = 1.0
    nu: float | None = None
    drag: bool | None = None
    baseline: str = "constant"
    engine: str = "grid"
    adhesion: str = "keep"
    peer: str | None = None
    compression_speed_mm_min: float = 50.0
    seed: int = 0


# Many parameters: the builder: the options of `palpbayes fit --rheology` by their Python names,
# checked into one RheologyOptions.
def rheology_options(rheology: str | Sequence[str] = "power-law", *,
                     segments: str | Sequence[str] | None = None, t0: float = 1.0,
                     nu: float | None = None, drag: bool | str | None = None,
                     baseline: str = "constant", engine: str = "grid", adhesion: str = "keep",
                     peer: str | None = None, compression_speed_mm_min: float = 50.0,
                     seed: int = 0) -> RheologyOptions:
    """Check a viscoelastic run's options (the checks ``palpbayes fit --rheology`` makes).

    Parameters are :class:`RheologyOptions`'; ``rheology`` may be one name, a comma-separated
    list or a sequence, ``segments`` names or a comma-separated string, ``drag`` also
    ``"auto"|"on"|"off"`` as the command line spells it.

    Raises
    ------
    InputError
        An unknown model, a bad t0, compression speed, nu, seed or segment list, or options
        that do not go together (the message names them).
    """

    names = (tuple(n.strip() for n in rheology.split(",") if n.strip())
             if isinstance(rheology, str) else tuple(rheology))
    names = tuple(dict.fromkeys(names))
    bad = [n for n in names if n not in RHEOLOGIES]
    if bad or not names:
        raise InputError(f"unknown model {bad[0] if bad else rheology!r}; use "
                         f"{', '.join(RHEOLOGIES)} (or several: elastic,power-law,sls)")
    if not (isinstance(t0, int | float) and math.isfinite(t0) and t0 > 0):
        raise InputError(f"--t0 {t0!r} must be a positive time in seconds")
    if not (isinstance(compression_speed_mm_min, int | float)
            and math.isfinite(compression_speed_mm_min) and compression_speed_mm_min > 0):
        raise InputError(f"--compression-speed {compression_speed_mm_min!r} must be a "
                         "positive speed in mm/min")
    seed = check_seed(seed)
    if engine not in (*ENGINES, "exact"):
        raise InputError(f"engine {engine!r}: use one of {', '.join(ENGINES)} (or exact, "
                         "which is grid)")
    if baseline not in BASELINES:
        raise InputError(f"baseline {baseline!r}: use one of {', '.join(BASELINES)}")
    if adhesion not in ADHESION:
        raise InputError(f"adhesion {adhesion!r}: use one of {', '.join(ADHESION)}")
    if isinstance(drag, str):
        if drag not in ("auto", "on", "off"):
            raise InputError(f"drag {drag!r}: use auto, on or off (or None, True, False)")
        drag = {"auto": None, "on": True, "off": False}[drag]
    nu = None if nu is None else check_nu(nu)
    if peer is not None and peer not in PEERS:
        raise InputError(f"peer {peer!r}: palpbayes can read a trace as {', '.join(PEERS)} does")
    if peer is not None:
        for flag, given in (("--segments", segments is not None), ("--t0", t0 != 1.0),
                            ("--drag", drag is not None)):
            if given:
                raise InputError(f"--peer-compatible {peer} sets {flag} as the peer does; "
                                 f"leave {flag} out")
        if "sls" in names:
            raise InputError(f"--peer-compatible {peer} fits the retract by Ting's rule, which "
                             "palpbayes fits with the power law only: use --rheology power-law "
                             "(or elastic,power-law)")
        segments = "approach,retract"
    seg = check_segments(segments or "approach,hold")
    if adhesion == "cut" and "retract" not in seg:
        raise InputError(f"--adhesion cut cuts the pull-off out of the retract, which "
                         f"--segments {','.join(seg)} does not fit: add the retract (e.g. "
                         "--segments approach,retract) or leave --adhesion at keep")
    if "retract" in seg and "sls" in names:
        raise InputError("--segments with the retract is fitted with the power law only "
                         "(Ting's rule under the SLS is not linear in its moduli); use "
                         "--rheology power-law, or --segments approach,hold for the SLS")
    return RheologyOptions(names, ",".join(seg), float(t0), nu, drag, baseline, engine,
                           adhesion, peer, float(compression_speed_mm_min), int(seed))


def _error_row(trace_id: str, source: str, rheology: str, exc: Exception) -> dict:
    what = str(exc) if isinstance(exc, PalpbayesError) else (
        f"the fit failed numerically ({type(exc).__name__}: {exc}); report this record")
    return {"trace_id": trace_id, "source": source, "rheology": rheology, "model_ok": False,
            "error": what}


def fit_traces(traces: Iterable[IndentationTrace | tuple[str, str, Callable[[], IndentationTrace]]],
               options: RheologyOptions, out: str | os.PathLike, *,
               progress: bool | None = None, total: int | None = None,
               on_fit: Callable[[IndentationTrace, RheologyFit], None] | None = None
               ) -> pd.DataFrame:
    """Fit every trace with :func:`~palpbayes.rheology.fit_rheology` as ``options`` say and
    write ``out/rheology.csv`` (module docstring); returns the table.

    With several models (``options.rheology``), every trace gets a row per model and
    :func:`~palpbayes.rheology.choice.compare_rheology`'s columns (``elpd_loo``,
    ``elpd_loo_se``, ``p_loo``, ``pareto_k_max``, ``elpd_diff``, ``elpd_diff_se``,
    ``preferred``).  ``options.seed`` + the trace's position seeds its draws (the same table
    every run); ``options.nu`` gives way to the trace's own ``metadata["nu"]`` (a manifest's
    ``nu`` column); with ``options.peer`` (``"pyfmrheo"``) every trace is read as the peer
    does (:func:`~palpbayes.rheology.peer.pyfmrheo_compatible`: straight ramps, its drag
    fixed), for comparing with the peer's numbers, and each row's ``peer_compatible`` says so.
    Errors of one trace and model (:class:`~palpbayes.errors.PalpbayesError`, or a linear
    algebra failure) go into that row's ``error``; the other models of the trace keep theirs.

    Parameters
    ----------
    traces
        Traces, or (trace_id, source, load) triples with ``load()`` reading the trace (a
        manifest's rows: a file that cannot be read keeps its row too).
    options
        The checked options (:func:`rheology_options`).
    out
        Results folder (created).
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

    o = options
    models, peer = o.rheology, o.peer
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
            trace_nu = (trace.metadata or {}).get("nu", o.nu)
            fits, new = {}, []
            motion = {"segments": o.segments, "t0": o.t0, "drag": o.drag}
            if peer is not None:
                try:
                    trace, motion = peer_compatible(trace, peer)
                except PalpbayesError as exc:
                    rows.extend(_error_row(trace_id, source, m, exc) for m in models)
                    bar.update(1)
                    continue
            for m in models:  # one model failing keeps the others' rows
                try:
                    fits[m] = fit_rheology(trace, m, nu=trace_nu, baseline=o.baseline,
                                           engine=o.engine, adhesion=o.adhesion,
                                           rng=o.seed + i, **motion)
                    row = summary_row(trace, fits[m], o.compression_speed_mm_min / 6e4)
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
