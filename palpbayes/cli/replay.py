"""``palpbayes replay TRACE --target 5%``: where would online estimation have stopped?

The target is tested on the interval of E with the uncertainty budget (``--target-on full``)
unless ``--target-on stat`` (:data:`~palpbayes.cli.online_options.DEFAULT_TARGET_ON`); both
intervals are printed, and the model checks of the offline fit are run on the samples up to
the stop.  The interval with the budget is ``fit``'s ``E_budget_lo_pa..E_budget_hi_pa``, not
its ``E_lo_pa..E_hi_pa``: the model form, which widens that one when a check finds a material
misfit, is not computed online (the console says so, and says it again under checks that find
one).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .. import outputs
from ..checks import checks_summary
from ..contact import DEFAULT_NU_NOTE
from ..units import format_force, format_length, format_pressure
from .console import _wrap
from .online_options import add_online_options, parse_fraction, request_from_args
from .options import add_trace_options, trace_from_args

__all__ = ["register", "run", "parse_fraction", "check_lines", "INTERVALS_NOTE", "MISFIT_NOTE"]


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "replay", help="replay a recorded trace as if live: where would it have stopped?",
        description="Feed a recorded trace to the online estimator in chunks, as a robot "
        "would stream it, and show where the stopping rule fires: time, depth and peak force, "
        "E then against E from the whole trace, and the interval narrowing with depth; "
        "the model checks of 'palpbayes fit' are run on the samples up to the stop.",
    )
    p.add_argument("input", metavar="TRACE", help="trace CSV")
    add_online_options(p)
    p.add_argument("--truth", type=float, default=None, metavar="PA",
                   help="true modulus [Pa] of a simulated trace, drawn on the figure")
    p.add_argument("--out", metavar="DIR", default=None,
                   help=f"write {outputs.REPLAY_HISTORY}, {outputs.REPLAY_SUMMARY} and "
                        f"{outputs.REPLAY_FIGURE} here")
    add_trace_options(p)


#: What replay's two intervals hold, printed above its lines: the one with the budget is
#: 'fit''s E_budget_lo..E_budget_hi, not its E_lo..E_hi (the model form is not run online).
INTERVALS_NOTE = (
    "E: median [90 % interval]; statistical: from the data alone; with the budget: also nu, "
    "tip radius, gain and compliance, the interval 'fit' reports as E_budget_lo..E_budget_hi "
    "(summary.csv E_budget_lo_pa, E_budget_hi_pa); its E_lo..E_hi adds the model form when a "
    "check finds a material misfit, which replay does not compute")
#: Said under the checks at the stop when they find a material misfit.
MISFIT_NOTE = (
    "note: with this material misfit 'palpbayes fit' widens E's interval by the model form "
    "(the envelope of its alternatives' 90 % intervals, E_lo..E_hi), often by tens of per cent; "
    "the intervals here hold the budget only: fit the trace for the full one")


def _show(label: str, s, budget) -> str:
    """Two lines: where (time, depth, peak force), E with its statistical 90 % interval and
    half-width, then the full 90 % interval (with the budget) and its half-width, both
    (hi − lo)/(2·median) as --target tests them."""
    med = s.E.median
    return (f"{label:<14} t = {s.t:7.3f} s  depth {format_length(s.depth):>9}  peak force "
            f"{format_force(s.peak_force):>9}  E = {format_pressure(med)} "
            f"[{format_pressure(s.E.lo)}, {format_pressure(s.E.hi)}]  "
            f"(statistical ±{100 * s.E.rel_half_width:.2g} %)\n"
            f"{'':<14} with the budget: [{format_pressure(budget.lo)}, "
            f"{format_pressure(budget.hi)}]  (±{100 * budget.rel_half_width:.2g} %)")


def check_lines(checks, where: str) -> list[str]:
    """The model checks run at ``where`` in words: one line when all pass, else a line per
    failure (material ones as warnings, negligible ones as info)."""
    if not checks:
        return [f"model checks {where}: too few samples to run them"]
    summary = checks_summary(checks)
    names = ", ".join(c.name for c in checks)
    if not summary["flags"]:
        return [f"model checks {where}: all {len(checks)} passed ({names})"]
    head = ("model checks {where}: material misfit ({bad})" if not summary["model_ok"]
            else "model checks {where}: no material misfit")
    return [head.format(where=where, bad=summary["misfit_checks"])] + [
        f"  {'info' if flag.startswith('info: ') else 'warning'}: "
        f"{flag.removeprefix('info: ')}" for flag in summary["flags"]]


def run(args: argparse.Namespace) -> int:
    request = request_from_args(args)  # palpbayes.replay builds the same
    trace = trace_from_args(args)
    res = request.run(trace)
    s, f, rule, model = res.at_stop, res.final, res.rule, res.model
    tested = ("the one with the budget (--target-on full)" if rule.target_on == "full"
              else "the statistical one (--target-on stat)")
    for line in _wrap(INTERVALS_NOTE):
        print(line)
    if rule.target is not None:
        print(f"--target ±{100 * rule.target:.3g} % is tested on {tested}")
    if model.has_layer:
        print(f"layer: {format_length(model.thickness)} thick on a {model.bonding} base")
    if s is None:
        print("the stopping rule never fired: the whole trace was needed")
    else:
        print(_show(f"stop ({s.stop})", s, res.budget_at_stop))
        for line in check_lines(res.checks_at_stop, "at the stop"):
            print(line)
        if res.checks_at_stop and not checks_summary(res.checks_at_stop)["model_ok"]:
            for line in _wrap(MISFIT_NOTE):
                print(line)
    print(_show("whole trace", f, res.budget_final))
    row = res.row
    if s is not None:
        print(f"saved against the recorded protocol: {row['depth_saved_pct']:.0f} % of the "
              f"depth, {row['force_saved_pct']:.0f} % of the peak force")
    for flag in f.flags:
        print(f"warning: {flag}")
    if args.nu is None:
        print(f"note: {DEFAULT_NU_NOTE.replace(', or a nu column in the manifest', '')}")
    if args.out:
        out = res.save(Path(args.out), truth=args.truth)
        print(f"wrote {out / outputs.REPLAY_HISTORY}, {out / outputs.REPLAY_SUMMARY} and "
              f"{out / outputs.REPLAY_FIGURE}")
    return 0
