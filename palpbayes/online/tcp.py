"""A TCP connection as a stream of text lines for :func:`palpbayes.online.stream.batches`.

Either palpbayes listens and the robot connects (:func:`listen`, then :func:`accept_lines`),
or the robot listens and palpbayes connects (:func:`connect_lines`).  A session of several
presses over one listener (``palpbayes follow --map``) takes one connection per press with
:func:`accept_session`: its lines in, and lines back to the robot on the same connection.
A listener binds to the loopback interface, :data:`DEFAULT_HOST`, unless another host is
given on purpose: samples from another machine are then accepted by anyone who can reach
the port.  What arrives is only read as text (UTF-8 lines), never unpickled or evaluated.
"""

from __future__ import annotations

import queue
import selectors
import socket
import threading
import time
from collections.abc import Iterator
from contextlib import suppress
from typing import TextIO

from ..errors import InputError

__all__ = ["DEFAULT_HOST", "listen", "accept_lines", "connect_lines", "parse_address",
           "SessionConnection", "accept_session", "SEND_TIMEOUT", "SAMPLE_TIMEOUT"]

#: The interface a listener binds to unless told otherwise: loopback only.
DEFAULT_HOST = "127.0.0.1"

#: [s] Longest a :meth:`SessionConnection.send` of one line may wait for the peer to make
#: room (a peer that stops reading fills the socket's buffers; then the send gives up).
SEND_TIMEOUT = 10.0
#: [s] Default longest wait for the next sample line of a press in ``follow --map`` (at
#: 800 Hz lines come every 1.25 ms; a gap this long is a robot that stalled).
SAMPLE_TIMEOUT = 30.0

#: ``send`` flag for a write that never blocks (POSIX); 0 elsewhere, where a write is only
#: begun once the socket is writable (and may then block until it is done).
_NO_WAIT = getattr(socket, "MSG_DONTWAIT", 0)


def parse_address(text: str, default_host: str = DEFAULT_HOST) -> tuple[str, int]:
    """'5000' -> (default_host, 5000); 'host:5000' -> ('host', 5000); port 0-65535."""
    host, sep, port = str(text).strip().rpartition(":")
    host = host.strip("[]") if sep else default_host
    try:
        p = int(port)
    except ValueError:
        raise InputError(f"{text!r} is not a TCP address: give PORT or HOST:PORT") from None
    if not 0 <= p <= 65535:
        raise InputError(f"{text!r}: port {p} must lie in 0-65535")
    return host or default_host, p


def listen(port: int, host: str = DEFAULT_HOST) -> socket.socket:
    """A socket listening on ``host``:``port`` (port 0: one the system picks; read it with
    ``getsockname()``) for one connection."""
    try:
        server = socket.create_server((host, port), backlog=1)
    except OSError as exc:
        raise InputError(f"cannot listen on {host}:{port}: {exc.strerror or exc}") from None
    return server


def accept_lines(server: socket.socket) -> tuple[TextIO, str]:
    """Wait for one connection on ``server``; its lines (close them to close the connection)
    and the peer's ``host:port``."""
    conn, peer = server.accept()
    lines = conn.makefile("r", encoding="utf-8", newline=None)
    conn.close()  # the socket closes with its lines
    return lines, f"{peer[0]}:{peer[1]}"


def connect_lines(host: str, port: int, timeout: float = 10.0) -> TextIO:
    """The lines sent by a server at ``host``:``port`` (connecting within ``timeout`` [s])."""
    try:
        conn = socket.create_connection((host, port), timeout=timeout)
    except OSError as exc:
        raise InputError(f"cannot connect to {host}:{port}: {exc.strerror or exc}") from None
    conn.settimeout(None)
    lines = conn.makefile("r", encoding="utf-8", newline=None)
    conn.close()  # the socket closes with its lines
    return lines


_EOF = object()  # the pump's mark: the peer closed its side (or the connection is closed)


class SessionConnection:
    """One connection of a session: the lines the peer sends, and lines sent back to it.

    One background thread (the pump) is the only reader of the socket: it reads lines until
    the peer closes its side, and hands them to :meth:`readline` and to the iterator of
    :meth:`lines` (for :func:`palpbayes.online.stream.batches`, whose own reader thread
    iterates it); once :meth:`close` has begun it reads on and drops what arrives, so that
    the connection is not reset with data unread.  :meth:`send` writes one line, flushed at
    once (Nagle's algorithm off), from any thread, within ``send_timeout``.  What arrives is
    only decoded as UTF-8 text, never evaluated or unpickled.

    Parameters
    ----------
    conn
        The accepted socket (the connection owns it from now on).
    peer
        The peer's ``host:port``, for messages.
    send_timeout
        [s] Longest wait of one :meth:`send` for room in the socket's buffers (a peer that
        stops reading); None: :data:`SEND_TIMEOUT`.
    read_timeout
        [s] Longest wait of :meth:`lines` for the next line (a peer that stops sending
        without closing): the iterator then ends and :attr:`read_timed_out` is True; None:
        no limit.

    Attributes
    ----------
    lines_read
        Lines handed out so far (by :meth:`readline` and :meth:`lines`).
    broken
        Why sending failed (the peer is gone, or stopped reading); "" while sending works.
    send_timed_out
        True once a send gave up after ``send_timeout`` (then :attr:`broken` says so too).
    read_timed_out
        True once :meth:`lines` waited ``read_timeout`` for a line that did not come.
    """

    def __init__(self, conn: socket.socket, peer: str, send_timeout: float | None = None,
                 read_timeout: float | None = None) -> None:
        self.peer = peer
        self.lines_read = 0  # lines handed out so far (readline and lines())
        self.broken: str = ""  # why sending failed (the peer is gone), "" while it works
        self.send_timed_out = self.read_timed_out = False
        self.send_timeout = SEND_TIMEOUT if send_timeout is None else float(send_timeout)
        self.read_timeout = None if read_timeout is None else float(read_timeout)
        if not (self.send_timeout > 0 and (read_timeout is None or self.read_timeout > 0)):
            conn.close()
            raise InputError(f"send timeout {send_timeout!r} and read timeout "
                             f"{read_timeout!r} must be > 0 [s]")
        self._conn = conn
        self._file = conn.makefile("r", encoding="utf-8", newline=None)
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self._send_lock = threading.Lock()
        self._closing = threading.Event()
        with suppress(OSError):
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._pump = threading.Thread(target=self._read, name="palpbayes-session", daemon=True)
        self._pump.start()

    def _read(self) -> None:
        """The pump: every line to the queue (dropped once closing), then the end."""
        try:
            while True:
                line = self._file.readline()
                if not line:
                    break
                if not self._closing.is_set():
                    self._queue.put(line)
        except (OSError, ValueError, UnicodeDecodeError) as exc:  # broken, closed, not UTF-8
            if not self._closing.is_set():
                self._queue.put(exc)
        self._queue.put(_EOF)

    def _next(self, timeout: float | None = None) -> str:
        """The next line ('' at the end); raises what reading it raised."""
        if self._closing.is_set():
            return ""
        try:
            item = self._queue.get(timeout=timeout)
        except queue.Empty:
            raise TimeoutError(f"tcp {self.peer}: no line for {timeout:g} s") from None
        if item is _EOF:
            self._queue.put(_EOF)  # the end stays the end for every later call
            return ""
        if isinstance(item, BaseException):
            self._queue.put(_EOF)
            raise item
        self.lines_read += 1
        return item

    def readline(self, timeout: float | None = None) -> str:
        """The next line the peer sent, with its newline; '' once the peer has closed its
        side (or :meth:`close` has begun).

        Raises
        ------
        TimeoutError
            No line within ``timeout`` [s] (None: wait for it).
        OSError, UnicodeDecodeError
            Reading the connection failed, or a line is not UTF-8.
        """
        return self._next(timeout)

    def lines(self) -> Iterator[str]:
        """The lines the peer sends from here on, until it closes its side, :meth:`close`
        begins (the iterator then ends, whichever thread is waiting on it) or no line comes
        within ``read_timeout`` (then :attr:`read_timed_out` is set)."""
        while True:
            try:
                line = self._next(self.read_timeout)
            except TimeoutError:
                self.read_timed_out = True
                return
            if not line:
                return
            yield line

    def send(self, line: str) -> bool:
        """Write ``line`` and a newline to the peer at once, waiting at most
        :attr:`send_timeout` [s] for room; False (and :attr:`broken` set) when the peer is
        gone or has not made room in time (:attr:`send_timed_out`), which is not an error:
        the caller goes on without it (every later send returns False at once)."""
        if self.broken:
            return False
        data = (line.rstrip("\n") + "\n").encode("utf-8")
        with self._send_lock:
            if self.broken:
                return False
            try:
                self._send_within(memoryview(data), time.monotonic() + self.send_timeout)
            except TimeoutError:
                self.send_timed_out = True
                self.broken = (f"a line could not be sent within {self.send_timeout:g} s: "
                               "the peer stopped reading")
                return False
            except OSError as exc:
                self.broken = exc.strerror or type(exc).__name__
                return False
        return True

    def _send_within(self, view: memoryview, deadline: float) -> None:
        """Write all of ``view`` before ``deadline`` (time.monotonic) or raise TimeoutError;
        never blocks past it (the socket stays blocking for the pump's reads)."""
        with selectors.DefaultSelector() as sel:
            sel.register(self._conn, selectors.EVENT_WRITE)
            while view:
                left = deadline - time.monotonic()
                if left <= 0 or not sel.select(left):
                    raise TimeoutError
                try:
                    n = self._conn.send(view, _NO_WAIT)
                except (BlockingIOError, InterruptedError):
                    continue
                view = view[n:]

    def close(self, grace: float = 2.0) -> None:
        """Say the end to the peer (FIN after what was sent), wait up to ``grace`` [s] for it
        to close its side while the pump reads and drops what it still sends, then close.
        A peer still sending after ``grace`` is cut off (its last data may then be reset).
        Safe to call twice, and from a ``finally``."""
        if self._closing.is_set():
            return
        self._closing.set()
        self._queue.put(_EOF)  # wakes a thread waiting in lines() or readline()
        with suppress(OSError):
            self._conn.shutdown(socket.SHUT_WR)
        self._pump.join(max(0.0, grace))
        if self._pump.is_alive():  # the peer neither closes nor stops: stop reading
            with suppress(OSError):
                self._conn.shutdown(socket.SHUT_RD)  # wakes the pump's blocked read
            self._pump.join(1.0)
        if not self._pump.is_alive():  # else leave the file to the pump (never close it
            self._file.close()         # under a read in progress: that would block here)
        self._conn.close()

    def __enter__(self) -> SessionConnection:
        return self

    def __exit__(self, *exc) -> None:
        self.close(grace=2.0 if exc[0] is None else 0.0)


def accept_session(server: socket.socket, timeout: float | None = None,
                   send_timeout: float | None = None,
                   read_timeout: float | None = None) -> SessionConnection:
    """Wait for the next connection on ``server`` (a :func:`listen` socket) and return it as
    a :class:`SessionConnection`: its lines (:meth:`~SessionConnection.readline`,
    :meth:`~SessionConnection.lines`) and a line writer back to the peer
    (:meth:`~SessionConnection.send`); close it with :meth:`~SessionConnection.close`.

    Parameters
    ----------
    server
        The listening socket.
    timeout
        [s] Longest wait for a connection (None: as long as it takes).
    send_timeout
        [s] The connection's longest wait to send one line (None: :data:`SEND_TIMEOUT`).
    read_timeout
        [s] Its longest wait for the next line in :meth:`~SessionConnection.lines` (None: no
        limit).

    Raises
    ------
    TimeoutError
        No connection within ``timeout``.
    """
    server.settimeout(timeout)
    try:
        conn, peer = server.accept()
    finally:
        server.settimeout(None)
    conn.settimeout(None)
    return SessionConnection(conn, f"{peer[0]}:{peer[1]}", send_timeout, read_timeout)
