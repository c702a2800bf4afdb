"""One session with omegad: address parsing, unix/TCP/TLS sockets, the hello/welcome and HMAC
handshake, and routing of frames to the request (by id) that waits for them. Mirrors
client/address.cpp and client/connection.cpp, so the environment variables mean the same."""
from __future__ import annotations

import collections
import os
import socket
import ssl
import time
from dataclasses import dataclass

from . import codec
from .errors import ConnectionFailed, DaemonError, Error, ProtocolError, Timeout

DEFAULT_CLIENT_NAME = "omega-python/0.1"


@dataclass(frozen=True)
class Address:
    kind: str  # "unix" or "tcp"
    path: str = ""
    host: str = ""
    port: int = 0
    tls: bool = False

    def text(self) -> str:
        if self.kind == "unix":
            return "unix:" + self.path
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{'tls' if self.tls else 'tcp'}:{host}:{self.port}"


def parse_address(text: str) -> Address:
    """unix:/path, tcp:host:port, tls:host:port (IPv6: tcp:[::1]:7878)."""
    def bad(why):
        return ValueError(f"bad daemon address '{text}': {why} (expected unix:/path, tcp:host:port or tls:host:port)")

    if text.startswith("unix:"):
        path = text[5:]
        if not path:
            raise bad("empty socket path")
        if "\0" in path:
            raise bad("NUL in socket path")
        if len(path.encode()) >= 108:
            raise bad("socket path longer than 107 bytes")
        return Address("unix", path=path)
    if text.startswith(("tcp:", "tls:")):
        rest = text[4:]
        if rest.startswith("["):
            close = rest.find("]")
            if close < 0 or rest[close + 1:close + 2] != ":":
                raise bad("an IPv6 address is written [addr]:port")
            host, port = rest[1:close], rest[close + 2:]
        else:
            host, sep, port = rest.rpartition(":")
            if not sep:
                raise bad("missing port")
            if ":" in host:
                raise bad("an IPv6 address is written [addr]:port")
        if not host:
            raise bad("empty host")
        if not port.isdigit() or not 1 <= int(port) <= 65535:
            raise bad("port must be a number in 1..65535")
        return Address("tcp", host=host, port=int(port), tls=text.startswith("tls:"))
    raise bad("unknown scheme")


def default_address() -> str:
    """$OMEGA_HOST, else the per-user socket when it exists, else the system daemon's."""
    host = os.environ.get("OMEGA_HOST")
    if host:
        return host
    runtime = os.environ.get("XDG_RUNTIME_DIR")
    if runtime and os.path.exists(os.path.join(runtime, "omega", "omegad.sock")):
        return "unix:" + os.path.join(runtime, "omega", "omegad.sock")
    return "unix:/run/omega/omegad.sock"


def _login_name() -> str:
    try:
        import pwd
        return pwd.getpwuid(os.getuid()).pw_name
    except (ImportError, KeyError):
        return ""


def _token_from_env() -> str:
    token = os.environ.get("OMEGA_TOKEN", "")
    if not token:
        path = os.environ.get("OMEGA_TOKEN_FILE", "")
        if path:
            try:
                with open(path, encoding="utf-8") as f:
                    token = f.readline().rstrip("\r\n")
            except OSError as e:
                raise Error(f"cannot read the token file '{path}' ($OMEGA_TOKEN_FILE): {e.strerror}") from None
    return token


class Connection:
    """A blocking session. Not thread-safe: use one Connection per thread."""

    def __init__(self, address: str | None = None, *, user: str | None = None, token: str | bytes | None = None,
                 connect_timeout: float = 5.0, reply_timeout: float = 30.0, client_name: str = DEFAULT_CLIENT_NAME):
        self.address = parse_address(address or default_address())
        self.reply_timeout = reply_timeout
        self._sock = None
        self._decoder = codec.Decoder()
        self._queues: dict[int, collections.deque] = {}
        self._ignored: set[int] = set()  # ids whose frames are dropped (ended subscriptions)
        self._next_id = 1
        self._sock = self._open(connect_timeout)
        try:
            self.welcome = self._handshake(client_name, user, token)
        except BaseException:
            self.close(send_bye=False)
            raise

    # ---- opening ----

    def _open(self, timeout: float):
        a = self.address
        try:
            if a.kind == "unix":
                s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                s.settimeout(timeout)
                try:
                    s.connect(a.path)
                except BaseException:
                    s.close()
                    raise
            else:
                s = socket.create_connection((a.host, a.port), timeout=timeout)
                s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        except OSError as e:
            raise ConnectionFailed(f"cannot reach the daemon at {a.text()}: {e.strerror or e}") from None
        if a.tls:
            s = self._start_tls(s, timeout)
        return s

    def _start_tls(self, s, timeout: float):
        # Like the C++ client: the daemon's certificate is checked for HOST (name or IP address)
        # against $OMEGA_TLS_CA when set, else the system CAs.
        ca = os.environ.get("OMEGA_TLS_CA") or None
        try:
            ctx = ssl.create_default_context(cafile=ca)
        except (OSError, ssl.SSLError) as e:
            s.close()
            raise Error(f"cannot read the CA file '{ca}' ($OMEGA_TLS_CA): {e}") from None
        ctx.minimum_version = ssl.TLSVersion.TLSv1_2
        try:
            s.settimeout(timeout)
            return ctx.wrap_socket(s, server_hostname=self.address.host)
        except ssl.SSLCertVerificationError as e:
            s.close()
            raise ConnectionFailed(f"TLS with the daemon at {self.address.text()}: certificate not trusted: "
                                   f"{e.verify_message}") from None
        except OSError as e:
            s.close()
            raise ConnectionFailed(f"TLS with the daemon at {self.address.text()}: {e}") from None

    def _handshake(self, client_name, user, token):
        hid = self.next_id()
        h, _ = self.request(codec.hello(hid, client_name), hid)
        if h["type"] != "welcome":
            raise ProtocolError(f"expected welcome, got {h['type']}", "invalid_value")
        version = h.get("version")
        if not isinstance(version, int) or not codec.MIN_PROTOCOL_VERSION <= version <= codec.PROTOCOL_VERSION:
            raise ConnectionFailed(f"the daemon at {self.address.text()} chose protocol version {version}, "
                                   f"this client speaks {codec.MIN_PROTOCOL_VERSION}..{codec.PROTOCOL_VERSION}")
        self.user = h.get("user")
        if h.get("auth") != "hmac-sha256":
            return h
        user = user or os.environ.get("OMEGA_USER") or _login_name()
        token = token or _token_from_env()
        if not token:
            raise Error(f"the daemon at {self.address.text()} asks for authentication: pass token= or set "
                        "OMEGA_TOKEN or OMEGA_TOKEN_FILE (and OMEGA_USER)")
        nonce = h.get("nonce")
        if not isinstance(nonce, str):
            raise ProtocolError("welcome.nonce: missing for hmac-sha256", "missing_field")
        aid = self.next_id()
        r, _ = self.request(codec.auth(aid, user, codec.auth_mac(token, nonce, user)), aid)
        if r["type"] != "ok":
            raise ProtocolError(f"expected ok to auth, got {r['type']}", "invalid_value")
        self.user = user
        return h

    # ---- frames ----

    def next_id(self) -> int:
        i = self._next_id
        self._next_id += 1
        return i

    def send(self, frame: bytes) -> None:
        if self._sock is None:
            raise ConnectionFailed(f"connection to {self.address.text()} is closed")
        try:
            self._sock.settimeout(max(self.reply_timeout, 1.0))
            self._sock.sendall(frame)
        except OSError as e:
            raise self._lost(f"lost: {e}") from None

    def _lost(self, what: str) -> ConnectionFailed:
        """Closes the socket; returns the exception to raise."""
        self.close(send_bye=False)
        return ConnectionFailed(f"connection to {self.address.text()} {what}")

    def _dispatch(self, header: dict, payload: bytes) -> None:
        t, i = header["type"], header["id"]
        if t == "ping":  # answered here, never seen by callers
            self.send(codec.bare("pong", i))
        elif t == "bye":
            raise self._lost("closed by the daemon (bye)")
        elif t == "error" and i == 0:  # a frame the daemon could not read: it answers nothing
            raise DaemonError(str(header.get("code")), str(header.get("message", "")), self.address.text())
        elif i not in self._ignored:
            self._queues.setdefault(i, collections.deque()).append((header, payload))

    def _read_more(self, deadline: float | None) -> None:
        if self._sock is None:
            raise ConnectionFailed(f"connection to {self.address.text()} is closed")
        left = None if deadline is None else deadline - time.monotonic()
        if left is not None and left <= 0:
            raise Timeout(f"no reply from the daemon at {self.address.text()} in time")
        try:
            self._sock.settimeout(left)
            data = self._sock.recv(1 << 20)
        except socket.timeout:
            raise Timeout(f"no reply from the daemon at {self.address.text()} in time") from None
        except OSError as e:
            raise self._lost(f"lost: {e}") from None
        if not data:
            if self._decoder.buffered:
                self.close(send_bye=False)
                raise ProtocolError(f"the daemon at {self.address.text()} closed inside a frame", "truncated")
            raise self._lost("closed by the daemon")
        self._decoder.feed(data)
        self._drain()

    def _drain(self) -> bool:
        """Dispatches every complete frame buffered; True if there was one. Frames stay buffered
        when a dispatch raises (an error with id 0), so they are drained on the next call."""
        any_frame = False
        try:
            for h, p in self._decoder.frames():
                any_frame = True
                self._dispatch(h, p)
        except codec.FrameError as e:
            self.close(send_bye=False)
            raise ProtocolError(f"bad frame from the daemon at {self.address.text()}: {e}", e.code) from None
        return any_frame

    def wait_for(self, id: int, timeout: float | None = None) -> tuple[dict, bytes]:
        """The next frame with this id (frames for other ids stay queued). timeout None: forever."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            q = self._queues.get(id)
            if q:
                item = q.popleft()
                if not q:
                    del self._queues[id]
                return item
            if not (self._decoder.buffered and self._drain()):
                self._read_more(deadline)

    def request(self, frame: bytes, id: int, timeout: float | None = -1) -> tuple[dict, bytes]:
        """Sends frame and returns the first reply with its id; an `error` reply raises DaemonError.
        timeout -1: the connection's reply_timeout."""
        self.send(frame)
        return self.reply(id, timeout)

    def reply(self, id: int, timeout: float | None = -1) -> tuple[dict, bytes]:
        h, p = self.wait_for(id, self.reply_timeout if timeout == -1 else timeout)
        if h["type"] == "error":
            raise DaemonError(str(h.get("code")), str(h.get("message", "")), self.address.text())
        return h, p

    def forget(self, id: int) -> None:
        """Drops queued and future frames with this id (a subscription that ended)."""
        self._ignored.add(id)
        self._queues.pop(id, None)

    @property
    def closed(self) -> bool:
        return self._sock is None

    def close(self, send_bye: bool = True) -> None:
        s, self._sock = self._sock, None
        if s is None:
            return
        if send_bye:
            try:
                s.settimeout(1.0)
                s.sendall(codec.bare("bye", 0))
            except OSError:
                pass
        try:
            s.close()
        except OSError:
            pass
