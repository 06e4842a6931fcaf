"""Replay a recorded trace as if it were live: where would the stopping rule have stopped?

The loading segment is fed to an :class:`~palpbayes.online.estimator.OnlineEstimator` in chunks
of ``chunk`` samples (100 by default: 0.125 s at the paper's 800 Hz, 0.2 s at a UR robot's
500 Hz).  The run goes on to the end of the recording after the rule fires, so that the
estimate at the stop can be set beside the estimate from the whole trace, and the depth and
peak force saved against the recorded protocol (the paper's fixed 10 % indentation) measured.
The model checks of the offline fit (:mod:`palpbayes.checks`) are run on the samples up to the
stop (:attr:`ReplayResult.checks_at_stop`).  :func:`palpbayes.replay` is the front door (a
file or a trace, with the command line's options); its :class:`~palpbayes.api_replay.Replay`
adds the figure and the files of ``palpbayes replay --out`` to a :class:`ReplayResult`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..bayes.budget import BudgetSpec
from ..bayes.mixture import MixtureSummary
from ..checks import CheckResult, checks_summary
from ..errors import InputError, PalpbayesError
from ..fitdata import ModelSpec
from ..trace import IndentationTrace
from .estimator import OnlineEstimator, OnlineState, StoppingRule

__all__ = ["ReplayResult", "replay", "run_to_stop", "chunks", "check_chunk",
           "needed_indentation", "HISTORY_COLUMNS", "STUDY_COLUMNS"]

#: Columns of :attr:`ReplayResult.history` (one row per update after contact).
HISTORY_COLUMNS = ("n", "t_s", "z_m", "depth_m", "peak_force_n", "E_pa", "E_lo_pa", "E_hi_pa",
                   "rel_half_width", "z_surf_m", "z_surf_sd_m", "stop", "E_total_lo_pa",
                   "E_total_hi_pa", "total_rel_half_width")


@dataclass
class ReplayResult:
    """A replayed trace.

    Attributes
    ----------
    history
        One row per update after contact (:data:`HISTORY_COLUMNS`).
    at_stop, final
        The state when the rule first fired (None if it never did) and at the last sample.
    budget_at_stop, budget_final
        E [Pa] with the uncertainty budget at those two points.
    rule
        The stopping rule.
    model
        The contact model replayed (its nu and layer go into :meth:`summary`).
    checks_at_stop
        The model checks (:meth:`OnlineEstimator.model_checks`) on the samples up to the stop;
        empty when the rule never fired.
    trace_id
        The replayed trace's id (the title of :meth:`plot`).
    """

    history: pd.DataFrame
    at_stop: OnlineState | None
    final: OnlineState
    budget_at_stop: MixtureSummary | None
    budget_final: MixtureSummary
    rule: StoppingRule
    model: ModelSpec | None = None
    checks_at_stop: list[CheckResult] = field(default_factory=list)
    trace_id: str = ""

    @property
    def row(self) -> dict:
        """The row of :meth:`summary` as a dict: stop time [s], depth [m], peak force [N],
        E [Pa] then and from the whole trace with both intervals, savings [%], the interval
        the target was tested on, the model (nu, thickness [m], base) and the model checks at
        the stop (the stop's columns only when the rule fired)."""
        f, s = self.final, self.at_stop
        row = {"stopped": s is not None, "reason": s.stop if s else "",
               "target_on": self.rule.target_on,
               "E_final_pa": f.E.median, "E_final_lo_pa": f.E.lo, "E_final_hi_pa": f.E.hi,
               "E_total_final_lo_pa": self.budget_final.lo,
               "E_total_final_hi_pa": self.budget_final.hi,
               "depth_final_m": f.depth, "peak_force_final_n": f.peak_force, "t_final_s": f.t}
        if self.model is not None:
            row.update(nu=self.model.nu, thickness_m=(np.nan if self.model.thickness is None
                                                      else self.model.thickness),
                       bonding=self.model.bonding if self.model.has_layer else "")
        if s is not None:
            row.update({
                "t_stop_s": s.t, "depth_stop_m": s.depth, "peak_force_stop_n": s.peak_force,
                "E_stop_pa": s.E.median, "E_stop_lo_pa": s.E.lo, "E_stop_hi_pa": s.E.hi,
                "rel_half_width_stop": s.E.rel_half_width,
                "E_total_stop_lo_pa": self.budget_at_stop.lo,
                "E_total_stop_hi_pa": self.budget_at_stop.hi,
                "depth_saved_pct": 100 * (1 - s.depth / f.depth) if f.depth > 0 else np.nan,
                "force_saved_pct": (100 * (1 - s.peak_force / f.peak_force)
                                    if f.peak_force > 0 else np.nan),
            })
            checks = checks_summary(self.checks_at_stop)
            row.update({"model_ok_stop": checks["model_ok"],
                        "misfit_checks_stop": checks["misfit_checks"],
                        "misfit_effect_stop": checks["misfit_effect"],
                        "check_flags_stop": "; ".join(checks["flags"])})
        return row

    def summary(self) -> pd.DataFrame:
        """``replay_summary.csv`` (docs/outputs.md) as a one-row table: :attr:`row`'s columns
        in its order (:meth:`palpbayes.api_replay.Replay.save` writes it)."""
        return pd.DataFrame([self.row])

    def __repr__(self) -> str:
        from ..units import format_force, format_length, format_pressure

        def interval(E, budget) -> str:
            if E is None or budget is None:
                return "no E yet"
            return (f"E {format_pressure(E.median)} [{format_pressure(budget.lo)}, "
                    f"{format_pressure(budget.hi)}]")

        s, f = self.at_stop, self.final
        if s is None:
            where = "never stopped"
        else:
            where = (f"stopped ({s.stop}) at {format_length(s.depth)} deep, "
                     f"{format_force(s.peak_force)}: {interval(s.E, self.budget_at_stop)}")
        return (f"{type(self).__name__}({self.trace_id!r}: {where}; whole trace "
                f"({format_length(f.depth)}): {interval(f.E, self.budget_final)}; 90 % "
                "intervals with the budget)")


#: Columns of :func:`needed_indentation` (one row per trace).
STUDY_COLUMNS = ("trace_id", "stopped", "reason", "t_stop_s", "depth_stop_m", "depth_full_m",
                 "peak_force_stop_n", "peak_force_full_n", "E_stop_pa", "E_stop_lo_pa",
                 "E_stop_hi_pa")


def needed_indentation(traces, models, rule: StoppingRule, *, chunk: int = 100,
                       noise: str = "gaussian") -> pd.DataFrame:
    """How much of each recorded indentation the stopping rule needed.

    Parameters
    ----------
    traces
        Recorded traces.
    models
        One :class:`~palpbayes.fitdata.ModelSpec` per trace.
    rule
        The stopping rule.
    chunk, noise
        As :func:`replay`.

    Returns
    -------
    pandas.DataFrame
        :data:`STUDY_COLUMNS`: where the rule fired (depth below the surface estimated then
        [m], peak force above the baseline [N], E with its interval [Pa]) against the whole
        recording (its deepest point below that surface, its peak force); a trace on which
        the rule never fired has ``stopped = False`` and its last state; one that could not be
        replayed (no approach, no contact) has the error in ``reason``.
    """
    rows = []
    for trace, model in zip(traces, models, strict=True):
        est = OnlineEstimator(model, noise=noise, rule=rule)
        row = dict.fromkeys(STUDY_COLUMNS, np.nan)
        try:
            s = run_to_stop(trace, est, chunk)
            seg = trace.loading_segment()
        except PalpbayesError as exc:  # one unusable recording does not stop the study
            row.update(trace_id=trace.trace_id, stopped=False, reason=f"error: {exc}")
            rows.append(row)
            continue
        row.update(trace_id=trace.trace_id, stopped=bool(s is not None and s.should_stop),
                   reason="" if s is None else s.stop)
        if s is not None and s.in_contact and s.E is not None:
            row.update(t_stop_s=s.t, depth_stop_m=s.depth,
                       depth_full_m=s.z_surf.median - float(seg.z.min()),
                       peak_force_stop_n=s.peak_force,
                       peak_force_full_n=float(seg.force.max()) - est.baseline_level,
                       E_stop_pa=s.E.median, E_stop_lo_pa=s.E.lo, E_stop_hi_pa=s.E.hi)
        rows.append(row)
    return pd.DataFrame(rows, columns=list(STUDY_COLUMNS))


def _row(s: OnlineState) -> dict:
    T = s.E_total
    return {"n": s.n, "t_s": s.t, "z_m": s.z, "depth_m": s.depth, "peak_force_n": s.peak_force,
            "E_pa": s.E.median, "E_lo_pa": s.E.lo, "E_hi_pa": s.E.hi,
            "rel_half_width": s.E.rel_half_width, "z_surf_m": s.z_surf.median,
            "z_surf_sd_m": s.z_surf.sd, "stop": s.stop,
            "E_total_lo_pa": T.lo if T else np.nan, "E_total_hi_pa": T.hi if T else np.nan,
            "total_rel_half_width": T.rel_half_width if T else np.nan}


def check_chunk(chunk: int) -> None:
    """Raise an :class:`~palpbayes.errors.InputError` unless ``chunk`` is a whole number of
    samples >= 1 (:func:`chunks`' check, run by ``palpbayes replay`` on its options first)."""
    if isinstance(chunk, bool) or not isinstance(chunk, int | np.integer):
        raise InputError(f"chunk = {chunk!r} must be a whole number of samples (at least 1)")
    if chunk < 1:
        raise InputError(f"chunk = {chunk} samples must be at least 1")


def chunks(trace: IndentationTrace, chunk: int,
           limit: Callable[[np.ndarray, np.ndarray], tuple[int, str] | None] | None = None):
    """The loading segment of ``trace`` as (t [s], z [m], F [N]) chunks of ``chunk`` samples,
    in time order: what a robot would stream.

    ``limit`` (an estimator's :meth:`~palpbayes.online.OnlineEstimator.limit`, asked for
    every chunk after the previous one has been used) ends a chunk at the sample it names, as
    ``palpbayes follow`` does; the next chunk starts after it.
    """
    check_chunk(chunk)
    seg = trace.loading_segment()
    a, n = 0, seg.time.size
    while a < n:
        b = min(a + chunk, n)
        hit = None if limit is None else limit(seg.z[a:b], seg.force[a:b])
        if hit is not None:
            b = a + hit[0] + 1
        yield seg.time[a:b], seg.z[a:b], seg.force[a:b]
        a = b


def run_to_stop(trace: IndentationTrace, estimator: OnlineEstimator,
                chunk: int = 100) -> OnlineState:
    """Feed ``trace`` to ``estimator`` until its rule fires (or the trace ends); the last
    state.  The quick form of :func:`replay` for simulation studies of the stopping rule."""
    state = None
    for t, z, f in chunks(trace, chunk, estimator.limit):
        state = estimator.update(t, z, f)
        if state.should_stop:
            break
    return state


# Many parameters: a replay's trace, model, rule and stream settings (chunk, noise); ReplayRequest
# gathers them at the door.
def replay(trace: IndentationTrace, model: ModelSpec | None = None, *,
           rule: StoppingRule | None = None, chunk: int = 100, noise: str = "gaussian",
           noise_pp: float | None = None, f_unc: float | None = None,
           budget: BudgetSpec | None = None, seed: int = 0, total: bool = False,
           checks: bool = True) -> ReplayResult:
    """Feed ``trace``'s loading segment to an online estimator, ``chunk`` samples at a time.

    ``total`` computes E with the budget at every update (the history's ``E_total_*``
    columns; always when the rule's target is on the full interval, NaN otherwise);
    ``checks`` runs the model checks on the samples up to the stop.

    Raises
    ------
    InputError
        If the trace has no tip and no model is given, ``chunk`` < 1, or contact is never
        detected.
    """
    if model is None:
        if trace.tip is None:
            raise InputError(f"{trace.trace_id}: no tip geometry; give the tip (--tip ...)")
        model = ModelSpec(trace.tip)
    rule = rule or StoppingRule()
    est = OnlineEstimator(model, noise=noise, noise_pp=noise_pp, f_unc=f_unc, rule=rule,
                          total=total, budget=budget, seed=seed)
    rows, at_stop, budget_at_stop, found = [], None, None, []
    for t, z, f in chunks(trace, chunk, est.limit):
        state = est.update(t, z, f)
        if state.in_contact and state.E is not None:
            rows.append(_row(state))
        if state.in_contact and at_stop is None and state.should_stop:
            at_stop = state
            if state.E is not None:
                budget_at_stop = state.E_total or est.budget_interval(seed=seed)
                found = est.model_checks(seed) if checks else []
    if est.state is None or not est.state.in_contact:
        raise InputError(f"{trace.source or trace.trace_id}: no contact detected (the force "
                         "never stays above the baseline noise); check the recording")
    history = pd.DataFrame(rows, columns=list(HISTORY_COLUMNS))
    return ReplayResult(history=history, at_stop=at_stop, final=est.state,
                        budget_at_stop=budget_at_stop,
                        budget_final=est.state.E_total or est.budget_interval(seed=seed),
                        rule=rule, model=model, checks_at_stop=found,
                        trace_id=str(trace.trace_id))
