"""The studio's door: who may load its page and open its WebSocket.

Every web page a user visits can make the browser open a WebSocket to ``127.0.0.1`` (browsers do not apply the
same-origin policy to WebSockets), and anyone on the network can reach a studio that listens on ``0.0.0.0``. So,
as Jupyter does, every run has a secret (:func:`new_secret`) that the printed address carries as its first path
segment, ``http://HOST:PORT/SECRET/``, and :class:`Gate` lets a request through only when

* its path starts with the secret (the page) or is exactly the secret (the WebSocket the page opens);
* its ``Host`` header names this machine when the studio listens on a loopback address (a page that rebinds its
  own host name to 127.0.0.1 is refused), and the port the studio listens on;
* for the WebSocket: its ``Origin`` header is present and is the studio's own page (``http``, the port it listens
  on, and the host the browser connected to, or on loopback any of this machine's names for itself).

Anything else gets ``403`` with a sentence that tells nothing about the studio. viser 1.1 has no hook for this, so
:func:`guarded_viser` wraps the ``process_request`` of the one ``websockets`` server that viser starts while it is
being constructed (a lock keeps two constructions apart), and switches viser's share tunnel off: no client can ask
it to publish the studio on the internet.
"""

from __future__ import annotations

import dataclasses
import hmac
import ipaddress
import secrets
import threading
from typing import Any
from urllib.parse import unquote, urlsplit

FORBIDDEN = "op2motion studio: open the address the studio printed"
LOOPBACK_NAMES = frozenset({"localhost", "127.0.0.1", "::1"})
SECRET_BYTES = 24                  # the per-run secret: 24 random bytes, URL-safe base64 (32 characters)
_construct = threading.Lock()


def new_secret() -> str:
    """A fresh per-run secret for the studio's address."""
    return secrets.token_urlsafe(SECRET_BYTES)


def is_loopback(host: str) -> bool:
    """Whether ``host`` (a name or an address) stays on this machine."""
    name = host.strip("[]").lower()
    if name == "localhost":
        return True
    try:
        return ipaddress.ip_address(name).is_loopback
    except ValueError:
        return False


def _split_host(value: str) -> tuple[str, int | None]:
    """``host[:port]`` of a Host header (IPv6 in brackets) as (lower-case host, port: 80 when left out)."""
    try:
        parts = urlsplit(f"//{value}")
        return (parts.hostname or "").lower(), parts.port or 80
    except ValueError:
        return "", None


@dataclasses.dataclass
class Gate:
    """The checks of the module docstring for a studio listening on ``host`` at ``port`` with ``secret``."""

    host: str
    secret: str
    port: int = 0

    def refusal(self, path: str, headers: Any) -> str | None:
        """Why a request is refused (a phrase for the log), or None to let it through."""
        if any(len(headers.get_all(name)) > 1 for name in ("Host", "Origin", "Upgrade")):
            return "a header given twice"
        host, port = _split_host(headers.get("Host", ""))
        if not host or port != self.port:
            return "Host header not this studio"
        if is_loopback(self.host) and host not in LOOPBACK_NAMES:
            return "Host header not this machine"
        segment = unquote(path.partition("?")[0]).lstrip("/").split("/", 1)[0]
        if not hmac.compare_digest(segment.encode(), self.secret.encode()):
            return "no secret"
        if headers.get("Upgrade", "").lower() == "websocket":
            if unquote(path.partition("?")[0]).strip("/") != self.secret:
                return "WebSocket path"
            origin = headers.get("Origin")
            if origin is None:
                return "no Origin"
            parts = urlsplit(origin)
            try:
                origin_port = parts.port or {"http": 80, "https": 443}.get(parts.scheme)
            except ValueError:
                return "bad Origin"
            origin_host = (parts.hostname or "").lower()
            same = origin_host == host or is_loopback(self.host) and origin_host in LOOPBACK_NAMES
            if parts.scheme != "http" or not same or origin_port != port:
                return "foreign Origin"
        return None

    def page_path(self, path: str) -> str:
        """The path viser's file server sees: the secret segment taken off."""
        rest = path.partition("?")[0].lstrip("/")[len(self.secret):]
        return rest if rest.startswith("/") else "/" + rest


def guarded_viser(host: str, port: int, gate: Gate) -> Any:
    """A ``viser.ViserServer`` on ``host:port`` behind ``gate`` (see the module docstring); ``gate.port`` is set
    to the port it listens on."""
    import viser
    import websockets.asyncio.server as ws_server

    original = ws_server.serve

    class GuardedServe(original):  # type: ignore[misc, valid-type]
        """viser's server, with the gate before viser's own request handler."""

        def __init__(self, handler: Any, *args: Any, process_request: Any = None, **kwargs: Any):
            inner = process_request

            def check(connection: Any, request: Any) -> Any:
                if gate.port == 0:          # not listening yet
                    gate.port = connection.local_address[1]
                if gate.refusal(request.path, request.headers) is not None:
                    return connection.respond(403, FORBIDDEN + "\n")
                if request.headers.get("Upgrade", "").lower() == "websocket" or inner is None:
                    return None
                return inner(connection, dataclasses.replace(request, path=gate.page_path(request.path)))

            super().__init__(handler, *args, process_request=check, **kwargs)

    with _construct:
        ws_server.serve = GuardedServe  # type: ignore[misc]
        try:
            server = viser.ViserServer(host=host, port=port, verbose=False)
        finally:
            ws_server.serve = original  # type: ignore[misc]
    gate.port = int(server.get_port())
    _no_share_tunnel(server)
    return server


def _no_share_tunnel(server: Any) -> None:
    """Switch viser's share tunnel off: the page's "share" request does nothing."""
    from viser import _messages

    infra = server._websock_server
    for message in (_messages.ShareUrlRequest, _messages.ShareUrlDisconnect):
        if message in infra._incoming_handlers:
            infra.unregister_handler(message)
    server.request_share_url = lambda *args, **kwargs: None
