"""``palpbayes map MANIFEST|AFMMAP --out DIR``: a stiffness map with its uncertainty and the lump.

The manifest's rows carry the palpation position (``x_m``, ``y_m`` in metres) on a regular
grid (``material`` is optional: a map is one block).  Its trace files are read as ``palpbayes
fit`` reads a manifest's: a robot log's columns, units and signs are given with fit's own
options (``--time-column timestamp --z-column tcp_z_mm --z-unit mm --force-sign -1``,
:func:`palpbayes.cli.options.add_column_options`), and every file's header is checked with
them before a cluster starts.  An AFM force map (``.jpk-force-map``, ``.jpk-qi-data``, an
AFM Workshop zip: any map afmformats reads) is mapped directly: positions from the file, the
tip from ``--tip`` and its size (no AFM file records it), grid nodes without a curve kept as
holes (:mod:`palpbayes.maps.afm_source`).  The lump model is off by default for an AFM map: a map
of cells has no buried sphere and no block thickness; the field and P(E > k × median) are the
answer (``--lump`` turns it on).  Per-point fits run on Dask (a LocalCluster by default,
``--scheduler ADDRESS`` for a cluster whose workers see the same files); then the spatial
field and the lump model (:mod:`palpbayes.maps`).  Files: :mod:`palpbayes.maps.files`.
Try it with::

    palpbayes simulate phantom --map
    palpbayes map phantom/manifest.csv --out phantom-map
    palpbayes map robot/manifest.csv --time-column timestamp --z-column tcp_z_mm \
        --force-column fz --z-unit mm --force-sign -1 --out robot-map
    palpbayes map cells.jpk-force-map --tip paraboloid --radius 5e-6 --nu 0.5 --out cells-map
"""

from __future__ import annotations

import argparse

from ..bayes.noisemodels import EXACT_NOISE_MODELS
from ..contact import DEFAULT_NU_NOTE, check_nu
from ..errors import InputError
from ..flagcodes import level_and_text
from ..io.afm import is_afm_file
from ..units import format_length, format_pressure
from .afm_options import add_afm_meta_options, afm_meta_from_args
from .options import (
    add_column_options,
    add_f_unc_option,
    add_nu_option,
    add_tip_options,
    positive_force,
    read_options_from_args,
    tip_from_args,
)

__all__ = ["register", "run"]


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``map`` subcommand to an argparse ``subparsers`` object; return its parser."""
    p = subparsers.add_parser(
        "map",
        help="stiffness map of a grid of palpations: E with its uncertainty, P(stiff lump), "
             "the lump's centre, size and stiffness ratio",
        description=(
            "Fit every trace of MANIFEST (columns x_m, y_m: palpation position in metres) with "
            "the exact engine on Dask, fit the stiff lump (one spherical inclusion), then a "
            "spatial GMRF field to what it leaves; write map.csv, points.csv, lump.csv, map.nc, "
            "map.png and map-report.pdf into --out.  The trace files take fit's column, unit "
            "and sign options (a robot log: --time-column timestamp --z-unit mm "
            "--force-sign -1 ...).  An AFM force map is read directly (positions from the "
            "file; the tip from --tip; the lump model off unless --lump)."),
    )
    p.add_argument("input", metavar="INPUT",
                   help="manifest CSV with trace_id, file, tip (and its size), x_m and y_m "
                        "columns (material optional), or an AFM force map (.jpk-force-map, "
                        ".jpk-qi-data, AFM Workshop .zip)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    p.add_argument("--force", action="store_true", help="replace the map files in DIR")
    add_column_options(p, "columns, units and signs of the trace files (as fit; the signs "
                          "also for an AFM map)")
    a = p.add_argument_group("AFM force maps (no AFM file records the tip)")
    add_tip_options(a)
    add_afm_meta_options(a)
    a.add_argument("--thickness", type=float, metavar="M",
                   help="specimen thickness [m]: the lump model (--lump) needs it; an AFM "
                        "file does not record it")
    g = p.add_argument_group("per-point fits")
    add_nu_option(g, summary=False)
    g.add_argument("--noise", choices=EXACT_NOISE_MODELS, default="gaussian",
                   help="noise model of the exact engine (default gaussian)")
    g.add_argument("--tare", action="store_true", help="subtract the pre-contact force level")
    add_f_unc_option(g)
    g.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="Dask scheduler address (tcp://host:8786); default: a LocalCluster; "
                        "'synchronous' runs in this process")
    g.add_argument("--workers", type=int, default=None, metavar="N",
                   help="LocalCluster worker processes (default: one per core)")
    g = p.add_argument_group("map")
    g.add_argument("--threshold", type=float, default=1.1, metavar="K",
                   help="report P(E > K x the map's median E) per point (default 1.1)")
    g.add_argument("--detect", type=float, default=0.5, metavar="P",
                   help="report a lump as found when P(its apparent peak ratio > K) >= P "
                        "(default 0.5; 0: always)")
    g.add_argument("--lump", action=argparse.BooleanOptionalAction, default=None,
                   help="fit the lump model (one buried stiff sphere; default: on for a "
                        "manifest, off for an AFM map, whose cells have no buried sphere)")
    g.add_argument("--lump-max-steps", type=int, default=20000, metavar="N",
                   help="cap on the emcee steps per walker of the lump model; it stops "
                        "earlier once converged (default 20000)")
    g.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    g.add_argument("--no-report", action="store_true", help="skip map.png and the PDF")
    g.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bars (default: when stderr is a terminal)")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    """Fit, map, write; print where and the lump.  Returns 0."""
    from ..api_map import MapRequest, prepare_map, run_map
    from ..maps.files import check_out_dir

    if args.lump_max_steps < 1000:
        raise InputError(f"--lump-max-steps {args.lump_max_steps} is too few; use at least "
                         "1000")
    afm = is_afm_file(args.input)
    if not afm:
        given = [o for o, v in (("--tip", args.tip), ("--thickness", args.thickness),
                                ("--spring-constant", args.spring_constant),
                                ("--sensitivity", args.sensitivity),
                                ("--sample-rate", args.sample_rate)) if v is not None]
        if given:
            raise InputError(f"{', '.join(given)}: for an AFM force map; a manifest gives the "
                             "tip and the thickness in its columns (tip, radius_m ..., "
                             "thickness_m)")
    else:
        given = [f"--{q}-{w}" for q in ("time", "z", "force") for w in ("column", "unit")
                 if getattr(args, f"{q}_{w}")]
        if given:
            raise InputError(f"{args.input} is an AFM force map: {', '.join(given)} apply to "
                             "a manifest's trace CSVs (an AFM file names its own channels)")
        if args.thickness is not None and not args.thickness > 0:
            raise InputError(f"--thickness {args.thickness!r} must be a positive length [m]")
    request = MapRequest(
        tip=tip_from_args(args) if afm else None, thickness=args.thickness if afm else None,
        nu=None if args.nu is None else check_nu(args.nu), noise=args.noise, tare=args.tare,
        f_unc=positive_force("--f-unc", args.f_unc), seed=args.seed,
        threshold=args.threshold, detect=args.detect, lump=args.lump,
        lump_max_steps=args.lump_max_steps,
        read_options=read_options_from_args(args),  # columns, units, signs: only those given
        afm_meta=(afm_meta_from_args(args) or {}) if afm else {})
    job = prepare_map(args.input, request, scheduler=args.scheduler)
    check_out_dir(args.out, args.force)  # before the fits: a bad --out fails fast
    fit = run_map(job, scheduler=args.scheduler, workers=args.workers, progress=args.progress)
    res, elapsed, manifest, nu = fit.result, fit.elapsed_s, job.manifest, request.nu
    out = fit.save(args.out, force=args.force, report=not args.no_report)
    n_ok = int((res.points["error"].fillna("") == "").sum())
    lat = res.field.lattice
    print(f"mapped {n_ok} of {len(res.points)} palpations on a {lat.nx} x {lat.ny} lattice "
          f"(step {format_length(lat.step)}) in {elapsed:.1f} s "
          f"({len(res.points) / elapsed:.1f} traces/s) -> {out}")
    med, lo, hi = res.background_interval()
    print(f"  map median E {format_pressure(med, 4)} [{format_pressure(lo, 4)}, "
          f"{format_pressure(hi, 4)}] (90 %; the field's median over every node, a lump's "
          "included: what P(E > k x median) compares with)")
    print(f"  largest P(E > {args.threshold:g} x map median) over the map: {res.detection:.3f}")
    if res.lump is not None:
        b = res.lump.summary().set_index("quantity").loc["E_background_pa"]
        print(f"  background E outside the lump (lump model) {format_pressure(b['median'], 4)} "
              f"[{format_pressure(b['lo'], 4)}, {format_pressure(b['hi'], 4)}] (90 %)")
        print(f"  P(lump with apparent peak ratio > {args.threshold:g}): {res.p_lump:.3f}"
              + ("" if res.lump_found else " -> no lump found"))
    if res.lump_found:
        s = res.lump.summary().set_index("quantity")
        for q, label, fmt in (("x_m", "centre x", format_length),
                              ("y_m", "centre y", format_length),
                              ("radius_m", "radius", format_length),
                              ("apparent_ratio", "apparent peak ratio", lambda v: f"{v:.3g}"),
                              ("ratio", "stiffness ratio", lambda v: f"{v:.3g}")):
            r = s.loc[q]
            print(f"  lump {label}: {fmt(r['median'])} [{fmt(r['lo'])}, {fmt(r['hi'])}] (90 %)")
    for f in res.flags:
        level, text = level_and_text(f)
        print(f"  {level}: {text}")
    if nu is None and "nu" not in manifest.columns:
        print(f"note: {DEFAULT_NU_NOTE}")
    return 0
