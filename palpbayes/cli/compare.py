"""``palpbayes compare RESULTS_DIR [--groundtruth FILE] [--seed N]`` (docs/design.md §7).

Reads ``RESULTS_DIR/summary.csv`` and the posteriors written by ``palpbayes fit`` on a campaign,
pools the Bayesian fits per material × tip (:mod:`palpbayes.pooling`), compares least squares,
Bayes, the ground truth and the paper's published numbers (:mod:`palpbayes.campaign.comparison`),
writes ``comparison.csv``, ``pooled.csv`` and ``budget.csv`` into RESULTS_DIR (atomically) and
prints the comparison in the paper's layout.
"""

from __future__ import annotations

import argparse

from .. import outputs

__all__ = ["register", "run"]


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``compare`` subcommand to an argparse ``subparsers`` object; return its parser."""
    p = subparsers.add_parser(
        "compare",
        help="compare ground truth, least squares and Bayes per material and tip",
        description=(
            "Pool the per-trace fits of a results folder per material x tip (hierarchical "
            "model with the uncertainty budget applied once per group), compare with the "
            "Instron ground truth and the paper's published robot estimates, write "
            "comparison.csv, pooled.csv and budget.csv into RESULTS_DIR and print the table."),
    )
    p.add_argument("results_dir", metavar="RESULTS_DIR",
                   help="the --out folder of 'palpbayes fit' on a campaign manifest")
    p.add_argument("--groundtruth", metavar="FILE", default=None,
                   help="groundtruth_summary.csv from 'palpbayes groundtruth', or a ground-truth "
                        "manifest / compression export / folder of exports to analyse "
                        "(default: the campaign's groundtruth/ folder, if any)")
    p.add_argument("--seed", type=int, default=None, metavar="N",
                   help="seed of the pooling sampler (default: the fit's seed)")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    """Run ``palpbayes compare``; return 0.  Bad input raises InputError (exit status 2)."""
    from ..campaign.comparison import compare  # here: building the parser stays quick

    result = compare(args.results_dir, groundtruth=args.groundtruth, seed=args.seed)
    print(result.format())
    if "bayes" in set(result.comparison["method"].astype(str)):
        print("\nnote: the Bayes cells above are the prediction for a NEW SPECIMEN, median [90 % "
              "interval] (comparison.csv E_new_pa [E_new_lo_pa, E_new_hi_pa]); the pooled "
              "MATERIAL modulus (E_pa ± E_sd_pa) is the report's 'Bayes material E ± sd' column")
    res = result.results_dir
    print(f"\nwrote {res / outputs.COMPARISON}, {res / outputs.POOLED} and {res / outputs.BUDGET}")
    return 0
