"""``palpbayes simulate OUT_DIR``: write a synthetic palpation campaign (docs/design.md §7).

The folder holds a manifest, one CSV per trace, Instron-like ground-truth exports and the true
values (see :mod:`palpbayes.sim.campaign`).  Its specimens are layers of the paper's thickness
lying on a rigid plate without friction (``--base free``; the paper's blocks rest on a plate).
The shipped example was made with::

    palpbayes simulate data/example-campaign --seed 2026 --repetitions 3

With ``--map`` it writes a stiffness-map phantom instead (:mod:`palpbayes.sim.map`): a grid of
palpations over a block hiding a stiff sphere, e.g.::

    palpbayes simulate phantom --map --grid 15x15 --step 3e-3 --lump-ratio 10
"""

from __future__ import annotations

import argparse
import re

from ..errors import InputError
from ..noise import PAPER_NOISE_PP
from ..paper import PAPER_MATERIALS, PAPER_TIPS
from ..sim import Inclusion, default_inclusion, read_map_truth, simulate_campaign, simulate_map
from ..units import format_force, format_length, format_pressure

__all__ = ["register", "run"]


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``simulate`` subcommand to an argparse ``subparsers`` object; return its parser."""
    p = subparsers.add_parser(
        "simulate",
        help="write a synthetic campaign folder (traces, manifest, ground truth, true values) "
             "or, with --map, a stiffness-map phantom",
        description=(
            "Simulate the paper's campaign: 3 foams (White/Pink/Grey) x 3 tips (flat, sphere, "
            "paraboloid) x REPETITIONS palpations, plus Instron-like compression tests, with "
            "the true values in truth.csv.  With --map: a grid of palpations over a block "
            "hiding a stiff sphere, with the true field in truth.csv and the lump in "
            "truth_lump.json."
        ),
    )
    p.add_argument("out_dir", metavar="OUT_DIR", help="output folder (must be empty)")
    p.add_argument("--seed", type=int, default=0, metavar="N",
                   help="random seed; the same seed gives byte-identical files (default 0)")
    p.add_argument("--force", action="store_true",
                   help="write into a non-empty OUT_DIR (a previous campaign or map is replaced)")
    p.add_argument("--noise-pp", type=float, default=PAPER_NOISE_PP, metavar="N",
                   help="peak-to-peak force noise in newtons, sigma = pp/6 (default %(default)g)")
    c = p.add_argument_group("campaign (without --map)")
    c.add_argument("--repetitions", type=int, default=None, metavar="N",
                   help="palpations per material and tip (default 3)")
    c.add_argument("--ar1", type=float, default=None, metavar="PHI",
                   help="AR(1) coefficient of the force noise, |PHI| < 1 (default 0: white)")
    c.add_argument("--gt-specimens", type=int, default=None, metavar="N",
                   help="compression tests per material (default 5)")
    c.add_argument("--base", type=_base, default=None, metavar="BASE",
                   help="the specimens as layers of their thickness on a rigid plate: 'free' "
                        "(lying on it without friction, the default), 'bonded', a partial bond "
                        "in [0, 1], or 'none' (half-spaces, the paper's model)")
    m = p.add_argument_group(
        "stiffness map (--map)", "a grid of palpations over a block hiding a stiff sphere; "
        "lengths in metres, the lump centred near the middle of the grid, off its nodes")
    m.add_argument("--map", action="store_true",
                   help="write a stiffness-map phantom instead of a campaign")
    m.add_argument("--grid", type=_grid, default=None, metavar="NXxNY",
                   help="palpations along x and y (default 15x15)")
    m.add_argument("--step", type=float, default=None, metavar="M",
                   help="grid spacing (default 3e-3)")
    m.add_argument("--background-e", type=float, default=None, metavar="PA",
                   help="background Young's modulus (default 50e3)")
    m.add_argument("--tip", choices=sorted(PAPER_TIPS), default=None,
                   help="the paper's tip (default paraboloid)")
    m.add_argument("--lump-ratio", type=float, default=None, metavar="R",
                   help="lump modulus / background (default 10)")
    m.add_argument("--lump-radius", type=float, default=None, metavar="M",
                   help="lump radius (default 6e-3)")
    m.add_argument("--lump-depth", type=float, default=None, metavar="M",
                   help="depth of the lump's centre (default 7e-3: 1 mm of cover)")
    m.add_argument("--lump-x", type=float, default=None, metavar="M", help="lump centre x")
    m.add_argument("--lump-y", type=float, default=None, metavar="M", help="lump centre y")
    m.add_argument("--no-lump", action="store_true", help="a homogeneous block")
    m.add_argument("--heterogeneity", type=float, default=None, metavar="CV",
                   help="point-to-point sd of ln E (default 0.03)")
    m.add_argument("--workers", type=int, default=None, metavar="N",
                   help="processes writing the traces (default 1)")
    p.set_defaults(func=run)
    return p


_MAP_ONLY = ("grid", "step", "background_e", "tip", "lump_ratio", "lump_radius", "lump_depth",
             "lump_x", "lump_y", "heterogeneity", "workers")
_LUMP = ("lump_ratio", "lump_radius", "lump_depth", "lump_x", "lump_y")
_CAMPAIGN_ONLY = ("repetitions", "ar1", "gt_specimens", "base")
#: How the campaign's specimens rest on their plate unless --base says otherwise.
DEFAULT_BASE = "free"


def _base(text: str):
    """argparse type of --base: a name, 'none' or a number in [0, 1]."""
    t = text.strip().lower()
    if t in ("bonded", "free", "none"):
        return t
    try:
        w = float(t)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"base {text!r} is not 'bonded', 'free', 'none' or a number in [0, 1]") from None
    if not 0.0 <= w <= 1.0:
        raise argparse.ArgumentTypeError(f"partial bond {text!r} must lie in [0, 1]")
    return w


def _grid(text: str) -> tuple[int, int]:
    """argparse type of --grid: 'NXxNY' with positive whole numbers."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*", text)
    if not match or min(int(match[1]), int(match[2])) < 1:
        raise argparse.ArgumentTypeError(
            f"grid {text!r} is not NXxNY with positive whole numbers, e.g. 15x15")
    return int(match[1]), int(match[2])


def _option(name: str) -> str:
    return "--" + name.replace("_", "-")


def _given(args: argparse.Namespace, names) -> list[str]:
    return [_option(n) for n in names if getattr(args, n, None) not in (None, False)]


def run(args: argparse.Namespace) -> int:
    """Write the campaign (or with ``--map`` the map phantom) and say where and what; return 0.

    Bad options, or options of the other mode, raise InputError (exit status 2).
    """
    if args.map:
        wrong = _given(args, _CAMPAIGN_ONLY)
        if wrong:
            raise InputError(f"{', '.join(wrong)} only apply to a campaign, not to --map; "
                             "drop them")
        return _run_map(args)
    wrong = _given(args, (*_MAP_ONLY, "no_lump"))
    if wrong:
        raise InputError(f"{', '.join(wrong)} only apply with --map (a stiffness-map "
                         "phantom); add --map or drop them")
    for name, default in (("repetitions", 3), ("ar1", 0.0), ("gt_specimens", 5),
                          ("base", DEFAULT_BASE)):
        if getattr(args, name) is None:
            setattr(args, name, default)
    out = simulate_campaign(
        args.out_dir,
        seed=args.seed,
        repetitions=args.repetitions,
        overwrite=args.force,
        noise_pp=args.noise_pp,
        noise_ar1=args.ar1,
        gt_specimens=args.gt_specimens,
        base=None if args.base == "none" else args.base,
    )
    n_mat, n_tip = len(PAPER_MATERIALS), len(PAPER_TIPS)
    noise = f"{format_force(args.noise_pp, 6)} p-p"
    noise += f", AR(1) phi = {args.ar1:g}" if args.ar1 else ", white"
    print(f"wrote a synthetic campaign to {out} (seed {args.seed}, noise {noise}):")
    print(f"  {n_mat * n_tip * args.repetitions} traces ({n_mat} materials x {n_tip} tips x "
          f"{args.repetitions} repetitions) in traces/, listed in manifest.csv")
    names = {"none": "half-spaces", "free": "layers lying free on a rigid plate",
             "bonded": "layers bonded to a rigid plate"}
    rest = (names[args.base] if isinstance(args.base, str)
            else f"layers partly bonded ({args.base:g}) to a rigid plate")
    print(f"  specimens simulated as {rest}")
    if args.gt_specimens:
        print(f"  {n_mat * args.gt_specimens} Instron-style compression exports in "
              "groundtruth/ (listed in groundtruth/manifest.csv)")
    print("  true values in truth.csv, truth_groundtruth.csv and truth_materials.csv")
    return 0


def _run_map(args: argparse.Namespace) -> int:
    """The ``--map`` branch of :func:`run`."""
    nx, ny = args.grid or (15, 15)
    step = 3e-3 if args.step is None else args.step
    lump_given = _given(args, _LUMP)
    if args.no_lump and lump_given:
        raise InputError(f"--no-lump contradicts {', '.join(lump_given)}; drop one of them")
    inclusion: Inclusion | None = None
    if not args.no_lump:
        if not step > 0:  # default_inclusion needs a usable step
            raise InputError(f"grid step {step!r} m must be positive")
        d = default_inclusion(nx, ny, step)
        pick = {"lump_x": d.x, "lump_y": d.y, "lump_depth": d.depth, "lump_radius": d.radius,
                "lump_ratio": d.ratio}
        pick.update({k: getattr(args, k) for k in _LUMP if getattr(args, k) is not None})
        inclusion = Inclusion(x=pick["lump_x"], y=pick["lump_y"], depth=pick["lump_depth"],
                              radius=pick["lump_radius"], ratio=pick["lump_ratio"])
    options = {"tip": PAPER_TIPS[args.tip]} if args.tip else {}
    for name, key in (("background_e", "E_background"), ("heterogeneity", "heterogeneity"),
                      ("workers", "workers")):
        if getattr(args, name) is not None:
            options[key] = getattr(args, name)
    out = simulate_map(args.out_dir, seed=args.seed, nx=nx, ny=ny, step=step,
                       inclusion=inclusion, noise_pp=args.noise_pp, overwrite=args.force,
                       **options)
    t = read_map_truth(out)
    print(f"wrote a stiffness-map phantom to {out} (seed {args.seed}, noise "
          f"{format_force(args.noise_pp, 6)} p-p):")
    print(f"  {nx * ny} traces ({nx} x {ny} grid, step {format_length(step)}, tip {t['tip']}, "
          f"E_b {format_pressure(t['E_background_pa'])}, heterogeneity {t['heterogeneity']:g}) "
          "in traces/, listed in manifest.csv with x_m, y_m")
    if t["has_lump"]:
        mm = {k: format_length(t[k]) for k in ("x_m", "y_m", "depth_m", "radius_m")}
        print(f"  lump at ({mm['x_m']}, {mm['y_m']}), centre depth {mm['depth_m']}, radius "
              f"{mm['radius_m']}, modulus ratio {t['ratio']:g}: apparent peak ratio "
              f"{t['peak_apparent_ratio']:.3f}, FWHM "
              + ("n/a (no contrast)" if t["apparent_fwhm_diameter_m"] is None
                 else format_length(t["apparent_fwhm_diameter_m"])))
    else:
        print("  no lump (a homogeneous block)")
    print("  true values in truth.csv (per trace) and truth_lump.json")
    return 0
