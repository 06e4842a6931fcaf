"""The options, checks and console lines of ``palpbayes fit --rheology power-law|sls``.

:mod:`palpbayes.cli.fit` registers these options on ``fit``, reads the recordings and hands
them to :func:`palpbayes.rheology.results.fit_traces`; this module says which options belong
to which fit, checks them, and prints the table.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..units import FORCE_PREFIXES, format_pressure_interval, format_si, interval_digits

__all__ = ["ELASTIC_ONLY", "VISCO_ONLY", "INTERVALS_NOTE", "add_rheology_options",
           "given_options", "parse_rheologies", "check_rheology_args", "print_rheology",
           "print_pooled", "value_interval"]

#: Options of the elastic fit that --rheology power-law|sls does not use (dest -> flag).
ELASTIC_ONLY = {
    "noise": "--noise", "noise_pp": "--noise-pp", "f_unc": "--f-unc", "tare": "--tare",
    "surface_prior": "--surface-prior", "fit_fraction": "--fit-fraction",
    "max_depth": "--max-depth", "half_space": "--half-space", "bonding": "--bonding",
    "thickness_range": "--thickness-range", "radius_tolerance": "--radius-tolerance",
    "gain_sd": "--gain-sd", "compliance_max": "--compliance-max", "engine": "--engine",
    "model_form": "--model-form", "strict": "--strict", "max_steps": "--max-steps",
    "workers": "--workers", "scheduler": "--scheduler"}
#: Peers ``--peer-compatible`` imitates: :data:`palpbayes.rheology.peer.PEERS`, spelled out so
#: that building the parser does not import the viscoelastic package.
PEER_NAMES = ("pyfmrheo",)
#: Options only the viscoelastic fit uses.
VISCO_ONLY = {"segments": "--segments", "t0": "--t0", "compression_speed": "--compression-speed",
              "drag": "--drag", "rheology_engine": "--rheology-engine",
              "adhesion": "--adhesion", "peer_compatible": "--peer-compatible"}


def given_options(args: argparse.Namespace, options: dict[str, str]) -> list[str]:
    """Flags of ``options`` whose value differs from the parser's default."""
    defaults = getattr(args, "fit_defaults", {})
    return [flag for dest, flag in options.items()
            if dest in defaults and getattr(args, dest, None) != defaults[dest]]


def parse_rheologies(text: str) -> tuple[str, ...]:
    """--rheology: one model, or several separated by commas to compare them (``elastic``
    alone is the elastic fit of the loading; in a list, the constant modulus fitted to the same
    cycle as the others)."""
    from ..rheology.posterior import RHEOLOGIES  # here: the parser does not load rheology

    names = tuple(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))
    bad = [n for n in names if n not in RHEOLOGIES]
    if bad or not names:
        raise argparse.ArgumentTypeError(f"unknown model {bad[0] if bad else text!r}; use "
                                         f"{', '.join(RHEOLOGIES)} (or several: "
                                         "elastic,power-law,sls)")
    return names


def add_rheology_options(p: argparse.ArgumentParser) -> None:
    """The viscoelastic group of ``fit``'s options."""
    v = p.add_argument_group(
        "viscoelastic fit (the loading and hold; --segments adds the retract, power law "
        "only)")
    v.add_argument("--rheology", type=parse_rheologies, default=("elastic",), metavar="MODEL",
                   help="relaxation modulus: elastic (the fits above, default), power-law "
                        "E*(t) = E0*·(t/t0)^-alpha or sls E*(t) = E_inf* + E1*·exp(-t/tau); "
                        "writes DIR/rheology.csv, one row per trace; several, e.g. "
                        "elastic,power-law,sls, fits each to the same cycle (elastic: a "
                        "constant E*) and says which the record prefers (PSIS-LOO, with its "
                        "error)")
    v.add_argument("--segments", default=None, metavar="NAMES",
                   help="segments fitted by --rheology power-law|sls, comma-separated from "
                        "approach, hold, retract (default approach,hold; the retract, by "
                        "Ting's rule, with the power law only; a recording without segments "
                        "gets them from the motion)")
    v.add_argument("--t0", type=float, default=1.0, metavar="S",
                   help="reference time of the power law [s] (E0* is E*(t0); default 1)")
    v.add_argument("--drag", choices=("auto", "on", "off"), default="auto",
                   help="fit a viscous drag on the probe, F = b·(-dz/dt) (b in N·s/m, the "
                        "hydrodynamic force on an AFM cantilever in liquid): auto (default) "
                        "fits it when the retract is fitted, whose out-of-contact force tells "
                        "it from the offset")
    v.add_argument("--adhesion", choices=("keep", "cut"), default="keep",
                   help="an adhesive pull-off on the retract (the force dips below its own "
                        "baseline where the tip lets go, which Ting's rule does not model): "
                        "keep (default) fits the record as it is and flags the dip; cut "
                        "removes the retract from where its force comes down to its baseline "
                        "to where it has recovered before the fit (needs the retract in "
                        "--segments; rheology.csv gives the cut in adhesion_cut_from_s, "
                        "adhesion_cut_to_s)")
    v.add_argument("--peer-compatible", choices=PEER_NAMES, default=None, metavar="PEER",
                   help="read every trace as a peer does, to compare with its numbers like "
                        "for like: pyfmrheo (its Ting fit as its viscoelastic notebook runs "
                        "it: straight ramps at constant speed in place of the recorded "
                        "heights, its drag 2.5e-6 N·s/m fixed, approach and retract, t0 1 s; "
                        "sets --segments, --drag and --t0). Not a measurement: the tip did "
                        "not move at constant speed")
    v.add_argument("--rheology-engine", choices=("grid", "exact", "emcee"), default="grid",
                   help="posterior engine of --rheology: grid (or exact: the same; moduli, "
                        "offset and noise integrated in closed form; default) or emcee (the "
                        "same posterior with "
                        "every parameter sampled, started from the grid: a cross-check, a few "
                        "times slower)")
    v.add_argument("--compression-speed", type=float, default=50.0, metavar="MM_PER_MIN",
                   help="cross-head speed [mm/min] of the compression test the fit is set "
                        "beside: with --nu and the thickness, rheology.csv gets the modulus "
                        "that test would report (default 50, the paper's Instron)")


def check_rheology_args(args: argparse.Namespace):
    """Check the options of a ``fit --rheology`` run: those of the command line here, the
    run's own by :func:`palpbayes.api_rheology.rheology_options` (as
    :func:`palpbayes.fit_rheology` checks them); returns the
    :class:`~palpbayes.api_rheology.RheologyOptions`.

    Raises
    ------
    InputError
        An option of the elastic fit, a bad t0, compression speed or segment list, or an
        existing table without ``--force`` (one line each).
    """
    from ..api_rheology import rheology_options
    from ..rheology.results import RHEOLOGY_TABLE

    out = Path(args.out)
    given = given_options(args, ELASTIC_ONLY)
    if given:
        raise InputError(f"{given[0]} is an option of the elastic fit; --rheology "
                         f"{','.join(args.rheology)} does not use it (leave it out)")
    if args.method != "bayes":
        raise InputError(f"--rheology {','.join(args.rheology)} is a Bayesian fit; --method "
                         f"{args.method} is for the elastic fit (leave it out, or use "
                         "--rheology elastic)")
    if args.resume:
        raise InputError("--resume is for elastic campaigns; a viscoelastic run writes "
                         f"{RHEOLOGY_TABLE} at the end: run it again with --force")
    if args.nu_range is not None:
        raise InputError("--nu-range is for the elastic fit's budget; give --nu (or leave it "
                         "out: the table then has E* only)")
    options = rheology_options(
        args.rheology, segments=args.segments, t0=args.t0, nu=args.nu, drag=args.drag,
        baseline=args.baseline, engine=args.rheology_engine,
        adhesion=getattr(args, "adhesion", "keep"),
        peer=getattr(args, "peer_compatible", None),
        compression_speed_mm_min=args.compression_speed, seed=args.seed)
    if (out / RHEOLOGY_TABLE).exists() and not args.force:
        raise InputError(f"{out / RHEOLOGY_TABLE} exists; pass --force to overwrite it")
    return options


#: What every interval of the viscoelastic console holds, said above its lines.
INTERVALS_NOTE = (
    "posterior medians [90 % intervals]; the intervals are statistical only (the record's "
    "noise: no uncertainty budget of nu, tip radius, force gain or compliance, and no model "
    "form, which the elastic fit's E_lo..E_hi carries), so a true value can lie just outside "
    "them; moduli as E* = E/(1-nu^2) (with --nu, rheology.csv has E too)")


def print_rheology(table) -> None:
    """One line per trace and model (wrapped at 100 characters): the parameters with 90 %
    intervals, the model check, the flags; with several models, which one the record
    prefers.  Above them, what the intervals hold (:data:`INTERVALS_NOTE`)."""
    from .console import _wrap

    for line in _wrap(INTERVALS_NOTE):
        print(line)
    for trace_id, rows in table.groupby("trace_id", sort=False):
        for _, r in rows.iterrows():
            label = trace_id if len(rows) == 1 else f"{trace_id} ({r['rheology']})"
            if isinstance(r.get("error"), str) and r["error"]:
                print(f"  {label}: not fitted: {r['error']}")
                continue
            for line in _packed(label, _rheology_parts(r)):
                print(line)
            if isinstance(r["notes"], str) and r["notes"]:
                for note in r["notes"].split(" | "):
                    print(f"      - {note}")
        if len(rows) > 1 and "elpd_diff" in rows and rows["elpd_diff"].notna().all():
            print(f"  {trace_id}: {_choice_line(rows)}")


def print_pooled(table, out: Path) -> None:
    """The pooled power laws of a manifest (``rheology_pooled.csv``:
    :class:`~palpbayes.rheology.campaign.SpeedPools`), and the table's path when one was
    written (none when no group pools)."""
    from ..rheology.campaign import RHEOLOGY_POOLED, pooled_lines

    print("\n".join(pooled_lines(table)))
    if not table.empty:
        print(f"wrote {out / RHEOLOGY_POOLED}")


#: Column suffix -> unit printed on the console (moduli: :func:`format_pressure`).
_SUFFIXES = (("_n_s_per_m", " N·s/m"), ("_n_per_m", " N/m"), ("_pa", " Pa"), ("_s", " s"))


def value_interval(x: float, lo: float, hi: float, unit: str = "") -> str:
    """``x [lo, hi]`` with the digits :func:`~palpbayes.units.interval_digits` gives: a modulus
    (``unit`` " Pa") with the package's SI prefix (``'34.9 kPa [34.81 kPa, 34.99 kPa]'``), a
    drag or stiffness (" N·s/m", " N/m") with the force's prefix, anything else as a plain
    number and its unit."""
    if unit == " Pa":
        return format_pressure_interval(x, lo, hi)
    d = interval_digits(lo, hi)
    if unit in (" N·s/m", " N/m"):
        def one(v):
            return format_si(v, unit.strip(), FORCE_PREFIXES, d)
        return f"{one(x)} [{one(lo)}, {one(hi)}]"
    return f"{x:.{d}g} [{lo:.{d}g}, {hi:.{d}g}]{unit}"


def _rheology_parts(r) -> list[str]:
    names = {"power-law": ("E0_star_pa", "alpha"), "elastic": ("E_star_pa",),
             "sls": ("E_inf_star_pa", "E1_star_pa", "tau_s")}[r["rheology"]]
    names += tuple(c for c in ("drag_n_s_per_m", "tilt_n_per_m")
                   if np.isfinite(r.get(c, np.nan)))
    parts = []
    for c in names:
        unit, stem = next(((u, c.removesuffix(s)) for s, u in _SUFFIXES if c.endswith(s)),
                          ("", c))
        lo, hi = (r[f"{stem}_{p}{c[len(stem):]}"] for p in ("lo", "hi"))
        parts.append(f"{stem.replace('_star', '*')} {value_interval(r[c], lo, hi, unit)}")
    if np.isfinite(r.get("E_compression_pa", np.nan)):
        parts.append(f"a compression test at {r['compression_speed_mm_min']:g} mm/min "
                     "would read E " + value_interval(
                         r["E_compression_pa"], r["E_compression_lo_pa"],
                         r["E_compression_hi_pa"], " Pa"))
    if np.isfinite(r.get("adhesion_cut_from_s", np.nan)):
        parts.append(f"adhesion cut {r['adhesion_cut_from_s']:.4g}-"
                     f"{r['adhesion_cut_to_s']:.4g} s")
    parts.append("model check passed" if r["model_ok"]
                 else f"model check FAILED ({r['flag_codes']})")
    peer = r.get("peer_compatible")
    if isinstance(peer, str):
        parts.insert(0, f"read as {peer} reads it (to compare, not to report)")
    return parts


def _packed(head: str, parts: list[str], width: int = 100) -> list[str]:
    """``head`` then ``parts`` joined by "; ", a line broken between parts only (a part
    longer than a line wrapped on its own), continuation lines indented by four spaces."""
    from .console import _wrap

    lines, line = [], f"  {head}:"
    for k, part in enumerate(parts):
        piece = part + (";" if k < len(parts) - 1 else "")
        if len(line) + 1 + len(piece) <= width:
            line += " " + piece
            continue
        lines.append(line)
        *done, line = _wrap(piece, "    ", width)
        lines += done
    return lines + [line]


def _choice_line(rows) -> str:
    from ..rheology.choice import K_WARN

    best = rows.loc[rows["elpd_diff"].idxmax()]
    others = ", ".join(f"{r['rheology']} by {-r['elpd_diff']:.1f} ± {r['elpd_diff_se']:.1f}"
                       for _, r in rows.iterrows() if r["rheology"] != best["rheology"])
    k = rows[rows["pareto_k_max"] > K_WARN]["rheology"].tolist()
    shaky = f" (PSIS-LOO unreliable for {', '.join(k)}: Pareto k > {K_WARN})" if k else ""
    if bool(best["preferred"]):
        return f"prefers {best['rheology']}: elpd_loo higher than {others}{shaky}"
    return f"no model preferred (elpd_loo difference within 2 se: {others}){shaky}"
