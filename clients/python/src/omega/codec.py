"""Frames and messages of the Omega wire protocol, version 1 (docs/protocol.md). No I/O.

Headers are written in the canonical form (one line of JSON, keys in the documented order), so
every frame this module builds is byte for byte what omegad itself would write. omegad replies
only in that form, so the json module reads everything it sends.
"""
from __future__ import annotations

import hashlib
import hmac
import json
import struct

MAGIC = b"OMG1"
PRELUDE = struct.Struct("<4sIQ")  # magic, u32 header length, u64 payload length
PROTOCOL_VERSION = 1
MIN_PROTOCOL_VERSION = 1

# Frame limits (docs/protocol.md, "Limits"); the daemon may be configured otherwise, but a
# client must not trust a peer to stay within them.
MAX_HEADER = 1 << 20
MAX_PAYLOAD = 1 << 30
MIN_PRIORITY, MAX_PRIORITY = -1000, 1000
MAX_SPP = 1 << 40


class FrameError(Exception):
    """The byte stream is not a frame; `code` is the framing error's name (bad_magic, ...)."""

    def __init__(self, code: str, message: str = ""):
        super().__init__(f"{code}: {message}" if message else code)
        self.code = code
        self.message = message


def sha256_hex(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def encode_frame(header: dict, payload: bytes = b"") -> bytes:
    """header: a dict in documented key order, `type` and `id` first."""
    text = json.dumps(header, ensure_ascii=False, allow_nan=False).encode("utf-8")
    return PRELUDE.pack(MAGIC, len(text), len(payload)) + text + payload


class Decoder:
    """Incremental: feed() any split of the stream; frames() yields (header dict, payload)."""

    def __init__(self, max_header: int = MAX_HEADER, max_payload: int = MAX_PAYLOAD):
        self._buf = bytearray()
        self.max_header = max_header
        self.max_payload = max_payload

    def feed(self, data: bytes) -> None:
        self._buf += data

    @property
    def buffered(self) -> int:
        return len(self._buf)

    def frames(self):
        while True:
            buf = self._buf
            # The magic is checked byte by byte, so garbage is caught before a prelude arrives.
            head = bytes(buf[:4])
            if head != MAGIC[:len(head)]:
                raise FrameError("bad_magic", "frame does not start with OMG1")
            if len(buf) < PRELUDE.size:
                return
            _, hlen, plen = PRELUDE.unpack_from(buf)
            if hlen > self.max_header:
                raise FrameError("header_too_large", f"{hlen} bytes")
            if plen > self.max_payload:
                raise FrameError("payload_too_large", f"{plen} bytes")
            end = PRELUDE.size + hlen + plen
            if len(buf) < end:
                return
            try:
                header = json.loads(bytes(buf[PRELUDE.size:PRELUDE.size + hlen]).decode("utf-8"))
            except UnicodeDecodeError as e:
                raise FrameError("header_not_utf8", str(e)) from None
            except ValueError as e:
                raise FrameError("header_not_yaml", f"not canonical JSON: {e}") from None
            if not isinstance(header, dict):
                raise FrameError("header_not_mapping")
            if "type" not in header:
                raise FrameError("missing_type")
            if not isinstance(header.get("id"), int) or header["id"] < 0:
                raise FrameError("missing_id" if "id" not in header else "bad_id")
            payload = bytes(buf[PRELUDE.size + hlen:end])
            del buf[:end]
            yield header, payload


# ---- authentication ----

def auth_mac(token: bytes | str, nonce_hex: str, user: str) -> str:
    """hex(HMAC-SHA256(token, "omega-auth-v1\\n" + nonce + "\\n" + user)): the token never travels."""
    if isinstance(token, str):
        token = token.encode("utf-8")
    text = ("omega-auth-v1\n" + nonce_hex + "\n" + user).encode("utf-8")
    return hmac.new(token, text, hashlib.sha256).hexdigest()


# ---- client-to-daemon messages, fields in the documented order ----

def hello(id: int, client: str, version: int = PROTOCOL_VERSION, min_version: int = MIN_PROTOCOL_VERSION) -> bytes:
    return encode_frame({"type": "hello", "id": id, "version": version, "min_version": min_version,
                         "client": client})


def auth(id: int, user: str, mac: str) -> bytes:
    return encode_frame({"type": "auth", "id": id, "user": user, "mac": mac})


def bare(type: str, id: int) -> bytes:
    """Messages with no fields: ping, pong, bye, list."""
    return encode_frame({"type": type, "id": id})


def halt(spp: int | None = None, time_s: float | None = None, target_error: float | None = None) -> dict:
    h = {}
    if spp is not None:
        h["spp"] = int(spp)
    if time_s is not None:
        h["time_s"] = float(time_s)  # f64 is written with a point: 30.0, not 30
    if target_error is not None:
        h["target_error"] = float(target_error)
    return h


def asset_ref(name: str, sha256: str, size: int) -> dict:
    return {"name": name, "sha256": sha256, "size": size}


def submit(id: int, scene: bytes, name: str = "", priority: int = 0, halt_: dict | None = None, seed: int = 0,
           integrator: str | None = None, assets=(), sampler: str | None = None) -> bytes:
    """assets: dicts from asset_ref(); the scene YAML is the payload."""
    h = {"type": "submit", "id": id, "name": name, "priority": priority, "halt": halt_ or {}, "seed": seed}
    if integrator is not None:
        h["integrator"] = integrator
    if sampler is not None:
        h["sampler"] = sampler  # "sobol" | "independent": overrides the scene's
    h["assets"] = list(assets)
    return encode_frame(h, scene)


def asset(id: int, data: bytes, sha256: str | None = None) -> bytes:
    """id: the submit's id."""
    return encode_frame({"type": "asset", "id": id, "sha256": sha256 or sha256_hex(data)}, data)


def job_request(type: str, id: int, job: int) -> bytes:
    """status, cancel, pause, resume, delete, subscribe, unsubscribe, fetch."""
    return encode_frame({"type": type, "id": id, "job": job})


def set_priority(id: int, job: int, priority: int) -> bytes:
    return encode_frame({"type": "set_priority", "id": id, "job": job, "priority": priority})
