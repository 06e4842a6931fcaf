"""``palpbayes next DIR``: where to press next to find a lump, and when to stop.

DIR is a search state (``palpbayes next DIR --init ...``, then presses added by ``palpbayes
follow --map DIR`` or by the user) or the output folder of ``palpbayes map``.  Prints the
posterior after the presses so far (P(lump), the centre and its 90 % radius, the apparent
size) and the next press(es), or the decision (:mod:`palpbayes.active`).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import textwrap

from ..errors import InputError
from .options import add_tip_options, tip_from_args

__all__ = ["register", "run", "answer_json", "answer_text", "state_overrides",
           "search_rule_from_args", "add_rule_options", "EXIT_DECIDED", "EXIT_GO_ON",
           "EXIT_UNDECIDED"]

#: Exit status: the search has decided (lump or none).
EXIT_DECIDED = 0
#: Exit status: press again (the next press is printed).
EXIT_GO_ON = 10
#: Exit status: stopped undecided (the budget, or no candidate left).
EXIT_UNDECIDED = 11

EPILOG = f"""\
exit status:
  {EXIT_DECIDED}    decided: a lump (P >= --p-decide, centre placed) or none (P <= 1 - it)
  {EXIT_GO_ON}   not decided: the next press is printed
  {EXIT_UNDECIDED}   stopped undecided: the --budget is spent or no candidate is left
  2    bad input (the message names the file, column or option)

The criteria (--criterion): eig, expected information gain on lump presence and centre
(Lindley 1956); lse, level-set estimation of {{E > k x background}} (Gotovos et al. 2013);
ucb, upper confidence bound of the lump's excess (Srinivas et al. 2010), the baseline."""


def _floats(text: str, n: int, what: str) -> tuple[float, ...]:
    try:
        vals = tuple(float(v) for v in str(text).split(","))
    except ValueError:
        vals = ()
    if len(vals) != n or not all(map(math.isfinite, vals)):
        raise InputError(f"{what} {text!r}: give {n} numbers separated by commas [m]")
    return vals


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "next", help="where to press next to find a lump, and when to stop",
        description=textwrap.fill(
            "Score candidate presses on the footprint by a stated criterion against the lump "
            "posterior of the presses so far (one lump or none, its centre and size), print "
            "the next press or batch, or the decision: a lump (P(lump) >= --p-decide and its "
            "centre's 90 % radius <= --centre-radius) or none (P(lump) <= 1 - --p-decide).",
            90), epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("state", metavar="DIR",
                   help="a search-state folder (search.json, presses.csv) or the --out folder "
                        "of 'palpbayes map'")
    p.add_argument("-k", type=int, default=1, help="presses to return (a batch; default 1)")
    p.add_argument("--criterion", choices=("eig", "lse", "ucb"), default="eig",
                   help="how candidates are scored (default eig; below)")
    p.add_argument("--json", action="store_true", help="one JSON object on stdout")
    p.add_argument("--out", metavar="FILE", help="also write the answer as a CSV table "
                   "(NextPresses.table(): one row per next press with the posterior summary)")
    p.add_argument("--plot", metavar="FILE", help="write the press sequence with P(lump) "
                                                  "after each press (png or pdf)")
    add_rule_options(p.add_argument_group("stopping rule"))
    s = p.add_argument_group("specimen and candidates (override the state's)")
    s.add_argument("--footprint", metavar="X0,X1,Y0,Y1",
                   help="[m] the rectangle that may be pressed and may hold the lump")
    s.add_argument("--keep-out", action="append", metavar="X,Y,R", default=None,
                   help="[m] a disc not to press (repeat for more)")
    s.add_argument("--min-spacing", type=float, metavar="M",
                   help="[m] no press closer than M to another (default 0.001)")
    s.add_argument("--min-excess", type=float, metavar="X",
                   help="smallest apparent peak excess that counts as a lump (default 0.03)")
    s.add_argument("--background", choices=("white", "correlated"), default=None,
                   help="the heterogeneity's model: independent press to press (white, the "
                        "default) or with a spatially correlated field (correlated)")
    s.add_argument("--thickness", type=float, metavar="M", help="[m] block thickness")
    i = p.add_argument_group("--init: create the state folder DIR (no press yet)")
    i.add_argument("--init", action="store_true", help="create DIR's search.json")
    i.add_argument("--depth", type=float, metavar="M",
                   help="[m] indentation depth of a press that gives none (default the "
                        "smallest of --depths, else 10 %% of --thickness)")
    i.add_argument("--depths", metavar="F1,F2,...", default=None,
                   help="allowed indentation depths as fractions of --thickness (e.g. "
                        "0.1,0.2): 'follow --map' refuses a press at any other depth; with "
                        "two or more the search chooses each press's depth (eig: the most "
                        "information per second of pressing)")
    i.add_argument("--press-overhead", type=float, metavar="S", default=None,
                   help="[s] time of a press besides the indentation (move and approach; "
                        "default 3), for the cost of each depth")
    i.add_argument("--max-force", type=float, metavar="N", default=None,
                   help="[N] largest force a press may reach: 'follow --map' refuses a press "
                        "whose predicted peak force exceeds it and stops one that reaches it")
    i.add_argument("--force", action="store_true", help="replace DIR's state")
    add_tip_options(i)
    p.set_defaults(input="next --init")


def add_rule_options(g) -> None:
    """``--p-decide``, ``--centre-radius``, ``--budget`` (read by :func:`search_rule_from_args`;
    ``next``, ``follow --map``)."""
    g.add_argument("--p-decide", type=float, default=0.95, metavar="P",
                   help="decide at P(lump) >= P or <= 1 - P (default 0.95)")
    g.add_argument("--centre-radius", type=float, default=2e-3, metavar="M",
                   help="a lump is placed when its centre's 90 %% radius is <= M (default "
                        "0.002)")
    g.add_argument("--budget", type=int, default=None, metavar="N",
                   help="stop undecided after N presses")


def state_overrides(args: argparse.Namespace) -> dict:
    """The :class:`~palpbayes.active.SearchState` fields the options replace."""
    out = {"min_spacing": args.min_spacing, "min_excess": args.min_excess,
           "background": getattr(args, "background", None)}
    if args.footprint is not None:
        out["footprint"] = _floats(args.footprint, 4, "--footprint")
    if args.keep_out is not None:
        out["keep_out"] = tuple(_floats(z, 3, "--keep-out") for z in args.keep_out)
    return out


def search_rule_from_args(args: argparse.Namespace):
    from ..active import SearchStopRule

    return SearchStopRule(p_decide=args.p_decide, centre_radius=args.centre_radius,
                          max_presses=args.budget)


def _init(args: argparse.Namespace) -> int:
    from ..active.files import init_state
    from ..inclusion import contact_radius

    if args.footprint is None or args.thickness is None:
        raise InputError("--init needs --footprint X0,X1,Y0,Y1 and --thickness M (and the "
                         "tip: --tip and its size)")
    from ..active.safety import PressLimits, parse_depths

    tip = tip_from_args(args)
    fractions = () if args.depths is None else parse_depths(args.depths)
    depth = (args.depth if args.depth is not None else
             min(fractions) * args.thickness if fractions else 0.1 * args.thickness)
    if not (math.isfinite(depth) and depth > 0):
        raise InputError(f"--depth {args.depth!r} must be > 0 [m]")
    PressLimits(depths=fractions, max_force=args.max_force, depth=depth)  # checked
    limits = {k: v for k, v in (("depths", list(fractions) or None),
                                ("max_force_n", args.max_force)) if v is not None}
    a = contact_radius(tip, depth)
    others = sorted(f * args.thickness for f in fractions
                    if not math.isclose(f * args.thickness, depth, rel_tol=1e-9))
    if others:  # the search chooses the depth: the reference first, then the others
        ds = [depth, *others]
        limits.update(press_depths_m=ds, contact_radii_m=[contact_radius(tip, d) for d in ds])
        if args.press_overhead is not None:
            limits["press_overhead_s"] = args.press_overhead
    elif args.press_overhead is not None:
        raise InputError("--press-overhead prices a choice of depths: give --depths with two "
                         "or more")
    over = {k: v for k, v in state_overrides(args).items() if v is not None}
    extra = {f"{k}_m" if k == "min_spacing" else k: v for k, v in over.items()
             if k in ("min_spacing", "min_excess", "background")}
    init_state(args.state, footprint=over["footprint"], contact_radius=a,
               thickness=args.thickness, keep_out=over.get("keep_out", ()),
               overwrite=args.force, tip=tip.kind, tip_radius_m=tip.radius, depth_m=depth,
               **limits, **extra)
    said = "".join([f"; depths {args.depths} of the thickness" if fractions else "",
                    f"; max force {args.max_force:g} N" if args.max_force else ""])
    print(f"search state in {args.state}: footprint {args.footprint} m, contact radius "
          f"{1e3 * a:.2f} mm at {1e3 * depth:.2f} mm, block {1e3 * args.thickness:g} mm"
          f"{said}; now press (palpbayes follow --map {args.state}) and ask 'palpbayes next "
          f"{args.state}'")
    return 0


def _num(v):
    return None if v is None or not math.isfinite(v) else float(v)


def answer_json(ans) -> str:
    """The answer of :func:`palpbayes.active.next_presses` as one JSON object: ``event``
    "next" (press again) or "done" (the search has stopped), ``decision``, ``reason``, the
    posterior summary and ``presses`` (order, x_m, y_m, score, criterion)."""
    rows = [{k: (_num(v) if isinstance(v, float) else v) for k, v in r.items()}
            for r in ans.presses.to_dict("records")]
    for r in rows:
        r["order"] = int(r["order"])
    return json.dumps({"event": "done" if ans.stop else "next", "decision": ans.decision,
                       "reason": ans.reason,
                       **{k: _num(v) if isinstance(v, float) else v
                          for k, v in ans.summary.items()}, "presses": rows})


def answer_text(ans) -> str:
    """The answer as lines of text."""
    s = ans.summary
    lines = [f"presses so far: {s['n']}  P(lump) = {s['p_lump']:.3f}"]
    if s["n"] and math.isfinite(s["x_m"]):
        lines.append(f"if a lump: centre ({1e3 * s['x_m']:.2f}, {1e3 * s['y_m']:.2f}) mm, 90 % "
                     f"radius {1e3 * s['centre_radius_m']:.2f} mm; apparent diameter (FWHM) "
                     f"{1e3 * s['size_m']:.1f} mm; apparent peak ratio "
                     f"{s['apparent_ratio']:.3f}; heterogeneity {s['tau']:.3f}")
    if ans.stop:
        what = {"lump": "DECIDED: a lump", "no lump": "DECIDED: no lump"}.get(
            ans.decision, "STOPPED undecided")
        lines.append(f"{what} ({ans.reason})")
    else:
        for r in ans.presses.itertuples():
            score = "" if not math.isfinite(r.score) else f"  ({r.criterion} {r.score:.4g})"
            depth = (f", depth {1e3 * r.depth_m:.2f} mm" if "depth_m" in ans.presses
                     and math.isfinite(r.depth_m) else "")
            lines.append(f"next press {r.order}: x {1e3 * r.x_m:.2f} mm, y {1e3 * r.y_m:.2f} "
                         f"mm{depth}{score}")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    if args.init:
        return _init(args)
    used = [o for o, v in (("--depth", args.depth), ("--depths", args.depths),
                           ("--max-force", args.max_force),
                           ("--press-overhead", args.press_overhead)) if v is not None]
    if used:
        raise InputError(f"{', '.join(used)} belong(s) to --init (they are recorded in the "
                         "state's search.json); give --init, or leave them out")
    from ..active import next_presses
    from ..active.files import read_state

    rule = search_rule_from_args(args)
    state = read_state(args.state, thickness=args.thickness, **state_overrides(args))
    ans = next_presses(state, args.k, criterion=args.criterion, rule=rule)
    print(answer_json(ans) if args.json else answer_text(ans), flush=True)
    if args.out:
        from ..io.atomic import write_csv_atomic

        write_csv_atomic(ans.table(), args.out, index=False)
        print(f"wrote {args.out}", file=sys.stderr)
    if args.plot and state.n == 0:
        print(f"note: no press yet, so no {args.plot}", file=sys.stderr)
    elif args.plot:
        from ..plots.active import plot_search

        plot_search(state, rule=rule).savefig(args.plot, dpi=150, bbox_inches="tight")
        print(f"wrote {args.plot}", file=sys.stderr)
    if ans.stop:
        return EXIT_DECIDED if ans.decision else EXIT_UNDECIDED
    return EXIT_GO_ON
