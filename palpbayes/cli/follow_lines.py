"""The lines ``palpbayes follow`` prints: each update, the stop line and the last line.

Every line as text or as one JSON object (``--json``; NaN as null): :func:`update_text` /
:func:`update_json` after each update, :func:`stop_text` / :func:`stop_json` the stop line
that :class:`StopLine` says once, the moment the stop is known (from the reader thread for a
limit), and :func:`final_text` / :func:`final_json` the last line, with the model checks.
What comes when is the command's (:mod:`palpbayes.cli.follow`); the live loop of an active
search sends the same lines back on its connection (:mod:`palpbayes.cli.follow_map`).
"""

from __future__ import annotations

import json
import math
import threading
from collections.abc import Callable

from ..checks import CheckResult, checks_summary
from ..online import OnlineEstimator, OnlineState
from ..online.stream import Batch, LimitHit
from ..units import format_force, format_length, format_pressure

__all__ = ["update_text", "update_json", "final_json", "final_text", "StopLine", "stop_json",
           "stop_text"]


def _value(x) -> float | None:
    return None if x is None or not math.isfinite(x) else float(x)


def update_json(state: OnlineState, batch: Batch) -> str:
    """One update as a JSON object (NaN as null): ``E_lo_pa``/``E_hi_pa``/``rel_half_width``
    the statistical interval, ``E_total_*``/``total_rel_half_width`` the full one (with the
    budget), ``budget_floor`` the budget's own relative half-width, ``flags`` the state's."""
    E, T = state.E, state.E_total
    row = {"event": "update", "n": state.n, "line": batch.last_line, "t_s": _value(state.t),
           "z_m": _value(state.z), "in_contact": state.in_contact,
           "depth_m": _value(state.depth), "peak_force_n": _value(state.peak_force),
           **_E_fields(state),
           "rel_half_width": _value(E.rel_half_width) if E else None,
           "total_rel_half_width": _value(T.rel_half_width) if T else None,
           "budget_floor": _value(state.floor), "stop": state.stop,
           "flags": list(state.flags)}
    return json.dumps(row)


def _stat_fields(E) -> dict[str, float | None]:
    """E [Pa] with its statistical interval (null where not known), the keys every line
    that gives E has."""
    return {"E_pa": _value(E.median) if E else None, "E_lo_pa": _value(E.lo) if E else None,
            "E_hi_pa": _value(E.hi) if E else None}


def _E_fields(state: OnlineState | None) -> dict[str, float | None]:
    """E [Pa] with its statistical interval and the full one's ends (null where not known),
    the keys an update and the last line share."""
    T = None if state is None else state.E_total
    return {**_stat_fields(None if state is None else state.E),
            "E_total_lo_pa": _value(T.lo) if T else None,
            "E_total_hi_pa": _value(T.hi) if T else None}


def _checks_json(checks: list[CheckResult]) -> list[dict]:
    return [{"name": c.name, "passed": bool(c.passed), "statistic": _value(c.statistic),
             "severity": c.details.get("severity", "" if c.passed else "material"),
             "effect": _value(c.details.get("effect")), "flag": c.flag} for c in checks]


def final_json(state: OnlineState | None, checks: list[CheckResult]) -> str:
    """The last line of ``--json``: ``event`` "stop" (the rule fired) or "end" (the stream
    ended), ``final`` true, where, E with both intervals, and the model checks on the samples
    received (``model_ok`` null when none could run)."""
    stopped = state is not None and state.should_stop
    summary = checks_summary(checks)
    row = {"event": "stop" if stopped else "end", "final": True,
           "stop": state.stop if stopped else "", "n": 0 if state is None else state.n,
           "t_s": None if state is None else _value(state.t),
           "in_contact": bool(state is not None and state.in_contact),
           **_E_fields(state),
           "model_ok": (None if not checks else bool(summary["model_ok"])),
           "misfit_checks": summary["misfit_checks"], "checks": _checks_json(checks),
           "check_flags": summary["flags"]}
    return json.dumps(row)


def final_text(state: OnlineState | None, checks: list[CheckResult]) -> str:
    """The last line of text: 'stop: REASON at n N (t T s)' or 'end: ...', then how the model
    checks came out."""
    if state is not None and state.should_stop:
        head = f"stop: {state.stop} at n {state.n} (t {state.t:.4f} s)"
    else:
        n = 0 if state is None else state.n
        why = "" if state is not None and state.in_contact else ", no contact detected"
        head = f"end: the stream ended after {n} samples without a stop{why}"
    if state is None or state.E is None:
        return head
    if not checks:
        return f"{head}; model checks: too few samples"
    summary = checks_summary(checks)
    if summary["model_ok"]:
        info = sum(not c.passed for c in checks)
        return (f"{head}; model checks: no material misfit ({len(checks) - info} of "
                f"{len(checks)} passed)")
    return f"{head}; model checks: MATERIAL MISFIT ({summary['misfit_checks']}; see stderr)"


def update_text(state: OnlineState, batch: Batch) -> str:
    """One update as a line of text: where, then E [90 % interval] and its half-width, and
    the full interval (with the budget) and its half-width."""
    head = f"n {state.n:6d}  t {state.t:8.3f} s"
    if not state.in_contact:
        return f"{head}  no contact yet"
    where = (f"{head}  depth {format_length(state.depth):>9}  peak force "
             f"{format_force(state.peak_force):>9}")
    if state.E is None:
        return f"{where}  in contact, no estimate yet"
    E, T = state.E, state.E_total
    line = (f"{where}  E = {format_pressure(E.median)} [{format_pressure(E.lo)}, "
            f"{format_pressure(E.hi)}]  (±{100 * E.rel_half_width:.2g} %)")
    if T is None:
        return line
    return (f"{line}  budget [{format_pressure(T.lo)}, {format_pressure(T.hi)}]  "
            f"(±{100 * T.rel_half_width:.2g} %)")


def _stop_row(reason: str, n: int, line: int, t: float, z: float, force: float | None,
              depth: float | None, E=None) -> dict:
    return {"event": "stop", "final": False, "stop": reason, "n": n, "line": line,
            "t_s": _value(t), "z_m": _value(z),
            "force_n": None if force is None else _value(force),
            "depth_m": None if depth is None else _value(depth), **_stat_fields(E),
            "rel_half_width": _value(E.rel_half_width) if E else None}


def stop_json(row: dict) -> str:
    """The stop line of ``--json`` (:class:`StopLine`): ``event`` "stop", ``final`` false,
    ``stop`` the reason, ``n``/``line``/``t_s``/``z_m`` the sample it is at, ``force_n``
    [N] its force above the baseline, ``depth_m`` [m] its depth below the surface (of the
    last update for a limit; null where not known), and E with its statistical interval
    (``E_pa``, ``E_lo_pa``, ``E_hi_pa``, ``rel_half_width``), null for a limit, which is
    judged before any posterior work."""
    return json.dumps(row)


def stop_text(row: dict) -> str:
    """The stop line as text: 'stop: REASON at n N (t T s): force F, depth D[, E = ...]; the
    update and the model checks follow'."""
    force = "?" if row["force_n"] is None else format_force(row["force_n"])
    depth = "not known yet" if row["depth_m"] is None else format_length(row["depth_m"])
    E = ""
    if row["E_pa"] is not None:
        E = (f", E = {format_pressure(row['E_pa'])} [{format_pressure(row['E_lo_pa'])}, "
             f"{format_pressure(row['E_hi_pa'])}]  (±{100 * row['rel_half_width']:.2g} %)")
    return (f"stop: {row['stop']} at n {row['n']} (t {row['t_s']:.4f} s): force {force} above "
            f"the baseline, depth {depth}{E}; the update and the model checks follow")


class StopLine:
    """The stop line of ``follow``: said once, flushed, the moment the stop is known.

    For a max force or max depth, :meth:`limit` is the ``on_limit`` of
    :func:`~palpbayes.online.stream.batches`, called in the reader thread at the very sample,
    before any posterior work; for a stop an update decides (a precision target, or a limit
    passed in the chunk where the contact is found), :meth:`state` is the ``on_stop`` of
    :meth:`OnlineEstimator.update <palpbayes.online.OnlineEstimator.update>`, called before
    the update's full interval is computed where the stop does not need it.

    Parameters
    ----------
    emit
        Prints one line (flushed; safe to call from two threads).
    estimator
        The estimator (its baseline and last surface give a limit's force and depth).
    as_json
        JSON (:func:`stop_json`) or text (:func:`stop_text`).
    """

    def __init__(self, emit: Callable[[str], None], estimator: OnlineEstimator,
                 as_json: bool = False) -> None:
        self.emit, self.estimator, self.as_json = emit, estimator, as_json
        self.said: dict | None = None  # the row said
        self._lock = threading.Lock()

    def _say(self, row: dict) -> None:
        with self._lock:
            if self.said is not None:
                return
            self.said = row
            self.emit(stop_json(row) if self.as_json else stop_text(row))

    def limit(self, hit: LimitHit) -> None:
        """The stop at the sample ``hit`` (judged against the last update)."""
        est = self.estimator
        state = est.limit_state  # what the limit was judged against
        depth = (state.z_surf.median - hit.z
                 if state is not None and state.z_surf is not None else None)
        self._say(_stop_row(hit.reason, hit.n, hit.line, hit.t, hit.z,
                            hit.force - est.baseline_level, depth))

    def state(self, state: OnlineState, batch: Batch) -> None:
        """The stop an update on ``batch`` fired (``state.stop``)."""
        self._say(_stop_row(state.stop, state.n, batch.last_line, state.t, state.z,
                            state.force, state.depth if state.z_surf is not None else None,
                            state.E))
