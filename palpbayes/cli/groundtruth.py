"""``palpbayes groundtruth INPUT... --out DIR``: Young's modulus from compression-test exports.

Writes ``DIR/groundtruth.csv`` (one row per test file: ``file, specimen, material, E_pa,
E_sd_pa, strain_lo, strain_hi, strain_toe, r2, n_points``) and ``DIR/groundtruth_summary.csv``
(one row per material: ``material, n, E_mean_pa, E_sd_pa, E_sem_pa, strain_lo, strain_hi,
window_lo, window_hi``), atomically, and prints the summary and the strain window used.  Strains
in the files are fractions; ``--strain-window`` takes **percent**.  The fitting rule is documented
in :mod:`palpbayes.compression`.  With ``--platens bonded --nu X`` each test's E is also
corrected for the friction of its platens (``E_corrected_pa``, ``platen_factor``:
:mod:`palpbayes.compression.platens`), the block being the test's cross-section and height.
The analysis and the files are :func:`palpbayes.groundtruth`'s (:mod:`palpbayes.api_groundtruth`),
the same bytes from Python.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from .. import outputs
from ..compression import DEFAULT_STRAIN_WINDOW
from ..errors import InputError

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
                   help=f"output folder for {outputs.GROUNDTRUTH} and "
                        f"{outputs.GROUNDTRUTH_SUMMARY}")
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
    h = p.add_argument_group("finite strain (a hyperelastic law fitted to the whole curve)")
    h.add_argument("--law", default="linear", metavar="NAME|auto",
                   help="linear (default: the line over the strain window, E0 = E), a "
                        "hyperelastic law fitted to the whole loading curve with a posterior "
                        "of its parameters and of its small-strain modulus E0 (neo-hookean, "
                        "mooney-rivlin, yeoh, yeoh-2, ogden, ogden-2, ogden-3, exponential, "
                        "hyperfoam, hyperfoam-2), or auto: the laws neo-hookean, "
                        "mooney-rivlin, yeoh-2, yeoh, ogden and exponential compared by PSIS-LOO "
                        f"and each material's best kept ({outputs.GROUNDTRUTH_LAWS})")
    h.add_argument("--strain", default=None, metavar="LO,HI",
                   help="also each test's chord modulus between these compressive strains "
                        "(fractions, e.g. 0.05,0.20) under its law: two tests set side by side "
                        "at one strain")
    h.add_argument("--seed", type=int, default=0, help="seed of the law fits' draws (default 0)")
    h.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="a progress bar over the law fits (default: when stderr is a terminal)")
    c = p.add_argument_group("platen friction (the specimen twin's compression test)")
    c.add_argument("--platens", choices=("lubricated", "bonded"), default=None,
                   help="correct each test's E for its platens: bonded (the faces could not "
                        "slide: the test read c*E, c > 1 growing with nu and the block's "
                        "width/height) or lubricated (c = 1); needs --nu")
    c.add_argument("--nu", type=float, default=None,
                   help="Poisson ratio of the blocks for --platens (foams 0.1-0.3, silicone "
                        "and gels 0.45-0.5)")
    return p


def run(args: argparse.Namespace) -> int:
    """Run ``palpbayes groundtruth``; return the exit status (0 on success).

    The analysis and the files are :func:`palpbayes.groundtruth`'s
    (:mod:`palpbayes.api_groundtruth`); this turns the options into its call (the window from
    percent to fractions) and prints the summary.

    Raises
    ------
    InputError
        Bad options or input files (the caller maps it to exit status 2).
    """
    # here, not at the top: building the parser stays quick
    from ..api_groundtruth import FLAGS, GroundTruthOptions, analyse_groundtruth

    lo_pct, hi_pct = args.strain_window
    if not (math.isfinite(lo_pct) and math.isfinite(hi_pct) and 0 <= lo_pct < hi_pct <= 100):
        raise InputError(f"--strain-window takes percent with 0 <= LO < HI <= 100, got "
                         f"{lo_pct:g} {hi_pct:g}")
    options = GroundTruthOptions(
        strain_window=(lo_pct / 100.0, hi_pct / 100.0), toe_compensation=args.toe_compensation,
        skip_toe=args.skip_toe, area_m2=args.area_m2, height_m=args.height_m, law=args.law,
        strain=args.strain, seed=args.seed, platens=args.platens, nu=args.nu).checked(FLAGS)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} exists and is not a folder")

    gt = analyse_groundtruth(args.inputs, options, progress=args.progress)
    gt.save(out)
    per_file, summary, laws, skipped = gt.tests, gt.materials, gt.laws, gt.skipped

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
    if args.law != "linear":
        for line in law_lines(summary, laws, per_file):
            print(line)
    print(f"wrote {out / outputs.GROUNDTRUTH} and {out / outputs.GROUNDTRUTH_SUMMARY}"
          + (f" and {out / outputs.GROUNDTRUTH_LAWS}" if args.law != "linear" else ""))
    return 0


def law_lines(summary, laws, per_file) -> list[str]:
    """What ``--law`` adds to the console: per material, the law kept with E0 (mean ± sd over
    the tests, against the linear E), the chord with ``--strain``, how clearly the law was
    chosen, and every law's E0 beside it when several were compared."""
    from ..units import format_pressure

    out = ["finite strain: the small-strain modulus E0 of each material's law, fitted to the "
           "whole loading curve (mean ± sd over its tests; E: the line over the window)"]
    for _, r in summary.iterrows():
        mine = laws[laws["material"] == r["material"]]
        line = (f"  {r['material']}: {r['law']} E0 {format_pressure(r['E0_mean_pa'], 4)} ± "
                f"{format_pressure(r['E0_sd_pa'], 2)} ({r['E0_mean_pa'] / r['E_mean_pa'] - 1:+.1%}"
                f" against E {format_pressure(r['E_mean_pa'], 4)})")
        if "E_chord_mean_pa" in r and r["E_chord_mean_pa"] == r["E_chord_mean_pa"]:
            rows = per_file[per_file["material"] == r["material"]]
            line += (f"; chord {100 * rows['chord_lo'].iloc[0]:g}-"
                     f"{100 * rows['chord_hi'].iloc[0]:g} % "
                     f"{format_pressure(r['E_chord_mean_pa'], 4)}")
        out.append(line)
        if len(mine) > 1:
            chosen = mine[mine["chosen"]].iloc[0]
            out.append("    chosen by PSIS-LOO " + ("clearly (ahead of every other law by > 2 se)"
                                                    if chosen["clear"] else
                                                    "but not clearly (another law within 2 se)")
                       + "; every law's E0: " + ", ".join(
                           f"{x['law']} {format_pressure(x['E0_mean_pa'], 3)}"
                           for _, x in mine.iterrows() if x["E0_mean_pa"] == x["E0_mean_pa"]))
    notes = per_file["law_note"].fillna("").astype(str)
    for _, r in per_file[notes != ""].iterrows():
        out.append(f"  note: {r['file']}: {r['law_note']}")
    return out
