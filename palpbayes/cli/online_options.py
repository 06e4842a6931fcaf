"""The options of online estimation shared by ``replay`` (a recorded trace) and ``follow``
(live samples): the stopping rule, the chunk, the noise, nu and the layer's base, and what
they become: the :class:`~palpbayes.online.StoppingRule`, the contact model and the
:class:`~palpbayes.online.OnlineEstimator`.  Their defaults and checks have one home,
:mod:`palpbayes.api_replay` (:class:`~palpbayes.api_replay.ReplayRequest`, which
:func:`palpbayes.replay` builds too)."""

from __future__ import annotations

import argparse

from ..api_replay import (
    BONDINGS,
    DEFAULT_CHUNK,
    DEFAULT_NOISE,
    DEFAULT_TARGET_ON,
    ReplayRequest,
    online_model,
    stopping_rule,
)
from ..api_replay import parse_fraction as _fraction
from ..bayes.noisemodels import EXACT_NOISE_MODELS
from ..contact import Tip
from ..errors import InputError
from ..fitdata import ModelSpec
from ..online import TARGET_ON, OnlineEstimator, StoppingRule
from ..online.full_interval import SHOWN_BUDGET_DRAWS
from .options import add_nu_option

__all__ = ["parse_fraction", "add_online_options", "rule_from_args", "model_from_args",
           "estimator_from_args", "request_from_args", "DEFAULT_TARGET_ON"]


def parse_fraction(text: str) -> float:
    """'2%' -> 0.02, '0.02' -> 0.02 (a relative half-width; argparse's type of --target)."""
    try:
        return _fraction(str(text))
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


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
    p.add_argument("--chunk", type=int, default=DEFAULT_CHUNK, metavar="SAMPLES",
                   help="samples per update (default 100: 0.2 s at a UR robot's 500 Hz)")
    p.add_argument("--noise", choices=EXACT_NOISE_MODELS, default=DEFAULT_NOISE,
                   help="noise model (default gaussian)")
    p.add_argument("--noise-pp", type=float, default=None, metavar="N",
                   help="sensor peak-to-peak noise [N] (default: 6 sd of the baseline)")
    add_nu_option(p, manifest=False, summary=False)
    p.add_argument("--bonding", choices=BONDINGS, default=None,
                   help="base of a layer of known --thickness: bonded to it or free (lying "
                        "on it without friction); required with --thickness, because the "
                        "online estimator takes one base (the offline fit weighs both)")


def rule_from_args(args: argparse.Namespace) -> StoppingRule:
    """The stopping rule of --target, --max-force and --max-depth (at least one is needed;
    :func:`~palpbayes.api_replay.stopping_rule`)."""
    return stopping_rule(args.target, args.max_force, args.max_depth,
                         getattr(args, "target_on", DEFAULT_TARGET_ON))


def model_from_args(args: argparse.Namespace, tip: Tip) -> ModelSpec:
    """The contact model of ``tip`` with --nu (default :data:`~palpbayes.contact.DEFAULT_NU`)
    and the layer (:func:`~palpbayes.api_replay.online_model`)."""
    return online_model(tip, args.nu, getattr(args, "thickness", None), args.bonding)


def request_from_args(args: argparse.Namespace) -> ReplayRequest:
    """``palpbayes replay``'s :class:`~palpbayes.api_replay.ReplayRequest` (checked: the rule
    first) from its options."""
    return ReplayRequest(target=args.target, max_force=args.max_force,
                         max_depth=args.max_depth,
                         target_on=getattr(args, "target_on", DEFAULT_TARGET_ON),
                         chunk=args.chunk, noise=args.noise, noise_pp=args.noise_pp,
                         nu=args.nu, thickness=getattr(args, "thickness", None),
                         bonding=args.bonding)


def estimator_from_args(args: argparse.Namespace, tip: Tip,
                        rule: StoppingRule) -> OnlineEstimator:
    """The online estimator ``follow`` runs for ``tip`` and ``rule``, with the full interval
    (E with the budget) at every update: from :data:`~palpbayes.online.full_interval.
    SHOWN_BUDGET_DRAWS` draws where it is only shown, from all of them where a target on it
    may fire."""
    return OnlineEstimator(model_from_args(args, tip), noise=args.noise,
                           noise_pp=args.noise_pp, rule=rule, total=True,
                           budget_draws=SHOWN_BUDGET_DRAWS)
