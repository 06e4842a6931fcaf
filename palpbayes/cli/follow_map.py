"""``palpbayes follow --listen PORT --map DIR``: the live loop of an active search.

One listener, one TCP connection per press, so that a robot program runs press → decide →
move with nothing but a socket:

1. the robot connects and sends ``press X Y`` or ``press X Y DEPTH`` (the press position
   [m] and its indentation depth below the surface [m], numbers read with ``float``) as the
   first non-blank line; without DEPTH the press is at the search's depth (``depth_m`` of
   ``search.json``);
2. the press is checked before any sample is read (:mod:`palpbayes.active.safety`): off the
   footprint, inside a keep-out zone, at a depth not in (0, thickness) or not one of the
   allowed depths (``--depths``, fractions of the thickness), or with a predicted peak force
   over ``--max-force`` (the contact law of follow's tip, nu and layer at the largest
   plausible E: the stiffest press so far, the upper end of its one-sided 99 % interval,
   times the search prior's largest lump ratio, 3 by default), it gets one line,
   ``{"event": "refused", "rule": "footprint" | "keep-out" | "depth" | "force", "message":
   ..., "x_m", "y_m", "depth_m"}`` (the message names the position, the rule broken and what
   to do), is not recorded, and the connection is closed; the loop takes the next one
   (exit status unchanged).  Otherwise it gets ``{"event": "accepted", "x_m", "y_m",
   "depth_m", "max_force_n", "predicted_force_n"}`` (null where not known; no force is
   predicted before the first press): a robot that waits for this line before it moves is
   refused before the press;
3. the press's samples, exactly as to ``palpbayes follow`` (CSV with a header, or JSON
   lines), are followed by a fresh online estimator (:func:`~.follow.follow_stream`) that
   stops at the press's depth too (the stricter of it and ``--max-depth``); every line it
   prints (the updates, the stop line, the last line) goes to stdout **and** to the
   connection, flushed, so the robot can stop on the stop line without reading stdout.  A
   sample whose force above the baseline reaches ``--max-force`` gives the stop line at
   once (``"stop": "max force"``);
4. at the stop (or when the robot shuts its sending side), the press's estimate of E becomes
   its posterior of log(E/Pa) (:func:`press_posterior`), added to ``DIR/presses.csv`` with
   P(lump) after it.  Not added, and said in the answer's ``"warning"``: a press without an
   estimate (no contact; press again), and a press the force limit stopped
   (:data:`FORCE_STOP`: it did not reach its depth, so its E would be read as the wrong
   signature; the answer may name the same position again: press there shallower, or
   elsewhere);
5. the answer of :func:`palpbayes.active.next_presses` on the new state is one JSON line
   (:func:`~.next.answer_json`; ``"event"`` ``"next"`` with the next press, or ``"done"``)
   on the connection and stdout; then the connection is closed (after the robot closes its
   side, or a grace period) and, unless the answer is ``"done"``, the next one is accepted.

A press whose next sample does not come within ``--sample-timeout`` [s] (30 s) is dropped
the same way (one ``{"event": "error"}`` line, not recorded, the connection closed): a robot
that stalls without closing does not hold the loop.  Every line sent waits at most
``--send-timeout`` [s] (:data:`~palpbayes.online.tcp.SEND_TIMEOUT`, 10 s) for the robot to
make room.  A robot that stops reading fills the
sockets' buffers (some MB on loopback, so it shows only after many lines) and then loses its
press: said on stderr (``error: ...``), not recorded, no answer, the connection closed at
once, and the loop takes the next connection.

The answer does not wait for the robot to stop sending: what it still sends after the stop
line is read and dropped.  Line numbers in messages count the connection's lines, the press
line included.  A first line that is not a press line gets ``{"event": "error", "message":
...}`` and ends the loop with exit status 2, as does a bad sample line.  Exit status at the
end: :data:`~.next.EXIT_DECIDED` (decided) or :data:`~.next.EXIT_UNDECIDED` (the budget is
spent, or no candidate is left).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import threading
from collections.abc import Callable, Iterable
from itertools import chain, repeat
from pathlib import Path

from ..active import NextPresses, SearchState, next_presses
from ..active.files import SEARCH_FILE, append_press, read_state
from ..errors import InputError
from ..intervals import normal_z
from ..online import OnlineState
from ..online.tcp import DEFAULT_HOST, SessionConnection, accept_session, listen, parse_address
from .follow_safety import PressChecks, deepest_allowed, map_limits, note_limits
from .next import EXIT_DECIDED, EXIT_UNDECIDED, answer_json, search_rule_from_args

__all__ = ["live_loop", "parse_press_line", "press_posterior", "error_json", "CLOSE_GRACE",
           "NO_ESTIMATE", "PRESS_TIMEOUT", "FORCE_STOP"]

#: [s] Longest wait, after the answer, for the robot to close its side of a connection before
#: it is closed anyway (what the robot sends meanwhile is read and dropped).
CLOSE_GRACE = 2.0

#: [s] Longest wait for a connection's ``press X Y`` line (a robot that connects and dies
#: must not block the loop).
PRESS_TIMEOUT = 30.0

#: The answer's ``"warning"`` for a press without an estimate of E.
NO_ESTIMATE = ("no estimate of E from this press ({why}): it is not added to the search; "
               "press again")

#: The answer's ``"warning"`` for a press the force limit stopped.
FORCE_STOP = ("the force limit --max-force {F:g} N was reached at ({x:g}, {y:g}) m before the "
              "press's depth: it is not added to the search (its E would be read as a press "
              "to the full depth); press elsewhere, or there at a shallower allowed depth")

_PRESS_FIX = ("send 'press X Y' or 'press X Y DEPTH' (the press position and its indentation "
              "depth [m], numbers) as the first line of each connection, then the press's "
              "samples")

#: One press: follows ``lines`` (named ``source``), each line out through ``emit``, stopping
#: at the depth [m] (None: the rule's own); returns the last state
#: (:func:`palpbayes.cli.follow.follow_stream` with a fresh estimator).
PressFn = Callable[[Iterable[str], str, Callable[[str], None], float | None],
                   OnlineState | None]


def error_json(message: str) -> str:
    """The error line sent to the robot: ``{"event": "error", "message": ...}``."""
    return json.dumps({"event": "error", "message": message})


def parse_press_line(line: str, source: str, lineno: int) -> tuple[float, float, float | None]:
    """(x, y, depth) [m] of a ``press X Y`` or ``press X Y DEPTH`` line (numbers read with
    ``float`` only, finite; depth None when not given).  Whether the depth is allowed is
    :func:`palpbayes.active.safety.check_press`'s to say.

    Parameters
    ----------
    line
        The connection's first non-blank line ('' when it ended before one).
    source, lineno
        The connection and the line's number in it, for the message.

    Raises
    ------
    InputError
        Not a press line: the message names the line and what to send.
    """
    parts = line.split()
    if not parts:
        raise InputError(f"{source}: the connection ended before its first line; "
                         f"{_PRESS_FIX}")
    try:
        if len(parts) not in (3, 4) or parts[0].lower() != "press":
            raise ValueError
        vals = [float(v) for v in parts[1:]]
    except ValueError:
        raise InputError(f"{source} line {lineno}: {line.strip()[:80]!r} is not a press line; "
                         f"{_PRESS_FIX}") from None
    if not all(map(math.isfinite, vals)):
        raise InputError(f"{source} line {lineno}: {line.strip()[:80]!r}: the position and "
                         f"depth must be finite; {_PRESS_FIX}")
    return vals[0], vals[1], vals[2] if len(vals) == 3 else None


def press_posterior(state: OnlineState | None) -> tuple[float, float] | None:
    """A press's posterior of log(E/Pa) from its last online state: the mean log of E's
    median [Pa], the sd the half-width of the log of its statistical interval (``state.E``,
    90 %: the data's noise and surface, not the budget of ``E_total``) over the normal
    quantile of that level (1.6448536 at 90 %); None without a usable estimate."""
    E = None if state is None else state.E
    if E is None:
        return None
    med, lo, hi = float(E.median), float(E.lo), float(E.hi)
    if not all(math.isfinite(v) and v > 0 for v in (med, lo, hi)) or not 0 < E.level < 1:
        return None
    sd = (math.log(hi) - math.log(lo)) / (2.0 * normal_z(E.level))
    if not (math.isfinite(sd) and sd > 0):
        return None
    return math.log(med), sd


def _no_estimate_why(state: OnlineState | None) -> str:
    if state is None:
        return "no sample arrived"
    if not state.in_contact:
        return "no contact detected"
    return "too few samples in contact"


def _listen(address: str):
    """The listener of ``address``, said on stderr as follow says it."""
    host, port = parse_address(address)
    if host not in (DEFAULT_HOST, "localhost", "::1"):
        print(f"note: listening on {host}, not loopback: anyone who can reach port {port} "
              "can send presses", file=sys.stderr, flush=True)
    server = listen(port, host)
    h, p = server.getsockname()[:2]
    print(f"listening on {h}:{p}", file=sys.stderr, flush=True)
    return server


def _note_state_record(folder: Path, args: argparse.Namespace) -> None:
    """A note on stderr where follow's tip or depth differs from the one the state was
    created for (its contact radius is that tip's at that depth)."""
    try:
        rec = json.loads((folder / "search.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return
    said = []
    if rec.get("tip") and args.tip and rec["tip"] != args.tip:
        said.append(f"tip {rec['tip']} (follow: --tip {args.tip})")
    r = rec.get("tip_radius_m")
    if isinstance(r, (int, float)) and args.radius and not math.isclose(r, args.radius,
                                                                        rel_tol=1e-6):
        said.append(f"tip radius {r:g} m (follow: --radius {args.radius:g})")
    d = rec.get("depth_m")
    if isinstance(d, (int, float)) and args.max_depth and not math.isclose(
            d, args.max_depth, rel_tol=0.1):
        said.append(f"depth {d:g} m (follow: --max-depth {args.max_depth:g})")
    if said:
        print(f"note: the search in {folder} was set up for {'; '.join(said)}: its contact "
              "radius is that tip's at that depth", file=sys.stderr, flush=True)


def _status(ans: NextPresses) -> int:
    return EXIT_DECIDED if ans.decision else EXIT_UNDECIDED


def live_loop(args: argparse.Namespace, press: PressFn, say: Callable[[str], None],
              force_at: Callable[[float, float], float] | None = None) -> int:
    """Run the live loop on ``--listen`` for the search state ``--map`` (module docstring).

    Parameters
    ----------
    args
        follow's options: ``map``, ``listen``, ``criterion``, the search's stopping rule
        (``p_decide``, ``centre_radius``, ``budget``), ``json``, the tip, the limits
        (``depths``, ``max_force``) and ``send_timeout`` [s].
    press
        Follows one press's lines (:data:`PressFn`).
    say
        Prints one line on stdout, flushed, whole (from two threads).
    force_at
        Peak force [N] of a press at (E [Pa], depth [m])
        (:func:`~.follow_safety.force_law`); None: the force is not predicted (only the
        stop line guards it).

    Returns
    -------
    int
        :data:`~.next.EXIT_DECIDED` or :data:`~.next.EXIT_UNDECIDED` when the search stops.

    Raises
    ------
    InputError
        ``DIR`` holds no search state (the message names it; a ``palpbayes map`` folder is
        not one here: its presses are its points), a bad option, a connection
        whose first line is not a press line, or a bad sample line (the robot is sent the
        error first).  A refused press, a robot that stops reading or a press the force
        limit stops are not errors: the loop goes on.
    """
    folder = Path(args.map)
    state = read_state(folder)
    if not (folder / SEARCH_FILE).is_file():  # a map's folder: its presses are its points
        raise InputError(f"--map {folder}: a 'palpbayes map' output folder, not a search "
                         "state; the live loop adds its presses to a search state: create "
                         "one with 'palpbayes next DIR --init ...'")
    rule = search_rule_from_args(args)
    limits = map_limits(args)
    _note_state_record(folder, args)

    def answer(s: SearchState) -> NextPresses:  # never a depth over the force limit
        return next_presses(s, 1, criterion=args.criterion, rule=rule,
                            deepest=deepest_allowed(s, limits, force_at))

    first = answer(state)
    if first.stop:  # nothing to press: say so, do not listen
        say(answer_json(first))
        print(f"note: the search in {folder} has already stopped ({first.reason}); start "
              "another with 'palpbayes next DIR --init'", file=sys.stderr, flush=True)
        return _status(first)
    note_limits(state, limits, force_at)
    with _listen(args.listen) as server:
        while True:
            with accept_session(server, send_timeout=args.send_timeout,
                                read_timeout=getattr(args, "sample_timeout", None)) as conn:
                state, ans = _one_press(conn, state, folder, press, answer, say,
                                        PressChecks(limits, force_at))
                conn.close(CLOSE_GRACE)
            if ans is not None and ans.stop:
                print(f"search stopped: {ans.decision or 'undecided'} ({ans.reason})",
                      file=sys.stderr, flush=True)
                return _status(ans)


def _fail(conn: SessionConnection, exc: InputError) -> None:
    """Send the robot ``exc`` as an error line and close (the caller raises it)."""
    conn.send(error_json(str(exc)))
    conn.close(grace=1.0)


def _read_press_line(conn: SessionConnection, source: str) -> tuple[float, float, float | None]:
    """The connection's press line, parsed; an error is sent to the robot, then raised."""
    try:
        line = ""
        while not line.strip():
            line = conn.readline(timeout=PRESS_TIMEOUT)
            if not line:
                break
        return parse_press_line(line, source, conn.lines_read)
    except TimeoutError:
        err = InputError(f"{source}: no press line within {PRESS_TIMEOUT:g} s of "
                         f"connecting; {_PRESS_FIX}")
        _fail(conn, err)
        raise err from None
    except InputError as exc:
        _fail(conn, exc)
        raise
    except (OSError, UnicodeDecodeError) as exc:
        err = InputError(f"{source}: reading the press line failed ({exc}); {_PRESS_FIX}")
        _fail(conn, err)
        raise err from None


def _send_both(conn: SessionConnection, say: Callable[[str], None], row: dict) -> None:
    text = json.dumps(row)
    say(text)
    conn.send(text)


def _one_press(conn: SessionConnection, state: SearchState, folder: Path, press: PressFn,
               answer: Callable[[SearchState], NextPresses], say: Callable[[str], None],
               checks: PressChecks) -> tuple[SearchState, NextPresses | None]:
    """One connection: its press line, checked (a refusal is one line, and None for the
    answer), its samples, the press added, the answer sent; returns the new state and the
    answer (None when no answer was sent: a refusal, a robot that stopped reading)."""
    source = f"tcp {conn.peer}"
    x, y, depth = _read_press_line(conn, source)
    refusal, depth, F = checks(state, x, y, depth)
    if refusal is not None:  # before the press: one line, nothing recorded, the next one
        _send_both(conn, say, {"event": "refused", "rule": refusal.rule,
                               "message": refusal.message, "x_m": x, "y_m": y,
                               "depth_m": depth})
        print(f"refused: {refusal.message}", file=sys.stderr, flush=True)
        return state, None
    _send_both(conn, say, {"event": "accepted", "x_m": x, "y_m": y, "depth_m": depth,
                           "max_force_n": checks.limits.max_force, "predicted_force_n": F})
    lock = threading.Lock()

    def emit(text: str) -> None:  # the same lines in the same order on both (two threads)
        with lock:
            say(text)
            conn.send(text)
        if conn.send_timed_out:  # the robot stopped reading: end the press now
            conn.close(grace=0.0)

    # the lines already read come back blank, so that the parser's line numbers are the
    # connection's (blank lines are skipped)
    lines = chain(repeat("\n", conn.lines_read), conn.lines())
    try:
        last = press(lines, source, emit, depth)
    except InputError as exc:  # a bad sample line: the robot hears it too
        _fail(conn, exc)
        raise
    where = f"press at ({x:g}, {y:g}) m"
    if conn.read_timed_out:  # the robot stalled mid-press: the press is incomplete
        msg = (f"{source}: no sample for {conn.read_timeout:g} s (--sample-timeout); the "
               f"{where} is not added; connection closed, waiting for the next press")
        conn.send(error_json(msg))
        print(f"error: {msg}", file=sys.stderr, flush=True)
        return state, None
    if conn.send_timed_out:
        print(f"error: {source}: {conn.broken}; the {where} is not added (the robot may not "
              "have had its stop line); connection closed, waiting for the next press",
              file=sys.stderr, flush=True)
        return state, None
    post = press_posterior(last)
    if last is not None and last.stop == "max force":
        warning = FORCE_STOP.format(F=checks.limits.max_force or math.nan, x=x, y=y)
    elif post is None:
        warning = NO_ESTIMATE.format(why=_no_estimate_why(last))
    else:
        warning = ""
    if warning:
        ans = answer(state)
        print(f"{where}: {warning}", file=sys.stderr, flush=True)
    else:
        at = {} if state.press_depths is None or depth is None else {"depth_m": depth}
        ans = answer(state.with_press(x, y, *post, **at))  # P(lump) after it, for its row
        state = append_press(folder, state, x, y, *post, p_lump=float(ans.summary["p_lump"]),
                             **at)
        print(f"press {state.n} at ({x:g}, {y:g}) m: log(E/Pa) = {post[0]:.4f} ± "
              f"{post[1]:.4f}; P(lump) = {ans.summary['p_lump']:.3f}", file=sys.stderr,
              flush=True)
    text = answer_json(ans)
    if warning:
        text = json.dumps({**json.loads(text), "warning": warning})
    say(text)
    if conn.broken:
        print(f"note: {source} closed before the answer ({conn.broken}); it is on stdout",
              file=sys.stderr, flush=True)
    else:
        conn.send(text)
    return state, ans
