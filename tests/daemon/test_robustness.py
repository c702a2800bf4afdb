"""Hostile and careless clients: garbage bytes, truncated frames, oversized lengths, a bad scene,
assets missing, mismatched or out of bounds, a client that stops reading mid-stream, one that
disconnects, and eight clients submitting and watching at once. In every case the daemon keeps
serving the others and its log names the cause."""
import hashlib
import os
import socket
import struct
import threading
import time

from harness import Daemon, Test, op, small_cornell, wait_state, watch


def ping(d):
    c = d.client()
    h = c.request(lambda id: op.bare("ping", id))
    assert h["type"] == "pong", h
    c.close()


def raw(d, data, expect_reply=True, close_after=False):
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.settimeout(10)
    s.connect(d.sock)
    s.sendall(op.hello(1, "raw"))
    dec, frames = op.Decoder(), []
    if close_after:
        # Read the welcome first: a client that leaves before it is written makes the daemon's
        # write fail (peer gone), and it closes without reading what followed (TSan showed it).
        while not frames:
            chunk = s.recv(65536)
            if not chunk:
                break
            dec.feed(chunk)
            frames.extend(dec.frames())
        s.sendall(data)
        s.close()
        return []
    s.sendall(data)
    while True:
        try:
            chunk = s.recv(65536)
        except socket.timeout:
            break
        if not chunk:
            break
        dec.feed(chunk)
        frames.extend(dec.frames())
    s.close()
    return frames


def test_bad_bytes(tmp, daemons):
    d = Daemon(tmp).start()
    daemons.append(d)
    # Garbage: error bad_frame (bad_magic), then the daemon closes the connection.
    f = raw(d, b"GET / HTTP/1.1\r\nHost: x\r\n\r\n")
    assert [h["type"] for h, _ in f] == ["welcome", "error"], f
    assert f[1][0]["code"] == "bad_frame" and "bad_magic" in f[1][0]["message"], f
    d.wait_log(r"bad frame: bad_magic")
    ping(d)
    # Oversized lengths, refused from the prelude alone.
    f = raw(d, op.PRELUDE.pack(op.MAGIC, 1 << 31, 0))
    assert f[-1][0]["code"] == "bad_frame" and "header_too_large" in f[-1][0]["message"], f
    f = raw(d, op.PRELUDE.pack(op.MAGIC, 10, 1 << 62))
    assert "payload_too_large" in f[-1][0]["message"], f
    hdr = b'{"type": "ping", "id": 9}'
    f = raw(d, op.PRELUDE.pack(op.MAGIC, len(hdr), 5) + hdr + b"12345")
    assert "payload_too_large_for_type" in f[-1][0]["message"], f
    d.wait_log(r"bad frame: payload_too_large_for_type")
    # A frame cut short, then the client leaves.
    frame = op.job_request("status", 5, 1)
    raw(d, frame[:len(frame) - 3], close_after=True)
    d.wait_log(r"stream ended inside a frame \(truncated")
    # A well-formed frame with bad fields keeps the connection.
    c = d.client()
    h = c.request(lambda id: op.encode_frame({"type": "status", "id": id, "job": "seven"}))
    assert h["type"] == "error" and h["code"] == "bad_request", h
    h = c.request(lambda id: op.bare("ping", id))
    assert h["type"] == "pong"
    # A request before hello.
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.connect(d.sock)
    s.sendall(op.bare("ping", 3))
    s.settimeout(10)
    dec = op.Decoder()
    dec.feed(s.recv(65536))
    (h, _), = list(dec.frames())
    assert h["code"] == "auth_required", h
    s.close()
    ping(d)


def test_bad_scenes_and_assets(tmp, daemons):
    d = Daemon(tmp).start()
    daemons.append(d)
    c = d.client()
    h = c.submit(small_cornell().replace(b"fov: 19.5", b"fov: nineteen"), name="bad")
    assert h["type"] == "error" and h["code"] == "scene_invalid", h
    assert h["message"].startswith("bad.yaml:") and "fov" in h["message"], h
    d.wait_log(r"submit 'bad' .* refused \(scene_invalid\): bad.yaml:\d+: .*fov")
    mesh = small_cornell().replace(b"shapes:\n", b"shapes:\n  - {type: mesh, file: meshes/m.obj, material: FloorBSDF}\n", 1)
    # Missing: the scene names a file that was not sent.
    h = c.submit(mesh, name="missing")
    assert h["code"] == "scene_invalid" and "meshes/m.obj" in h["message"], h
    # Out of bounds: absolute paths and .. are refused even when the file exists.
    for path in (b"/etc/hostname", b"../../../../../../etc/hostname"):
        h = c.submit(mesh.replace(b"meshes/m.obj", path), name="escape")
        assert h["type"] == "error" and h["code"] == "scene_invalid", h
        assert "is not a submitted asset or a regular file under an allowed root" in h["message"], h
    # Wrong hash: the bytes sent are not the ones announced.
    obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    sid = c.new_id()
    c.send(op.submit(sid, mesh, name="m", assets=[("meshes/m.obj", obj)]))
    h, _ = c.recv_for(sid)
    assert h["type"] == "need_assets"
    evil = obj.replace(b"v 1", b"v 9")
    c.send(op.encode_frame({"type": "asset", "id": sid, "sha256": hashlib.sha256(obj).hexdigest()}, evil))
    h, _ = c.recv_for(sid)
    assert h["type"] == "error" and h["code"] == "asset_mismatch" and "hashes to" in h["message"], h
    d.wait_log(r"submit \d+ refused: asset 'meshes/m.obj' hashes to")
    # An asset nobody asked for.
    h = c.request(lambda id: op.asset(id, obj))
    assert h["code"] == "asset_mismatch" and "not requested" in h["message"], h
    # A job with a bad mesh file content fails validation, not the render.
    h = c.submit(mesh, name="garbage-mesh", assets=[("meshes/m.obj", b"this is not an obj file\n")])
    assert h["type"] == "error", h
    # After all that, a good submit still works on the same connection.
    h = c.submit(mesh, name="good", assets=[("meshes/m.obj", obj)], halt_=op.halt(spp=2))
    assert h["type"] == "accepted", h
    wait_state(c, h["job"], {"done"})
    ping(d)


def test_slow_reader_and_disconnect(tmp, daemons):
    d = Daemon(tmp, config="output_buffer_bytes: 1048576\n").start()
    daemons.append(d)
    scene = small_cornell(width=192, height=160, spp=16)
    c = d.client()
    job = c.submit(scene, name="big", halt_=op.halt(spp=16))["job"]
    # A subscriber that never reads, and one that leaves mid-stream.
    slow = d.client()
    slow.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    slow_sid = slow.new_id()
    slow.send(op.job_request("subscribe", slow_sid, job))
    gone = d.client()
    gone.send(op.job_request("subscribe", gone.new_id(), job))
    gone.recv()
    gone.close()
    t0 = time.monotonic()
    tiles, progress, done = watch(c, job)  # a normal watcher is not held up
    assert done["state"] == "done" and done["progress"]["spp"] == 16, done
    assert len(tiles) == 30 and all(h["spp"] == 16 for h, _ in tiles.values())
    ping(d)
    # Now the slow one reads: the newest version of every tile, then done, last.
    latest, frames = {}, 0
    while True:
        h, p = slow.recv_for(slow_sid, timeout=30)
        frames += 1
        if h["type"] == "tile":
            latest[tuple(h["rect"])] = h["version"]
        if h["type"] == "done":
            break
    assert len(latest) == 30 and set(latest.values()) == {16}, latest
    print(f"  slow reader got {frames} frames for {len(progress)} progress updates; watcher took "
          f"{time.monotonic() - t0:.1f} s")
    d.wait_log(r"connection \d+ .*(peer closed|write failed|read error)")


def test_eight_clients(tmp, daemons):
    d = Daemon(tmp, config="max_running: 2\n").start()
    daemons.append(d)
    results, errors = {}, []

    def client(i):
        try:
            c = d.client(tcp=(i % 2 == 1))
            h = c.submit(small_cornell(width=48, height=32, spp=4), name=f"c{i}", seed=i, halt_=op.halt(spp=4))
            assert h["type"] == "accepted", h
            tiles, _, done = watch(c, h["job"])
            f = c.job("fetch", h["job"])
            assert done["state"] == "done" and f["type"] == "image", (done, f)
            results[i] = (h["job"], len(tiles), len(f["_payload"]))
            c.close()
        except Exception as e:  # noqa: BLE001
            errors.append((i, repr(e)))

    threads = [threading.Thread(target=client, args=(i,)) for i in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert not errors, errors
    assert len(results) == 8 and len({j for j, _, _ in results.values()}) == 8, results
    ping(d)


if __name__ == "__main__":
    t = Test()
    t.run(test_bad_bytes)
    t.run(test_bad_scenes_and_assets)
    t.run(test_slow_reader_and_disconnect)
    t.run(test_eight_clients)
    t.exit()
