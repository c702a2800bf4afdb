"""Submit, stream and fetch: the streamed tiles and the fetched image equal, bit for bit, a local
`omega render` of the same scene with the same seed and spp. Over the Unix socket and TCP; a scene
with a mesh asset (sent once, then cached); a subscriber that joins after the end. Path
tracing's tiles go out as each finishes, not when the whole pass has."""
import hashlib
import os
import subprocess
import time

from harness import OMEGA, SLOWDOWN, Daemon, Test, exr_equal, local_render, op, small_cornell, wait_state, watch

SPP, SEED = 12, 7
TRI_OBJ = b"v -0.5 0.2 -0.5\nv 0.5 0.2 -0.5\nv 0 1.2 0\nf 1 2 3\n"


def write(path, data):
    with open(path, "wb") as f:
        f.write(data)


def check_job(tmp, c, job, local, label):
    tiles, progress, done = watch(c, job)
    assert done["state"] == "done", done
    assert done["progress"]["spp"] == SPP, done
    assert tiles, "no tiles streamed"
    for (rect, (h, payload)) in tiles.items():
        assert h["spp"] == SPP, f"latest tile {rect} has spp {h['spp']}"
        p = os.path.join(tmp, f"{label}-tile-{'-'.join(map(str, rect))}.exr")
        write(p, payload)
        assert exr_equal(local, p), f"tile {rect} differs from the local render"
    fetched = c.job("fetch", job)
    assert fetched["type"] == "image", fetched
    assert fetched["spp"] == SPP and fetched["width"] == 80 and fetched["height"] == 48, fetched
    p = os.path.join(tmp, f"{label}-fetched.exr")
    write(p, fetched["_payload"])
    assert exr_equal(local, p) and exr_equal(p, local), "fetched image differs from the local render"
    return tiles


def render_here_and_submit(tmp, daemons, scene, label):
    """Renders `scene` locally (SPP, SEED) to local-LABEL.exr, starts a daemon and submits the
    same scene to it. Returns the local path, the client and the `accepted` reply."""
    local = os.path.join(tmp, f"local-{label}.exr")
    local_render(scene, local, SPP, SEED, tmp)
    d = Daemon(tmp).start()
    daemons.append(d)
    c = d.client()
    a = c.submit(scene, name=f"cornell-{label}", seed=SEED, halt_=op.halt(spp=SPP))
    assert a["type"] == "accepted", a
    return local, c, a


def test_stream_and_fetch_equal_local_render(tmp, daemons):
    scene = small_cornell()
    local = os.path.join(tmp, "local.exr")
    local_render(scene, local, SPP, SEED, tmp)
    d = Daemon(tmp).start()
    daemons.append(d)
    for tcp in (False, True):
        c = d.client(tcp=tcp)
        assert c.welcome[0]["type"] == "welcome", c.welcome
        if not tcp:
            assert c.welcome[0]["auth"] == "peer" and c.welcome[0]["user"] == str(os.getuid())
        a = c.submit(scene, name="cornell", seed=SEED, halt_=op.halt(spp=SPP))
        assert a["type"] == "accepted", a
        tiles = check_job(tmp, c, a["job"], local, "tcp" if tcp else "unix")
        assert len(tiles) == 6, sorted(tiles)  # 80x48 in 32-pixel tiles: 3 x 2, edges clipped
        info = wait_state(c, a["job"], {"done"})
        assert info["progress"]["spp"] == SPP and info["owner"] == (str(os.getuid()) if not tcp else "tcp")
        c.close()
    assert "job 2: done" in d.log()


def test_aovs_in_tiles_and_fetch(tmp, daemons):
    """A scene whose film names light path expression outputs: every streamed tile and the
    fetched image carry aov.NAME layers bit-identical to a local render's."""
    scene = small_cornell().replace(b"film: {width: 80", b'film: {aov: {direct: "L D E", indirect: "L D D+ E"}, width: 80')
    assert b"aov:" in scene
    layers = ("aov.direct", "aov.direct.var", "aov.indirect", "aov.indirect.var")
    local, c, a = render_here_and_submit(tmp, daemons, scene, "aov")
    tiles, progress, done = watch(c, a["job"])
    assert done["state"] == "done", done
    for (rect, (h, payload)) in tiles.items():
        p = os.path.join(tmp, f"aov-tile-{'-'.join(map(str, rect))}.exr")
        write(p, payload)
        assert exr_equal(local, p, layers), f"tile {rect} differs from the local render"
    fetched = c.job("fetch", a["job"])
    p = os.path.join(tmp, "aov-fetched.exr")
    write(p, fetched["_payload"])
    assert exr_equal(local, p, layers), "fetched image differs from the local render"
    c.close()


def test_breakdown_in_fetch_and_result(tmp, daemons):
    """A scene whose film asks for the path-class breakdown (film key `breakdown`, the job
    option): the fetched image's omega.breakdown header equals a local render's, text for text
    (its sums are exact, so the daemon's threads and passes cannot change a digit)."""
    scene = small_cornell().replace(b"film: {width: 80", b"film: {breakdown: {length: 4}, width: 80")
    assert b"breakdown:" in scene
    local, c, a = render_here_and_submit(tmp, daemons, scene, "breakdown")
    d = daemons[-1]
    wait_state(c, a["job"], {"done"})
    fetched = c.job("fetch", a["job"])
    p = os.path.join(tmp, "breakdown-fetched.exr")
    write(p, fetched["_payload"])
    assert exr_equal(local, p, attrs=("omega.breakdown",)), "fetched breakdown differs from the local render's"
    # `omega submit --breakdown` sets the same key in a scene that lacks it.
    plain = os.path.join(tmp, "plain.yaml")
    write(plain, small_cornell())
    r = subprocess.run([OMEGA, "submit", plain, "--host", d.unix, "--spp", str(SPP), "--seed", str(SEED), "-q",
                        "--breakdown", "--breakdown-length", "4"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    job = int(r.stdout.strip())
    wait_state(c, job, {"done"})
    p2 = os.path.join(tmp, "breakdown-submitted.exr")
    write(p2, c.job("fetch", job)["_payload"])
    assert exr_equal(local, p2, attrs=("omega.breakdown",)), "omega submit --breakdown differs from the local render's"
    bad = subprocess.run([OMEGA, "submit", plain, "--host", d.unix, "--breakdown-box", "1,2"], capture_output=True,
                         text=True, timeout=120)
    assert bad.returncode == 2 and "breakdown box" in bad.stderr, bad.stderr
    c.close()


def test_mesh_asset_cached_and_late_subscriber(tmp, daemons):
    scene = small_cornell().replace(
        b"shapes:\n", b"shapes:\n  - {type: mesh, file: meshes/tri.obj, material: FloorBSDF}\n", 1)
    scene_dir = os.path.join(tmp, "scene")
    os.makedirs(os.path.join(scene_dir, "meshes"))
    write(os.path.join(scene_dir, "meshes", "tri.obj"), TRI_OBJ)
    write(os.path.join(scene_dir, "scene.yaml"), scene)
    local = os.path.join(tmp, "local.exr")
    local_render(scene, local, SPP, SEED, scene_dir)
    d = Daemon(tmp).start()
    daemons.append(d)
    c = d.client()
    assets = [("meshes/tri.obj", TRI_OBJ)]
    sid = c.new_id()
    c.send(op.submit(sid, scene, name="tri", seed=SEED, halt_=op.halt(spp=SPP), assets=assets))
    h, _ = c.recv_for(sid)
    assert h["type"] == "need_assets" and h["missing"] == [hashlib.sha256(TRI_OBJ).hexdigest()], h
    c.send(op.asset(sid, TRI_OBJ))
    h, _ = c.recv_for(sid)
    assert h["type"] == "accepted", h
    job = h["job"]
    wait_state(c, job, {"done"})
    # A late subscriber gets every tile's final state, then done.
    check_job(tmp, c, job, local, "late")
    # The asset is cached: a second submit needs nothing.
    sid = c.new_id()
    c.send(op.submit(sid, scene, name="tri2", seed=SEED, halt_=op.halt(spp=SPP), assets=assets))
    h, _ = c.recv_for(sid)
    assert h["type"] == "need_assets" and h["missing"] == [], h
    h, _ = c.recv_for(sid)
    assert h["type"] == "accepted", h
    wait_state(c, h["job"], {"done"})
    # The result stays fetchable after a restart, until deleted.
    d.terminate()
    d.start()
    c = d.client()
    f = c.job("fetch", job)
    assert f["type"] == "image", f
    write(os.path.join(tmp, "after.exr"), f["_payload"])
    assert exr_equal(local, os.path.join(tmp, "after.exr"))
    assert c.job("delete", job)["type"] == "ok"
    f = c.job("fetch", job)
    assert f["type"] == "error" and f["code"] == "unknown_job", f


def test_tiles_stream_before_their_pass_ends(tmp, daemons):
    """A tile is published as soon as its pixels finish a pass. Measured against the pass's own
    duration, so it holds on a loaded machine and under a sanitizer alike: without streaming,
    every tile of a pass arrives together with that pass's progress."""
    d = Daemon(tmp).start()
    daemons.append(d)
    c = d.client()
    size = 160 if SLOWDOWN > 1 else 384
    a = c.submit(small_cornell(width=size, height=size, spp=4), name="stream", halt_=op.halt(spp=4))
    sid = c.new_id()
    c.send(op.job_request("subscribe", sid, a["job"]))
    h, _ = c.recv_for(sid)
    assert h["type"] == "ok", h
    first_tile, seen, prev_elapsed = {}, [], 0.0
    while True:
        h, _ = c.recv_for(sid, timeout=120 * SLOWDOWN)
        now = time.monotonic()
        if h["type"] == "tile":
            first_tile.setdefault(h["pass"], now)
        elif h["type"] == "progress" and h["progress"]["pass"] in first_tile:
            p = h["progress"]["pass"]
            duration = h["progress"]["elapsed_s"] - prev_elapsed
            seen.append((p, now - first_tile[p], duration))
        elif h["type"] == "done":
            break
        if h["type"] == "progress":
            prev_elapsed = h["progress"]["elapsed_s"]
    assert seen, "no pass had both tiles and progress"
    # The first tile of a pass leads its progress by most of the pass (one tile per thread, of
    # 25-144 tiles, is all that must finish first).
    assert any(lead >= 0.5 * dur and dur > 0.05 for (_, lead, dur) in seen), seen
    d.wait_log(r"job 1: done")  # the log line may trail the done frame


if __name__ == "__main__":
    t = Test()
    t.run(test_tiles_stream_before_their_pass_ends)
    t.run(test_stream_and_fetch_equal_local_render)
    t.run(test_aovs_in_tiles_and_fetch)
    t.run(test_breakdown_in_fetch_and_result)
    t.run(test_mesh_asset_cached_and_late_subscriber)
    t.exit()
