"""Minimal Omega wire protocol client codec, written from docs/protocol.md alone.

Standard library only. Headers are written in the canonical form (one-line JSON, keys in the
documented order) and read with the json module, which suffices for everything omegad sends.
"""
import hashlib
import hmac
import json
import struct

MAGIC = b"OMG1"
PRELUDE = struct.Struct("<4sIQ")  # magic, u32 header length, u64 payload length
PROTOCOL_VERSION = 1

PAYLOAD_TYPES = {"submit", "asset", "tile", "image"}


class ProtocolError(Exception):
    def __init__(self, code, message):
        super().__init__(f"{code}: {message}")
        self.code = code


def canonical_header(fields):
    """fields: a dict in documented key order, starting with type and id."""
    return json.dumps(fields, ensure_ascii=False, allow_nan=False).encode("utf-8")


def encode_frame(fields, payload=b""):
    header = canonical_header(fields)
    return PRELUDE.pack(MAGIC, len(header), len(payload)) + header + payload


class Decoder:
    """Incremental: feed() any split of the stream, frames() yields (header dict, payload)."""

    def __init__(self, max_header=1 << 20, max_payload=1 << 30):
        self.buf = bytearray()
        self.max_header = max_header
        self.max_payload = max_payload

    def feed(self, data):
        self.buf += data

    def frames(self):
        while True:
            if len(self.buf) >= 4 and self.buf[:4] != MAGIC:
                raise ProtocolError("bad_magic", "frame does not start with OMG1")
            if len(self.buf) < PRELUDE.size:
                return
            _, hlen, plen = PRELUDE.unpack_from(self.buf)
            if hlen > self.max_header:
                raise ProtocolError("header_too_large", str(hlen))
            if plen > self.max_payload:
                raise ProtocolError("payload_too_large", str(plen))
            end = PRELUDE.size + hlen + plen
            if len(self.buf) < end:
                return
            header = json.loads(bytes(self.buf[PRELUDE.size:PRELUDE.size + hlen]).decode("utf-8"))
            if not isinstance(header, dict):
                raise ProtocolError("header_not_mapping", "")
            payload = bytes(self.buf[PRELUDE.size + hlen:end])
            del self.buf[:end]
            yield header, payload


# ---- message builders, fields in the documented order ----

def hello(id, client, version=PROTOCOL_VERSION, min_version=PROTOCOL_VERSION):
    return encode_frame({"type": "hello", "id": id, "version": version,
                         "min_version": min_version, "client": client})


def welcome(id, version, server, auth, nonce=None, user=None):
    h = {"type": "welcome", "id": id, "version": version, "server": server, "auth": auth}
    if nonce is not None:
        h["nonce"] = nonce
    if user is not None:
        h["user"] = user
    return encode_frame(h)


def auth_mac(token, nonce_hex, user):
    text = ("omega-auth-v1\n" + nonce_hex + "\n" + user).encode("utf-8")
    return hmac.new(token, text, hashlib.sha256).hexdigest()


def auth(id, user, mac):
    return encode_frame({"type": "auth", "id": id, "user": user, "mac": mac})


def bare(type, id):
    """ok, ping, pong, bye, list."""
    return encode_frame({"type": type, "id": id})


def error(id, code, message):
    return encode_frame({"type": "error", "id": id, "code": code, "message": message})


def halt(spp=None, time_s=None, target_error=None):
    h = {}
    if spp is not None:
        h["spp"] = spp
    if time_s is not None:
        h["time_s"] = float(time_s)
    if target_error is not None:
        h["target_error"] = float(target_error)
    return h


def submit(id, scene, name="", priority=0, halt_=None, seed=0, integrator=None, assets=()):
    """assets: (name, data bytes) pairs; their hashes and sizes go in the header."""
    h = {"type": "submit", "id": id, "name": name, "priority": priority,
         "halt": halt_ or {}, "seed": seed}
    if integrator is not None:
        h["integrator"] = integrator
    h["assets"] = [{"name": n, "sha256": hashlib.sha256(d).hexdigest(), "size": len(d)}
                   for n, d in assets]
    return encode_frame(h, scene)


def need_assets(id, missing):
    return encode_frame({"type": "need_assets", "id": id, "missing": list(missing)})


def asset(id, data):
    return encode_frame({"type": "asset", "id": id, "sha256": hashlib.sha256(data).hexdigest()}, data)


def job_request(type, id, job):
    """status, cancel, pause, resume, delete, subscribe, unsubscribe, fetch; accepted."""
    return encode_frame({"type": type, "id": id, "job": job})


def set_priority(id, job, priority):
    return encode_frame({"type": "set_priority", "id": id, "job": job, "priority": priority})


def progress_info(pass_, spp, elapsed_s, samples_per_s, rel_error=None):
    p = {"pass": pass_, "spp": spp, "elapsed_s": float(elapsed_s)}
    if rel_error is not None:
        p["rel_error"] = float(rel_error)
    p["samples_per_s"] = float(samples_per_s)
    return p


def job_info_fields(job, name, state, priority, owner, halt_, progress):
    return {"job": job, "name": name, "state": state, "priority": priority, "owner": owner,
            "halt": halt_, "progress": progress}


def job_info(id, info):
    return encode_frame({"type": "job_info", "id": id, **info})


def job_list(id, infos):
    return encode_frame({"type": "job_list", "id": id, "jobs": list(infos)})


def tile(id, job, rect, pass_, spp, version, exr):
    return encode_frame({"type": "tile", "id": id, "job": job, "rect": list(rect), "pass": pass_,
                         "spp": spp, "version": version}, exr)


def progress(id, job, state, info):
    return encode_frame({"type": "progress", "id": id, "job": job, "state": state, "progress": info})


def done(id, job, state, info, message=None):
    h = {"type": "done", "id": id, "job": job, "state": state, "progress": info}
    if message is not None:
        h["message"] = message
    return encode_frame(h)


def image(id, job, pass_, spp, width, height, exr):
    return encode_frame({"type": "image", "id": id, "job": job, "pass": pass_, "spp": spp,
                         "width": width, "height": height}, exr)


# ---- a blocking client over a socket (tests and tools) ----

class Client:
    """One session with omegad. addr: "unix:/path" or "tcp:host:port". Every wait is bounded."""

    def __init__(self, addr, timeout=20.0, client_name="omega_proto.py", source=None):
        """source: a local address to connect from (TCP), e.g. "127.0.0.2"."""
        import socket
        if addr.startswith("unix:"):
            self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            target = addr[5:]
        elif addr.startswith("tcp:"):
            host, port = addr[4:].rsplit(":", 1)
            self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            target = (host, int(port))
        else:
            raise ValueError(addr)
        self.sock.settimeout(timeout)
        if source is not None:
            self.sock.bind((source, 0))
        self.sock.connect(target)
        self.timeout = timeout
        self.decoder = Decoder()
        self.pending = []  # frames read but not yet consumed
        self.next_id = 1
        self.welcome = None
        if client_name is not None:
            self.sock.sendall(hello(self.new_id(), client_name))
            self.welcome = self.recv()

    def new_id(self):
        i = self.next_id
        self.next_id += 1
        return i

    def send(self, data):
        self.sock.sendall(data)

    def close(self):
        try:
            self.sock.close()
        except OSError:
            pass

    def _read_more(self, deadline):
        import time
        left = deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError("no frame from omegad in time")
        self.sock.settimeout(left)
        data = self.sock.recv(1 << 20)
        if not data:
            raise ConnectionError("omegad closed the connection")
        self.decoder.feed(data)
        self.pending.extend(self.decoder.frames())

    def recv(self, timeout=None):
        """The next frame as (header, payload)."""
        import time
        deadline = time.monotonic() + (timeout or self.timeout)
        while not self.pending:
            self._read_more(deadline)
        return self.pending.pop(0)

    def recv_for(self, id, timeout=None):
        """The next frame whose id is `id`; other frames stay queued."""
        import time
        deadline = time.monotonic() + (timeout or self.timeout)
        while True:
            for i, (h, p) in enumerate(self.pending):
                if h.get("id") == id:
                    return self.pending.pop(i)
            self._read_more(deadline)

    def request(self, build, *args, **kw):
        """Sends build(id, *args) and returns the reply header (payload in ["_payload"])."""
        id = self.new_id()
        self.send(build(id, *args, **kw))
        h, p = self.recv_for(id)
        h["_payload"] = p
        return h

    def job(self, type, job):
        return self.request(lambda id: job_request(type, id, job))

    def submit(self, scene, assets=(), send_assets=True, **kw):
        """Full submit exchange. Returns the final reply header (accepted or error)."""
        id = self.new_id()
        self.send(submit(id, scene, assets=assets, **kw))
        h, _ = self.recv_for(id)
        if h["type"] != "need_assets":
            return h
        if send_assets:
            by_hash = {hashlib.sha256(d).hexdigest(): d for _, d in assets}
            for sha in h["missing"]:
                self.send(asset(id, by_hash[sha]))
        h, _ = self.recv_for(id)
        return h
