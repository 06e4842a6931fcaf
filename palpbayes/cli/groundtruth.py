"""``palpbayes groundtruth INPUT... --out DIR``: Young's modulus from compression-test exports.

Writes ``DIR/groundtruth.csv`` (one row per test file: ``file, specimen, material, E_pa,
E_sd_pa, strain_lo, strain_hi, strain_toe, r2, n_points``) and ``DIR/groundtruth_summary.csv``
(one row per material: ``material, n, E_mean_pa, E_sd_pa, E_sem_pa, strain_lo, strain_hi,
window_lo, window_hi``), atomically, and prints the summary and the strain window used.  Strains
in the files are fractions; ``--strain-window`` takes **percent**.  The fitting rule is documented
in :mod:`palpbayes.groundtruth`.  With ``--platens bonded --nu X`` each test's E is also
corrected for the friction of its platens (``E_corrected_pa``, ``platen_factor``:
:mod:`palpbayes.groundtruth.platens`), the block being the test's cross-section and height.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..campaign import layout
from ..contact import check_nu
from ..errors import InputError
from ..groundtruth import DEFAULT_STRAIN_WINDOW

__all__ = ["register", "run"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``groundtruth`` subcommand to ``subparsers``; return its parser."""
    lo, hi = (100 * v for v in DEFAULT_STRAIN_WINDOW)
    p = subparsers.add_parser(
        "groundtruth",
        help="Young's modulus from Instron compression exports (ground truth)",
        description=(
            "Fit engineering stress = E·(strain - toe offset) over a strain window of each "
            "compression test and summarise per material. INPUT is test files, folders "
            "(searched recursively for *.csv; files that are not compression tests are "
            "skipped) or a ground-truth manifest CSV (file, specimen, material, area_m2, "
            "height_m; paths relative to the manifest)."),
    )
    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="compression-test CSV files, folders, or a ground-truth manifest")
    p.add_argument("--out", required=True, metavar="DIR", type=Path,
                   help=f"output folder for {layout.GROUNDTRUTH} and {layout.GROUNDTRUTH_SUMMARY}")
    p.add_argument("--strain-window", nargs=2, type=float, metavar=("LO", "HI"),
                   default=[lo, hi],
                   help="fit window in PERCENT engineering strain, measured from the toe offset "
                        f"(default {lo:g} {hi:g}, i.e. 0-5 %%)")
    p.add_argument("--no-toe-compensation", dest="toe_compensation", action="store_false",
                   help="measure the window from zero measured strain instead of the toe offset")
    p.add_argument("--skip-toe", action="store_true",
                   help="also drop points below twice the toe offset (exact for a quadratic toe)")
    p.add_argument("--area-m2", type=float, default=None, metavar="M2",
                   help="specimen cross-section [m^2] for every test (overrides headers)")
    p.add_argument("--height-m", type=float, default=None, metavar="M",
                   help="specimen height [m] for every test (overrides headers)")
    c = p.add_argument_group("platen friction (the specimen twin's compression test)")
    c.add_argument("--platens", choices=("lubricated", "bonded"), default=None,
                   help="correct each test's E for its platens: bonded (the faces could not "
                        "slide: the test read c*E, c > 1 growing with nu and the block's "
                        "width/height) or lubricated (c = 1); needs --nu")
    c.add_argument("--nu", type=float, default=None,
                   help="Poisson ratio of the blocks for --platens (foams 0.1-0.3, silicone "
                        "and gels 0.45-0.5)")
    return p


def _positive_option(value: float | None, flag: str) -> float | None:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise InputError(f"{flag} must be a positive number, got {value}")
    return value


def run(args: argparse.Namespace) -> int:
    """Run ``palpbayes groundtruth``; return the exit status (0 on success).

    Raises
    ------
    InputError
        Bad options or input files (the caller maps it to exit status 2).
    """
    from ..campaign.pipeline import write_groundtruth  # here: building the parser stays quick
    from ..groundtruth import analyse, correct_for_platens, summarise_corrected
    from ..io.groundtruth_inputs import scan_inputs

    lo_pct, hi_pct = args.strain_window
    if not (math.isfinite(lo_pct) and math.isfinite(hi_pct) and 0 <= lo_pct < hi_pct <= 100):
        raise InputError(f"--strain-window takes percent with 0 <= LO < HI <= 100, got "
                         f"{lo_pct:g} {hi_pct:g}")
    window = (lo_pct / 100.0, hi_pct / 100.0)
    area = _positive_option(args.area_m2, "--area-m2")
    height = _positive_option(args.height_m, "--height-m")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} exists and is not a folder")
    if (args.platens is None) != (args.nu is None):
        raise InputError("--platens and --nu go together: the platen correction depends on "
                         "the Poisson ratio (e.g. --platens bonded --nu 0.3)")
    if args.nu is not None:
        check_nu(args.nu)

    _, _, skipped = scan_inputs(args.inputs)
    per_file, summary = analyse(args.inputs, strain_window=window,
                                toe_compensation=args.toe_compensation,
                                skip_toe=args.skip_toe, area_m2=area, height_m=height)
    if args.platens is not None:
        per_file = correct_for_platens(per_file, args.platens, args.nu)
        summary = summarise_corrected(per_file, summary)
    out.mkdir(parents=True, exist_ok=True)
    write_groundtruth(per_file, summary, out)

    origin = "the toe offset" if args.toe_compensation else "zero measured strain"
    extra = "; points below twice the toe offset skipped" if args.skip_toe else ""
    print(f"groundtruth: {len(per_file)} test(s), {len(summary)} material(s)"
          + (f", {len(skipped)} other CSV file(s) skipped" if skipped else ""))
    print(f"strain window: {lo_pct:g}-{hi_pct:g} % engineering strain measured from "
          f"{origin}{extra}")
    shown = summary.assign(
        E_mean_kPa=summary["E_mean_pa"] / 1e3, E_sd_kPa=summary["E_sd_pa"] / 1e3,
        E_sem_kPa=summary["E_sem_pa"] / 1e3,
        strain_lo_pct=100 * summary["strain_lo"], strain_hi_pct=100 * summary["strain_hi"],
    )[["material", "n", "E_mean_kPa", "E_sd_kPa", "E_sem_kPa", "strain_lo_pct",
       "strain_hi_pct"]]
    if args.platens is not None:
        shown["E_corrected_kPa"] = summary["E_corrected_mean_pa"] / 1e3
        c = per_file["platen_factor"]
        print(f"{args.platens} platens at nu {args.nu:g}: the tests read E x "
              f"{c.min():.4g}" + (f"-{c.max():.4g}" if c.max() > c.min() else "")
              + " (the blocks' twins); E_corrected_kPa = the material's E")
    print(shown.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    print(f"wrote {out / layout.GROUNDTRUTH} and {out / layout.GROUNDTRUTH_SUMMARY}")
    return 0
