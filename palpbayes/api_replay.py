"""The replay's front door: one builder of a replay's options that :func:`palpbayes.replay` and
``palpbayes replay`` both call (as :mod:`palpbayes.api` is the fit's and
:mod:`palpbayes.api_map` the map's).

:class:`ReplayRequest` holds and checks what a user chooses (the stopping rule, the chunk, the
noise, nu and a layer's base), with the command line's defaults, and runs it on a trace
(:meth:`ReplayRequest.run`: :func:`palpbayes.online.recorded.replay` with the budget's interval
at every update, as the command does).  :func:`stopping_rule` and :func:`online_model` build
the rule and the contact model; ``palpbayes follow`` builds its own from them too.

>>> import palpbayes as pb
>>> r = pb.replay("press.csv", tip="sphere", radius=0.01, target="5%")   # doctest: +SKIP
>>> r.summary(); r.plot(); r.save("press-replay")                        # doctest: +SKIP
"""

from __future__ import annotations

import numbers
import os
from dataclasses import dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from . import outputs
from .arguments import check_seed, check_thickness
from .contact import DEFAULT_NU, Tip, check_nu
from .errors import InputError
from .fitdata import ModelSpec
from .online import recorded
from .online.estimator import StoppingRule, check_noise_options
from .online.recorded import ReplayResult, check_chunk
from .trace import IndentationTrace

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["ReplayRequest", "Replay", "replay", "stopping_rule", "online_model", "parse_fraction",
           "DEFAULT_TARGET_ON", "DEFAULT_CHUNK", "DEFAULT_NOISE", "BONDINGS"]

#: The interval ``--target`` is tested on unless ``--target-on`` says otherwise: the full one,
#: with the uncertainty budget, because that is the interval E is reported with (the offline
#: summary row's ``E_lo_pa``/``E_hi_pa``).  A statistical target can stop a run with an
#: interval of ±2 % that the budget alone (nu ± 0.05, tip radius, gain, compliance) widens
#: to ±3.5 % or more, and that a model-form bias can miss entirely; ``--target-on stat`` is
#: the old rule, for a study of how the data alone narrow.
DEFAULT_TARGET_ON = "full"
#: Samples per online update (``--chunk``): 0.2 s at a UR robot's 500 Hz.
DEFAULT_CHUNK = 100
#: The noise model (``--noise``).
DEFAULT_NOISE = "gaussian"
#: The bases of a layer the online estimator takes (``--bonding``): one of them, not both.
BONDINGS = ("bonded", "free")
#: The stopping rule's least samples in contact before its target may fire (its default).
_MIN_CONTACT = StoppingRule.__dataclass_fields__["min_contact"].default


def parse_fraction(value: str | float, name: str | None = None) -> float:
    """A relative half-width in (0, 1): ``"2%"`` -> 0.02, ``"0.02"`` -> 0.02, 0.02 -> 0.02.

    Raises
    ------
    InputError
        Not a fraction, or outside (0, 100 %); the message starts with ``name`` when given.
    """
    label = "" if name is None else f"{name} "
    if isinstance(value, str):
        t = value.strip()
        try:
            v = float(t[:-1]) / 100 if t.endswith("%") else float(t)
        except ValueError:
            raise InputError(f"{label}{value!r} is not a fraction: give e.g. 2% or "
                             "0.02") from None
    elif isinstance(value, numbers.Real) and not isinstance(value, bool):
        v = float(value)
    else:
        raise InputError(f"{label}{value!r} is not a fraction: give e.g. 2% or 0.02")
    if not 0 < v < 1:
        raise InputError(f"{label}{value!r} must lie between 0 and 100 %")
    return v


def stopping_rule(target: float | str | None = None, max_force: float | None = None,
                  max_depth: float | None = None, target_on: str = DEFAULT_TARGET_ON,
                  min_contact: int = _MIN_CONTACT) -> StoppingRule:
    """The stopping rule of ``palpbayes replay`` and ``follow`` (at least one condition).

    Parameters
    ----------
    target
        Relative half-width of E's 90 % interval to reach (0.05 or ``"5%"``), or None.
    max_force
        [N] Largest force above the baseline, or None.
    max_depth
        [m] Largest depth below the estimated surface, or None.
    target_on
        The interval the target is tested on: ``"full"`` (with the budget; the command
        line's default) or ``"stat"``.
    min_contact
        Fewest samples in contact before the target may stop the run.

    Raises
    ------
    InputError
        No condition, or a value out of range (the message names it).
    """
    if target is None and max_force is None and max_depth is None:
        raise InputError("give a stopping rule: --target 2% (precision), --max-force N or "
                         "--max-depth M")
    return StoppingRule(target=None if target is None else parse_fraction(target, "target"),
                        max_force=max_force, max_depth=max_depth, min_contact=min_contact,
                        target_on=target_on)


def _known_thickness(thickness: float | str | None) -> float | None:
    """[m] A layer's thickness (None: a half-space); ``"unknown"`` is refused (the online
    model takes a known one)."""
    h = check_thickness(thickness, "--thickness")
    if h == "unknown":
        raise InputError("--thickness unknown: online estimation needs a known thickness "
                         "(or none, for a half-space); fit the whole trace with "
                         "'palpbayes fit ... --thickness unknown' to infer it")
    return h


def _check_bonding(bonding: str | None) -> None:
    if bonding is not None and bonding not in BONDINGS:
        raise InputError(f"bonding {bonding!r} must be {' or '.join(map(repr, BONDINGS))} "
                         "(--bonding: the layer's base), or None for a half-space")


def online_model(tip: Tip, nu: float | None = None, thickness: float | str | None = None,
                 bonding: str | None = None) -> ModelSpec:
    """The contact model of online estimation: ``tip`` at ``nu`` (None: :data:`DEFAULT_NU`),
    a half-space, or a layer ``thickness`` [m] thick on a ``bonding`` base (both needed: a
    thickness is never dropped, the half-space would read a thin block as stiffer).

    Raises
    ------
    InputError
        A bad nu or thickness, ``"unknown"``, a thickness without its base or a base without
        a thickness.
    """
    nu = DEFAULT_NU if nu is None else check_nu(nu)
    h = _known_thickness(thickness)
    _check_bonding(bonding)
    if h is None:
        if bonding is not None:
            raise InputError("--bonding is the base of a layer: give --thickness M too")
        return ModelSpec(tip, nu=nu)
    if bonding is None:
        raise InputError(f"--thickness {h:g} m: give the layer's base, --bonding bonded "
                         "(glued, or on a plate it cannot slide on) or --bonding free "
                         "(lubricated); the online estimator takes one base")
    return ModelSpec(tip, nu=nu, thickness=h, bonding=bonding)


@dataclass(repr=False)
class Replay(ReplayResult):
    """A replayed trace (:func:`replay`, ``palpbayes replay``): the
    :class:`~palpbayes.online.recorded.ReplayResult` (``history``, ``at_stop``, ``final``,
    both intervals, ``checks_at_stop``, :meth:`summary`, :attr:`row`) with its figure and the
    files ``palpbayes replay --out`` writes.  (Here, not in :mod:`palpbayes.online`: the
    figures' module sits above the online estimator.)
    """

    @classmethod
    def of(cls, result: ReplayResult) -> Replay:
        """``result`` with its figure and files."""
        return cls(**{f.name: getattr(result, f.name) for f in fields(ReplayResult)})

    def plot(self, truth: float | None = None) -> Figure:
        """``replay.png``'s figure (:func:`palpbayes.plots.online.plot_replay`): E with its
        interval against depth, the relative half-width with the target, the stop (a vertical
        line marked "stop") and the trace id as the title.

        Parameters
        ----------
        truth
            [Pa] The true modulus of a simulated trace, drawn as a line (``--truth``).

        Returns
        -------
        matplotlib.figure.Figure
        """
        from .plots.online import plot_replay

        return plot_replay(self.history, stop_n=None if self.at_stop is None else self.at_stop.n,
                           target=self.rule.target, truth=truth, title=self.trace_id)

    def save(self, out: str | os.PathLike, *, truth: float | None = None) -> Path:
        """Write what ``palpbayes replay --out OUT`` writes into ``out`` (created):
        ``replay.csv`` (``history``), ``replay_summary.csv`` (:meth:`summary`) and
        ``replay.png`` (:meth:`plot` with ``truth`` [Pa], 150 dpi).  The three are written into
        a staging folder inside ``out`` first and moved out together: a failure leaves
        ``out``'s files as they were.  Other files in ``out`` are left alone.

        Parameters
        ----------
        out
            The folder.
        truth
            [Pa] The true modulus drawn on the figure (``--truth``).

        Returns
        -------
        pathlib.Path
            ``out``.

        Raises
        ------
        InputError
            The folder cannot be created (a file of that name, no permission).
        """
        from .io.atomic import staged_folder, write_csv_atomic, write_with

        out = Path(out)
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(f"cannot create the folder {out} ({exc.strerror or exc}); "
                             "choose another") from None
        with staged_folder(out, prefix=".replay-partial-") as stage:
            write_csv_atomic(self.history, stage / outputs.REPLAY_HISTORY)
            write_csv_atomic(self.summary(), stage / outputs.REPLAY_SUMMARY)
            fig = self.plot(truth)
            write_with(lambda tmp: fig.savefig(tmp, dpi=150, format="png"),
                       stage / outputs.REPLAY_FIGURE, suffix=".png")
        return out


@dataclass(frozen=True)
class ReplayRequest:
    """What a replay is asked to do: the options of ``palpbayes replay`` by their Python names
    and with its defaults, checked when made (the rule first, as the command line checks it).

    Parameters
    ----------
    target, max_force, max_depth, target_on, min_contact
        The stopping rule (:func:`stopping_rule`; at least one of the first three): a relative
        half-width (0.05 or ``"5%"``, kept as a float), [N], [m], the interval tested
        (``"full"`` or ``"stat"``), the fewest samples in contact before the target may fire.
    chunk
        Samples per update.
    noise, noise_pp
        Noise model (``"gaussian"`` or ``"ar1"``) and the sensor's peak-to-peak noise [N]
        (None: 6 sd of the baseline).
    nu
        Poisson ratio [-] (None: :data:`~palpbayes.contact.DEFAULT_NU`, 0.3).
    thickness, bonding
        A layer: its thickness [m] (None: the trace's own, else a half-space) and its base
        (``"bonded"`` or ``"free"``; needed with a thickness).
    seed
        Seed of the posterior and budget draws and of the model checks (0: the command
        line's).
    """

    target: float | str | None = None
    max_force: float | None = None
    max_depth: float | None = None
    target_on: str = DEFAULT_TARGET_ON
    min_contact: int = _MIN_CONTACT
    chunk: int = DEFAULT_CHUNK
    noise: str = DEFAULT_NOISE
    noise_pp: float | None = None
    nu: float | None = None
    thickness: float | str | None = None
    bonding: str | None = None
    seed: int = 0

    def __post_init__(self) -> None:
        rule = stopping_rule(self.target, self.max_force, self.max_depth, self.target_on,
                             self.min_contact)
        object.__setattr__(self, "target", rule.target)
        check_chunk(self.chunk)
        check_noise_options(self.noise, self.noise_pp)
        if self.nu is not None:
            object.__setattr__(self, "nu", check_nu(self.nu))
        object.__setattr__(self, "thickness", _known_thickness(self.thickness))
        _check_bonding(self.bonding)
        check_seed(self.seed)

    @property
    def rule(self) -> StoppingRule:
        """The stopping rule."""
        return stopping_rule(self.target, self.max_force, self.max_depth, self.target_on,
                             self.min_contact)

    def model(self, trace: IndentationTrace) -> ModelSpec:
        """The contact model for ``trace``: its tip, :attr:`nu`, and a layer of
        :attr:`thickness` (else the trace's own thickness) on the :attr:`bonding` base
        (:func:`online_model`)."""
        if trace.tip is None:
            raise InputError(f"{trace.trace_id}: no tip geometry; give the tip (--tip ..., "
                             "tip= from Python)")
        h = self.thickness if self.thickness is not None else trace.thickness
        return online_model(trace.tip, self.nu, h, self.bonding)

    def run(self, trace: IndentationTrace) -> Replay:
        """Replay ``trace`` (:func:`palpbayes.online.recorded.replay`) with E's interval with
        the budget at every update, as ``palpbayes replay`` does.

        Raises
        ------
        InputError
            No tip, a layer without its base, no contact in the recording.
        """
        return Replay.of(recorded.replay(trace, self.model(trace), rule=self.rule,
                                         chunk=self.chunk, noise=self.noise,
                                         noise_pp=self.noise_pp, seed=self.seed, total=True))


#: The options of :func:`replay` beyond its named ones: the request's other fields.
_REQUEST_KEYS = frozenset(f.name for f in fields(ReplayRequest))


# Many parameters: the tip, specimen and stopping rule by name, as `palpbayes replay` takes them
# (ReplayRequest holds them): the door a user types.
def replay(source: str | os.PathLike | IndentationTrace | pd.DataFrame, *,
           tip: str | Tip | None = None, radius: float | None = None,
           half_angle: float | None = None, c: float | None = None, n: float | None = None,
           nu: float | None = None, thickness: float | None = None,
           target: float | str | None = None, seed: int = 0, **options) -> Replay:
    """Replay a recorded trace as if live, as ``palpbayes replay`` does: where would the
    stopping rule have stopped, and what was E then (docs/api.md)?

    Parameters
    ----------
    source
        A recording (trace CSV, UR RTDE log, ROS 2 bag, AFM file; read as :func:`palpbayes.read`
        reads it, an AFM file's approach), an :class:`~palpbayes.trace.IndentationTrace` or a
        DataFrame with ``time_s, z_m, force_n``.
    tip, radius, half_angle, c, n
        The tip (:func:`palpbayes.api.make_tip`; a trace's own when None); a file needs it.
    nu
        Poisson ratio [-] (None: 0.3, as the command line assumes).
    thickness
        [m] A layer's thickness (with ``bonding``); None: a trace's own, else a half-space.
    target
        Relative half-width of E's 90 % interval to stop at: 0.05 or ``"5%"`` (``--target``).
    seed
        Seed of the draws and checks (0, the command line's).
    **options
        The other fields of :class:`ReplayRequest` (``max_force`` [N], ``max_depth`` [m],
        ``target_on``, ``min_contact``, ``chunk``, ``noise``, ``noise_pp`` [N],
        ``bonding``) and the reader's (``columns``, ``units``, ``force_sign``, ``z_sign``,
        ``curve``, ``material``, ... as :func:`palpbayes.read` takes them).

    Returns
    -------
    Replay
        ``.summary()`` is ``replay_summary.csv``, ``.history`` ``replay.csv``, ``.plot()``
        the figure and ``.save(DIR)`` writes the three files ``palpbayes replay --out DIR``
        writes (the same bytes for the same inputs: ``tests/integration/test_replay_door.py``).

    Raises
    ------
    InputError, GeometryError, DataFileError
        An unknown or bad option (named), no stopping rule, no tip, a file that cannot be
        read, no contact.
    """
    from .api import READER_KEYS, _trace_of, make_tip

    reader = {k: options.pop(k) for k in list(options) if k in READER_KEYS}
    unknown = sorted(set(options) - _REQUEST_KEYS)
    if unknown:
        known = sorted(_REQUEST_KEYS - {"target", "nu", "thickness", "seed"})
        raise InputError(f"replay: unknown option(s) {', '.join(unknown)}; use {', '.join(known)}"
                         " or a reader option (columns, units, force_sign, z_sign, curve ...)")
    request = ReplayRequest(target=target, nu=nu, thickness=thickness, seed=seed, **options)
    the_tip = make_tip(tip, radius=radius, half_angle=half_angle, c=c, n=n)
    if isinstance(source, str | os.PathLike):
        if the_tip is None:
            raise InputError(f"{source}: replaying a file needs the tip: tip='sphere', "
                             "radius=0.01 (or a palpbayes.Tip), as --tip and its size")
        from .io.afm import is_afm_file

        if is_afm_file(source):  # the approach, as palpbayes replay reads an AFM file
            reader.setdefault("segments", ("approach",))
    elif not isinstance(source, IndentationTrace | pd.DataFrame):
        raise InputError(f"replay takes a path, an IndentationTrace or a DataFrame, not "
                         f"{type(source).__name__}")
    trace = _trace_of(source, the_tip, request.thickness, reader)
    return request.run(trace)
