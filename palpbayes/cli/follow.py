"""``palpbayes follow --tip ... --target 5%``: E live, from samples as they arrive.

Reads samples (time, z, force) from stdin or a TCP connection, as CSV lines with a header or
JSON lines (:mod:`palpbayes.online.stream`), feeds them to the online estimator in chunks as
``replay`` does, prints one line per update (flushed at once), and the stop line the moment
the stopping rule fires, then runs the model checks and exits with a status that says why
(:data:`EXIT_STATUS`).  Every sample sent is used (``replay`` keeps a recording's loading
segment): the sender stops at the deepest point.  With ``--timeout`` a pause in the stream
gives a partial chunk, so the updates (and the sample the rule fires at) can then differ from
``replay``'s; ``--timeout 0`` keeps them equal.

What comes when, at a stop (:class:`~palpbayes.cli.follow_lines.StopLine`; every line's
format is :mod:`palpbayes.cli.follow_lines`'s):

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
import math
import sys
import textwrap
import threading
import time
from collections.abc import Callable, Iterable

from ..checks import checks_summary
from ..contact import DEFAULT_NU_NOTE
from ..errors import InputError
from ..online import OnlineEstimator, OnlineState
from ..online.stream import Batch, SampleParser, batches
from ..online.tcp import (
    DEFAULT_HOST,
    SAMPLE_TIMEOUT,
    SEND_TIMEOUT,
    accept_lines,
    connect_lines,
    listen,
    parse_address,
)
from .follow_lines import StopLine, final_json, final_text, update_json, update_text
from .next import add_rule_options
from .online_options import add_online_options, estimator_from_args, rule_from_args
from .options import (
    add_column_options,
    add_specimen_options,
    read_options_from_args,
    tip_from_args,
)

__all__ = ["register", "run", "follow", "follow_stream", "EXIT_STATUS", "EXIT_ENDED",
           "EXIT_BAD_INPUT", "HELP_WIDTH", "SWITCH_INTERVAL"]

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
per press.  The robot sends 'press X Y' or 'press X Y DEPTH' [m] (no DEPTH: the state's
depth), waits for the verdict, then sends the samples.  The verdict, one JSON line:
  {{"event": "refused", "rule": ..., "message": ...}}: off the footprint, inside a keep-out
     zone, a depth not allowed (--depths), or a predicted peak force over --max-force (the
     contact law at the stiffest press so far x the prior's largest lump ratio); the press
     is not recorded, the connection is closed, the loop takes the next one;
  {{"event": "accepted", ..., "predicted_force_n": ...}}: press, to DEPTH at most.
Every line above then also comes back on the connection; a sample reaching --max-force
gives the stop line at once (the press is then not recorded); at the stop (or when the
robot shuts its sending side) the press's E is added to DIR/presses.csv and the answer
follows, one JSON line with a "decision" key: "event" "next" (the next press: connect
again) or "done" (exit 0 decided, 11 undecided: the --budget is spent or no candidate is
left).  A line that cannot be sent within --send-timeout (the robot stopped reading) drops
the press (stderr says so) and closes its connection; the loop goes on.  A first line that
is not a press line gets {{"event": "error", "message": ...}} and exit status 2."""

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
                        "per press ('press X Y [DEPTH]', then its samples), refuse an unsafe "
                        "one, add each press's E to DIR/presses.csv and answer with the next "
                        "press or the decision")
    m.add_argument("--criterion", choices=("eig", "lse", "ucb"), default="eig",
                   help="how the next press is chosen (default eig; 'palpbayes next --help')")
    m.add_argument("--depths", metavar="F1,F2,...", default=None,
                   help="allowed indentation depths as fractions of the state's thickness "
                        "(e.g. 0.1,0.2; default the state's, from 'next --init --depths'): a "
                        "press at another depth is refused before it (--max-force, above, is "
                        "the force limit: default the state's)")
    m.add_argument("--send-timeout", type=float, default=SEND_TIMEOUT, metavar="S",
                   help=f"longest wait to send one line to a robot that stopped reading "
                        f"(default {SEND_TIMEOUT:g} s): the press is then dropped and its "
                        "connection closed")
    m.add_argument("--sample-timeout", type=float, default=SAMPLE_TIMEOUT, metavar="S",
                   help=f"longest wait for the next sample of a press (default "
                        f"{SAMPLE_TIMEOUT:g} s): a robot that stops sending without closing "
                        "loses its press, its connection is closed and the loop goes on")
    add_rule_options(m)
    p.set_defaults(input="the stream", map_only=tuple(
        (a.option_strings[0], a.dest, a.default) for a in m._group_actions[1:]))


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
    if args.map is not None:
        from ..active.files import read_limits

        for opt, v in (("--send-timeout", args.send_timeout),
                       ("--sample-timeout", args.sample_timeout)):
            if not (math.isfinite(v) and v > 0):
                raise InputError(f"{opt} {v!r} must be a time > 0 [s]")
        if args.max_force is None:  # the state's force limit stops a press too
            args.max_force = read_limits(args.map).max_force
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
        from dataclasses import replace

        from .follow_map import live_loop
        from .follow_safety import force_law
        from .online_options import model_from_args

        def press(lines: Iterable[str], source: str, emit: Callable[[str], None],
                  depth: float | None):
            stop = rule if depth is None else replace(rule, max_depth=min(
                depth, rule.max_depth or depth))  # never past the press's depth
            est = estimator_from_args(args, tip, stop)  # a fresh estimator per press
            return follow_stream(args, est, opts, lines, source, emit)

        return live_loop(args, press, _say, force_at=force_law(model_from_args(args, tip)))
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
