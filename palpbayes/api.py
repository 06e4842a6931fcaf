"""The front door: palpbayes from Python, by the code path the command line takes.

>>> import palpbayes as pb                                     # doctest: +SKIP
>>> f = pb.fit("press.csv", tip="sphere", radius=0.01, nu=0.45)  # doctest: +SKIP
>>> f.E, f.interval                                            # doctest: +SKIP
>>> f.save("press-fit")         # what palpbayes fit --out press-fit writes # doctest: +SKIP
>>> pb.load_fit("press-fit")    # either folder, read back                  # doctest: +SKIP

:func:`fit` builds its options with :func:`fit_options`, the function ``palpbayes fit`` builds
its own with (:func:`palpbayes.cli.options.options_from_args` calls it), reads a file with the
reader ``fit`` uses (:func:`palpbayes.io.recording.read_recording`), and fits with
:func:`palpbayes.campaign.fitjob.fit_trace`, the fit of every trace of a run: the same file,
options and seed give the same numbers in a notebook and on the command line
(``Fit.summary()`` equals ``summary.csv``, field by field; ``tests/integration/test_api.py``),
the default seed included (0, ``--seed``'s).  The :class:`Fit` (:mod:`palpbayes.api_fit`)
saves the folder ``palpbayes fit --out`` writes, and :func:`load_fit` reads either back.
docs/api.md shows every public name with examples that the test suite runs.
"""

from __future__ import annotations

import dataclasses
import math
import os

import pandas as pd

from .api_fit import Fit, load_fit
from .arguments import check_seed, check_thickness
from .campaign.fitjob import fit_trace_rows
from .campaign.options import FitOptions, fit_options
from .contact import TIP_PARAMETERS, Tip
from .errors import FitError, GeometryError, InputError
from .io.recording import AFM_META_KEYS, READER_OPTIONS
from .trace import IndentationTrace
from .twin import Specimen, parse_specimen

__all__ = ["read", "fit", "Fit", "load_fit", "fit_options", "fit_campaign", "make_tip",
           "check_specimen"]

#: Reader options :func:`fit` passes to :func:`read`: every reader's own
#: (:data:`~palpbayes.io.recording.READER_OPTIONS`: a table's columns, units and signs, a
#: bag's topics, an AFM file's segments), an AFM file's calibration by its Python name, the
#: curve of a force map, and the trace's labels.
READER_KEYS = frozenset(
    (set().union(*READER_OPTIONS.values()) - {"curves", "meta_override"})
    | set(AFM_META_KEYS) | {"curve", "trace_id", "material", "specimen", "repetition",
                            "rest_time"})
#: The reader options a DataFrame takes (:func:`~palpbayes.io.trace_csv.trace_from_frame`).
FRAME_KEYS = frozenset(READER_OPTIONS["table"] - {"delimiter"}
                       | {"trace_id", "material", "specimen", "repetition", "rest_time"})


def make_tip(tip: str | Tip | None, *, radius: float | None = None,
             half_angle: float | None = None, c: float | None = None,
             n: float | None = None) -> Tip | None:
    """A :class:`~palpbayes.contact.Tip` from a kind and its sizes in the command line's units
    (``radius`` [m], ``half_angle`` [deg], ``c``, ``n``), or ``tip`` itself; None without one.

    Raises
    ------
    GeometryError
        An unknown kind, a missing or bad size, or sizes given with a :class:`Tip`.
    """
    sizes = {"radius": radius, "half_angle": half_angle, "c": c, "n": n}
    if isinstance(tip, Tip):
        if any(v is not None for v in sizes.values()):
            raise GeometryError("give the tip's sizes in the Tip, or a kind with its sizes, "
                                "not both")
        return tip
    if tip is None:
        if any(v is not None for v in sizes.values()):
            raise GeometryError("tip sizes given without a tip kind (tip='sphere', ...)")
        return None
    values = {name: None if sizes.get(name) is None else TIP_PARAMETERS[name].from_user(
        sizes[name]) for name in TIP_PARAMETERS}
    return Tip(str(tip), **values)


def check_specimen(specimen: Specimen | str | None, thickness: float | str | None = None,
                   half_space: bool = False) -> Specimen | None:
    """The block as tested (a :class:`~palpbayes.twin.Specimen` or its ``"L,W,H"``/``"D,H"``
    text), checked against the thickness and the half-space option (``--specimen``'s rules).

    Raises
    ------
    InputError
        A thickness that differs from the block's height, an unknown thickness or the
        half-space with a block, or a bad specimen text.
    """
    if specimen is None:
        return None
    if isinstance(specimen, str):
        try:
            specimen = parse_specimen(specimen)
        except GeometryError as exc:
            raise InputError(f"--specimen: {exc}") from None
    if str(thickness).strip().lower() == "unknown":
        raise InputError("--specimen gives the thickness: it contradicts --thickness unknown")
    if thickness is not None and not math.isclose(float(thickness), specimen.height,
                                                  rel_tol=1e-9):
        raise InputError(f"--thickness {float(thickness):g} m differs from the height "
                         f"{specimen.height:g} m of --specimen {specimen.as_text()}: give "
                         "the specimen alone")
    if half_space:
        raise InputError("--specimen and --half-space contradict each other: the specimen's "
                         "twin models the block, the half-space the paper's model")
    return specimen


def read(path: str | os.PathLike, *, tip: str | Tip | None = None,
         radius: float | None = None, half_angle: float | None = None, c: float | None = None,
         n: float | None = None, thickness: float | None = None, material: str = "",
         curve: int | None = None, **reader_options) -> IndentationTrace:
    """One trace from a file, as ``palpbayes fit FILE`` reads it: a trace CSV (``columns``,
    ``units``, ``force_sign``, ``z_sign``), a UR RTDE log (``tool_offset``, ``z_source``,
    ``force_axis``, ``force_sign``), a ROS 2 bag or an AFM file (every segment; a force map
    needs ``curve``), in SI units.

    Parameters
    ----------
    path
        The recording.
    tip, radius, half_angle, c, n
        The tip (:func:`make_tip`; stored in the trace).
    thickness
        [m] Specimen thickness, stored in the trace.
    material
        Material label.
    curve
        Which curve of an AFM force map.
    **reader_options
        The reader's options (:func:`palpbayes.io.recording.read_recording`).

    Raises
    ------
    InputError, DataFileError
        As the readers; a force map without ``curve``.
    """
    from .io.recording import read_recording, recording_kind

    opts = dict(reader_options)
    meta = {}
    for attr, key in AFM_META_KEYS.items():  # --spring-constant, ... by their Python names
        value = opts.pop(attr, None)
        if value is not None:
            if not (math.isfinite(value) and value > 0):
                raise InputError(f"{attr} {value!r} must be a positive number")
            meta[key] = float(value)
    if meta:
        opts["meta_override"] = meta
    if recording_kind(path) == "afm":
        opts.setdefault("segments", "all")
        if curve is not None:
            opts["curves"] = [int(curve)]
    elif curve is not None:
        raise InputError(f"{path}: curve= picks a curve of an AFM force map")
    traces = read_recording(path, tip=make_tip(tip, radius=radius, half_angle=half_angle,
                                               c=c, n=n),
                            thickness=thickness, material=material, **opts)
    if len(traces) != 1:
        raise InputError(f"{path} holds {len(traces)} curves; pick one with curve=I "
                         f"(0 to {len(traces) - 1})")
    return traces[0]


def _thickness(thickness) -> float | None:
    """[m] A thickness given as a number (None and ``"unknown"``: None), or an InputError."""
    h = check_thickness(thickness)
    return None if h == "unknown" else h


def _trace_of(source, tip: Tip | None, thickness, reader_options: dict) -> IndentationTrace:
    h = _thickness(thickness)
    if isinstance(source, IndentationTrace):
        if reader_options:
            raise InputError(f"reader options {sorted(reader_options)} apply to a file, not "
                             "to a trace")
        changes = {}
        if tip is not None:
            changes["tip"] = tip
        if h is not None:
            changes["thickness"] = h
        return dataclasses.replace(source, **changes) if changes else source
    if isinstance(source, pd.DataFrame):
        from .io.trace_csv import trace_from_frame

        wrong = sorted(set(reader_options) - FRAME_KEYS)
        if wrong:
            raise InputError(f"reader option(s) {wrong} apply to a file, not to a DataFrame "
                             f"(a DataFrame takes {', '.join(sorted(FRAME_KEYS))})")
        opts = dict(reader_options)
        opts.setdefault("trace_id", "frame")
        return trace_from_frame(source, "a DataFrame", tip=tip, thickness=h, **opts)
    if isinstance(source, str | os.PathLike):
        return read(source, tip=tip, thickness=h, **reader_options)
    raise InputError(f"fit takes a path, an IndentationTrace or a DataFrame, not "
                     f"{type(source).__name__}")


# Many parameters: the tip's sizes and the specimen by name, as `palpbayes fit` takes them (the
# rest in **options): the door a user types.
def fit(source, *, tip: str | Tip | None = None, radius: float | None = None,
        half_angle: float | None = None, c: float | None = None, n: float | None = None,
        nu: float | None = None, thickness: float | str | None = None,
        specimen: Specimen | str | None = None, method: str = "bayes", engine: str = "emcee",
        seed: int | None = None, half_space: bool = False, law: str = "linear",
        **options) -> Fit:
    """Fit one trace, as ``palpbayes fit`` does (docs/api.md).

    Parameters
    ----------
    source
        A file (trace CSV, ROS 2 bag, AFM file), an :class:`~palpbayes.trace.IndentationTrace`
        or a DataFrame with ``time_s, z_m, force_n`` (or ``columns``/``units``).
    tip, radius, half_angle, c, n
        The tip (:func:`make_tip`; a trace's own when None).
    nu
        Poisson ratio [-] (None: 0.3, a foam value, said in ``nu_source``).
    thickness
        [m] Specimen thickness (a layer on its plate), ``"unknown"`` (sampled) or None.
    specimen
        The block as tested (a :class:`~palpbayes.twin.Specimen` or ``"L,W,H"``/``"D,H"``):
        its finite-element twin, and ``E_instron``.
    method, engine
        ``"bayes"``, ``"lsq"`` or ``"both"``; ``"emcee"`` or ``"exact"``.
    seed
        Base seed (None: 0, the command line's default: the same numbers as ``palpbayes
        fit`` without ``--seed``).
    half_space
        Fit a half-space even with a thickness (``--half-space``).
    law
        The material law: ``"linear"`` (the paper's model, default) or a registered
        hyperelastic law (``"neo-hookean"``, ``"hyperfoam"``, ...): ``E`` is then its
        small-strain modulus E0 (docs/reference.md, "Finite strain in the fits"); with
        ``law_shape``, ``law_mesh`` and ``instron_strain`` among the ``options``.
    **options
        :func:`fit_options`' keywords (``bonding``, ``platens``, ``noise``, ``baseline``,
        ``tare``, ``f_unc``, ``model_form``, ...) and the reader's (``columns``, ``units``,
        ``force_sign``, ``z_sign``, ``curve``, ...).

    Returns
    -------
    Fit

    Raises
    ------
    InputError, GeometryError, DataFileError
        Bad input, named as the command line names it.
    FitError
        Only with ``strict=True``: a fit failed (otherwise its row says why, as in
        ``summary.csv``).

    Notes
    -----
    Each trace's seed derives from ``seed`` and the trace's id, as on the command line: a
    DataFrame's trace is called ``trace_id`` (default ``"frame"``); give the file's stem to
    reproduce ``palpbayes fit FILE.csv`` number for number.
    """
    reader = {k: options.pop(k) for k in list(options) if k in READER_KEYS}
    unknown = thickness is not None and str(thickness).strip().lower() == "unknown"
    if half_space and unknown:
        raise InputError("--half-space and --thickness unknown contradict each other; give "
                         "one of them")
    if seed is not None:
        check_seed(seed)
    block = check_specimen(specimen, thickness, half_space)
    layer = "off" if half_space else "unknown" if unknown else "auto"
    opts = fit_options(method=method, nu=nu, layer=layer, specimen=block, engine=engine,
                       seed=0 if seed is None else int(seed), law=law, **options)
    trace = _trace_of(source, make_tip(tip, radius=radius, half_angle=half_angle, c=c, n=n),
                      thickness, reader)
    outcome = fit_trace_rows(trace, opts)  # a failed fit is a row, as on the command line
    if opts.strict:
        failed = [r for r in outcome.rows
                  if "fit_failed" in str(r.get("flag_codes") or "").split(";")]
        if failed:
            raise FitError(f"{trace.trace_id}: the {' and '.join(r['method'] for r in failed)} "
                           f"fit failed in strict mode: {failed[0].get('notes', '')}")
    return Fit(trace=trace, options=opts, outcome=outcome)


# Many parameters: the campaign door: fit_campaign's run settings, with pb.fit's keywords in
# **fit_kw.
def fit_campaign(source, out_dir: str | os.PathLike | None = None,
                 options: FitOptions | None = None, *, seed: int | None = None,
                 workers: int | None = None, resume: bool = False, force: bool = False,
                 progress: bool | None = None, read_options: dict | None = None,
                 scheduler: str | None = None, on_plan=None, **fit_kw) -> pd.DataFrame:
    """Fit every trace of a campaign, as ``palpbayes fit MANIFEST --out DIR`` does
    (:func:`palpbayes.campaign.run.fit_campaign`: its parameters, the folder it writes).

    The fit options are :func:`fit_options`' keywords (``nu=``, ``engine=``, ``method=`` ...,
    and ``seed=``, default 0 as on the command line), or a built ``options`` object: one or
    the other; an unknown keyword is an InputError naming it.  Returns the summary table, as
    written to ``summary.csv``.
    """
    from .campaign.run import fit_campaign as run_campaign

    if options is not None and (fit_kw or seed is not None):
        given = sorted(fit_kw) + (["seed"] if seed is not None else [])
        raise InputError(f"fit_campaign: give the fit options as keywords ({', '.join(given)}) "
                         "or as options=pb.fit_options(...), not both")
    import inspect

    known = set(inspect.signature(fit_options).parameters) - {"seed"}
    unknown = sorted(set(fit_kw) - known)
    if unknown:
        raise InputError(f"fit_campaign: unknown option(s) {', '.join(unknown)}; a manifest "
                         "gives each trace's tip and thickness, and the fit options are "
                         f"{', '.join(sorted(known))}")
    if options is None:
        options = fit_options(seed=0 if seed is None else seed, **fit_kw)
    return run_campaign(source, out_dir, options, workers=workers, resume=resume, force=force,
                        progress=progress, read_options=read_options, scheduler=scheduler,
                        on_plan=on_plan)
