"""Durability: kill -9 during a render, a restart, and the job completes with the expected sample
count and the same image as an uninterrupted run; queued jobs stay queued. SIGTERM drains at a
pass boundary; a second SIGTERM exits at once; SIGHUP reloads the config."""
import os
import signal
import time

from harness import Daemon, Test, exr_equal, local_render, op, small_cornell, wait_spp, wait_state



SPP = 200


def test_kill9_and_resume(tmp, daemons):
    # Every integrator resumes bit-identically, variance included (light and bdpt add one batch
    # per sample index, so the passes before and after the kill do not show).
    # Under a sanitizer (5-15x slower) light and bdpt render a smaller film; slow enough either way
    # that the kill lands mid-render.
    small = bool(os.environ.get("OMEGA_SANITIZER"))
    for integrator, spp, w, h_ in (("path", SPP, 64, 48), ("light", 64 if small else SPP, 32 if small else 64, 24 if small else 48),
                                   ("bdpt", 64 if small else SPP, 32 if small else 64, 24 if small else 48)):
        work = os.path.join(tmp, integrator)
        os.makedirs(work)
        kill9_and_resume(work, daemons, integrator, spp, small_cornell(width=w, height=h_).replace(b"max_depth: 65", b"max_depth: 8"))


def test_kill9_and_resume_aovs(tmp, daemons):
    # Light path expression outputs are in the checkpoint too: after the kill their layers resume
    # bit-identically with the beauty; so are the breakdown's exact sums (film key `breakdown`),
    # whose report then equals the uninterrupted render's text for text. Under a sanitizer both
    # render fewer samples, and bdpt the smaller film, as in test_kill9_and_resume: at full size
    # TSan ran past the test's time limit (bdpt once; then, beside the other daemon tests on 2
    # cores, path's 200 spp with AOVs and the breakdown).
    small = bool(os.environ.get("OMEGA_SANITIZER"))
    for integrator, spp, w, h_ in (("path", 64 if small else SPP, 64, 48),
                                   ("bdpt", 64 if small else SPP, 32 if small else 64, 24 if small else 48)):
        scene = small_cornell(width=w, height=h_).replace(b"max_depth: 65", b"max_depth: 8")
        scene = scene.replace(b"film: {width: %d" % w,
                              b'film: {aov: {direct: "L D E", indirect: "L D D+ E"}, breakdown: {length: 4}, width: %d' % w)
        assert b"aov:" in scene
        work = os.path.join(tmp, integrator)
        os.makedirs(work)
        kill9_and_resume(work, daemons, integrator, spp, scene,
                         layers=("aov.direct", "aov.direct.var", "aov.indirect", "aov.indirect.var"),
                         attrs=("omega.breakdown", "omega.breakdown_samples"))


def kill9_and_resume(tmp, daemons, integrator, SPP, scene, layers=(), attrs=()):
    local = os.path.join(tmp, "local.exr")
    local_render(scene, local, SPP, 11, tmp, integrator=integrator)
    d = Daemon(tmp, config="max_running: 1\n").start()
    daemons.append(d)
    c = d.client()
    job = c.submit(scene, name="crash", seed=11, halt_=op.halt(spp=SPP), integrator=integrator)["job"]
    queued = c.submit(scene, name="later", seed=1, halt_=op.halt(spp=2))["job"]
    h = wait_spp(c, job, 8)
    assert h["progress"]["spp"] < SPP, "the render finished before the kill: make it longer"
    d.kill9()
    ck = os.path.join(d.state_dir, "jobs", str(job), "checkpoint.bin")
    assert os.path.exists(ck), "no checkpoint after several passes"
    d.start()
    c = d.client()
    assert c.job("status", queued)["state"] == "queued"
    d.wait_log(rf"job {job}: was running at the last stop")
    m = d.wait_log(rf"job {job}: rendering from (\d+) spp")
    resumed_from = int(m.group(1))
    assert resumed_from > 0, "the job restarted from scratch"
    info = wait_state(c, job, {"done"})
    assert info["progress"]["spp"] == SPP, info
    f = c.job("fetch", job)
    out = os.path.join(tmp, "daemon.exr")
    with open(out, "wb") as fh:
        fh.write(f["_payload"])
    assert f["spp"] == SPP
    assert exr_equal(local, out, layers, attrs), f"{integrator}: resumed render differs from the uninterrupted one"
    wait_state(c, queued, {"done"})
    d.stop()
    print(f"  {integrator}: killed at >= 8 spp, resumed from {resumed_from} spp, finished at {SPP} spp, bit-identical")


def test_sigterm_drain_second_sigterm_and_sighup(tmp, daemons):
    scene = small_cornell(width=64, height=48)
    d = Daemon(tmp, config="max_running: 1\n").start()
    daemons.append(d)
    c = d.client()
    job = c.submit(scene, name="long", halt_=op.halt(spp=100000))["job"]
    wait_spp(c, job, 4)
    # SIGHUP: reload (a changed value is picked up).
    with open(d.config_path, "a") as f:
        f.write("max_running: 2\n".replace("max_running: 2", "tile_size: 16"))
    d.proc.send_signal(signal.SIGHUP)
    d.wait_log(r"config reloaded")
    # SIGTERM: the job stops at a pass boundary, is checkpointed, and the daemon exits 0.
    t0 = time.monotonic()
    rc = d.terminate(timeout=30)
    assert rc == 0, rc
    assert "drained; exiting" in d.log()
    drain_s = time.monotonic() - t0
    d.start()
    c = d.client()
    m = d.wait_log(rf"job {job}: rendering from (\d+) spp")
    assert int(m.group(1)) > 0
    wait_spp(c, job, int(m.group(1)) + 1)
    # Two SIGTERMs: the second one exits at once, without waiting for the pass. A bigger job
    # (passes of about a second) preempts the first so that the drain has something to wait for.
    # Under a sanitizer a quarter of the film keeps passes near a second there too.
    side = 128 if os.environ.get("OMEGA_SANITIZER") else 256
    big = c.submit(small_cornell(width=side, height=side), name="big", priority=9, halt_=op.halt(spp=100000))["job"]
    wait_spp(c, big, 4)
    mark = len(d.lines)
    d.proc.send_signal(signal.SIGTERM)
    d.wait_log(r"draining", start=mark)
    d.proc.send_signal(signal.SIGTERM)
    t0 = time.monotonic()
    d.proc.wait(10)
    log = d.log()
    if "second SIGTERM: exiting now" not in log:
        assert log.index("drained; exiting") >= 0
        print("  (the drain finished before the second SIGTERM arrived; not checked this time)")
    print(f"  drain took {drain_s:.2f} s; second SIGTERM exit in {time.monotonic() - t0:.2f} s")
    # Still resumable.
    d.start()
    c = d.client()
    d.wait_log(rf"job {big}: rendering from [1-9]\d* spp")
    assert c.job("cancel", big)["type"] == "ok"
    d.wait_log(rf"job {job}: rendering from [1-9]\d* spp")
    assert c.job("cancel", job)["type"] == "ok"


if __name__ == "__main__":
    t = Test()
    t.run(test_kill9_and_resume)
    t.run(test_kill9_and_resume_aovs)
    t.run(test_sigterm_drain_second_sigterm_and_sighup)
    t.exit()
