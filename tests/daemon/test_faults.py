"""Faults: a corrupt checkpoint, a corrupt cached asset (caught by its hash), the SQLite database
locked by another process (at a submit, and at a job's end and a pause). Each keeps every accepted job and leaves a clear log line. (kill -9
mid-pass is test_crash.py; a half frame held open is test_security.py.)"""
import contextlib
import hashlib
import os
import random
import re
import sqlite3
import subprocess
import threading
import time

from harness import SLOWDOWN, Daemon, Test, exr_equal, local_render, op, small_cornell, wait_spp, wait_state

TRI_OBJ = b"v -0.5 0.2 -0.5\nv 0.5 0.2 -0.5\nv 0 0.9 0\nf 1 2 3\n"


def fetch_to(c, job, path):
    f = c.job("fetch", job)
    assert f["type"] == "image", f
    with open(path, "wb") as out:
        out.write(f["_payload"])
    return path


def test_corrupt_checkpoint(tmp, daemons):
    scene = small_cornell(width=48, height=32)
    local = os.path.join(tmp, "local.exr")
    local_render(scene, local, 60, 5, tmp)
    d = Daemon(tmp, config="max_running: 1\n").start()
    daemons.append(d)
    c = d.client()
    job = c.submit(scene, name="ck", seed=5, halt_=op.halt(spp=60))["job"]
    deadline = time.monotonic() + 60
    while c.job("status", job)["progress"]["spp"] < 4 and time.monotonic() < deadline:
        time.sleep(0.05)
    d.kill9()
    ck = os.path.join(d.state_dir, "jobs", str(job), "checkpoint.bin")
    data = bytearray(open(ck, "rb").read())
    data[len(data) // 2] ^= 0xFF
    open(ck, "wb").write(bytes(data))
    d.start()
    d.wait_log(rf"job {job}: corrupt checkpoint .*rendering again from 0 spp")
    c = d.client()
    info = wait_state(c, job, {"done"})
    assert info["progress"]["spp"] == 60, info
    assert exr_equal(local, fetch_to(c, job, os.path.join(tmp, "out.exr")))
    assert os.path.exists(ck + ".corrupt")


def test_corrupt_cached_asset(tmp, daemons):
    scene = small_cornell(width=32, height=32).replace(
        b"shapes:\n", b"shapes:\n  - {type: mesh, file: meshes/tri.obj, material: FloorBSDF}\n", 1)
    assets = [("meshes/tri.obj", TRI_OBJ)]
    sha = hashlib.sha256(TRI_OBJ).hexdigest()
    d = Daemon(tmp).start()
    daemons.append(d)
    c = d.client()
    j1 = c.submit(scene, name="a", assets=assets, halt_=op.halt(spp=1))["job"]
    wait_state(c, j1, {"done"})
    cached = os.path.join(d.state_dir, "assets", sha[:2], sha)
    with open(cached, "r+b") as f:  # bit rot in place
        f.seek(3)
        f.write(b"X")
    h = c.submit(scene, name="b", assets=assets, halt_=op.halt(spp=1))
    assert h["type"] == "error" and h["code"] == "asset_mismatch" and "corrupt" in h["message"], h
    d.wait_log(r"cached asset [0-9a-f]{64} is corrupt")
    assert not os.path.exists(cached)
    # Sent again, it is accepted and renders.
    h = c.submit(scene, name="c", assets=assets, halt_=op.halt(spp=1))
    assert h["type"] == "accepted", h
    wait_state(c, h["job"], {"done"})


def test_database_locked(tmp, daemons):
    scene = small_cornell(width=32, height=32)
    d = Daemon(tmp, config="max_running: 1\n").start()
    daemons.append(d)
    c = d.client()
    running = c.submit(scene, name="r", halt_=op.halt(spp=40))["job"]
    held = threading.Event()
    release = threading.Event()

    def locker():
        db = sqlite3.connect(os.path.join(d.state_dir, "jobs.sqlite"), timeout=30, isolation_level=None)
        db.execute("BEGIN EXCLUSIVE")
        held.set()
        release.wait(30)
        db.execute("COMMIT")
        db.close()

    t = threading.Thread(target=locker)
    t.start()
    held.wait(10)
    h = c.submit(scene, name="while-locked", halt_=op.halt(spp=1))
    release.set()
    t.join()
    assert h["type"] == "error" and h["code"] == "busy" and "locked" in h["message"], h
    d.wait_log(r"database is locked")
    assert d.proc.poll() is None, "omegad died while the database was locked"
    info = wait_state(c, running, {"done"})
    assert info["progress"]["spp"] == 40, info
    h = c.submit(scene, name="after", halt_=op.halt(spp=1))
    assert h["type"] == "accepted", h
    wait_state(c, h["job"], {"done"})


def hold_lock(d):
    """Locks jobs.sqlite from another process (BEGIN EXCLUSIVE: in WAL mode readers go on, writers
    get SQLITE_BUSY). Returns (thread, release event) once the lock is held."""
    held, release = threading.Event(), threading.Event()

    def locker():
        db = sqlite3.connect(os.path.join(d.state_dir, "jobs.sqlite"), timeout=30, isolation_level=None)
        db.execute("BEGIN EXCLUSIVE")
        held.set()
        release.wait(120)
        db.execute("COMMIT")
        db.close()

    t = threading.Thread(target=locker)
    t.start()
    assert held.wait(30), "could not lock the database"
    return t, release


def test_database_locked_at_job_end(tmp, daemons):
    """The store refuses every write while a job ends and while it is paused: the pause gets an
    error frame and changes nothing, the job's end is retried until the lock goes (not left
    'running' until a restart), and the queue carries on."""
    scene = small_cornell(width=32, height=32)
    d = Daemon(tmp, config="max_running: 1\n").start()
    daemons.append(d)
    c = d.client()
    job = c.submit(scene, name="timed", halt_=op.halt(time_s=3))["job"]
    wait_state(c, job, {"running"})
    t, release = hold_lock(d)
    try:
        h = c.job("pause", job)
        assert h["type"] == "error" and h["code"] == "busy" and "locked" in h["message"], h
        d.wait_log(rf"job {job}: cannot record its end in the job store: .*locked.*retrying every second", timeout=90)
        assert d.proc.poll() is None, "omegad died while the database was locked"
        info = c.job("status", job)
        assert info["state"] == "running", info  # the store has not got it yet
    finally:
        release.set()
        t.join()
    d.wait_log(rf"job {job}: its end is recorded in the job store now", timeout=30)
    info = wait_state(c, job, {"done"}, timeout=30)
    assert info["progress"]["spp"] > 0, info
    assert not re.search(rf"job {job}: (paused|stopped)", d.log()), "the refused pause stopped the job"
    h = c.submit(scene, name="after", halt_=op.halt(spp=1))
    assert h["type"] == "accepted", h
    wait_state(c, h["job"], {"done"})


def test_kill9_at_random_moments(tmp, daemons):
    """Rounds of: clients submit (with a fresh asset each time) and render; kill -9 after a random
    delay (so at accept, during an upload, mid-pass or in a checkpoint write); restart. Every job
    that got `accepted` must end done with its full spp."""
    rng = random.Random(int(os.environ.get("OMEGA_FAULT_SEED", "7")))
    scene = small_cornell(width=32, height=32).replace(
        b"shapes:\n", b"shapes:\n  - {type: mesh, file: m.obj, material: FloorBSDF}\n", 1)
    d = Daemon(tmp, config="max_running: 2\n")
    daemons.append(d)
    accepted = {}
    n = 0
    for round_ in range(6):
        d.start()
        stop = threading.Event()

        def client():
            nonlocal n
            try:
                c = d.client(timeout=5)
                while not stop.is_set():
                    n += 1
                    obj = TRI_OBJ + b"# %d\n" % n + b"#" * rng.randrange(1, 200000) + b"\n"
                    h = c.submit(scene, name=f"k{n}", assets=[("m.obj", obj)], halt_=op.halt(spp=6))
                    if h.get("type") == "accepted":
                        accepted[h["job"]] = 6
            except (ConnectionError, OSError, TimeoutError):
                pass

        t = threading.Thread(target=client)
        t.start()
        time.sleep(rng.uniform(0.05, 1.5))
        d.kill9()
        stop.set()
        t.join(10)
    d.start()
    d.wait_log(r"omegad ready")
    c = d.client()
    for job, spp in accepted.items():
        info = wait_state(c, job, {"done"}, timeout=120)
        assert info["progress"]["spp"] == spp, info
    print(f"  6 kill -9 rounds, {len(accepted)} accepted jobs, all done")


@contextlib.contextmanager
def daemon_on_tmpfs(tmp, daemons, name, size):
    """omegad (one job at a time) whose state dir is on a fresh tmpfs of `size`, unmounted after;
    yields (None, path) where no tmpfs can be mounted (not root)."""
    mnt = os.path.join(tmp, name)
    os.makedirs(mnt)
    if subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", mnt], capture_output=True).returncode != 0:
        yield None, mnt
        return
    try:
        d = Daemon(tmp, config="max_running: 1\n", state_dir=os.path.join(mnt, "state")).start()
        daemons.append(d)
        yield d, mnt
    finally:
        subprocess.run(["umount", "-l", mnt], capture_output=True)


def test_disk_full(tmp, daemons):
    """The state dir on a small tmpfs: a submit that does not fit gets `busy` naming the disk,
    the daemon carries on, and jobs accepted before still finish (a checkpoint that finds the
    disk full is skipped with a warning, not the job failed: under a sanitizer the first job is
    often still rendering while the big asset fills the disk)."""
    with daemon_on_tmpfs(tmp, daemons, "small", "4m") as (d, mnt):
        if d is None:
            print("  SKIP test_disk_full: cannot mount a tmpfs here (needs root)")
            return
        c = d.client()
        scene = small_cornell(width=32, height=32).replace(
            b"shapes:\n", b"shapes:\n  - {type: mesh, file: m.obj, material: FloorBSDF}\n", 1)
        first = c.submit(scene, name="fits", assets=[("m.obj", TRI_OBJ)], halt_=op.halt(spp=4))
        assert first["type"] == "accepted", first
        big = TRI_OBJ + b"#" * (6 << 20) + b"\n"
        h = c.submit(scene, name="too-big", assets=[("m.obj", big)], halt_=op.halt(spp=1))
        assert h["type"] == "error" and h["code"] == "busy" and "space" in h["message"].lower(), h
        d.wait_log(r"No space left on device")
        # The half-written asset was removed, so the disk has room again for the job's own writes.
        # Only the asset cache is looked at: the first job may be rendering, and its checkpoint's
        # or result's own .tmp can exist for a moment (a walk of the whole state dir saw one).
        assets = os.path.join(mnt, "state", "assets")
        assert os.path.isdir(assets), assets
        assert not [f for _, _, fs in os.walk(assets) for f in fs if f.endswith(".tmp")]
        info = wait_state(c, first["job"], {"done"})
        assert info["progress"]["spp"] == 4, info
        d.stop()


def test_disk_full_at_job_end(tmp, daemons):
    """The disk is full when a job reaches its halt: its final checkpoint and result image are
    written once there is room again (tried every second), and the job ends done, with every
    sample and the image of a local render, instead of failed."""
    with daemon_on_tmpfs(tmp, daemons, "small-end", "8m") as (d, mnt):
        if d is None:
            print("  SKIP test_disk_full_at_job_end: cannot mount a tmpfs here (needs root)")
            return
        c = d.client()
        scene = small_cornell(width=32, height=32)
        spp = 1024 // SLOWDOWN  # long enough to fill the disk while it renders
        h = c.submit(scene, name="ends-on-a-full-disk", seed=3, halt_=op.halt(spp=spp))
        assert h["type"] == "accepted", h
        wait_spp(c, h["job"], 1)
        filler = os.path.join(mnt, "filler")
        with open(filler, "wb", buffering=0) as f:  # unbuffered: nothing left to fail at close
            try:
                while True:
                    f.write(b"\0" * (1 << 16))
            except OSError:
                pass
        d.wait_log(r"not written \(.*No space left on device.*\); trying again every second", timeout=120)
        assert c.job("status", h["job"])["state"] == "running"
        os.remove(filler)
        info = wait_state(c, h["job"], {"done", "failed"})
        assert info["state"] == "done" and info["progress"]["spp"] == spp, info
        d.wait_log(r"written once the disk had room")
        local = os.path.join(tmp, "local-end.exr")
        local_render(scene, local, spp, 3, tmp)
        assert exr_equal(local, fetch_to(c, h["job"], os.path.join(tmp, "end.exr")))
        d.stop()


if __name__ == "__main__":
    t = Test()
    for fn in (test_corrupt_checkpoint, test_corrupt_cached_asset, test_database_locked, test_database_locked_at_job_end,
               test_kill9_at_random_moments,
               test_disk_full, test_disk_full_at_job_end):
        t.run(fn)
    t.exit()
