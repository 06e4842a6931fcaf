"""The contact model a trace is fitted with (:func:`trace_model`): its tip, its Poisson ratio
and the specimen it was pressed into (a half-space, a layer, or the block's finite-element twin
when its footprint is known: :func:`trace_specimen`), and the twin's tables built before the
fit (:func:`prepare_twin`); each trace's seed (:func:`trace_seed`)."""

from __future__ import annotations

import numpy as np

from ..bayes.budget import nu_nodes
from ..bayes.layers import default_thickness_range
from ..contact import DEFAULT_NU, check_tip_plausible
from ..errors import GeometryError, InputError
from ..fitdata import ModelSpec
from ..specimen import FOOTPRINT_COLUMNS
from ..trace import IndentationTrace
from ..twin import Specimen, prepare_tables, specimen_from_sizes
from .options import FitOptions

__all__ = ["nu_source", "trace_seed", "trace_model", "trace_specimen", "prepare_twin"]


def nu_source(trace: IndentationTrace, options: FitOptions) -> str:
    """Where a trace's Poisson ratio came from: ``"manifest"`` (its row's ``nu``),
    ``"option"`` (the run's ``nu``) or ``"default"`` (:data:`~palpbayes.contact.DEFAULT_NU`)."""
    if "nu" in (trace.metadata or {}):
        return "manifest"
    return "default" if options.nu is None else "option"


def trace_seed(base: int, trace_id: str) -> int:
    """A per-trace seed from the base seed and the trace id (independent of trace order)."""
    words = np.frombuffer(trace_id.encode("utf-8"), dtype=np.uint8).astype(np.uint32)
    return int(np.random.SeedSequence([int(base), *words.tolist()]).generate_state(1)[0])


def trace_model(trace: IndentationTrace, options: FitOptions,
                depth: float | None = None) -> ModelSpec:
    """The contact model a Bayesian fit of ``trace`` uses: its tip (checked for
    plausibility), the run's ``nu`` unless the manifest row gives its own
    (``trace.metadata["nu"]``), and its layer (``options.layer``, ``options.bonding``).

    Parameters
    ----------
    trace
        The trace.
    options
        The fit options.
    depth
        [m] Indentation depth, for the default range of an unknown thickness.

    Raises
    ------
    GeometryError
        No tip or an implausible tip size.
    """
    src = trace.source or trace.trace_id
    tip = trace.tip
    if tip is None:
        raise GeometryError(f"{src}: no tip geometry; give --tip and its size")
    try:
        check_tip_plausible(tip)
    except GeometryError as exc:
        raise GeometryError(f"{src}: {exc}") from None
    # a manifest's per-row nu (trace.metadata["nu"]) overrides the run's option
    nu = trace.metadata.get("nu", DEFAULT_NU if options.nu is None else options.nu)
    block = trace_specimen(trace, options)
    if options.layer == "off" or (options.layer == "auto" and trace.thickness is None
                                  and block is None):
        return ModelSpec(tip, nu=nu, bonding=options.bonding)
    if block is not None:
        if options.layer == "unknown":
            raise InputError(f"{src}: the specimen {block.describe()} has a known height; an "
                             "unknown thickness (--thickness unknown) contradicts it")
        return ModelSpec(tip, nu=nu, bonding=options.bonding, specimen=block)
    if options.layer == "auto":
        return ModelSpec(tip, nu=nu, thickness=trace.thickness, bonding=options.bonding)
    rng = options.thickness_range
    if rng is None:
        rng = default_thickness_range(np.nan if depth is None else depth)
    return ModelSpec(tip, nu=nu, bonding=options.bonding, thickness_range=tuple(rng))


def trace_specimen(trace: IndentationTrace, options: FitOptions) -> Specimen | None:
    """The block a trace was pressed into: its manifest row's footprint (``length_m``,
    ``width_m`` or ``diameter_m`` with ``thickness_m``), else the run's ``specimen`` option;
    None without either.

    Raises
    ------
    GeometryError
        An incomplete footprint, or a ``specimen`` option whose height differs from the
        trace's own thickness.
    """
    meta = trace.metadata or {}
    src = trace.source or trace.trace_id
    try:
        block = specimen_from_sizes(trace.thickness, *(meta.get(c) for c in FOOTPRINT_COLUMNS))
    except GeometryError as exc:
        raise GeometryError(f"{src}: {exc}") from None
    if block is not None or options.specimen is None:
        return block
    if trace.thickness is not None and not np.isclose(trace.thickness,
                                                      options.specimen.height, rtol=1e-9):
        raise GeometryError(
            f"{src}: the specimen's height {options.specimen.height:g} m (--specimen) differs "
            f"from the trace's thickness {trace.thickness:g} m (--thickness or thickness_m): "
            "give one of the two")
    return options.specimen


def prepare_twin(model: ModelSpec, options: FitOptions) -> int:
    """Build (or load from the cache) the twin's tables a fit of ``model`` needs: its nu and
    the budget's nodes of nu (a Bayesian fit), for both bases (the least-squares row reads its
    curve with each); 0 without a specimen.  A progress bar shows on stderr while new tables
    are solved (``options.settings.progress``; None: when stderr is a terminal)."""
    if model.specimen is None:
        return 0
    nus = [model.nu]
    if options.method in ("bayes", "both"):
        nus += list(nu_nodes(options.budget, model.nu))
    return prepare_tables(model.specimen, model.tip, nus, ("bonded", "free"),
                          progress=options.settings.progress)
