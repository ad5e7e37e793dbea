"""The socket ``gonio serve`` listens on: ``--host`` checked and resolved, and the port
bound, before anything is printed or served, so an address that cannot be bound is one
line (`GonioError`) naming the option, not the web server's log."""

from __future__ import annotations

import errno
import ipaddress
import re
import socket

from gonio.errors import GonioError

#: A host written with its port (``localhost:8765``, ``[::1]:8765``).
_WITH_PORT = re.compile(r"(\[[^\]]*\]|[^:]*):(\d+)")
#: What only an IPv4 address is written with (``999.1.1.1`` is refused, not looked up).
_DOTTED = re.compile(r"[0-9.]+")


def address(host: str) -> tuple[socket.AddressFamily, str]:
    """The address family and the numeric address (IPv4 or IPv6) that ``--host`` names:
    a literal address (an IPv6 one with or without brackets) or a host name that
    resolves. `GonioError` (one line) otherwise."""
    text = host.strip()
    literal = text[1:-1] if text.startswith("[") and text.endswith("]") else text
    try:
        ip = ipaddress.ip_address(literal)
    except ValueError:
        pass
    else:
        family = socket.AF_INET6 if ip.version == 6 else socket.AF_INET
        return family, str(ip)
    found = _WITH_PORT.fullmatch(text)
    if found:
        name, port = found.groups()
        raise GonioError(
            f"--host {host}: expected an address without a port; give the port with "
            f"--port (--host {name.strip('[]') or '127.0.0.1'} --port {port})"
        )
    if not text or _DOTTED.fullmatch(text) or any(c.isspace() or c in "/[]" for c in text):
        raise GonioError(
            f"--host {host if text else repr(host)}: expected an IPv4 or IPv6 address or a "
            "host name"
        )
    try:
        infos = socket.getaddrinfo(text, None, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError) as exc:
        why = exc.strerror if isinstance(exc, socket.gaierror) else str(exc)
        raise GonioError(
            f"--host {host}: expected an IPv4 or IPv6 address or a host name that resolves ({why})"
        ) from None
    inet = [i for i in infos if i[0] == socket.AF_INET] or infos  # IPv4 first, as uvicorn
    family, _, _, _, sockaddr = inet[0]
    return family, str(sockaddr[0])


def listen(family: socket.AddressFamily, ip: str, port: int) -> socket.socket:
    """A TCP socket bound to ``ip``:``port`` and listening (`GonioError`, one line, if
    the port is taken, not allowed, or the address is not this machine's)."""
    sock = socket.socket(family, socket.SOCK_STREAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # a restart at once
        sock.bind((ip, port))
        sock.listen(2048)
    except OSError as exc:
        sock.close()
        where = f"[{ip}]:{port}" if family == socket.AF_INET6 else f"{ip}:{port}"
        if exc.errno == errno.EADDRINUSE:
            why = "the port is in use (another gonio serve?); choose another with --port"
        elif exc.errno == errno.EACCES:
            why = "permission denied (a port below 1024 needs privileges); choose another"
        elif exc.errno == errno.EADDRNOTAVAIL:
            why = "not an address of this machine; --host names one of its own"
        else:
            why = exc.strerror or str(exc)
        raise GonioError(f"--host/--port {where}: cannot listen there: {why}") from None
    return sock


__all__ = ["address", "listen"]
