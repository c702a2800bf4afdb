"""Who may do what, and limits (docs/security.md): the HMAC-SHA256 handshake on TCP, owners and
admins, refusal of an open TCP listener without auth, per-owner and per-job limits, and the
timeouts that free a connection stuck in a half frame or a handshake."""
import os
import signal
import socket
import struct
import subprocess
import time

from harness import ALICE, BOB, OMEGAD, Daemon, Test, op, small_cornell, wait_state

CAROL = "carol-token-0123456789"

CONFIG = f"""tcp_users: {{alice: {ALICE}, bob: {BOB}, carol: {CAROL}}}
admins: [carol]
max_jobs_per_owner: 2
max_resolution: 200
max_spp: 100000
frame_timeout_s: 1.5
handshake_timeout_s: 1.5
"""


def login(d, user, token):
    c = d.client(tcp=True)
    w = c.welcome[0]
    assert w["auth"] == "hmac-sha256" and len(w["nonce"]) == 64 and "user" not in w, w
    h = c.request(lambda id: op.auth(id, user, op.auth_mac(token.encode(), w["nonce"], user)))
    assert h["type"] == "ok", h
    return c


def closed(c, timeout=10):
    try:
        while True:
            c.recv(timeout=timeout)
    except ConnectionError:
        return True


def test_tcp_handshake(tmp, daemons):
    d = Daemon(tmp, config=CONFIG).start()
    daemons.append(d)
    # Requests before auth are refused.
    c = d.client(tcp=True)
    h = c.job("status", 1)
    assert h["type"] == "error" and h["code"] == "auth_required", h
    # A wrong token, an unknown user and a MAC for another nonce all fail the same way and close.
    for user, token, nonce in (("alice", BOB, None), ("mallory", ALICE, None), ("alice", ALICE, "0" * 64)):
        c = d.client(tcp=True)
        n = nonce or c.welcome[0]["nonce"]
        h = c.request(lambda id: op.auth(id, user, op.auth_mac(token.encode(), n, user)))
        assert h["type"] == "error" and h["code"] == "auth_failed", h
        assert closed(c)
    d.wait_log(r"authentication failed for user 'mallory'")
    # Nonces are fresh.
    n1, n2 = d.client(tcp=True).welcome[0]["nonce"], d.client(tcp=True).welcome[0]["nonce"]
    assert n1 != n2
    login(d, "alice", ALICE)
    d.wait_log(r"authenticated as 'alice'")
    # Unix peers are still known by SO_PEERCRED.
    assert d.client().welcome[0]["auth"] == "peer"


def test_owners_and_admins(tmp, daemons):
    d = Daemon(tmp, config=CONFIG).start()
    daemons.append(d)
    alice, bob, carol = login(d, "alice", ALICE), login(d, "bob", BOB), login(d, "carol", CAROL)
    scene = small_cornell(width=32, height=32)
    job = alice.submit(scene, name="mine", halt_=op.halt(spp=4))["job"]
    info = wait_state(alice, job, {"done"})
    assert info["owner"] == "alice", info
    for req in ("cancel", "pause", "resume", "delete", "fetch", "subscribe"):
        h = bob.job(req, job)
        assert h["type"] == "error" and h["code"] == "permission_denied", (req, h)
    d.wait_log(rf"fetch of job {job} denied: it belongs to alice, not bob")
    assert bob.job("status", job)["type"] == "job_info"  # metadata is public
    assert alice.job("fetch", job)["type"] == "image"
    assert carol.job("fetch", job)["type"] == "image"  # an admin
    assert d.client().job("fetch", job)["type"] == "image"  # the daemon's own uid
    # Per-owner limit: alice may have 2 unfinished jobs.
    a1 = alice.submit(scene, name="a1", halt_=op.halt(spp=90000))["job"]
    a2 = alice.submit(scene, name="a2", halt_=op.halt(spp=90000))["job"]
    h = alice.submit(scene, name="a3", halt_=op.halt(spp=4))
    assert h["type"] == "error" and h["code"] == "busy" and "max_jobs_per_owner" in h["message"], h
    assert bob.submit(scene, name="b1", halt_=op.halt(spp=1))["type"] == "accepted"  # others are not limited
    assert carol.job("cancel", a1)["type"] == "ok" and alice.job("cancel", a2)["type"] == "ok"


def test_job_limits(tmp, daemons):
    d = Daemon(tmp, config=CONFIG).start()
    daemons.append(d)
    c = d.client()
    h = c.submit(small_cornell(width=320, height=32), name="wide", halt_=op.halt(spp=1))
    assert h["type"] == "error" and h["code"] == "scene_invalid" and "max_resolution" in h["message"], h
    h = c.submit(small_cornell(width=32, height=32), name="many", halt_=op.halt(spp=200000))
    assert h["type"] == "error" and h["code"] == "bad_request" and "max_spp" in h["message"], h
    h = c.submit(small_cornell(width=32, height=32, spp=200000), name="scene-spp")
    assert h["type"] == "error" and h["code"] == "scene_invalid" and "max_spp" in h["message"], h


def test_memory_estimate(tmp, daemons):
    d = Daemon(tmp, config="max_scene_memory_bytes: 1000000\n").start()
    daemons.append(d)
    h = d.client().submit(small_cornell(width=80, height=60), name="big", halt_=op.halt(spp=1))
    assert h["type"] == "error" and h["code"] == "scene_invalid" and "max_scene_memory_bytes" in h["message"], h
    assert d.client().submit(small_cornell(width=32, height=32), name="ok", halt_=op.halt(spp=1))["type"] == "accepted"


def test_asset_cache_lru(tmp, daemons):
    d = Daemon(tmp, config="max_asset_cache_bytes: 100\n").start()
    daemons.append(d)
    c = d.client()
    base = small_cornell(width=16, height=16).replace(
        b"shapes:\n", b"shapes:\n  - {type: mesh, file: m.obj, material: FloorBSDF}\n", 1)
    objs = [b"v -0.5 0.2 -0.5\nv 0.5 0.2 -0.5\nv 0 0.9 0\nf 1 2 3\n# %d padding padding\n" % i for i in range(3)]
    sha = [__import__("hashlib").sha256(o).hexdigest() for o in objs]
    j0 = c.submit(base, name="a", assets=[("m.obj", objs[0])], halt_=op.halt(spp=1))["job"]
    wait_state(c, j0, {"done"})
    assert c.job("delete", j0)["type"] == "ok"  # now no job needs objs[0]
    j1 = c.submit(base, name="b", assets=[("m.obj", objs[1])], halt_=op.halt(spp=1))["job"]
    d.wait_log(rf"asset cache: evicted {sha[0]}")
    # objs[1] is needed by job b (queued or done, it holds a link): never evicted.
    j2 = c.submit(base, name="c", assets=[("m.obj", objs[2])], halt_=op.halt(spp=1))["job"]
    for j in (j1, j2):
        wait_state(c, j, {"done"})
    assert f"evicted {sha[1]}" not in d.log()
    assert os.path.exists(os.path.join(d.state_dir, "assets", sha[1][:2], sha[1]))


def test_half_frame_and_silent_clients_time_out(tmp, daemons):
    d = Daemon(tmp, config=CONFIG).start()
    daemons.append(d)
    c = d.client()
    header = b'{"type": "ping", "id": 9}'
    c.send(b"OMG1" + struct.pack("<IQ", len(header), 0) + header[:10])  # half a frame, then silence
    t0 = time.monotonic()
    h, _ = c.recv(timeout=10)
    assert h["type"] == "error" and h["code"] == "bad_frame" and "timeout" in h["message"], h
    assert closed(c) and time.monotonic() - t0 < 6
    d.wait_log(r"no byte for \d+ s inside a frame \(frame_timeout_s\); closing")
    # A connection that never says hello.
    s = socket.socket(socket.AF_UNIX)
    s.connect(d.sock)
    s.settimeout(10)
    data = b""
    while True:
        chunk = s.recv(4096)
        if not chunk:
            break
        data += chunk
    assert b"auth_required" in data, data
    d.wait_log(r"handshake not completed within")
    # The daemon still serves.
    assert d.client().request(lambda id: op.bare("ping", id))["type"] == "pong"


def test_auth_fail_limit(tmp, daemons):
    """auth_fail_limit failed logins from one address within a minute: every further auth from it
    is refused with a clear auth_failed frame, even with the right token; other addresses and
    unix sockets are unaffected; a reload to 0 lifts the limit."""
    d = Daemon(tmp, config=CONFIG + "auth_fail_limit: 3\n").start()
    daemons.append(d)

    def attempt(token, source=None):
        c = op.Client(d.tcp, source=source)
        n = c.welcome[0]["nonce"]
        return c, c.request(lambda id: op.auth(id, "alice", op.auth_mac(token.encode(), n, "alice")))

    for _ in range(3):
        c, h = attempt(BOB)
        assert h["type"] == "error" and h["code"] == "auth_failed" and "too many" not in h["message"], h
        assert closed(c)
    c, h = attempt(ALICE)
    assert h["type"] == "error" and h["code"] == "auth_failed", h
    assert "too many failed authentications from 127.0.0.1" in h["message"] and "auth_fail_limit 3" in h["message"], h
    assert closed(c)
    d.wait_log(r"authentication as 'alice' refused: 3 failed attempts from 127\.0\.0\.1 in the last minute "
               r"\(auth_fail_limit 3\)")
    c, h = attempt(ALICE, source="127.0.0.2")
    assert h["type"] == "ok", h
    assert d.client().welcome[0]["auth"] == "peer"
    with open(d.config_path) as f:
        text = f.read()
    with open(d.config_path, "w") as f:
        f.write(text.replace("auth_fail_limit: 3", "auth_fail_limit: 0"))
    mark = len(d.lines)
    d.proc.send_signal(signal.SIGHUP)
    d.wait_log(r"config reloaded", start=mark)
    login(d, "alice", ALICE)


def test_open_tcp_needs_auth(tmp, daemons):
    r = subprocess.run([OMEGAD, "--state-dir", os.path.join(tmp, "s"), "--listen", "tcp:0.0.0.0:0"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode != 0 and "not a loopback address and TCP authentication is not configured" in r.stderr, r.stderr


if __name__ == "__main__":
    t = Test()
    for fn in (test_tcp_handshake, test_owners_and_admins, test_job_limits, test_memory_estimate, test_asset_cache_lru,
               test_half_frame_and_silent_clients_time_out, test_auth_fail_limit, test_open_tcp_needs_auth):
        t.run(fn)
    t.exit()
