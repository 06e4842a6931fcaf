"""The command line's shared options: model, fitted points, layer, budget, run (``fit``,
``report``), the trace file's tip, columns, units and signs (``fit``, ``replay``; the
columns, units and signs also ``map``), ``--nu`` (also ``map``), and what they become:
:class:`~palpbayes.campaign.fitjob.FitOptions`, reader options and the traces themselves."""

# Long module: one job, the options the commands share; 19 small functions, one per option group.

from __future__ import annotations

import argparse
import math

from ..arguments import check_thickness
from ..bayes.budget import BudgetSpec
from ..bayes.noisemodels import NOISE_MODELS
from ..bayes.priors import BASELINES, SURFACE_PRIORS
from ..campaign.options import METHODS, FitOptions
from ..contact import (
    DEFAULT_NU,
    TIP_PARAMETERS,
    Tip,
    default_fit_fraction_text,
    registered_kinds,
)
from ..errors import InputError
from ..fitdata import BONDINGS
from ..twin import PLATENS
from .afm_options import AFM_META_OPTIONS, add_afm_meta_options, afm_meta_from_args
from .law_options import add_law_options, law_options_from_args

__all__ = ["add_nu_option", "add_f_unc_option", "positive_force", "add_model_options",
           "add_trace_options", "add_tip_options", "add_specimen_options",
           "add_column_options", "sign", "SIGN_METAVAR", "options_from_args",
           "thickness_from_args", "layer_from_args", "specimen_from_args",
           "read_options_from_args", "dest",
           "RECORDING_FLAGS", "recording_options_from_args", "tip_from_args",
           "traces_from_args", "trace_from_args"]


def add_nu_option(g, manifest: bool = True, summary: bool = True) -> None:
    """``--nu``: the one Poisson-ratio option of ``fit``, ``report``, ``map`` and ``replay``
    (None: a manifest's ``nu`` column when ``manifest``, else
    :data:`palpbayes.contact.DEFAULT_NU` with a note on screen, and ``nu_source = default``
    in summary.csv when ``summary``)."""
    default = ("a manifest's nu column, else " if manifest else "") + f"{DEFAULT_NU:g}"
    told = (" with a note on screen and nu_source = default in summary.csv" if summary
            else " with a note on screen")
    g.add_argument("--nu", type=float, default=None,
                   help="Poisson ratio (foams 0.1-0.3, silicone, gels and tissue 0.45-0.5; "
                   f"default: {default}{told})")


def add_f_unc_option(g, default: str = "6 sd of the pre-contact baseline") -> None:
    """``--f-unc``: the contact threshold of ``fit``, ``report`` and ``map`` (``default``:
    the words for what it is when not given)."""
    g.add_argument("--f-unc", type=float, default=None, metavar="N",
                   help="contact threshold and least-squares surface constraint "
                        f"|F(z_surf) - baseline| <= F_unc [N] (default: {default}); a "
                        "shallow indentation (AFM QI curves) whose first samples in contact "
                        "lie within it needs a lower one")


def positive_force(option: str, value: float | None) -> float | None:
    """``value`` of ``option`` [N], checked to be a positive finite force (None passes)."""
    if value is not None and not (math.isfinite(value) and value > 0):
        raise InputError(f"{option} {value!r} must be a positive force in newtons (the "
                         "sensor's peak-to-peak noise)")
    return value


#: The posterior engines, the choices of --engine: :data:`palpbayes.bayes.fit.ENGINES`, written
#: out so that building the parser does not import the fitting code (a test holds them equal).
ENGINES = ("emcee", "exact")

#: The budget's defaults, said in the help (one home: :class:`~palpbayes.bayes.budget.BudgetSpec`).
_BUDGET = BudgetSpec()


def add_model_options(p: argparse.ArgumentParser) -> None:
    """Options shared by ``fit`` and ``report``, in the groups of their help: the model,
    the data it fits, the layer, the uncertainty budget and model form, the run."""
    g = p.add_argument_group("model")
    g.add_argument("--method", choices=METHODS, default="bayes",
                   help="bayes, lsq (the paper's baseline) or both "
                   "(default: bayes for fit, both for report)")
    nu = g.add_mutually_exclusive_group()
    add_nu_option(nu)
    nu.add_argument("--nu-range", type=float, nargs=2, metavar=("LO", "HI"),
                    help="uniform Poisson-ratio range for the budget (fit at its midpoint; "
                         f"default: nu ± {_BUDGET.nu_half_width:g}, cut at 0.5)")
    g.add_argument("--noise", choices=NOISE_MODELS, default="gaussian",
                   help="noise model of the Bayesian fit (default gaussian)")
    g.add_argument("--noise-pp", type=float, default=None, metavar="N",
                   help="sensor peak-to-peak noise [N] (the paper's sensor: 0.048; default: "
                        "read from the pre-contact baseline as 6 sd; sigma prior = pp/6)")
    g.add_argument("--baseline", choices=BASELINES, default="constant",
                   help="baseline of the Bayesian model (and of --rheology): constant offset "
                        "F0, or linear F0 + F1*(z - z_ref) for drift or a tilted baseline "
                        "(default constant)")
    g.add_argument("--surface-prior", choices=SURFACE_PRIORS, default="loading",
                   help="Bayesian surface prior: uniform over the loading range, or 'soft' "
                        "(plus the paper's |F(z_surf)| <= F_unc as a soft penalty)")
    g.add_argument("--engine", choices=ENGINES, default="emcee",
                   help="posterior engine: emcee (every noise model and prior) or exact "
                        "(quadrature over the surface height with the linear parameters and "
                        "the noise integrated out; gaussian or ar1 noise; 10-100x faster)")
    w = p.add_argument_group("fitted points")
    add_f_unc_option(w, "--noise-pp")
    w.add_argument("--tare", action="store_true",
                   help="subtract the pre-contact baseline from the force before fitting "
                        "(zero an untared sensor; the paper's least squares has no offset)")
    w.add_argument("--fit-fraction", type=float, default=None,
                   help="fraction of the penetration skipped (default "
                   f"{default_fit_fraction_text()})")
    w.add_argument("--max-depth", type=float, default=None, metavar="M",
                   help="fit only down to this depth below the contact onset [m]")
    t = p.add_argument_group("layer (finite thickness: give it with --thickness or the "
                             "manifest's thickness_m)")
    t.add_argument("--half-space", action="store_true",
                   help="fit the specimen as a half-space even where its thickness is known "
                        "(the paper's model; default: a layer on a rigid base wherever "
                        "--thickness or the manifest's thickness_m gives the thickness)")
    t.add_argument("--bonding", choices=BONDINGS, default="unknown",
                   help="base of the layer: bonded to it, free (lying on it without "
                        "friction) or unknown (default: both, weighted by the data)")
    t.add_argument("--thickness-range", type=float, nargs=2, metavar=("LO", "HI"),
                   help="log-uniform prior range of an unknown thickness [m] (with "
                        "--thickness unknown; default 1.5 to 1000 times the indentation "
                        "depth)")
    t.add_argument("--specimen", metavar="L,W,H|D,H",
                   help="the block as tested, in metres: L,W,H (a cuboid, e.g. "
                        "0.05,0.05,0.02) or D,H (a cylinder); the Bayesian model is then its "
                        "finite-element twin on its plate (--bonding), and each row carries "
                        "E_instron, what a compression test of the block would read (a "
                        "manifest's length_m, width_m or diameter_m columns give it per row)")
    t.add_argument("--platens", choices=PLATENS, default="unknown",
                   help="the compression test E_instron is for: lubricated (frictionless "
                        "platens: E), bonded (the faces cannot slide: stiffer) or unknown "
                        "(default: an interval spanning both); with --specimen or a "
                        "manifest's footprint")
    t.add_argument("--finite-thickness", action="store_true", help=argparse.SUPPRESS)
    t.add_argument("--non-bonded", action="store_true", help=argparse.SUPPRESS)
    b = p.add_argument_group(
        "uncertainty budget and model form",
        f"the budget: nu ± {_BUDGET.nu_half_width:g} (--nu-range), tip radius "
        f"± {_BUDGET.radius_tolerance:.0%}, force gain sd {_BUDGET.gain_sd:.0%}, series "
        f"compliance 0 to {_BUDGET.compliance_max * 1e6:g} µm/N, a known thickness "
        f"± {_BUDGET.thickness_tolerance:.0%}")
    b.add_argument("--radius-tolerance", type=float, default=_BUDGET.radius_tolerance,
                   metavar="REL", help="relative tip-radius tolerance of the budget "
                                       "(default %(default)g)")
    b.add_argument("--gain-sd", type=float, default=_BUDGET.gain_sd, metavar="REL",
                   help="relative force-gain sd of the budget (default %(default)g)")
    b.add_argument("--compliance-max", type=float, default=_BUDGET.compliance_max,
                   metavar="M_PER_N",
                   help="upper bound of the series compliance of the budget [m/N] "
                        f"(default %(default)g = {_BUDGET.compliance_max * 1e6:g} µm/N)")
    b.add_argument("--model-form", action=argparse.BooleanOptionalAction, default=True,
                   help="widen E's interval to the envelope of the alternatives a material "
                        "misfit points to: shallow half, deep half, a layer of unknown "
                        "thickness (default on; --no-model-form: statistical + budget only)")
    add_law_options(p)
    r = p.add_argument_group("run")
    r.add_argument("--seed", type=int, default=0, help="base random seed (default 0)")
    r.add_argument("--strict", action="store_true",
                   help="make non-converged or flagged Bayesian fits an error")
    r.add_argument("--max-steps", type=int, default=20000, help="emcee step cap")
    r.add_argument("--workers", type=int, default=None,
                   help="worker processes (default: all cores)")
    r.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="fit the traces on Dask: 'local' (a LocalCluster on this machine, "
                        "--workers processes, loopback only) or a scheduler address "
                        "(tcp://host:8786) whose workers see the trace files and --out under "
                        "the same paths; same results as without it")
    r.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bars (default: only on a terminal)")


def add_tip_options(g) -> None:
    """``--tip`` and the tip-size options on the argument group ``g`` (read back by
    :func:`tip_from_args`; ``fit``, ``replay``, ``follow``, ``map``)."""
    g.add_argument("--tip", choices=registered_kinds(), help="tip kind")
    for par in TIP_PARAMETERS.values():  # the tip's size, in the option's unit
        g.add_argument(par.option, type=float, metavar=par.metavar, dest=dest(par.option),
                       help=par.help)


def add_specimen_options(p: argparse.ArgumentParser, title: str = "single trace") -> None:
    """A group ``title`` with the tip, its size, the specimen's thickness and material
    (``fit``, ``replay``, ``follow``)."""
    t = p.add_argument_group(title)
    add_tip_options(t)
    t.add_argument("--thickness", metavar="M|unknown",
                   help="specimen thickness [m] (the Bayesian model then treats it as a layer "
                        "on a rigid base), or 'unknown' to sample it")
    t.add_argument("--material", default="", help="material label")


#: How ``--force-sign`` and ``--z-sign`` show their values in ``--help`` and errors (argparse's
#: ``choices=(1.0, -1.0)`` showed ``{1.0,-1.0}``).
SIGN_METAVAR = "{1,-1}"


def sign(text: str) -> float:
    """A sign option's value (``1``, ``+1``, ``-1``, ``1.0`` ...) as the float +1.0 or -1.0.

    Raises
    ------
    argparse.ArgumentTypeError
        Anything else: "invalid choice: '2' (choose from 1, -1)", which argparse prefixes
        with the option's name.
    """
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if value not in (1.0, -1.0):
        raise argparse.ArgumentTypeError(f"invalid choice: {text!r} (choose from 1, -1)")
    return value


def add_column_options(p: argparse.ArgumentParser,
                       title: str = "columns, units and signs (every trace, also of a "
                                    "manifest)") -> None:
    """Column names, units and signs of a text table or stream (``fit``, ``replay``,
    ``follow``, ``map``; read back by :func:`read_options_from_args`)."""
    c = p.add_argument_group(title)
    for q, unit, example in (("time", "s", "timestamp"), ("z", "m", "tcp_z_mm"),
                             ("force", "N", "fz")):
        c.add_argument(f"--{q}-column", metavar="NAME",
                       help=f"column holding {q}, spelled as in the header (e.g. {example})")
        c.add_argument(f"--{q}-unit", metavar="UNIT", help=f"unit of {q} (default {unit})")
    c.add_argument("--force-sign", type=sign, metavar=SIGN_METAVAR, default=None,
                   help="-1 if pressing gives negative force (default +1; for a ROS 2 bag the "
                        "sign that makes the force grow as the tip goes down)")
    c.add_argument("--z-sign", type=sign, metavar=SIGN_METAVAR, default=1.0,
                   help="-1 if z is down-positive")


def add_trace_options(p: argparse.ArgumentParser, title: str = "single trace") -> None:
    """Tip, specimen, columns, units and signs of a trace file (``fit``, ``replay``)."""
    add_specimen_options(p, title)
    add_column_options(p)
    r = p.add_argument_group("ROS 2 bags, UR RTDE logs and AFM files (palpbayes inspect FILE "
                             "lists what is in one)")
    r.add_argument("--force-topic", metavar="TOPIC",
                   help="geometry_msgs/WrenchStamped topic (default: the bag's only one)")
    r.add_argument("--pose-topic", metavar="TOPIC",
                   help="geometry_msgs/PoseStamped tip pose or sensor_msgs/JointState topic "
                        "(UR3e kinematics; default: the bag's only one)")
    r.add_argument("--force-axis", choices=("x", "y", "z"), default=None,
                   help="wrench force component along the indentation (a bag's wrench, an "
                        "RTDE log's actual_TCP_force; default z)")
    r.add_argument("--time-offset", type=float, metavar="S", default=None,
                   help="seconds added to the pose stamps (clocks that differ; default 0)")
    r.add_argument("--tool-offset", type=float, metavar="M", default=None,
                   help="sensor + tip length along the flange z axis for a JointState "
                        "topic or an RTDE log's joints, or an extra offset of a PoseStamped "
                        "tip or an RTDE log's TCP pose [m] (default 0)")
    r.add_argument("--z-source", choices=("q", "tcp"), default=None,
                   help="an RTDE log's tip height: from the joints actual_q by UR3e "
                        "kinematics plus --tool-offset (q, default), or from actual_TCP_pose_2 "
                        "(tcp, the TCP configured on the robot)")
    r.add_argument("--curve", type=int, action="append", metavar="I", dest="curves",
                   help="fit only curve I of an AFM force map (repeatable; default all)")
    add_afm_meta_options(r)


def options_from_args(args: argparse.Namespace) -> FitOptions:
    """Build :class:`FitOptions` from parsed arguments (validated) by
    :func:`palpbayes.campaign.options.fit_options`, the function :func:`palpbayes.fit` uses
    too."""
    from ..campaign.options import fit_options  # here: the parser does not load the fits

    if args.workers is not None and args.workers < 1:
        raise InputError(f"--workers {args.workers} must be at least 1")
    layer, bonding = layer_from_args(args)
    return fit_options(
        method=args.method, nu=args.nu, nu_range=args.nu_range, layer=layer, bonding=bonding,
        thickness_range=args.thickness_range, specimen=specimen_from_args(args),
        platens=getattr(args, "platens", "unknown"), engine=args.engine, noise=args.noise,
        noise_pp=args.noise_pp, f_unc=args.f_unc, baseline=args.baseline, tare=args.tare,
        surface_prior=args.surface_prior, fit_fraction=args.fit_fraction,
        max_depth=args.max_depth, radius_tolerance=args.radius_tolerance,
        gain_sd=args.gain_sd, compliance_max=args.compliance_max,
        model_form=getattr(args, "model_form", True), max_steps=args.max_steps,
        seed=args.seed, strict=args.strict, progress=args.progress,
        **law_options_from_args(args))


def specimen_from_args(args: argparse.Namespace):
    """The :class:`~palpbayes.twin.Specimen` of ``--specimen`` (None when absent), checked
    against ``--thickness`` and ``--half-space`` (:func:`palpbayes.api.check_specimen`)."""
    from ..api import check_specimen

    thickness_from_args(args)  # a number, or 'unknown'
    return check_specimen(getattr(args, "specimen", None), getattr(args, "thickness", None),
                          getattr(args, "half_space", False))


def thickness_from_args(args: argparse.Namespace) -> float | None:
    """The known thickness [m] of ``--thickness`` (None when absent or 'unknown')."""
    h = check_thickness(getattr(args, "thickness", None), "--thickness")
    return None if h == "unknown" else h


def layer_from_args(args: argparse.Namespace) -> tuple[str, str]:
    """(FitOptions.layer, .bonding) from --half-space, --thickness, --bonding and the old
    --finite-thickness (now the default) / --non-bonded (= --bonding free)."""
    unknown = str(getattr(args, "thickness", None) or "").strip().lower() == "unknown"
    thickness_from_args(args)  # validates a number
    if args.half_space and unknown:
        raise InputError("--half-space and --thickness unknown contradict each other; "
                         "give one")
    if args.thickness_range is not None and not unknown:
        raise InputError("--thickness-range is the prior of an unknown thickness: give it "
                         "with --thickness unknown")
    bonding = "free" if args.non_bonded and args.bonding == "unknown" else args.bonding
    return ("off" if args.half_space else "unknown" if unknown else "auto"), bonding


def read_options_from_args(args: argparse.Namespace) -> dict:
    """Reader options (``columns``, ``units``, ``force_sign``, ``z_sign``) from the column,
    unit and sign arguments; only those the user gave (empty dict: the canonical file)."""
    opts: dict = {}
    columns = {q: getattr(args, f"{q}_column") for q in ("time", "z", "force")
               if getattr(args, f"{q}_column")}
    units = {q: getattr(args, f"{q}_unit") for q in ("time", "z", "force")
             if getattr(args, f"{q}_unit")}
    if columns:
        opts["columns"] = columns
    if units:
        opts["units"] = units
    if args.force_sign not in (None, 1.0):
        opts["force_sign"] = args.force_sign
    if args.z_sign != 1.0:
        opts["z_sign"] = args.z_sign
    return opts


def dest(option: str) -> str:
    """The argparse attribute of a ``--long-option``."""
    return option.lstrip("-").replace("-", "_")


#: Reader option (= argparse attribute) -> its flag, of the options for bags, RTDE logs and AFM
#: files.
RECORDING_FLAGS = {"force_topic": "--force-topic", "pose_topic": "--pose-topic",
                    "force_axis": "--force-axis", "time_offset": "--time-offset",
                    "tool_offset": "--tool-offset", "z_source": "--z-source",
                    "curves": "--curve"}


def recording_options_from_args(args: argparse.Namespace) -> dict:
    """Reader options of a ROS 2 bag or AFM file from the arguments (only those given; an
    AFM file's missing calibration as ``meta_override``, :func:`afm_meta_from_args`)."""
    opts = {key: getattr(args, key) for key in RECORDING_FLAGS
            if getattr(args, key, None) is not None}
    meta = afm_meta_from_args(args)
    if meta:
        opts["meta_override"] = meta
    if args.force_sign is not None:
        opts["force_sign"] = args.force_sign
    if args.z_sign != 1.0:
        opts["z_sign"] = args.z_sign
    return opts


def tip_from_args(args: argparse.Namespace) -> Tip:
    """The tip of ``--tip`` and its size options; an error naming ``args.input`` without."""
    if args.tip is None:
        sizes = ", ".join(f"{p.option} {p.metavar}" if p.metavar else p.option
                          for p in TIP_PARAMETERS.values())
        raise InputError(f"{args.input}: a single trace needs --tip "
                         f"({', '.join(registered_kinds())}) and its size ({sizes}, as the "
                         "tip needs)")
    sizes = {}
    for p in TIP_PARAMETERS.values():  # in the option's unit (degrees for the half-angle)
        value = getattr(args, dest(p.option))
        sizes[p.name] = None if value is None else p.from_user(value)
    return Tip(args.tip, **sizes)


def traces_from_args(args: argparse.Namespace, segments: str | None = None) -> list:
    """Read the recording named by ``args.input`` (trace CSV, ROS 2 bag or AFM file, the
    reader chosen by :func:`palpbayes.io.recording.recording_kind`) with the tip, column,
    sign and recording options; one trace, or one per curve of an AFM force map.
    ``segments`` (names) are read from an AFM file instead of the approach alone (a trace
    CSV keeps its ``segment`` column; a bag gets segments from the motion when fitted)."""
    from ..io.recording import KIND_NAMES, READER_OPTIONS, read_recording, recording_kind

    tip = tip_from_args(args)
    kind = recording_kind(args.input)
    given = [o for o, (attr, _) in AFM_META_OPTIONS.items()
             if getattr(args, attr, None) is not None]
    if given and kind != "afm":
        raise InputError(f"{args.input} is {KIND_NAMES[kind]}: {', '.join(given)} apply to "
                         "AFM files only")
    if kind == "table":
        bag_or_afm = recording_options_from_args(args)
        extra = sorted(set(bag_or_afm) - {"force_sign", "z_sign"})
        if extra:
            owners = [KIND_NAMES[k].split(" ", 1)[1] + "s" for k, v in READER_OPTIONS.items()
                      if extra[0] in v] or ["AFM files"]
            raise InputError(f"{args.input} is {KIND_NAMES[kind]}: "
                             f"{RECORDING_FLAGS[extra[0]]} applies to {' and '.join(owners)} "
                             "only")
        opts = read_options_from_args(args)
    else:
        if any(getattr(args, f"{q}_{w}") for q in ("time", "z", "force")
               for w in ("column", "unit")):
            raise InputError(f"{args.input} is {KIND_NAMES[kind]}: --*-column and --*-unit "
                             "apply to text tables only (the file names its own columns)")
        opts = recording_options_from_args(args)
        if segments is not None and kind == "afm":
            opts["segments"] = segments
    return read_recording(args.input, tip=tip, thickness=thickness_from_args(args),
                          material=args.material, **opts)


def trace_from_args(args: argparse.Namespace):
    """The single trace named by ``args.input`` (:func:`traces_from_args`); an AFM force map
    must be narrowed to one curve with ``--curve I``."""
    traces = traces_from_args(args)
    if len(traces) != 1:
        raise InputError(f"{args.input} holds {len(traces)} curves; pick one with --curve I "
                         f"(0 to {len(traces) - 1})")
    return traces[0]
