"""The contact model a trace is fitted with (:func:`trace_model`): its tip, its Poisson ratio,
the specimen it was pressed into (a half-space, a layer, or the block's finite-element twin
when its footprint is known: :func:`trace_specimen`) and its material law (:func:`trace_law`),
and the twin's tables built before the fit (:func:`prepare_twin`); each trace's seed
(:func:`trace_seed`)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..bayes.budget import law_nu_nodes, nu_nodes
from ..bayes.lawmix import MAX_FREE, law_nodes
from ..bayes.layers import default_thickness_range
from ..contact import DEFAULT_NU, check_tip_plausible
from ..errors import GeometryError, InputError
from ..fitdata import ModelSpec
from ..material import LINEAR, material_law
from ..specimen import FOOTPRINT_COLUMNS
from ..trace import IndentationTrace
from ..twin import Specimen, prepare_tables, specimen_from_sizes
from ..twin.hyper_shape import LawModel, table_depth
from .options import FitOptions

__all__ = ["nu_source", "trace_seed", "trace_model", "trace_specimen", "prepare_twin",
           "trace_law"]


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
        [m] Indentation depth, for the default range of an unknown thickness and the depth of
        a material law's table (:func:`trace_law`; without it the model is linear).

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
    law = None if depth is None else trace_law(trace, options, depth)
    model = _geometry(trace, options, tip, nu, depth)
    return model if law is None else replace(model, law=law)


def _geometry(trace: IndentationTrace, options: FitOptions, tip, nu: float,
              depth: float | None) -> ModelSpec:
    """The linear model of :func:`trace_model`: tip, nu and the specimen's layer."""
    src = trace.source or trace.trace_id
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


def trace_law(trace: IndentationTrace, options: FitOptions, depth: float) -> LawModel | None:
    """The material law a Bayesian fit of ``trace`` uses (None: linear): its manifest row's
    ``law`` or ``options.law``, each shape parameter fixed (``--law-shape NAME=VALUE``; a
    foam's nu by ``--nu`` or the row's ``nu`` when given) or free over its range (its
    registry bounds or ``NAME=LO:HI``) on :func:`palpbayes.bayes.lawmix.law_nodes`, the table
    reaching :func:`~palpbayes.twin.hyper_shape.table_depth` of the indentation ``depth``
    [m].

    Raises
    ------
    InputError
        More than :data:`~palpbayes.bayes.lawmix.MAX_FREE` free shape parameters, or free
        ones with the emcee engine (one line naming what to give).
    """
    src = trace.source or trace.trace_id
    name = str(trace.metadata.get("law") or options.law.name).strip().lower()
    if name == LINEAR:
        return None
    law = material_law(name)
    given = dict(options.law.shape) if options.law.name == law.name else {}
    nu_given = "nu" in trace.metadata or options.nu is not None
    if law.nu_parameter is not None and law.nu_parameter not in given and nu_given:
        given[law.nu_parameter] = (float(trace.metadata.get("nu", options.nu)),)
    ranges = {s.name: given.get(s.name, s.bounds) for s in law.shape}
    free = [n for n, r in ranges.items() if len(r) == 2]
    if len(free) > MAX_FREE:
        raise InputError(f"{src}: the {law.title} law has {len(free)} free shape parameters "
                         f"({', '.join(free)}); a fit mixes over at most {MAX_FREE}: fix the "
                         "others with --law-shape NAME=VALUE")
    if free and options.engine != "exact":
        raise InputError(f"{src}: --law {law.name} mixes over its free shape parameters "
                         f"({', '.join(free)}), which only the exact engine integrates: give "
                         "--engine exact, or fix them with --law-shape NAME=VALUE")
    nodes = tuple((n, law_nodes(*r, len(free)) if len(r) == 2 else (float(r[0]),))
                  for n, r in ranges.items())
    return LawModel(law.name, nodes, point=None if free else (), depth=table_depth(depth),
                    resolution=options.law.mesh, instron_strain=options.law.instron_strain)


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
    are solved (``options.settings.progress``; None: when stderr is a terminal).  A material
    law's tables (every node of its grid, each base it allows, the budget's nodes of nu) are
    built too, with their own bar (:func:`palpbayes.twin.hyper_shape.law_table`)."""
    if model.law is not None and options.method in ("bayes", "both"):
        _prepare_law(model, options)
    if model.specimen is None:
        return 0
    nus = [model.nu]
    if options.method in ("bayes", "both"):
        nus += list(nu_nodes(options.budget, model.nu))
    return prepare_tables(model.specimen, model.tip, nus, ("bonded", "free"),
                          progress=options.settings.progress)


def _prepare_law(model: ModelSpec, options: FitOptions) -> None:
    """Solve (or read) the finite-strain curves of a law's fit before it starts, so that a
    failure is an error of the trace, not of its posterior."""
    from ..twin.hyper_shape import law_table

    bases = model.bases if model.has_layer else ("bonded",)
    nus = [model.nu]
    if not model.law.free:  # the budget's nodes of nu (free shapes: the fitted point's, later)
        nus = list(law_nu_nodes(options.budget, model.nu))
    for base in bases:
        for nu in nus:
            law_table(model.with_nu(nu).law, model.tip, nu, model.thickness, model.specimen,
                      base)
