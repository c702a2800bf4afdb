"""The user-facing API: Client (submit, jobs), Job (watch, fetch, cancel, pause, resume, ...) and
what they return. Each call is one request/reply of docs/protocol.md on the client's connection."""
from __future__ import annotations

import os
from dataclasses import dataclass, field

from . import assets, codec, exr
from .connection import Connection
from .errors import DaemonError, Error, ProtocolError

JOB_STATES = ("queued", "running", "paused", "done", "failed", "cancelled")
FINAL_STATES = ("done", "failed", "cancelled")


def _field(h: dict, key: str, types, where: str, optional: bool = False):
    """A field of a reply, checked the way docs/protocol.md names decode errors."""
    if key not in h:
        if optional:
            return None
        raise ProtocolError(f"{where}.{key}: missing", "missing_field")
    v = h[key]
    if isinstance(v, bool) or not isinstance(v, types):  # no field of the protocol is a bool
        raise ProtocolError(f"{where}.{key}: wrong type ({type(v).__name__})", "wrong_type")
    return v


def _expect(h: dict, type_: str) -> dict:
    if h["type"] != type_:
        raise ProtocolError(f"expected {type_}, got {h['type']}", "invalid_value")
    return h


def _numpy_or_none():
    try:
        import numpy
        return numpy
    except ImportError:
        return None


@dataclass(frozen=True)
class Progress:
    pass_: int                 # completed passes
    spp: int                   # samples per pixel so far
    elapsed_s: float           # render time
    samples_per_s: float
    rel_error: float | None = None  # absent until it can be estimated

    @classmethod
    def parse(cls, p, where: str) -> "Progress":
        if not isinstance(p, dict):
            raise ProtocolError(f"{where}: expected a map", "wrong_type")
        num = (int, float)
        return cls(_field(p, "pass", int, where), _field(p, "spp", int, where), float(_field(p, "elapsed_s", num, where)),
                   float(_field(p, "samples_per_s", num, where)),
                   None if "rel_error" not in p else float(_field(p, "rel_error", num, where)))


@dataclass(frozen=True)
class JobInfo:
    job: int
    name: str
    state: str
    priority: int
    owner: str
    halt: dict
    progress: Progress

    @classmethod
    def parse(cls, h: dict, where: str) -> "JobInfo":
        return cls(_field(h, "job", int, where), _field(h, "name", str, where), _field(h, "state", str, where),
                   _field(h, "priority", int, where), _field(h, "owner", str, where), _field(h, "halt", dict, where),
                   Progress.parse(h.get("progress"), where + ".progress"))

    @property
    def finished(self) -> bool:
        return self.state in FINAL_STATES


class _Exr:
    """An EXR payload: save() it as is; pixels/decode() read it (numpy)."""
    exr: bytes

    def save(self, path) -> str:
        """Writes the EXR bytes (atomically: a temp file renamed over path). Returns path."""
        path = os.fspath(path)
        tmp = f"{path}.tmp-{os.getpid()}"
        with open(tmp, "wb") as f:
            f.write(self.exr)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
        return path

    def decode(self) -> exr.ExrImage:
        """Every channel as numpy arrays (R, G, B, var.R, var.G, var.B, ...); needs numpy."""
        if _numpy_or_none() is None:
            raise ImportError("decoding EXR pixels needs numpy; save() the EXR instead")
        return exr.decode(self.exr)

    @property
    def pixels(self):
        """float32 RGB as a numpy array (height, width, 3), or None without numpy."""
        if _numpy_or_none() is None:
            return None
        return self.decode().rgb


@dataclass(frozen=True)
class ProgressUpdate:
    kind = "progress"
    job: int
    state: str
    progress: Progress


@dataclass(frozen=True)
class Tile(_Exr):
    kind = "tile"
    job: int
    rect: tuple   # (x0, y0, x1, y1): half-open pixel bounds in the image
    pass_: int
    spp: int
    version: int  # grows each time this rect is updated
    exr: bytes = field(repr=False)


@dataclass(frozen=True)
class Done:
    kind = "done"
    job: int
    state: str    # done, failed or cancelled
    progress: Progress
    message: str | None = None  # why it failed

    @property
    def ok(self) -> bool:
        return self.state == "done"


@dataclass(frozen=True)
class Image(_Exr):
    job: int
    pass_: int
    spp: int
    width: int
    height: int
    exr: bytes = field(repr=False)


class Job:
    """A job on the daemon, by id. Methods send one request each on the client's connection."""

    def __init__(self, client: "Client", id: int, name: str | None = None):
        self.client = client
        self.id = id
        self.name = name

    def __repr__(self):
        return f"Job({self.id}{', ' + repr(self.name) if self.name else ''})"

    def _simple(self, type_: str) -> None:
        c = self.client.connection
        i = c.next_id()
        _expect(c.request(codec.job_request(type_, i, self.id), i)[0], "ok")

    def status(self) -> JobInfo:
        c = self.client.connection
        i = c.next_id()
        h, _ = c.request(codec.job_request("status", i, self.id), i)
        return JobInfo.parse(_expect(h, "job_info"), "job_info")

    info = status

    def cancel(self) -> None:
        self._simple("cancel")

    def pause(self) -> None:
        self._simple("pause")

    def resume(self) -> None:
        self._simple("resume")

    def delete(self) -> None:
        """Removes the job and its result from the daemon."""
        self._simple("delete")

    def set_priority(self, priority: int) -> None:
        _check_priority(priority)
        c = self.client.connection
        i = c.next_id()
        _expect(c.request(codec.set_priority(i, self.id, priority), i)[0], "ok")

    def fetch(self) -> Image:
        """The current image (the result once done). DaemonError invalid_state before the first pass."""
        c = self.client.connection
        i = c.next_id()
        h, payload = c.request(codec.job_request("fetch", i, self.id), i)
        _expect(h, "image")
        w = "image"
        return Image(_field(h, "job", int, w), _field(h, "pass", int, w), _field(h, "spp", int, w),
                     _field(h, "width", int, w), _field(h, "height", int, w), payload)

    def watch(self, timeout: float | None = None, stale_tiles: bool = False):
        """Subscribes and yields ProgressUpdate and Tile events as they come, then one Done, last.
        A job that already ended yields its tiles (if any) and Done at once. timeout: the longest
        wait for the next event (None: no limit), omega.Timeout when it passes. The daemon keeps
        only each rect's newest tile for a slow reader; a tile older than one already yielded for
        its rect is dropped unless stale_tiles. Leaving the loop early unsubscribes."""
        c = self.client.connection
        sid = c.next_id()
        _expect(c.request(codec.job_request("subscribe", sid, self.id), sid)[0], "ok")
        latest: dict[tuple, int] = {}
        ended = False
        try:
            while True:
                h, payload = c.wait_for(sid, timeout)
                t = h["type"]
                if t == "tile":
                    rect = _field(h, "rect", list, "tile")
                    if len(rect) != 4 or not all(isinstance(v, int) for v in rect):
                        raise ProtocolError("tile.rect: expected 4 integers", "invalid_value")
                    tile = Tile(_field(h, "job", int, "tile"), tuple(rect), _field(h, "pass", int, "tile"),
                                _field(h, "spp", int, "tile"), _field(h, "version", int, "tile"), payload)
                    if not stale_tiles and latest.get(tile.rect, -1) > tile.version:
                        continue
                    latest[tile.rect] = tile.version
                    yield tile
                elif t == "progress":
                    yield ProgressUpdate(_field(h, "job", int, "progress"), _field(h, "state", str, "progress"),
                                         Progress.parse(h.get("progress"), "progress.progress"))
                elif t == "done":
                    ended = True
                    yield Done(_field(h, "job", int, "done"), _field(h, "state", str, "done"),
                               Progress.parse(h.get("progress"), "done.progress"),
                               _field(h, "message", str, "done", optional=True))
                    return
                elif t == "error":
                    ended = True
                    raise DaemonError(str(h.get("code")), str(h.get("message", "")), c.address.text())
                # other types on a subscription's id are ignored, like unknown fields
        finally:
            if ended:
                c.forget(sid)
            elif not c.closed:
                self._unsubscribe(sid)

    def _unsubscribe(self, sid: int) -> None:
        c = self.client.connection
        c.forget(sid)
        uid = c.next_id()
        try:
            c.request(codec.job_request("unsubscribe", uid, self.id), uid)
        except Error:
            pass  # the subscription is dropped on this side either way

    def wait(self, timeout: float | None = None) -> Done:
        """Watches until the job ends; returns its Done (check .ok or .state)."""
        for ev in self.watch(timeout=timeout):
            if ev.kind == "done":
                return ev
        raise ProtocolError("subscription ended without done", "invalid_value")


def _check_priority(priority: int) -> None:
    if not isinstance(priority, int) or not codec.MIN_PRIORITY <= priority <= codec.MAX_PRIORITY:
        raise ValueError(f"priority must be an integer in [{codec.MIN_PRIORITY}, {codec.MAX_PRIORITY}]")


class Client:
    """A session with omegad; see omega.connect(). Not thread-safe: one Client per thread."""

    def __init__(self, connection: Connection):
        self.connection = connection

    @property
    def address(self) -> str:
        return self.connection.address.text()

    @property
    def user(self) -> str | None:
        """Who the daemon knows this session as (a uid in decimal on a unix socket, the TCP user)."""
        return self.connection.user

    @property
    def server(self) -> str:
        return self.connection.welcome.get("server", "")

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self) -> None:
        """Says bye and closes."""
        self.connection.close()

    def ping(self) -> None:
        c = self.connection
        i = c.next_id()
        _expect(c.request(codec.bare("ping", i), i)[0], "pong")

    def job(self, id: int) -> Job:
        """A Job handle for an existing job id (nothing is sent)."""
        return Job(self, int(id))

    def jobs(self) -> list[JobInfo]:
        """Every job this session may see (its own; every job for an admin)."""
        c = self.connection
        i = c.next_id()
        h, _ = c.request(codec.bare("list", i), i)
        items = _field(_expect(h, "job_list"), "jobs", list, "job_list")
        return [JobInfo.parse(j if isinstance(j, dict) else {}, f"job_list.jobs[{k}]") for k, j in enumerate(items)]

    def submit(self, scene_path, spp: int | None = None, *, time_s: float | None = None,
               target_error: float | None = None, priority: int = 0, seed: int = 0,
               integrator: str | None = None, name: str | None = None, sampler: str | None = None) -> Job:
        """Sends a scene and the files it names; returns the new Job. spp, time_s and
        target_error override the scene's halting condition (the first reached stops the job);
        without any the scene's own applies. sampler ("sobol" | "independent") overrides the
        scene's sampler. A refused scene raises DaemonError with code
        scene_invalid and the parser's `file:line: key: what` lines in its message."""
        _check_priority(priority)
        if spp is not None and not 1 <= spp <= codec.MAX_SPP:
            raise ValueError(f"spp must be in [1, {codec.MAX_SPP}]")
        if time_s is not None and not 0 < time_s <= 1e9:
            raise ValueError("time_s must be in (0, 1e9]")
        if target_error is not None and not 0 < target_error <= 1e6:
            raise ValueError("target_error must be in (0, 1e6]")
        if not 0 <= seed < 1 << 64:
            raise ValueError("seed must be a u64")
        scene = assets.scan_scene(scene_path)
        name = scene.name if name is None else name
        c = self.connection
        sid = c.next_id()
        refs = [codec.asset_ref(a.name, a.sha256, a.size) for a in scene.assets]
        frame = codec.submit(sid, scene.yaml, name=name, priority=priority,
                             halt_=codec.halt(spp, time_s, target_error), seed=seed, integrator=integrator, assets=refs,
                             sampler=sampler)
        h, _ = c.request(frame, sid)
        if h["type"] == "need_assets":
            missing = _field(h, "missing", list, "need_assets")
            by_hash = {a.sha256: a for a in scene.assets}
            sent = set()
            for sha in missing:
                a = by_hash.get(sha)
                if a is None:
                    raise ProtocolError(f"the daemon asked for asset {sha}, which this scene does not use",
                                        "invalid_value")
                if sha in sent:
                    continue
                sent.add(sha)
                with open(a.path, "rb") as f:
                    data = f.read()
                if len(data) != a.size or codec.sha256_hex(data) != sha:
                    raise Error(f"{a.path}: changed while being submitted")
                c.send(codec.asset(sid, data, sha))
            h, _ = c.reply(sid)  # the daemon stores the assets, then answers
        h = _expect(h, "accepted")
        return Job(self, _field(h, "job", int, "accepted"), name)


def connect(address: str | None = None, *, user: str | None = None, token: str | bytes | None = None,
            connect_timeout: float = 5.0, reply_timeout: float = 30.0,
            client_name: str = "omega-python/0.1") -> Client:
    """Opens a session with omegad. address: unix:/path, tcp:HOST:PORT or tls:HOST:PORT; None:
    $OMEGA_HOST, else $XDG_RUNTIME_DIR/omega/omegad.sock when it exists, else
    /run/omega/omegad.sock. TCP asks for a user and token: the arguments, else $OMEGA_USER (else
    the login name) and $OMEGA_TOKEN (else the first line of $OMEGA_TOKEN_FILE). TLS verifies the
    daemon's certificate against $OMEGA_TLS_CA, else the system CAs."""
    return Client(Connection(address, user=user, token=token, connect_timeout=connect_timeout,
                             reply_timeout=reply_timeout, client_name=client_name))
