#!/usr/bin/env python3
"""The Python client package (clients/python, `import omega`) against a real omegad: a render
streamed and fetched equals `omega render` of the same scene, spp and seed bit for bit; a scene
with an OBJ + mtllib, a glTF + .bin named by an absolute path and a texture outside the scene's
folder renders the same through the daemon; cancel, pause, resume, jobs, delete and leaving a
watch early; scene_invalid, unknown_job and invalid_state as exceptions with .code; TCP with a
user token (arguments, environment, token file), auth_failed, and TLS checked against
$OMEGA_TLS_CA; the farm script of docs/python.md; pings, stray ids, an error with id 0, bye and
garbage from a scripted peer. Tiles and images decode to numpy arrays
(decode_check.py).

usage: test_client.py OMEGAD OMEGA EXR_COMPARE SOURCE_DIR
"""
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "src"))
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", "tests", "daemon"))
import omega  # noqa: E402
from omega import assets  # noqa: E402

from harness import Daemon, Test, exr_equal, small_cornell  # noqa: E402

SPP, SEED = 12, 7
TOKEN = "alice-token-0123456789"
TRI_OBJ = b"mtllib tri.mtl\nv -0.5 0.2 -0.5\nv 0.5 0.2 -0.5\nv 0 1.2 0\nusemtl m\nf 1 2 3\n"
TRI_MTL = b"newmtl m\nKd 1 0 0\n"
TRI_BIN = struct.pack("<9f3H", -0.9, 0.1, -0.8, -0.3, 0.1, -0.8, -0.6, 0.7, -0.8, 0, 1, 2)
PPM = b"P6\n2 2\n255\n" + bytes([255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255])


def gltf(uri):
    return json.dumps({
        "asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"uri": uri, "byteLength": 42}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [-0.9, 0.1, -0.8], "max": [-0.3, 0.7, -0.8]},
                      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]}).encode()


def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data)
    return path


def render_local(scene_path, out, spp=SPP, seed=SEED):
    from harness import OMEGA
    subprocess.run([OMEGA, "render", scene_path, "--spp", str(spp), "--seed", str(seed), "-o", out, "--threads", "2",
                    "-q"], check=True, timeout=120, stdout=subprocess.DEVNULL)
    return out


def expect_error(code, fn, *args, **kw):
    try:
        fn(*args, **kw)
    except omega.DaemonError as e:
        assert e.code == code, (code, e.code, str(e))
        return e
    raise AssertionError(f"expected a DaemonError {code}")


def wait_state(job, states, timeout=60):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        info = job.status()
        if info.state in states:
            return info
        time.sleep(0.05)
    raise AssertionError(f"job {job.id} did not reach {states} (last: {info})")


def numpy_python():
    """An interpreter with numpy: this one, else Debian's (install-deps installs python3-numpy)."""
    for exe in (sys.executable, "/usr/bin/python3", shutil.which("python3")):
        if exe and os.path.exists(exe):
            if subprocess.run([exe, "-c", "import numpy"], capture_output=True, timeout=60).returncode == 0:
                return exe
    return None


def decode_check(spp, image, tiles):
    args = [str(spp), image] + [",".join(map(str, r)) + "=" + p for r, p in tiles]
    exe = numpy_python()
    if exe is None:
        print("note: no python3 with numpy here; the EXR decoding check is skipped")
        return False
    if exe == sys.executable:
        sys.path.insert(0, HERE)
        import decode_check as dc
        dc.main(args)
    else:
        r = subprocess.run([exe, os.path.join(HERE, "decode_check.py")] + args, capture_output=True, text=True,
                           timeout=120)
        assert r.returncode == 0 and r.stdout.strip() == "OK", (exe, r.stdout, r.stderr)
    return True


def watch_to_end(job, tmp, label):
    """All events of job.watch(); the newest tile of each rect written to a file."""
    events = list(job.watch(timeout=60))
    assert events and events[-1].kind == "done" and all(e.kind != "done" for e in events[:-1]), events[-3:]
    latest = {}
    for e in events:
        assert e.job == job.id
        if e.kind == "tile":
            assert e.version >= latest.get(e.rect, e).version
            latest[e.rect] = e
    files = [(r, t.save(os.path.join(tmp, f"{label}-tile-{'-'.join(map(str, r))}.exr"))) for r, t in latest.items()]
    return events, latest, files


def test_render_equals_local(tmp, daemons):
    scene = write(os.path.join(tmp, "cornell.yaml"), small_cornell(spp=SPP))
    local = render_local(scene, os.path.join(tmp, "local.exr"))
    d = Daemon(tmp).start()
    daemons.append(d)
    with omega.connect(d.unix) as c:
        assert c.user == str(os.getuid()) and c.server.startswith("omegad"), (c.user, c.server)
        job = c.submit(scene, spp=SPP, seed=SEED, priority=5)
        assert job.name == "cornell" and job.id >= 1, job
        events, latest, files = watch_to_end(job, tmp, "unix")
        done = events[-1]
        assert done.ok and done.state == "done" and done.progress.spp == SPP and done.message is None, done
        # 80x48 in 32-pixel tiles: 3 x 2, edges clipped; each at its final spp, equal to the local render.
        assert sorted(latest) == [(x, y, min(x + 32, 80), min(y + 32, 48)) for x in (0, 32, 64) for y in (0, 32)], \
            sorted(latest)
        for rect, path in files:
            assert latest[rect].spp == SPP, latest[rect]
            assert exr_equal(local, path), f"tile {rect} differs from the local render"
        img = job.fetch()
        assert (img.job, img.spp, img.width, img.height) == (job.id, SPP, 80, 48), img
        fetched = img.save(os.path.join(tmp, "fetched.exr"))
        assert exr_equal(local, fetched) and exr_equal(fetched, local), "fetched image differs from the local render"
        # numpy arrays where numpy is installed, None where it is not.
        try:
            import numpy  # noqa: F401
            px = img.pixels
            assert px.shape == (48, 80, 3), px.shape
            t = latest[(0, 0, 32, 32)].pixels
            assert t.shape == (32, 32, 3) and (t == px[:32, :32]).all()
        except ImportError:
            assert img.pixels is None and latest[(0, 0, 32, 32)].pixels is None
        decode_check(SPP, fetched, files)
        info = job.status()
        assert (info.job, info.name, info.state, info.priority, info.owner) == \
            (job.id, "cornell", "done", 5, str(os.getuid())), info
        assert info.halt == {"spp": SPP} and info.progress.spp == SPP and info.finished, info
        listed = {j.job: j for j in c.jobs()}
        assert listed[job.id] == info, (listed, info)
        # A job that already ended: watch yields its final tiles and done at once.
        late = list(c.job(job.id).watch(timeout=30))
        assert late[-1].kind == "done" and late[-1].ok and sum(e.kind == "tile" for e in late) == 6, late
        c.ping()


def test_scene_with_assets(tmp, daemons):
    """Meshes and a texture by clean relative, absolute and climbing names; what a mesh names
    inside itself (mtllib, glTF buffer) travels beside it."""
    outside = os.path.join(tmp, "outside")
    write(os.path.join(outside, "tri.gltf"), gltf("tri.bin"))
    write(os.path.join(outside, "tri.bin"), TRI_BIN)
    write(os.path.join(tmp, "tex", "checker.ppm"), PPM)
    sdir = os.path.join(tmp, "scene")
    write(os.path.join(sdir, "meshes", "tri.obj"), TRI_OBJ)
    write(os.path.join(sdir, "meshes", "tri.mtl"), TRI_MTL)
    text = small_cornell(spp=SPP).decode()
    text = text.replace("materials:\n", "materials:\n  Tex: {type: diffuse, reflectance: {type: bitmap, "
                        "file: '../tex/checker.ppm', filter: nearest}}   # file: not/this.obj\n", 1)
    text = text.replace("shapes:\n", "shapes:\n  - {type: mesh, file: meshes/tri.obj, material: Tex}\n"
                        "  - type: mesh\n    file: " + os.path.join(outside, "tri.gltf") + "\n    material: FloorBSDF\n", 1)
    scene = write(os.path.join(sdir, "scene.yaml"), text.encode())
    local = render_local(scene, os.path.join(tmp, "local.exr"))

    s = assets.scan_scene(scene)
    sha = {a.name: a.sha256 for a in s.assets}
    g = next(n for n in sha if n.endswith("/tri.gltf"))
    t = next(n for n in sha if n.endswith("/checker.ppm"))
    assert sorted(sha) == sorted(["meshes/tri.obj", "meshes/tri.mtl", g, g[:-4] + "bin", t]), sorted(sha)
    assert re.fullmatch(r"assets/[0-9a-f]{16}/tri\.gltf", g) and g[7:23] == sha[g][:16], g
    assert re.fullmatch(r"assets/[0-9a-f]{16}/checker\.ppm", t) and t[7:23] == sha[t][:16], t
    # Only the two renamed values changed; comments and everything else travel as written.
    want = text.replace("'../tex/checker.ppm'", json.dumps(t)).replace(os.path.join(outside, "tri.gltf"), json.dumps(g))
    assert s.yaml.decode() == want, s.yaml.decode()

    d = Daemon(tmp).start()
    daemons.append(d)
    with omega.connect(d.unix) as c:
        job = c.submit(scene, spp=SPP, seed=SEED)
        done = job.wait(timeout=60)
        assert done.ok, done
        out = job.fetch().save(os.path.join(tmp, "fetched.exr"))
        assert exr_equal(local, out) and exr_equal(out, local), "the daemon's render differs from the local one"
        # Everything is cached now: the same scene again sends no file and renders the same.
        again = c.submit(scene, spp=SPP, seed=SEED)
        assert again.wait(timeout=60).ok
        assert exr_equal(local, again.fetch().save(os.path.join(tmp, "again.exr")))
    # The daemon refuses the OBJ without its mtllib, so the check above needed it sent.
    os.remove(os.path.join(sdir, "meshes", "tri.mtl"))
    with omega.connect(d.unix) as c:
        e = expect_error("scene_invalid", c.submit, scene, spp=1)
        assert "tri.mtl" in e.message, e.message


def test_job_control_and_errors(tmp, daemons):
    d = Daemon(tmp).start()
    daemons.append(d)
    long_scene = write(os.path.join(tmp, "long.yaml"), small_cornell(width=64, height=64, spp=1))
    with omega.connect(d.unix) as c:
        job = c.submit(long_scene, spp=1 << 24, name="long")
        wait_state(job, {"running"})
        # Leaving a watch early unsubscribes; the session goes on.
        seen = 0
        for ev in job.watch(timeout=30):
            assert ev.kind in ("progress", "tile"), ev
            seen += 1
            if seen == 3:
                break
        c.ping()
        job.pause()
        assert wait_state(job, {"paused"}).state == "paused"
        expect_error("invalid_state", job.pause)
        job.resume()
        wait_state(job, {"running", "queued"})
        expect_error("invalid_state", job.resume)
        job.set_priority(-7)
        assert job.status().priority == -7
        second = c.submit(long_scene, spp=2, time_s=60.0, target_error=0.5)
        assert sorted(j.job for j in c.jobs()) == [job.id, second.id]
        assert {j.job: j.halt for j in c.jobs()}[second.id] == {"spp": 2, "time_s": 60.0, "target_error": 0.5}
        job.cancel()
        done = job.wait(timeout=60)
        assert done.state == "cancelled" and not done.ok, done
        assert second.wait(timeout=60).ok
        assert {j.job: j.state for j in c.jobs()} == {job.id: "cancelled", second.id: "done"}
        job.delete()
        expect_error("unknown_job", job.status)
        expect_error("unknown_job", c.job(987654).fetch)
        # A bad scene is refused with the parser's file:line: key: what.
        bad = write(os.path.join(tmp, "bad.yaml"), small_cornell().replace(b"fov: 19.5", b"fov: wide"))
        e = expect_error("scene_invalid", c.submit, bad)
        assert "fov" in e.message and "scene_invalid" in str(e), str(e)
        assert isinstance(e, omega.Error)
        for kw in ({"priority": 1001}, {"spp": 0}):
            try:
                c.submit(long_scene, **kw)
                raise AssertionError(f"{kw} accepted")
            except ValueError:
                pass
        c.ping()
    try:
        omega.connect("unix:" + os.path.join(tmp, "nobody.sock"))
        raise AssertionError("connected to nothing")
    except omega.ConnectionFailed as e:
        assert "nobody.sock" in str(e), str(e)


def test_tcp_token_and_tls(tmp, daemons):
    d = Daemon(tmp, config=f"tcp_users: {{alice: {TOKEN}}}\n").start()
    daemons.append(d)
    scene = write(os.path.join(tmp, "s.yaml"), small_cornell(width=32, height=32, spp=2))
    saved = {k: os.environ.pop(k, None) for k in ("OMEGA_USER", "OMEGA_TOKEN", "OMEGA_TOKEN_FILE", "OMEGA_TLS_CA")}
    try:
        with omega.connect(d.tcp, user="alice", token=TOKEN) as c:
            assert c.user == "alice"
            job = c.submit(scene, seed=3)
            assert job.wait(timeout=60).ok
            assert job.status().owner == "alice" and job.fetch().spp == 2
        os.environ.update(OMEGA_USER="alice", OMEGA_TOKEN=TOKEN)
        with omega.connect(d.tcp) as c:
            assert [j.job for j in c.jobs()] == [job.id]
        del os.environ["OMEGA_TOKEN"]
        os.environ["OMEGA_TOKEN_FILE"] = write(os.path.join(tmp, "token"), TOKEN.encode() + b"\n")
        with omega.connect(d.tcp) as c:
            assert c.user == "alice"
        expect_error("auth_failed", omega.connect, d.tcp, user="alice", token="wrong-token")
        expect_error("auth_failed", omega.connect, d.tcp, user="mallory", token=TOKEN)
        del os.environ["OMEGA_TOKEN_FILE"]
        try:
            omega.connect(d.tcp, user="alice")
            raise AssertionError("connected without a token")
        except omega.DaemonError:
            raise
        except omega.Error as e:
            assert "OMEGA_TOKEN" in str(e), str(e)
        d.stop()

        # TLS: the same handshake inside, the certificate checked against $OMEGA_TLS_CA.
        cert, key = os.path.join(tmp, "cert.pem"), os.path.join(tmp, "key.pem")
        subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", key, "-out", cert,
                        "-days", "1", "-subj", "/CN=localhost", "-addext", "subjectAltName=DNS:localhost,IP:127.0.0.1"],
                       check=True, capture_output=True, timeout=60)
        t = Daemon(tmp, name="tls", state_dir=os.path.join(tmp, "tls-state"),
                   config=f"tls_cert: {cert}\ntls_key: {key}\ntcp_users: {{alice: {TOKEN}}}\n").start()
        daemons.append(t)
        addr = "tls:" + t.tcp[4:]
        try:
            omega.connect(addr, user="alice", token=TOKEN)
            raise AssertionError("TLS without the CA was trusted")
        except omega.ConnectionFailed as e:
            assert "certificate not trusted" in str(e), str(e)
        os.environ["OMEGA_TLS_CA"] = cert
        with omega.connect(addr, user="alice", token=TOKEN) as c:
            job = c.submit(scene, seed=3)
            assert job.wait(timeout=60).ok and c.jobs()[0].owner == "alice"
        expect_error("auth_failed", omega.connect, addr, user="alice", token="wrong-token")
    finally:
        for k, v in saved.items():
            os.environ.pop(k, None)
            if v is not None:
                os.environ[k] = v


def test_scripted_peer(tmp, daemons):
    """What omegad seldom does, from a scripted peer: a ping to answer in the middle of a request,
    frames for other ids that stay queued, an error with id 0, a bye, and bytes that are no frame."""
    import socket
    import threading
    from omega import codec
    path = os.path.join(tmp, "peer.sock")
    srv = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    srv.bind(path)
    srv.listen(4)
    srv.settimeout(30)
    log = []

    def serve():
        for script in ("ping", "error0", "garbage", "bye"):
            conn, _ = srv.accept()
            conn.settimeout(30)
            dec = codec.Decoder()

            def recv():
                while True:
                    frames = list(dec.frames())
                    if frames:
                        assert len(frames) == 1, frames
                        return frames[0][0]
                    dec.feed(conn.recv(65536))

            h = recv()
            conn.sendall(codec.encode_frame({"type": "welcome", "id": h["id"], "version": 1, "server": "peer/1",
                                             "auth": "peer", "user": "7"}))
            h = recv()
            if script == "ping":
                conn.sendall(codec.bare("ping", 99))
                log.append(recv())  # the pong, before any reply
                conn.sendall(codec.encode_frame({"type": "progress", "id": 12345, "job": 1, "state": "running",
                                                 "progress": {"pass": 0, "spp": 0, "elapsed_s": 0.0,
                                                              "samples_per_s": 0.0}}))
                conn.sendall(codec.encode_frame({"type": "job_list", "id": h["id"], "jobs": []}))
            elif script == "error0":
                conn.sendall(codec.encode_frame({"type": "error", "id": 0, "code": "bad_request", "message": "?"}))
            elif script == "garbage":
                conn.sendall(b"HTTP/1.1 400 Bad Request\r\n\r\n")
            else:
                conn.sendall(codec.bare("bye", 0))
            time.sleep(0.2)
            conn.close()

    th = threading.Thread(target=serve, daemon=True)
    th.start()
    try:
        with omega.connect("unix:" + path) as c:
            assert c.user == "7" and c.server == "peer/1"
            assert c.jobs() == []
            assert log == [{"type": "pong", "id": 99}], log
            assert c.connection.wait_for(12345, 5)[0]["type"] == "progress"  # kept for its id
        c = omega.connect("unix:" + path)
        expect_error("bad_request", c.jobs)
        c = omega.connect("unix:" + path)
        try:
            c.jobs()
            raise AssertionError("garbage read as a frame")
        except omega.ProtocolError as e:
            assert e.code == "bad_magic" and c.connection.closed, e
        c = omega.connect("unix:" + path)
        try:
            c.ping()
            raise AssertionError("bye not noticed")
        except omega.ConnectionFailed as e:
            assert "bye" in str(e), e
    finally:
        th.join(10)
        srv.close()


def test_docs_farm_script(tmp, daemons):
    """The farm script of docs/python.md, as printed there (fewer spp), against a real daemon."""
    from harness import SOURCE_DIR
    with open(os.path.join(SOURCE_DIR, "docs", "python.md"), encoding="utf-8") as f:
        doc = f.read()
    code = re.search(r"## A farm script\n.*?```python\n(.*?)```", doc, re.S).group(1)
    assert "omega.connect()" in code and "spp=256" in code, code
    script = write(os.path.join(tmp, "farm.py"), code.replace("spp=256", "spp=3").encode())
    for i in range(3):
        write(os.path.join(tmp, "frames", f"frame{i:02d}.yaml"), small_cornell(width=24 + 8 * i, height=16, spp=1))
    d = Daemon(tmp).start()
    daemons.append(d)
    env = dict(os.environ, OMEGA_HOST=d.unix, PYTHONPATH=os.path.join(HERE, "..", "src"))
    r = subprocess.run([sys.executable, script], cwd=tmp, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, (r.stdout, r.stderr)
    with omega.connect(d.unix) as c:
        jobs = c.jobs()
    assert [(j.name, j.state, j.progress.spp) for j in jobs] == [(f"frame{i:02d}", "done", 3) for i in range(3)], jobs
    for i in range(3):
        with open(os.path.join(tmp, f"frame{i:02d}.exr"), "rb") as f:
            assert f.read(4) == b"\x76\x2f\x31\x01"


if __name__ == "__main__":
    t = Test()
    t.run(test_render_equals_local)
    t.run(test_scene_with_assets)
    t.run(test_job_control_and_errors)
    t.run(test_tcp_token_and_tls)
    t.run(test_scripted_peer)
    t.run(test_docs_farm_script)
    t.exit()
