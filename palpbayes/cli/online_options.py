"""The options of online estimation shared by ``replay`` (a recorded trace) and ``follow``
(live samples): the stopping rule, the chunk, the noise, nu and the layer's base, and what
they become: the :class:`~palpbayes.online.StoppingRule`, the contact model and the
:class:`~palpbayes.online.OnlineEstimator`."""

from __future__ import annotations

import argparse

from ..bayes.noisemodels import EXACT_NOISE_MODELS
from ..contact import DEFAULT_NU, Tip, check_nu
from ..errors import InputError
from ..fitdata import ModelSpec
from ..online import TARGET_ON, OnlineEstimator, StoppingRule
from ..online.estimator import SHOWN_BUDGET_DRAWS
from .options import add_nu_option, thickness_from_args

__all__ = ["parse_fraction", "add_online_options", "rule_from_args", "layer_from_online_args",
           "model_from_args", "estimator_from_args", "DEFAULT_TARGET_ON"]

#: The interval ``--target`` is tested on unless ``--target-on`` says otherwise: the full one,
#: with the uncertainty budget, because that is the interval E is reported with (the offline
#: summary row's ``E_lo_pa``/``E_hi_pa``).  A statistical target can stop a run with an
#: interval of ±2 % that the budget alone (nu ± 0.05, tip radius, gain, compliance) widens
#: to ±3.5 % or more, and that a model-form bias can miss entirely; ``--target-on stat`` is
#: the old rule, for a study of how the data alone narrow.
DEFAULT_TARGET_ON = "full"


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


def add_online_options(p: argparse.ArgumentParser) -> None:
    """--target, --target-on, --max-force, --max-depth, --chunk, --noise, --noise-pp, --nu,
    --bonding."""
    p.add_argument("--target", type=parse_fraction, default=None, metavar="FRACTION",
                   help="target precision: stop when the 90 %% interval of E is within ± "
                   "this of E (e.g. 5%%); which interval: --target-on")
    p.add_argument("--target-on", choices=TARGET_ON, default=DEFAULT_TARGET_ON,
                   help="the interval --target tests: full (default; with the uncertainty "
                   "budget: nu ± 0.05, tip radius, force gain, compliance, as the fit "
                   "reports E; the budget alone keeps it above ~±3.5 %% for a half-space, "
                   "so a smaller target is said to be out of reach and never fires) or stat "
                   "(the data's noise and surface only); both intervals are printed")
    p.add_argument("--max-force", type=float, default=None, metavar="N",
                   help="stop at this force above the baseline [N]")
    p.add_argument("--max-depth", type=float, default=None, metavar="M",
                   help="stop at this depth below the estimated surface [m]")
    p.add_argument("--chunk", type=int, default=100, metavar="SAMPLES",
                   help="samples per update (default 100: 0.2 s at a UR robot's 500 Hz)")
    p.add_argument("--noise", choices=EXACT_NOISE_MODELS, default="gaussian",
                   help="noise model (default gaussian)")
    p.add_argument("--noise-pp", type=float, default=None, metavar="N",
                   help="sensor peak-to-peak noise [N] (default: 6 sd of the baseline)")
    add_nu_option(p, manifest=False, summary=False)
    p.add_argument("--bonding", choices=("bonded", "free"), default=None,
                   help="base of a layer of known --thickness: bonded to it or free (lying "
                        "on it without friction); required with --thickness, because the "
                        "online estimator takes one base (the offline fit weighs both)")


def rule_from_args(args: argparse.Namespace) -> StoppingRule:
    """The stopping rule of --target, --max-force and --max-depth (at least one is needed)."""
    if args.target is None and args.max_force is None and args.max_depth is None:
        raise InputError("give a stopping rule: --target 2% (precision), --max-force N or "
                         "--max-depth M")
    return StoppingRule(target=args.target, max_force=args.max_force,
                        max_depth=args.max_depth,
                        target_on=getattr(args, "target_on", DEFAULT_TARGET_ON))


def layer_from_online_args(args: argparse.Namespace) -> dict:
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


def model_from_args(args: argparse.Namespace, tip: Tip) -> ModelSpec:
    """The contact model of ``tip`` with --nu (default :data:`DEFAULT_NU`) and the layer."""
    nu = DEFAULT_NU if args.nu is None else check_nu(args.nu)
    return ModelSpec(tip, nu=nu, **layer_from_online_args(args))


def estimator_from_args(args: argparse.Namespace, tip: Tip,
                        rule: StoppingRule) -> OnlineEstimator:
    """The online estimator ``follow`` runs for ``tip`` and ``rule``, with the full interval
    (E with the budget) at every update: from :data:`~palpbayes.online.estimator.
    SHOWN_BUDGET_DRAWS` draws where it is only shown, from all of them where a target on it
    may fire."""
    return OnlineEstimator(model_from_args(args, tip), noise=args.noise,
                           noise_pp=args.noise_pp, rule=rule, total=True,
                           budget_draws=SHOWN_BUDGET_DRAWS)
