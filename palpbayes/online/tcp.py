"""A TCP connection as a stream of text lines for :func:`palpbayes.online.stream.batches`.

Either palpbayes listens and the robot connects (:func:`listen`, then :func:`accept_lines`),
or the robot listens and palpbayes connects (:func:`connect_lines`).  A listener binds to the
loopback interface, :data:`DEFAULT_HOST`, unless another host is given on purpose: samples
from another machine are then accepted by anyone who can reach the port.  What arrives is
only read as text (UTF-8 lines), never unpickled or evaluated.
"""

from __future__ import annotations

import socket
from typing import TextIO

from ..errors import InputError

__all__ = ["DEFAULT_HOST", "listen", "accept_lines", "connect_lines", "parse_address"]

#: The interface a listener binds to unless told otherwise: loopback only.
DEFAULT_HOST = "127.0.0.1"


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
