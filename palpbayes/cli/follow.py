"""``palpbayes follow --tip ... --target 5%``: E live, from samples as they arrive.

Reads samples (time, z, force) from stdin or a TCP connection, as CSV lines with a header or
JSON lines (:mod:`palpbayes.online.stream`), feeds them to the online estimator in chunks as
``replay`` does, prints one line per update (flushed at once), and the stop line the moment
the stopping rule fires, then runs the model checks and exits with a status that says why
(:data:`EXIT_STATUS`).  Every sample sent is used (``replay`` keeps a recording's loading
segment): the sender stops at the deepest point.  With ``--timeout`` a pause in the stream
gives a partial chunk, so the updates (and the sample the rule fires at) can then differ from
``replay``'s; ``--timeout 0`` keeps them equal.

What comes when, at a stop (:class:`StopLine`):

1. the **stop line** (``stop: REASON at n N ...``; with ``--json`` ``"event": "stop"``,
   ``"final": false``), flushed the moment the stop is known.  A max force or max depth is
   judged at every sample as it arrives, in the thread that reads the stream, before any
   posterior work (:meth:`~palpbayes.online.OnlineEstimator.limit`): its stop line gives the
   sample (n, line, t, z), the force above the baseline and the depth below the surface of
   the last update, and no E.  A precision target is judged after each chunk's update: its
   stop line comes as soon as the statistical E is known (with ``--target-on full``, once the
   full interval is), before the rest of the update;
2. the update on the samples up to the stop (E with both intervals, ``"stop"`` set);
3. the **last line** (``stop: ...; model checks: ...``; ``"event": "stop"``, ``"final":
   true``), after the model checks of the offline fit have run on the samples received.

When the stream ends first there is no stop line: the updates, then the last line, ``end:``
(``"event": "end"``).

With ``--map DIR`` (and ``--listen``) follow runs the live loop of an active search, one
connection per press, each answered with the next press (:mod:`palpbayes.cli.follow_map`).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import textwrap
import threading
import time
from collections.abc import Callable, Iterable

from ..checks import CheckResult, checks_summary
from ..contact import DEFAULT_NU_NOTE
from ..errors import InputError
from ..online import OnlineEstimator, OnlineState
from ..online.stream import Batch, LimitHit, SampleParser, batches
from ..online.tcp import DEFAULT_HOST, accept_lines, connect_lines, listen, parse_address
from ..units import format_force, format_length, format_pressure
from .next import add_rule_options
from .online_options import add_online_options, estimator_from_args, rule_from_args
from .options import (
    add_column_options,
    add_specimen_options,
    read_options_from_args,
    tip_from_args,
)

__all__ = ["register", "run", "follow", "follow_stream", "update_text", "update_json",
           "final_json", "final_text", "StopLine", "stop_json", "stop_text", "EXIT_STATUS",
           "EXIT_ENDED", "EXIT_BAD_INPUT", "HELP_WIDTH", "SWITCH_INTERVAL"]

#: Exit status when the stopping rule fires, per reason.
EXIT_STATUS = {"target precision": 0, "max force": 3, "max depth": 4}
#: Exit status when the stream ends before the rule fires (the robot must stop on its own).
EXIT_ENDED = 5
#: Exit status of bad input (a bad line, option or tip): the CLI's usual 2.
EXIT_BAD_INPUT = 2

EPILOG = f"""\
exit status:
  {EXIT_STATUS['target precision']}    stopped: target precision reached (--target)
  {EXIT_STATUS['max force']}    stopped: max force reached (--max-force)
  {EXIT_STATUS['max depth']}    stopped: max depth reached (--max-depth)
  {EXIT_ENDED}    the stream ended before the stopping rule fired
  {EXIT_BAD_INPUT}    bad input: a malformed line, a missing column, a non-finite value, time
       going backwards (stderr names the line), or a bad option
  1    failed otherwise;  130  interrupted

Every update is one line on stdout, flushed at once: E with its statistical interval and
its full one (with the budget).  When the rule fires, three lines, in this order:
  1. the stop line, 'stop: REASON at n N (t T s): ...' (--json: "event": "stop",
     "final": false), flushed the moment the stop is known, for the robot to stop on.
     --max-force and --max-depth are judged at every sample as it arrives, before any
     posterior work: the line gives the sample, the force above the baseline and the
     depth (below the surface of the last update), no E.  --target is judged after each
     chunk's update, as soon as the interval it is tested on is known;
  2. the update on the samples up to the stop (E with both intervals);
  3. the last line, 'stop: ...; model checks: ...' (--json: "event": "stop",
     "final": true, with the checks), once the model checks of 'palpbayes fit' have run
     on the samples received (failures on stderr).
When the stream ends first, the last line starts with 'end:' ("event": "end").
Input is parsed as numbers only (float, json.loads): nothing is evaluated or unpickled.

live loop (--listen PORT --map DIR, DIR from 'palpbayes next DIR --init'): one connection
per press.  The robot sends 'press X Y' [m], then the samples; every line above also comes
back on the connection; at the stop (or when the robot shuts its sending side) the press's
E is added to DIR/presses.csv and the answer follows, one JSON line with a "decision" key:
"event" "next" (the next press: connect again) or "done" (exit 0 decided, 11 undecided: the
--budget is spent or no candidate is left).  A first line other than 'press X Y' gets
{{"event": "error", "message": ...}} and exit status 2."""

#: [s] Longest a thread holds the interpreter while another waits for it, during the run
#: (:func:`sys.setswitchinterval`; Python's default is 5 ms): the reader thread gets it within
#: this to judge a sample that arrives while an update is running.
SWITCH_INTERVAL = 2e-4

#: Width the description of ``follow --help`` is wrapped to (the epilog's layout is kept, so
#: the formatter does not wrap the description).
HELP_WIDTH = 90

DESCRIPTION = textwrap.fill(
    "Read samples (time_s, z_m, force_n) as they arrive, as CSV lines with a header or JSON "
    "lines, from stdin or TCP; print E with its 90 % interval (statistical, and full: with "
    "the uncertainty budget) after every chunk, and a stop line the moment the stopping rule "
    "fires (a max force or max depth at the very sample, before any posterior work), so that "
    "a robot script can stop the motion; then the update up to the stop, the model checks "
    "and a last line, and exit with a status that says why (below). The "
    "estimator and its options are replay's; unlike replay, which keeps a recording's "
    "loading segment, follow uses every sample it is sent, so send the approach and the "
    "indentation only (not the hold or retract). With --map DIR, the live loop of an active "
    "search: one connection per press, each answered with the next press (below).",
    HELP_WIDTH)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "follow", help="E live from samples as they arrive; exit when the rule fires",
        description=DESCRIPTION, epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    src = p.add_mutually_exclusive_group()
    src.add_argument("--listen", metavar="[HOST:]PORT", default=None,
                     help=f"listen for one TCP connection on PORT (host {DEFAULT_HOST}, "
                          "loopback only, unless HOST is given; 0: any free port, printed on "
                          "stderr)")
    src.add_argument("--connect", metavar="HOST:PORT", default=None,
                     help="connect to a TCP server that sends the samples")
    p.add_argument("--timeout", type=float, default=0.5, metavar="S",
                   help="update with a partial chunk when no sample has arrived for S "
                        "seconds (default 0.5; 0: wait for full chunks)")
    p.add_argument("--json", action="store_true",
                   help="print each update as one JSON object instead of text, and the "
                        "last line (the stop or the end, with the model checks) too")
    add_online_options(p)
    add_specimen_options(p, "tip and specimen")
    add_column_options(p, "columns, units and signs of the samples")
    m = p.add_argument_group("live loop of an active search (--map DIR, with --listen)")
    m.add_argument("--map", metavar="DIR", default=None,
                   help="a search state ('palpbayes next DIR --init'): take one connection "
                        "per press ('press X Y', then its samples), add each press's E to "
                        "DIR/presses.csv and answer with the next press or the decision")
    m.add_argument("--criterion", choices=("eig", "lse", "ucb"), default="eig",
                   help="how the next press is chosen (default eig; 'palpbayes next --help')")
    add_rule_options(m)
    p.set_defaults(input="the stream", map_only=tuple(
        (a.option_strings[0], a.dest, a.default) for a in m._group_actions[1:]))


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


def follow(stream: Iterable[Batch], estimator: OnlineEstimator,
           emit: Callable[[str], None], as_json: bool = False,
           stop_line: StopLine | None = None) -> tuple[OnlineState | None, list[float]]:
    """Update ``estimator`` with each batch, ``emit`` each update, stop when its rule fires.

    ``stop_line`` (None: none) says the stop an update fires the moment it is known, before
    the update's line; a limit's is said by the stream (``on_limit`` of
    :func:`~palpbayes.online.stream.batches`).

    Returns
    -------
    state
        The last state (None if no sample arrived).
    latencies
        [s] Per update, from the arrival of the batch's last sample to the return of ``emit``.
    """
    fmt = update_json if as_json else update_text
    state, latencies, said = None, [], set()
    for batch in stream:
        on_stop = None if stop_line is None else (
            lambda s, b=batch: stop_line.state(s, b))
        state = estimator.update(batch.t, batch.z, batch.force, on_stop=on_stop)
        emit(fmt(state, batch))
        if not as_json:  # a flag once, on stderr, when it first appears
            for flag in state.flags:
                key = " ".join(flag.split()[:4])
                if key not in said:
                    said.add(key)
                    print(f"warning: {flag}", file=sys.stderr, flush=True)
        latencies.append(time.perf_counter() - batch.arrived)
        if state.should_stop:
            break
    return state, latencies


_OUT = threading.Lock()


def _say(line: str) -> None:
    """Print ``line`` and flush, whole (the stop line can come from the reader thread)."""
    with _OUT:
        out = sys.stdout
        out.write(line + "\n")
        out.flush()


def follow_stream(args: argparse.Namespace, estimator: OnlineEstimator, opts: dict,
                  lines: Iterable[str], source: str, emit: Callable[[str], None],
                  done: Callable[[], None] | None = None) -> OnlineState | None:
    """Follow one stream of samples to its stop or its end (module docstring).

    Parameters
    ----------
    args
        follow's options (``--json``, ``--chunk``, ``--timeout``).
    estimator
        A fresh estimator with the stopping rule.
    opts
        Columns, units and signs of the samples (:func:`~.options.read_options_from_args`).
    lines
        The stream, one sample per line.
    source
        Its name in error messages (``stdin``, ``tcp HOST:PORT``).
    emit
        Prints one line, flushed, whole (called from two threads): every update, the stop
        line and the last line.
    done
        Called once the updates are over (the stop, the end or an error), before the model
        checks: closes the stream (None: the caller closes it).

    Returns
    -------
    OnlineState or None
        The last state (None if no sample arrived).

    Raises
    ------
    StreamError
        On a bad line (its number, the column or value, what to do).
    """
    parser = SampleParser(source, columns=opts.get("columns"), units=opts.get("units"),
                          force_sign=opts.get("force_sign", 1.0),
                          z_sign=opts.get("z_sign", 1.0))
    stop_line = StopLine(emit, estimator, as_json=args.json)
    stream = batches(lines, parser, chunk=args.chunk, timeout=args.timeout or None,
                     limit=estimator.limit, on_limit=stop_line.limit,
                     current=estimator.limit_current)
    # the reader thread judges each sample as it arrives, while an update may be running in
    # this one: hand it the interpreter within SWITCH_INTERVAL, not Python's default 5 ms
    switch = sys.getswitchinterval()
    sys.setswitchinterval(min(switch, SWITCH_INTERVAL))
    try:
        state, _ = follow(stream, estimator, emit, as_json=args.json, stop_line=stop_line)
    finally:
        sys.setswitchinterval(switch)
        stream.close()
        if done is not None:
            done()
    # the update carrying the stop is out: now the checks, on the samples received; a check
    # that cannot run is said, and the exit status stays the rule's (robot scripts read it)
    try:
        checks = (estimator.model_checks() if state is not None and state.E is not None
                  else [])
    except Exception as exc:  # noqa: BLE001 - after the stop, nothing may turn into a crash
        print(f"model check: could not run ({type(exc).__name__}: {exc})", file=sys.stderr,
              flush=True)
        checks = []
    if args.json:
        emit(final_json(state, checks))
    else:
        for flag in checks_summary(checks)["flags"]:
            print(f"model check: {flag}", file=sys.stderr, flush=True)
        emit(final_text(state, checks))
    return state


def _check_map_options(args: argparse.Namespace) -> None:
    """--map needs --listen; the live loop's options need --map."""
    if args.map is not None and args.listen is None:
        raise InputError(f"--map {args.map} needs --listen [HOST:]PORT: the live loop takes "
                         "one connection per press (not stdin or --connect)")
    used = [opt for opt, dest, default in args.map_only if getattr(args, dest) != default]
    if args.map is None and used:
        raise InputError(f"{', '.join(used)} belong(s) to the live loop: give --map DIR "
                         "(with --listen PORT), or leave them out")


def run(args: argparse.Namespace) -> int:
    _check_map_options(args)
    rule = rule_from_args(args)
    tip = tip_from_args(args)
    estimator = estimator_from_args(args, tip, rule)
    opts = read_options_from_args(args)
    if not (math.isfinite(args.timeout) and args.timeout >= 0):
        raise InputError(f"--timeout {args.timeout!r} must be a time >= 0 [s]")
    estimator.warm_up()  # a layer's budget tables, before the robot starts
    if args.nu is None:
        print(f"note: {DEFAULT_NU_NOTE.replace(', or a nu column in the manifest', '')}",
              file=sys.stderr, flush=True)
    if args.map is not None:
        from .follow_map import live_loop

        def press(lines: Iterable[str], source: str, emit: Callable[[str], None]):
            est = estimator_from_args(args, tip, rule)  # a fresh estimator per press
            return follow_stream(args, est, opts, lines, source, emit)

        return live_loop(args, press, _say)
    if args.listen is not None:
        host, port = parse_address(args.listen)
        if host not in (DEFAULT_HOST, "localhost", "::1"):
            print(f"note: listening on {host}, not loopback: anyone who can reach port "
                  f"{port} can send samples", file=sys.stderr, flush=True)
        with listen(port, host) as server:
            h, p = server.getsockname()[:2]
            print(f"listening on {h}:{p}", file=sys.stderr, flush=True)
            lines, peer = accept_lines(server)
        source = f"tcp {peer}"
    elif args.connect is not None:
        host, port = parse_address(args.connect)
        lines, source = connect_lines(host, port), f"tcp {host}:{port}"
    else:
        lines, source = sys.stdin, "stdin"
    state = follow_stream(args, estimator, opts, lines, source, _say,
                          done=None if lines is sys.stdin else lines.close)
    if state is not None and state.should_stop:
        return EXIT_STATUS[state.stop]
    return EXIT_ENDED
