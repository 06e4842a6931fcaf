"""``palpbayes simulate OUT_DIR``: write a synthetic palpation campaign (docs/design.md §7).

The folder holds a manifest, one CSV per trace, Instron-like ground-truth exports and the true
values (see :mod:`palpbayes.sim.campaign`).  Its specimens are the paper's 50 × 50 mm blocks of
its thicknesses (their finite-element twins, :mod:`palpbayes.twin`), lying on a rigid plate
without friction (``--base free``), and its compression tests run between bonded platens
(``--platens bonded``: the Instron reads the blocks stiffer than E).
The shipped example was made with::

    palpbayes simulate data/example-campaign --seed 2026 --repetitions 3

With ``--map`` it writes a stiffness-map phantom instead (:mod:`palpbayes.sim.map`): a grid of
palpations over a block hiding a stiff sphere, e.g.::

    palpbayes simulate phantom --map --grid 15x15 --step 3e-3 --lump-ratio 10

With ``--rheology power-law|sls`` it writes a viscoelastic campaign instead
(:mod:`palpbayes.sim.visco_campaign`): ramp–hold–retract palpations of viscoelastic foams,
every tip at every speed, trace CSVs with their segment column, e.g.::

    palpbayes simulate visco --rheology power-law --speeds 5,50,500 --hold 5
    palpbayes fit visco/manifest.csv --rheology power-law --out visco-results
"""

from __future__ import annotations

import argparse
import math
import re

from ..errors import InputError
from ..sensor_noise import PAPER_NOISE_PP
from ..units import format_force, format_length, format_pressure

__all__ = ["register", "run"]

#: The paper's tips (the keys of :data:`palpbayes.paper.PAPER_TIPS`, sorted), the choices of
#: --tip: written out so that building the parser imports neither the simulator nor pandas.
PAPER_TIP_NAMES = ("flat", "paraboloid", "sphere")


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
            "truth_lump.json.  With --rheology power-law|sls: ramp-hold-retract palpations "
            "of viscoelastic foams at several speeds, with their true relaxation moduli in "
            "truth.csv."
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
                   help="palpations per material and tip (default 3); with --rheology per "
                        "material, tip and speed (default 1)")
    c.add_argument("--ar1", type=float, default=None, metavar="PHI",
                   help="AR(1) coefficient of the force noise, |PHI| < 1 (default 0: white)")
    c.add_argument("--gt-specimens", type=int, default=None, metavar="N",
                   help="compression tests per material (default 5)")
    c.add_argument("--platens", choices=("bonded", "lubricated"), default=None,
                   help="platens of the compression tests: bonded (default: a foam on dry "
                        "steel does not slide, the Instron reads c*E with c > 1) or lubricated "
                        "(it reads E)")
    c.add_argument("--layer-only", action="store_true",
                   help="simulate each block as a layer of infinite width (the physics before "
                        "the specimen twin) and leave its footprint out of the manifest")
    c.add_argument("--base", type=_base, default=None, metavar="BASE",
                   help="the specimens as layers of their thickness on a rigid plate: 'free' "
                        "(lying on it without friction, the default), 'bonded', a partial bond "
                        "in [0, 1], or 'none' (half-spaces, the paper's model)")
    v = p.add_argument_group(
        "viscoelastic campaign (--rheology)", "specimens x tips x speeds of ramp-hold-retract "
        "palpations; every specimen one relaxation modulus E*(t), so that its traces at "
        "several speeds pool (palpbayes fit MANIFEST --rheology power-law)")
    v.add_argument("--rheology", choices=("power-law", "sls"), default=None,
                   help="write a viscoelastic campaign: power-law foams E*(t) = "
                        "E0*·(t/1 s)^-alpha or standard linear solids E*(t) = E_inf* + "
                        "E1*·exp(-t/tau)")
    v.add_argument("--speeds", type=_speeds, default=None, metavar="MM_PER_MIN",
                   help="tip speeds in mm/min, comma-separated (default 5,50,500)")
    v.add_argument("--hold", type=float, default=None, metavar="S",
                   help="hold at the deepest point in seconds (default 5)")
    v.add_argument("--depth", type=float, default=None, metavar="M",
                   help="indentation depth in metres (default 2e-3)")
    v.add_argument("--rate", type=float, default=None, metavar="HZ",
                   help="sample rate in Hz (default 800)")
    v.add_argument("--materials", default=None, metavar="NAMES",
                   help="foams to simulate, comma-separated from Soft, Medium, Firm "
                        "(default all)")
    v.add_argument("--tips", default=None, metavar="NAMES",
                   help="tips, comma-separated from flat, paraboloid (default both; the "
                        "exact sphere has no power law)")
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
    m.add_argument("--tip", choices=PAPER_TIP_NAMES, default=None,
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
_CAMPAIGN_ONLY = ("repetitions", "ar1", "gt_specimens", "base", "platens", "layer_only")
_VISCO_ONLY = ("speeds", "hold", "depth", "rate", "materials", "tips")
_ELASTIC_ONLY = ("gt_specimens", "base", "platens", "layer_only")
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


def _speeds(text: str) -> tuple[float, ...]:
    """argparse type of --speeds: positive numbers in mm/min, comma-separated, each once."""
    try:
        v = tuple(float(s) for s in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"speeds {text!r} are not numbers in mm/min, e.g. 5,50,500") from None
    if not all(math.isfinite(s) and s > 0 for s in v):
        raise argparse.ArgumentTypeError(f"speeds {text!r} must be positive numbers in mm/min")
    if len(set(v)) < len(v):
        raise argparse.ArgumentTypeError(
            f"speeds {text!r} repeat a speed; give each once (--repetitions repeats them)")
    return v


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
    if args.map and args.rheology:
        raise InputError("--map writes a stiffness map, --rheology a viscoelastic campaign; "
                         "choose one")
    if not args.rheology:
        wrong = _given(args, _VISCO_ONLY)
        if wrong:
            raise InputError(f"{', '.join(wrong)} only apply with --rheology (a viscoelastic "
                             "campaign); add --rheology power-law|sls or drop them")
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
    if args.rheology:
        return _run_visco(args)
    from ..paper import PAPER_MATERIALS, PAPER_TIPS
    from ..sim import simulate

    for name, default in (("repetitions", 3), ("ar1", 0.0), ("gt_specimens", 5),
                          ("base", DEFAULT_BASE), ("platens", "bonded")):
        if getattr(args, name) is None:
            setattr(args, name, default)
    out = simulate(
        args.out_dir,
        seed=args.seed,
        repetitions=args.repetitions,
        overwrite=args.force,
        noise_pp=args.noise_pp,
        noise_ar1=args.ar1,
        gt_specimens=args.gt_specimens,
        base=None if args.base == "none" else args.base,
        blocks=not args.layer_only, platens=args.platens,
    )
    n_mat, n_tip = len(PAPER_MATERIALS), len(PAPER_TIPS)
    noise = f"{format_force(args.noise_pp, 6)} p-p"
    noise += f", AR(1) phi = {args.ar1:g}" if args.ar1 else ", white"
    print(f"wrote a synthetic campaign to {out} (seed {args.seed}, noise {noise}):")
    print(f"  {n_mat * n_tip * args.repetitions} traces ({n_mat} materials x {n_tip} tips x "
          f"{args.repetitions} repetitions) in traces/, listed in manifest.csv")
    what = ("layers" if args.layer_only else
            "50 x 50 mm blocks (finite-element twins, footprint in the manifest)")
    names = {"none": "half-spaces", "free": f"{what} lying free on a rigid plate",
             "bonded": f"{what} bonded to a rigid plate"}
    rest = (names[args.base] if isinstance(args.base, str)
            else f"{what} partly bonded ({args.base:g}) to a rigid plate")
    print(f"  specimens simulated as {rest}")
    if args.gt_specimens:
        print(f"  {n_mat * args.gt_specimens} Instron-style compression exports in "
              f"groundtruth/ (listed in groundtruth/manifest.csv), {args.platens} platens")
    print("  true values in truth.csv, truth_groundtruth.csv and truth_materials.csv")
    return 0


def _names(text: str | None, known, what: str) -> list[str]:
    """The names of a comma-separated option, checked against ``known``; all when None."""
    if text is None:
        return list(known)
    names = [n.strip() for n in text.split(",") if n.strip()]
    bad = [n for n in names if n not in known]
    if bad or not names:
        raise InputError(f"unknown {what} {bad[0] if bad else text!r}; choose from "
                         f"{', '.join(known)}")
    return list(dict.fromkeys(names))


def _run_visco(args: argparse.Namespace) -> int:
    """The ``--rheology`` branch of :func:`run`."""
    from ..sim import POWER_LAW_FOAMS, SLS_FOAMS, VISCO_TIPS, simulate_visco_campaign

    wrong = _given(args, _ELASTIC_ONLY)
    if wrong:
        raise InputError(f"{', '.join(wrong)} only apply to the elastic campaign; a "
                         "--rheology campaign has half-space specimens and no compression "
                         "tests")
    foams = POWER_LAW_FOAMS if args.rheology == "power-law" else SLS_FOAMS
    materials = {k: foams[k] for k in _names(args.materials, foams, "material")}
    tips = {k: VISCO_TIPS[k] for k in _names(args.tips, VISCO_TIPS, "tip")}
    speeds = args.speeds or (5.0, 50.0, 500.0)
    options = {k: getattr(args, k) for k in ("hold", "depth", "rate")
               if getattr(args, k) is not None}
    reps = 1 if args.repetitions is None else args.repetitions
    out = simulate_visco_campaign(
        args.out_dir, rheology=args.rheology, materials=materials, tips=tips,
        speeds=[s / 6e4 for s in speeds], repetitions=reps, seed=args.seed,
        noise_pp=args.noise_pp, noise_ar1=args.ar1 or 0.0, overwrite=args.force, **options)
    n = len(materials) * len(tips) * len(speeds) * reps
    print(f"wrote a viscoelastic campaign to {out} (seed {args.seed}, noise "
          f"{format_force(args.noise_pp, 6)} p-p):")
    counts = " x ".join(f"{k} {w}{'s' if k != 1 else ''}" for k, w in (
        (len(materials), "material"), (len(tips), "tip"), (len(speeds), "speed"),
        (reps, "repetition")))
    print(f"  {n} traces ({counts}; {', '.join(f'{s:g}' for s in speeds)} mm/min) in "
          "traces/, with their segments, listed in manifest.csv")
    for name, mat in materials.items():
        k = mat.kernel
        law = (f"E0* {format_pressure(k.E0)}, alpha {k.alpha:g}" if args.rheology == "power-law"
               else f"E_inf* {format_pressure(k.E_inf)}, E1* {format_pressure(k.E[0])}, "
                    f"tau {k.tau[0]:g} s")
        print(f"  {name}: {law}")
    print("  true values in truth.csv (per trace) and truth_materials.csv")
    return 0


def _run_map(args: argparse.Namespace) -> int:
    """The ``--map`` branch of :func:`run`."""
    from ..inclusion import Inclusion
    from ..paper import PAPER_TIPS
    from ..sim import default_inclusion, read_map_truth, simulate_map

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
