"""``palpbayes report [INPUT] [-o FILE.pdf]``: the PDF report of a campaign (docs/design.md §7).

INPUT is one of

* a results folder (it has ``summary.csv``, or ``rheology.csv`` from ``fit --rheology``, or
  both): the report is built from it as it is (viscoelastic fits get their own pages, read from
  ``rheology.csv`` and ``rheology/*.nc``);
* a campaign folder (it has ``manifest.csv``) or a campaign manifest: the campaign is fitted
  with both methods, its ground truth analysed (if it has ``groundtruth/``) and compared, into
  ``--out`` (default ``palpbayes-results/`` in the current folder; a folder fitted before from
  the same campaign is reused fit by fit: a trace whose file, manifest row, options and
  palpbayes version are unchanged keeps its fit, the others are refitted, and the console
  says how many of each), then the report is built;
* nothing: the shipped example campaign ``data/example-campaign`` of a source checkout.

The PDF goes to ``-o FILE.pdf`` (default ``report.pdf`` in the results folder).  See
:mod:`palpbayes.reporting` for the pages and :mod:`palpbayes.campaign.pipeline` for the fitting.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .. import outputs
from ..errors import InputError
from .options import add_model_options, options_from_args

__all__ = ["register", "run", "resolve_input", "plan_line", "DEFAULT_OUT"]

#: Results folder for a campaign INPUT when ``--out`` is not given.
DEFAULT_OUT = "palpbayes-results"


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``report`` subcommand to an argparse ``subparsers`` object; return its parser."""
    p = subparsers.add_parser(
        "report",
        help="PDF report of a results folder or a campaign (no INPUT: the shipped example)",
        description=(
            "Write a multi-page PDF report: settings, the comparison of ground truth, least "
            "squares and Bayes per material and tip (the paper's Table III), a page per "
            "material and tip with the force-depth fit and posteriors, convergence "
            "diagnostics, the uncertainty budget and the methods; viscoelastic fits (fit "
            "--rheology) get a table of their parameters and a page per trace and model. INPUT "
            "is a results folder (with summary.csv and/or rheology.csv), a campaign folder or "
            "manifest (fitted first, into --out), or nothing for the shipped example "
            "campaign."),
    )
    p.add_argument("input", nargs="?", metavar="INPUT", default=None,
                   help="results folder, campaign folder or campaign manifest (default: the "
                        "shipped example campaign)")
    p.add_argument("-o", "--output", metavar="FILE.pdf", default=None,
                   help="the PDF to write (default: report.pdf in the results folder)")
    p.add_argument("--out", metavar="DIR", default=None,
                   help=f"results folder when INPUT is a campaign (default ./{DEFAULT_OUT})")
    p.add_argument("--force", action="store_true",
                   help="refit every trace of a campaign into --out, even into another "
                        "campaign's results (default: a re-run reuses each fit whose trace, "
                        "manifest row, options and palpbayes version are unchanged, and "
                        "refits the others)")
    add_model_options(p)
    # the report compares the two methods: fit both unless told otherwise
    p.set_defaults(method="both", func=run)
    return p


def resolve_input(value: str | None) -> tuple[str, Path]:
    """Classify INPUT: ``("results", folder)`` or ``("campaign", manifest)``.

    Raises
    ------
    InputError
        INPUT does not exist or is neither a results folder, a campaign folder nor a
        manifest; no INPUT and no shipped example.
    """
    from ..campaign.pipeline import example_campaign_dir
    from ..io.manifest import is_manifest

    if value is None:
        return "campaign", example_campaign_dir() / "manifest.csv"
    p = Path(value)
    if not p.exists():
        raise InputError(f"{p}: no such file or folder")
    if p.is_dir():
        if (p / outputs.SUMMARY).is_file() or (p / outputs.RHEOLOGY_TABLE).is_file():
            return "results", p
        if (p / "manifest.csv").is_file():
            return "campaign", p / "manifest.csv"
        raise InputError(f"{p}: neither a results folder ({outputs.SUMMARY} from 'palpbayes fit', "
                         f"{outputs.RHEOLOGY_TABLE} from 'palpbayes fit --rheology') nor a "
                         "campaign folder (manifest.csv)")
    if is_manifest(p):
        return "campaign", p
    raise InputError(f"{p}: not a campaign manifest (a CSV with 'file' and 'tip' columns); "
                     "give a results folder, a campaign folder or a manifest")


def run(args: argparse.Namespace) -> int:
    """Fit if needed, build the report, print a short summary and the PDF's path."""
    from ..campaign.pipeline import run_pipeline
    from ..campaign.results import load_results
    from ..reporting import (
        BAYES_E_COL,
        BAYES_NEW_COL,
        GT_COL,
        HERTZ_COL,
        INSTRON_COL,
        INSTRON_COVER_COL,
        LS_E_COL,
        coverage_counts,
        report,
        summary_table,
    )

    kind, path = resolve_input(args.input)
    if args.output is not None and not str(args.output).lower().endswith(".pdf"):
        raise InputError(f"-o {args.output}: the report is a PDF; give a name ending in .pdf")
    if kind == "campaign":
        options = options_from_args(args)
        out = Path(args.out) if args.out is not None else Path.cwd() / DEFAULT_OUT
        print(f"campaign {path} into {out} (methods: {options.method}, seed {options.seed})")
        run_pipeline(path, out, options, workers=args.workers, force=args.force,
                     progress=args.progress, scheduler=args.scheduler,
                     on_plan=lambda *plan: print(plan_line(*plan), flush=True))
        results = out
    else:
        if args.out is not None:
            raise InputError(f"--out is for a campaign INPUT; {path} is already a results "
                             "folder (use -o FILE.pdf to choose the report's name)")
        results = path
        if not (path / outputs.SUMMARY).is_file():  # viscoelastic fits only
            info = report(path, args.output, seed=args.seed)
            print(f"report: {info.n_pages} pages, {info.n_traces} trace(s), "
                  f"{_rheology_line(info)}")
            print(f"wrote {info.path} (from the results folder {info.results_shown})")
            return 0
    res = load_results(results)
    info = report(res, args.output, seed=args.seed)
    table = summary_table(res)
    keep = [c for c in ("Material", "Tip", GT_COL, LS_E_COL, BAYES_E_COL, BAYES_NEW_COL,
                        "Bayes covers GT", INSTRON_COL, INSTRON_COVER_COL, HERTZ_COL,
                        "LS mean E ± sd over traces [kPa]",
                        "Bayes mean E ± sd over traces [kPa]") if c in table.columns]
    if len(table):
        print(table[keep].to_string(index=False))
    cover = coverage_counts(res)
    inst = cover.pop("instron", None)
    if cover:
        print("new-specimen 90 % interval covers the ground truth: "
              + ", ".join(f"{'Bayes' if m == 'bayes' else 'LS'} {k}/{n}"
                          for m, (k, n) in cover.items()))
    if inst is not None:
        print(f"like for like, the Bayesian Instron-equivalent interval of a new specimen (the "
              f"block's twin, its platens) covers the Instron in {inst[0]}/{inst[1]}")
    flagged = f"{info.n_flagged} flagged" if info.n_flagged else "all converged"
    line = f"report: {info.n_pages} pages, {info.n_traces} traces, Bayesian fits {flagged}"
    if info.n_pooled_flagged:
        line += f"; {info.n_pooled_flagged} pooled group(s) not converged (marked (!))"
    if info.n_rheology:
        line += f"; {_rheology_line(info)}"
    print(line)
    print(f"wrote {info.path} (from the results folder {info.results_shown})")
    return 0


def plan_line(reused: list[str], todo: list[str], reason: str | None) -> str:
    """What a campaign run reuses and fits, in one line: 'fitting 27 traces', 'reusing 26
    fits, refitting 1: White_sphere_r01' or 'refitting all 27 traces (it was fitted with other
    options)' (``reason``: why no fit is reused)."""
    if reason is not None:
        return f"refitting all {len(todo)} traces ({reason})"
    if not reused:
        return f"fitting {len(todo)} traces"
    line = f"reusing {len(reused)} fits (inputs unchanged), refitting {len(todo)}"
    if todo:
        shown = ", ".join(todo[:5]) + (f" and {len(todo) - 5} more" if len(todo) > 5 else "")
        line += f": {shown}"
    return line


def _rheology_line(info) -> str:
    """'3 viscoelastic fit(s), model check passed' or '…, 1 failed the model check'."""
    failed = info.n_rheology_failed_check
    return (f"{info.n_rheology} viscoelastic fit(s), "
            + (f"{failed} failed the model check" if failed else "model check passed"))
