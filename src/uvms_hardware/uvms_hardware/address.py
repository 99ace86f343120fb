"""Connection strings of the bridges: ``HOST[:PORT]``, ``udp:HOST:PORT``, ``serial:DEV[:BAUD]``.

Pure parsing, no sockets. Loopback is the default everywhere: a bridge or twin binds or
connects beyond 127.0.0.1 only when a user's own hardware file or parameter says so.
"""

from __future__ import annotations

from typing import NamedTuple

from uvms_hardware.errors import AddressError

#: The address every twin binds and every bridge connects to unless told otherwise.
LOOPBACK = '127.0.0.1'


class HostPort(NamedTuple):
    """A network endpoint."""

    host: str
    port: int


def parse_host_port(text: str, default_port: int, name: str = 'address') -> HostPort:
    """``HOST[:PORT]`` -> (host, port); the port defaults to ``default_port``.

    Raises:
        AddressError: naming ``name``, the text and the expected form.
    """
    host, sep, port_text = text.strip().rpartition(':')
    if not sep:
        host, port_text = text.strip(), str(default_port)
    if not host:
        raise AddressError(
            f'{name} = {text!r}: expected HOST[:PORT], e.g. {LOOPBACK}:{default_port}')
    return HostPort(host, parse_port(port_text, text, name))


def parse_port(port_text: str, text: str, name: str) -> int:
    """A TCP/UDP port number 1-65535 from ``port_text`` (part of ``text``, for the message)."""
    try:
        port = int(port_text)
    except ValueError:
        port = -1
    if not 0 < port < 65536:
        raise AddressError(f'{name} = {text!r}: the port {port_text!r} is not a number 1-65535')
    return port
