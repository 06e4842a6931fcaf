"""``palpbayes simulate OUT_DIR``: write a synthetic palpation campaign (docs/design.md §7).

The folder holds a manifest, one CSV per trace, Instron-like ground-truth exports and the true
values (see :mod:`palpbayes.sim.campaign`).  The shipped example was made with::

    palpbayes simulate data/example-campaign --seed 2026 --repetitions 3
"""

from __future__ import annotations

import argparse

from ..noise import PAPER_NOISE_PP
from ..paper import PAPER_MATERIALS, PAPER_TIPS
from ..sim import simulate_campaign
from ..units import format_force

__all__ = ["register", "run"]


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``simulate`` subcommand to an argparse ``subparsers`` object; return its parser."""
    p = subparsers.add_parser(
        "simulate",
        help="write a synthetic campaign folder (traces, manifest, ground truth, true values)",
        description=(
            "Simulate the paper's campaign: 3 foams (White/Pink/Grey) x 3 tips (flat, sphere, "
            "paraboloid) x REPETITIONS palpations, plus Instron-like compression tests, with "
            "the true values in truth.csv."
        ),
    )
    p.add_argument("out_dir", metavar="OUT_DIR", help="output folder (must be empty)")
    p.add_argument("--seed", type=int, default=0, metavar="N",
                   help="random seed; the same seed gives byte-identical files (default 0)")
    p.add_argument("--repetitions", type=int, default=3, metavar="N",
                   help="palpations per material and tip (default 3)")
    p.add_argument("--force", action="store_true",
                   help="write into a non-empty OUT_DIR (a previous campaign is replaced)")
    p.add_argument("--noise-pp", type=float, default=PAPER_NOISE_PP, metavar="N",
                   help="peak-to-peak force noise in newtons, sigma = pp/6 (default %(default)g)")
    p.add_argument("--ar1", type=float, default=0.0, metavar="PHI",
                   help="AR(1) coefficient of the force noise, |PHI| < 1 (default 0: white)")
    p.add_argument("--gt-specimens", type=int, default=5, metavar="N",
                   help="compression tests per material (default 5)")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    """Write the campaign and say where and what; return 0.  Bad options raise InputError."""
    out = simulate_campaign(
        args.out_dir,
        seed=args.seed,
        repetitions=args.repetitions,
        overwrite=args.force,
        noise_pp=args.noise_pp,
        noise_ar1=args.ar1,
        gt_specimens=args.gt_specimens,
    )
    n_mat, n_tip = len(PAPER_MATERIALS), len(PAPER_TIPS)
    noise = f"{format_force(args.noise_pp, 6)} p-p"
    noise += f", AR(1) phi = {args.ar1:g}" if args.ar1 else ", white"
    print(f"wrote a synthetic campaign to {out} (seed {args.seed}, noise {noise}):")
    print(f"  {n_mat * n_tip * args.repetitions} traces ({n_mat} materials x {n_tip} tips x "
          f"{args.repetitions} repetitions) in traces/, listed in manifest.csv")
    if args.gt_specimens:
        print(f"  {n_mat * args.gt_specimens} Instron-style compression exports in "
              "groundtruth/ (listed in groundtruth/manifest.csv)")
    print("  true values in truth.csv, truth_groundtruth.csv and truth_materials.csv")
    return 0
