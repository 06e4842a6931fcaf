"""Samples as they arrive: lines of text (CSV or JSON) into (t, z, F) batches.

A stream is either CSV, whose first line is a header naming the columns of the canonical
trace CSV (``time_s, z_m, force_n``: SI, z up, force positive when pressing; separated by
commas, semicolons, tabs or blanks), or JSON lines, one object per line with the same keys
(``{"time_s": 0.00125, "z_m": 0.101, "force_n": 0.002}``).  The first non-blank line decides
which.  Other column names, units and signs are taken as the trace CSV reader takes them
(``columns``, ``units``, ``force_sign``, ``z_sign``).  Values are parsed with ``float`` and
``json.loads`` only: nothing that arrives is evaluated or unpickled.

Every bad line (malformed, a missing column, a non-finite value, time going backwards) raises
:class:`~palpbayes.errors.StreamError` naming its line number, the column or value, and what
to do.

:func:`batches` groups the samples into chunks of ``chunk`` for the online estimator; a
partial chunk is given when the stream ends, and when no sample has arrived for ``timeout``
seconds, so a slow stream still gets decisions.  The lines are read and parsed by a background
thread that stamps each with its arrival time (:func:`time.perf_counter`), so that the latency
of a decision can be measured from the arrival of the last sample it used, and that asks an
estimator's ``limit`` about every sample as it arrives, before any posterior work: the sample
that reaches the stopping rule's max force or max depth ends its chunk at once, and
``on_limit`` is called there (``palpbayes follow`` prints its stop line), while the update of
the chunk before may still be running (:func:`batches`: when that cannot change the answer).
The reader runs at most :data:`MAX_BACKLOG` samples ahead of the batches handed over: a sender
faster than the estimator (a recording piped in) then waits, its pipe or socket full, instead
of the memory growing with the stream (~300 bytes a sample waiting: 240 MB for 400,000 piped
in); a live sender at the sensor's rate never meets the bound.
"""

# Long module: one job, lines of text into (t, z, F) batches; the parser and the feed share the
#   column and limit rules.

from __future__ import annotations

import json
import math
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, StreamError
from ..io.trace_csv import column_hint
from ..io.units import force_factor, length_factor, time_factor

__all__ = ["SampleParser", "Batch", "LimitHit", "batches", "CANONICAL_COLUMNS", "MAX_BACKLOG"]

#: Most samples read and not yet handed over in a batch (a minute at 800 Hz; at least two
#: chunks): the reader waits beyond it (module docstring).
MAX_BACKLOG = 50_000
#: Quantity -> canonical column (key) name, as in the trace CSV.
CANONICAL_COLUMNS = {"time": "time_s", "z": "z_m", "force": "force_n"}
_DEFAULT_UNIT = {"time": "s", "z": "m", "force": "N"}
_FACTOR = {"time": time_factor, "z": length_factor, "force": force_factor}
_FIX_COLUMNS = ("send the columns time_s, z_m, force_n or map them with --time-column, "
                "--z-column, --force-column (and --time-unit, --z-unit, --force-unit)")


class SampleParser:
    """Parse the lines of one stream into samples (time [s], z [m], force [N]).

    Parameters
    ----------
    source
        Name of the stream in error messages (``stdin``, ``tcp 127.0.0.1:5000``).
    columns
        Quantity (``time``, ``z``, ``force``) -> column or key name, where it is not the
        canonical one (:data:`CANONICAL_COLUMNS`).
    units
        Quantity -> unit of its values (default s, m, N).
    force_sign, z_sign
        -1 to flip a force that is negative when pressing, or a z that is down-positive.
    """

    def __init__(self, source: str = "stdin", columns: dict[str, str] | None = None,
                 units: dict[str, str] | None = None, force_sign: float = 1.0,
                 z_sign: float = 1.0) -> None:
        columns, units = dict(columns or {}), dict(units or {})
        unknown = (set(columns) | set(units)) - set(CANONICAL_COLUMNS)
        if unknown:
            raise InputError(f"unknown quantity {sorted(unknown)}; use time, z and force")
        if force_sign not in (1, -1) or z_sign not in (1, -1):
            raise InputError("force_sign and z_sign must be +1 or -1")
        self.source = source
        self.keys = {q: columns.get(q, CANONICAL_COLUMNS[q]) for q in CANONICAL_COLUMNS}
        sign = {"time": 1.0, "z": float(z_sign), "force": float(force_sign)}
        self.scale = {q: sign[q] * _FACTOR[q](units.get(q, _DEFAULT_UNIT[q]))
                      for q in CANONICAL_COLUMNS}
        self.kind: str | None = None  # "csv" or "json", from the first non-blank line
        self.index: dict[str, int] = {}  # CSV: quantity -> field position
        self.n_fields = 0
        self.delimiter: str | None = None
        self.last_time = -math.inf

    def parse(self, line: str, lineno: int) -> tuple[float, float, float] | None:
        """The sample (t [s], z [m], F [N]) of line ``lineno`` (from 1), or None for a blank
        line or the CSV header."""
        text = line.strip()
        if not text:
            return None
        if self.kind is None:
            self.kind = "json" if text.startswith("{") else "csv"
            if self.kind == "csv":
                self._header(text, lineno)
                return None
        raw = self._json(text, lineno) if self.kind == "json" else self._csv(text, lineno)
        values = {q: self._number(raw[q], q, lineno) for q in CANONICAL_COLUMNS}
        t = values["time"]
        if t < self.last_time:
            raise StreamError(self.source, lineno,
                              f"time goes backwards: {self.keys['time']} = {raw['time']} after "
                              f"{self.last_time / self.scale['time']:.10g}",
                              "send the samples in time order, one clock for the whole stream")
        self.last_time = t
        return t, values["z"], values["force"]

    def _header(self, text: str, lineno: int) -> None:
        self.delimiter = next((d for d in ",;\t" if d in text), None)  # None: blanks
        names = [n.strip().strip('"') for n in text.split(self.delimiter)]
        missing = [q for q in CANONICAL_COLUMNS if self.keys[q] not in names]
        if missing:
            try:
                float(names[0])
                first = " (the first line is numbers: a CSV stream starts with its header)"
            except ValueError:
                first = ""
            # the column that differs in case only, or a robot log's, with the options
            listed = ", ".join(
                repr(self.keys[q]) + column_hint(names, q, self.keys[q],
                                                 given=self.keys[q] != CANONICAL_COLUMNS[q])
                for q in missing)
            raise StreamError(self.source, lineno,
                              f"missing column {listed}{first}; the header has "
                              f"{', '.join(map(repr, names))}", _FIX_COLUMNS)
        self.index = {q: names.index(self.keys[q]) for q in CANONICAL_COLUMNS}
        self.n_fields = len(names)

    def _csv(self, text: str, lineno: int) -> dict[str, str]:
        if text.startswith("{"):
            raise StreamError(self.source, lineno, "a JSON object in a CSV stream",
                              "send one format for the whole stream")
        fields = [f.strip() for f in text.split(self.delimiter)]
        if len(fields) != self.n_fields:
            raise StreamError(self.source, lineno,
                              f"{len(fields)} fields where the header names {self.n_fields}: "
                              f"{text[:80]!r}", "send one value per header column")
        return {q: fields[i] for q, i in self.index.items()}

    def _json(self, text: str, lineno: int) -> dict:
        try:
            obj = json.loads(text)
        except json.JSONDecodeError as exc:
            raise StreamError(self.source, lineno, f"not a JSON object: {exc.msg} in "
                              f"{text[:80]!r}", "send one JSON object per line") from None
        if not isinstance(obj, dict):
            raise StreamError(self.source, lineno, f"not a JSON object: {text[:80]!r}",
                              "send one JSON object per line")
        missing = [self.keys[q] for q in CANONICAL_COLUMNS if self.keys[q] not in obj]
        if missing:
            raise StreamError(self.source, lineno,
                              f"missing key {', '.join(map(repr, missing))}; the object has "
                              f"{', '.join(map(repr, obj)) or 'no keys'}", _FIX_COLUMNS)
        return {q: obj[self.keys[q]] for q in CANONICAL_COLUMNS}

    def _number(self, raw, quantity: str, lineno: int) -> float:
        key = self.keys[quantity]
        if isinstance(raw, bool) or not isinstance(raw, (int, float, str)):
            raise StreamError(self.source, lineno, f"{key} = {raw!r} is not a number",
                              "send a decimal number")
        try:
            v = float(raw)
        except ValueError:
            comma = " (a decimal comma? send a decimal point)" if "," in str(raw) else ""
            raise StreamError(self.source, lineno, f"{key} = {raw!r} is not a number{comma}",
                              "send a decimal number") from None
        if not math.isfinite(v):
            raise StreamError(self.source, lineno, f"{key} = {raw!r} is not finite",
                              "drop the sample or send a measured value")
        return v * self.scale[quantity]


@dataclass(frozen=True)
class Batch:
    """Samples to give the estimator in one update.

    Attributes
    ----------
    t, z, force
        [s], [m], [N] The samples, in time order.
    last_line
        Line number of the last sample.
    arrived
        :func:`time.perf_counter` [s] when the last sample's line arrived.
    why
        ``"chunk"`` (a full chunk), ``"limit"`` (the ``limit`` of :func:`batches` ended it
        at this sample), ``"timeout"`` (no sample for the time-out) or ``"end"``.
    """

    t: np.ndarray
    z: np.ndarray
    force: np.ndarray
    last_line: int
    arrived: float
    why: str

    @property
    def size(self) -> int:
        return int(self.t.size)


@dataclass(frozen=True)
class LimitHit:
    """The sample at which ``limit`` of :func:`batches` said stop.

    Attributes
    ----------
    reason
        ``"max force"`` or ``"max depth"``.
    n
        Samples so far, this one included (the ``n`` of the update on its batch).
    line
        Its line number.
    t, z, force
        [s], [m], [N] The sample.
    arrived
        :func:`time.perf_counter` [s] when its line arrived.
    """

    reason: str
    n: int
    line: int
    t: float
    z: float
    force: float
    arrived: float


#: The end of the stream, in the reader's queue of lines.
_END = object()


class _Feed:
    """The samples between the reader thread and the consumer of :func:`batches`.

    The reader parses each line as it arrives and *judges* it (asks ``limit``, then puts it
    in the batch being filled, which a full chunk or a limit closes); the consumer takes the
    closed batches.  A sample is judged once every batch before it has been used (the
    consumer is back for more: ``limit`` then sees the state those batches made, as in
    ``replay``), or as soon as ``current(batches closed)`` says the state ``limit`` judges
    against is already that of all of them (the update still running has set its surface);
    until then it waits, unjudged, and is judged by the next line's arrival or by the
    consumer when it comes back.  All of it under one condition variable.
    """

    def __init__(self, chunk: int, limit, on_limit, current, source: str) -> None:
        self.chunk, self.limit, self.on_limit, self.current = chunk, limit, on_limit, current
        self.source = source
        self.cond = threading.Condition()
        self.unjudged: deque = deque()  # (line number, arrived, sample | _END | exception)
        self.buf: list[tuple[float, float, float]] = []  # the batch being filled
        self.ready: deque = deque()  # closed batches (or the exception to raise)
        self.busy = False  # a batch is out with the consumer (its update may be running)
        self.closed = False  # the end, an error or a limit: no batch after those ready
        self.n = 0  # samples judged
        self.closed_batches = 0  # batches closed (each one update)
        self.last_line, self.last_arrival = 0, 0.0
        # samples read, and handed over in batches: the reader waits while the difference
        # is at the backlog (at least two chunks, so that a partial batch is never starved)
        self.queued = self.handed = 0
        self.backlog = max(MAX_BACKLOG, 2 * chunk)

    def read(self, lines: Iterable[str], parser: SampleParser) -> None:
        """The reader thread: parse, judge, close batches until the stream or the run ends."""
        lineno = 0
        try:
            for line in lines:
                arrived = time.perf_counter()
                lineno += 1
                try:
                    sample = parser.parse(line, lineno)
                except StreamError as exc:
                    self.add(lineno, arrived, exc)
                    return
                if sample is not None and self.add(lineno, arrived, sample):
                    # a limit stopped the run: what the sender still sends is read and
                    # dropped, so that closing a connection with unread data does not reset it
                    for _ in lines:
                        pass
                    return
        except (OSError, ValueError, UnicodeDecodeError) as exc:  # a closed or broken stream
            if self.closed:
                return
            self.add(lineno, time.perf_counter(), InputError(
                f"{self.source}: reading the stream failed after line {lineno}: {exc}"))
            return
        except BaseException as exc:  # noqa: BLE001 - the consumer raises it, not this thread
            self.add(lineno, time.perf_counter(), exc)
            return
        self.add(lineno, time.perf_counter(), _END)

    def add(self, lineno: int, arrived: float, item) -> bool:
        """Queue an item from the reader and judge what can be judged; True once the run is
        over for the reader (a limit, an error while judging, or the consumer gone).  A
        sample waits first while :attr:`backlog` samples are read and not handed over."""
        with self.cond:
            if isinstance(item, tuple):
                while not self.closed and self.queued - self.handed >= self.backlog:
                    self.cond.wait()
                if self.closed:
                    return True
                self.queued += 1
            self.unjudged.append((lineno, arrived, item))
            try:
                self.judge()
            except BaseException as exc:  # noqa: BLE001 - e.g. the stop line's broken pipe
                self.fail(exc)
            return self.closed

    def fail(self, exc: BaseException) -> None:
        self.unjudged.clear()
        self.ready.append(exc)
        self.closed = True
        self.cond.notify_all()

    def emit(self, why: str) -> Batch:
        a = np.array(self.buf, dtype=float).reshape(-1, 3)
        self.buf.clear()
        self.closed_batches += 1
        return Batch(a[:, 0], a[:, 1], a[:, 2], self.last_line, self.last_arrival, why)

    def judge(self) -> None:
        """Judge the waiting samples in order while the state is that of every batch before
        them (or ``current`` says the state is already theirs); under the lock."""
        judged = False
        while self.unjudged and not self.closed:
            if (self.limit is not None and (self.busy or self.ready)
                    and not (self.current is not None and self.current(self.closed_batches))):
                break
            lineno, arrived, item = self.unjudged.popleft()
            judged = True
            if item is _END:
                if self.buf:
                    self.ready.append(self.emit("end"))
                self.closed = True
                break
            if isinstance(item, BaseException):
                self.fail(item)
                break
            self.buf.append(item)
            self.n += 1
            self.last_line, self.last_arrival = lineno, arrived
            hit = (None if self.limit is None
                   else self.limit(np.array(item[1:2]), np.array(item[2:3])))
            if hit is not None:
                self.closed = True
                self.unjudged.clear()
                if self.on_limit is not None:  # said before the batch is handed over
                    self.on_limit(LimitHit(hit[1], self.n, lineno, *item, arrived))
                self.ready.append(self.emit("limit"))
            elif len(self.buf) >= self.chunk:
                self.ready.append(self.emit("chunk"))
        if judged:
            self.cond.notify_all()


def batches(lines: Iterable[str], parser: SampleParser, chunk: int = 100,
            timeout: float | None = 0.5,
            limit: Callable[[np.ndarray, np.ndarray], tuple[int, str] | None] | None = None,
            on_limit: Callable[[LimitHit], None] | None = None,
            current: Callable[[int], bool] | None = None) -> Iterator[Batch]:
    """Batches of ``chunk`` samples from ``lines`` as they arrive (module docstring).

    Parameters
    ----------
    lines
        The stream, one sample per line (a file, ``sys.stdin``, a socket's ``makefile``).
    parser
        Parses each line (:class:`SampleParser`).
    chunk
        Samples per batch; a partial batch at the end of the stream.
    timeout
        [s] Give a partial batch when no sample has arrived for this long; None or 0: wait
        for a full chunk.
    limit
        An estimator's :meth:`~palpbayes.online.OnlineEstimator.limit`, asked with every
        sample (its z [m] and F [N], one-element arrays) in the thread that reads the
        stream, as the sample arrives, before any posterior work: a sample it names (one
        that reaches the rule's max force or max depth) ends the batch at once, as
        :func:`palpbayes.online.recorded.chunks` ends a recorded chunk, and the stream is
        read no further.  It is asked once every batch before the sample has been used (the
        loop over the batches is back for the next one), so that it judges with the state
        those batches made, as ``replay`` does, or earlier when ``current`` allows.
    on_limit
        Called with the :class:`LimitHit` the moment ``limit`` names a sample, before its
        batch is handed over (``follow`` prints the stop line there), in the thread that
        judged it: the reader's, or the consumer's for a sample that waited for an update.
    current
        An estimator's :meth:`~palpbayes.online.OnlineEstimator.limit_current`, asked with
        the number of batches closed so far while one is still being used: True when
        ``limit`` already judges as it will once all of them are (the update running has
        set its surface), so that a sample arriving during an update is judged at once
        (None: it waits for the update to end).

    Raises
    ------
    StreamError
        On the first bad line (its number, the column or value, what to do).
    InputError
        When reading the stream fails.
    """
    if chunk < 1:
        raise InputError(f"chunk = {chunk} samples must be at least 1")
    feed = _Feed(chunk, limit, on_limit, current, parser.source)
    threading.Thread(target=feed.read, args=(lines, parser), name="palpbayes-stream",
                     daemon=True).start()
    cond = feed.cond
    try:
        while True:
            with cond:
                feed.busy = False  # the batch handed over last has been used
                feed.judge()
                while not feed.ready and not feed.closed:
                    if feed.buf and timeout:
                        wait = feed.last_arrival + timeout - time.perf_counter()
                        if wait <= 0:
                            feed.ready.append(feed.emit("timeout"))
                            break
                        cond.wait(wait)
                    else:
                        cond.wait()
                if not feed.ready:  # closed: the stream ended
                    return
                item = feed.ready.popleft()
                feed.busy = True
                if isinstance(item, Batch):
                    feed.handed += item.size
                    cond.notify_all()  # a reader waiting at the backlog may go on
            if isinstance(item, BaseException):
                raise item
            yield item
    finally:  # the consumer is done (the end, a stop, an error): the reader keeps nothing more
        with cond:
            feed.closed = True
            feed.unjudged.clear()
            cond.notify_all()
