"""``palpbayes fit INPUT --out DIR``: least squares and/or Bayes on a trace or a manifest
(its options: :mod:`palpbayes.cli.options`, :mod:`palpbayes.cli.rheology`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from .. import outputs
from ..errors import DataFileError, InputError
from .console import console_lines
from .options import (
    RECORDING_FLAGS,
    add_model_options,
    add_trace_options,
    options_from_args,
    read_options_from_args,
    traces_from_args,
)
from .rheology import (
    ELASTIC_ONLY,
    VISCO_ONLY,
    add_rheology_options,
    check_rheology_args,
    given_options,
    print_pooled,
    print_rheology,
)

__all__ = ["register", "run"]


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "fit", help="fit E to a trace CSV, ROS 2 bag, AFM file or campaign manifest",
        description="Fit the elastic modulus of one trace, of every curve of an AFM force map "
        "or of every trace of a manifest. Writes DIR/summary.csv (one row per trace x method) "
        "and DIR/posterior/<id>.nc. With --rheology power-law|sls: the relaxation modulus of "
        "the loading and the hold instead, into DIR/rheology.csv.",
    )
    p.add_argument("input", metavar="INPUT",
                   help="trace CSV, ROS 2 bag (folder, .mcap, .db3), AFM file (.jpk-force, "
                        ".jpk-force-map, .ibw, ...) or campaign manifest CSV")
    p.add_argument("--out", required=True, metavar="DIR", help="results folder")
    p.add_argument("--force", action="store_true", help="overwrite an existing results folder")
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted run, keeping finished traces")
    add_model_options(p)
    add_rheology_options(p)
    add_trace_options(p, "single trace (ignored for a manifest)")
    p.set_defaults(fit_defaults={d: p.get_default(d) for d in (*ELASTIC_ONLY, *VISCO_ONLY)})


def _check_input_path(path: Path) -> None:
    """INPUT must be an existing file or bag folder; another folder gets its own message."""
    from ..io.bagfile import is_bag

    if path.is_dir() and not is_bag(path):
        manifest = path / "manifest.csv"
        fix = (f"did you mean {manifest}?" if manifest.is_file() else
               "give a trace CSV, a ROS 2 bag folder (with metadata.yaml), an AFM file or a "
               "campaign manifest CSV")
        raise DataFileError(path, "is a folder, not a file", fix)
    if not path.exists():
        raise DataFileError(path, "file not found", "check the path")


def _run_rheology(args: argparse.Namespace) -> int:
    """``fit --rheology power-law|sls``: the viscoelastic fit of every trace, one table
    (:func:`palpbayes.api_rheology.run_rheology`, as :func:`palpbayes.fit_rheology` runs)."""
    from ..api_rheology import manifest_traces, run_rheology
    from ..io.manifest import is_manifest
    from ..rheology.results import RHEOLOGY_TABLE

    path, out = Path(args.input), Path(args.out)
    _check_input_path(path)
    options = check_rheology_args(args)
    if path.is_file() and is_manifest(path):
        manifest, traces = manifest_traces(path, read_options_from_args(args))
    else:
        manifest, traces = None, traces_from_args(args, segments=options.segments)
    table, pooled = run_rheology(traces, options, out, manifest=manifest,
                                 progress=args.progress)
    print_rheology(table)
    print(f"wrote {out / RHEOLOGY_TABLE}")
    if pooled is not None:
        print_pooled(pooled, out)
    return 0


def run(args: argparse.Namespace) -> int:
    from ..campaign.run import fit_campaign  # here: building the parser stays quick
    from ..io.manifest import is_manifest

    if getattr(args, "rheology", ("elastic",)) != ("elastic",):
        return _run_rheology(args)
    given = given_options(args, VISCO_ONLY)
    if given:
        raise InputError(f"{given[0]} is an option of --rheology power-law|sls; the elastic "
                         "fit takes the loading part and does not use it")
    options = options_from_args(args)
    path = Path(args.input)
    _check_input_path(path)
    read_options = read_options_from_args(args)
    if path.is_file() and is_manifest(path):  # column/unit/sign options apply to every trace
        given = [f for k, f in RECORDING_FLAGS.items() if getattr(args, k) is not None]
        if given:
            raise InputError(f"{path} is a manifest of trace CSVs: {given[0]} applies to a ROS "
                             "2 bag or AFM file given as INPUT")
        source, manifest_options = path, read_options
    else:
        # every segment of an AFM file: the fit reads the approach, the rate check the rest
        source, manifest_options = traces_from_args(args, segments="all"), None
    if args.progress is not None:
        options = options.with_progress(args.progress)
    summary = fit_campaign(source, args.out, options, workers=args.workers, resume=args.resume,
                           force=args.force, progress=args.progress,
                           read_options=manifest_options, scheduler=args.scheduler)
    for line in console_lines(summary):
        print(line)
    print(f"wrote {Path(args.out) / outputs.SUMMARY}")
    return 0
