"""``palpbayes replay TRACE --target 2%``: where would online estimation have stopped?"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd

from ..campaign import layout
from ..contact import DEFAULT_NU, DEFAULT_NU_NOTE, check_nu
from ..errors import InputError
from ..fitdata import ModelSpec
from ..io.atomic import write_csv_atomic, write_with
from ..online import StoppingRule, replay
from ..units import format_force, format_length, format_pressure
from .options import add_nu_option, add_trace_options, thickness_from_args, trace_from_args

__all__ = ["register", "run", "parse_fraction"]


def parse_fraction(text: str) -> float:
    """'2%' -> 0.02, '0.02' -> 0.02 (a relative half-width)."""
    t = str(text).strip()
    try:
        v = float(t[:-1]) / 100 if t.endswith("%") else float(t)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a fraction: give e.g. 2% or 0.02") from None
    if not 0 < v < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must lie between 0 and 100 %")
    return v


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "replay", help="replay a recorded trace as if live: where would it have stopped?",
        description="Feed a recorded trace to the online estimator in chunks, as a robot "
        "would stream it, and show where the stopping rule fires: time, depth and peak force, "
        "E then against E from the whole trace, and the interval narrowing with depth.",
    )
    p.add_argument("input", metavar="TRACE", help="trace CSV")
    p.add_argument("--target", type=parse_fraction, default=None, metavar="FRACTION",
                   help="target statistical precision: stop when the 90 %% interval of E "
                   "from the data (noise and surface; not the budget's nu, tip radius, gain "
                   "and compliance) is within ± this of E (e.g. 2%%); the budget interval is "
                   "printed beside it")
    p.add_argument("--max-force", type=float, default=None, metavar="N",
                   help="stop at this force above the baseline [N]")
    p.add_argument("--max-depth", type=float, default=None, metavar="M",
                   help="stop at this depth below the estimated surface [m]")
    p.add_argument("--chunk", type=int, default=100, metavar="SAMPLES",
                   help="samples per update (default 100: 0.2 s at a UR robot's 500 Hz)")
    p.add_argument("--noise", choices=("gaussian", "ar1"), default="gaussian",
                   help="noise model (default gaussian)")
    p.add_argument("--noise-pp", type=float, default=None, metavar="N",
                   help="sensor peak-to-peak noise [N] (default: 6 sd of the baseline)")
    add_nu_option(p, manifest=False, summary=False)
    p.add_argument("--bonding", choices=("bonded", "free"), default=None,
                   help="base of a layer of known --thickness: bonded to it or free (lying "
                        "on it without friction); required with --thickness, because the "
                        "online estimator takes one base (the offline fit weighs both)")
    p.add_argument("--truth", type=float, default=None, metavar="PA",
                   help="true modulus [Pa] of a simulated trace, drawn on the figure")
    p.add_argument("--out", metavar="DIR", default=None,
                   help=f"write {layout.REPLAY_HISTORY}, {layout.REPLAY_SUMMARY} and "
                        f"{layout.REPLAY_FIGURE} here")
    add_trace_options(p)


def _show(label: str, s, budget) -> str:
    """Two lines: where (time, depth, peak force), E with its statistical 90 % interval and
    half-width (what --target tests), then the budget's 90 % interval and its half-width."""
    med = s.E.median
    rel = 100 * max(med - budget.lo, budget.hi - med) / med
    return (f"{label:<14} t = {s.t:7.3f} s  depth {format_length(s.depth):>9}  peak force "
            f"{format_force(s.peak_force):>9}  E = {format_pressure(med)} "
            f"[{format_pressure(s.E.lo)}, {format_pressure(s.E.hi)}]  "
            f"(statistical ±{100 * s.E.rel_half_width:.2g} %)\n"
            f"{'':<14} with the budget: [{format_pressure(budget.lo)}, "
            f"{format_pressure(budget.hi)}]  (±{rel:.2g} %)")


def _layer(args: argparse.Namespace) -> dict:
    """``thickness`` and ``bonding`` of the online model from --thickness and --bonding (a
    thickness is never dropped: the half-space would read a thin block as stiffer)."""
    if str(getattr(args, "thickness", None) or "").strip().lower() == "unknown":
        raise InputError("--thickness unknown: online estimation needs a known thickness "
                         "(or none, for a half-space); fit the whole trace with "
                         "'palpbayes fit ... --thickness unknown' to infer it")
    h = thickness_from_args(args)
    if h is None:
        if args.bonding is not None:
            raise InputError("--bonding is the base of a layer: give --thickness M too")
        return {}
    if args.bonding is None:
        raise InputError(f"--thickness {h:g} m: give the layer's base, --bonding bonded "
                         "(glued, or on a plate it cannot slide on) or --bonding free "
                         "(lubricated); the online estimator takes one base")
    return {"thickness": h, "bonding": args.bonding}


def run(args: argparse.Namespace) -> int:
    if args.target is None and args.max_force is None and args.max_depth is None:
        raise InputError("give a stopping rule: --target 2% (precision), --max-force N or "
                         "--max-depth M")
    rule = StoppingRule(target=args.target, max_force=args.max_force,
                        max_depth=args.max_depth)
    trace = trace_from_args(args)
    model = ModelSpec(trace.tip, nu=DEFAULT_NU if args.nu is None else check_nu(args.nu),
                      **_layer(args))
    res = replay(trace, model, rule=rule, chunk=args.chunk, noise=args.noise,
                 noise_pp=args.noise_pp)
    s, f = res.at_stop, res.final
    print("E: median [90 % interval]; statistical: from the data alone (what --target tests); "
          "with the budget: also nu, tip radius, gain and compliance")
    if model.has_layer:
        print(f"layer: {format_length(model.thickness)} thick on a {model.bonding} base")
    if s is None:
        print("the stopping rule never fired: the whole trace was needed")
    else:
        print(_show(f"stop ({s.stop})", s, res.budget_at_stop))
    print(_show("whole trace", f, res.budget_final))
    summary = res.summary()
    if s is not None:
        print(f"saved against the recorded protocol: {summary['depth_saved_pct']:.0f} % of the "
              f"depth, {summary['force_saved_pct']:.0f} % of the peak force")
    for flag in f.flags:
        print(f"warning: {flag}")
    if args.nu is None:
        print(f"note: {DEFAULT_NU_NOTE.replace(', or a nu column in the manifest', '')}")
    if args.out:
        from ..plots.online import plot_replay

        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        write_csv_atomic(res.history, out / layout.REPLAY_HISTORY)
        write_csv_atomic(pd.DataFrame([summary]), out / layout.REPLAY_SUMMARY)
        fig = plot_replay(res.history, stop_n=None if s is None else s.n, target=args.target,
                          truth=args.truth, title=trace.trace_id)
        write_with(lambda tmp: fig.savefig(tmp, dpi=150, format="png"),
                   out / layout.REPLAY_FIGURE, suffix=".png")
        print(f"wrote {out / layout.REPLAY_HISTORY}, {out / layout.REPLAY_SUMMARY} and "
              f"{out / layout.REPLAY_FIGURE}")
    return 0
