"""The durable queue: priorities (with preemption), FIFO among equals, pause, resume, cancel,
re-prioritising, permissions and invalid states. A preempted or paused job resumes from its last
pass boundary and still ends bit-identical to an uninterrupted local render. Jobs running side by
side share the render threads by priority weight."""
import os
import re
import time

from harness import SLOWDOWN, Daemon, Test, exr_equal, local_render, op, small_cornell, wait_spp, wait_state, watch


def log_index(d, pattern):
    for i, line in enumerate(d.log().splitlines()):
        if re.search(pattern, line):
            return i
    raise AssertionError(f"no /{pattern}/ in the log")



def test_priorities_preemption_fifo(tmp, daemons):
    scene = small_cornell(width=64, height=48)
    local = os.path.join(tmp, "local.exr")
    local_render(scene, local, 160, 3, tmp)
    d = Daemon(tmp, config="max_running: 1\n").start()
    daemons.append(d)
    c = d.client()
    a = c.submit(scene, name="a", seed=3, halt_=op.halt(spp=160))["job"]
    wait_spp(c, a, 1)
    b = c.submit(scene, name="b", halt_=op.halt(spp=4))["job"]
    hi = c.submit(scene, name="hi", priority=5, halt_=op.halt(spp=4))["job"]
    wait_state(c, hi, {"done"})
    assert c.job("status", a)["state"] in ("queued", "running")
    wait_state(c, b, {"done"})
    wait_state(c, a, {"done"})
    # hi preempted a; then a (older) ran before b (same priority, FIFO).
    assert log_index(d, rf"job {a}: preempted") < log_index(d, rf"job {hi}: started")
    assert log_index(d, rf"job {hi}: done") < log_index(d, rf"job {a}: done") < log_index(d, rf"job {b}: started")
    info = c.job("status", a)
    assert info["progress"]["spp"] == 160, info
    f = c.job("fetch", a)
    with open(os.path.join(tmp, "a.exr"), "wb") as out:
        out.write(f["_payload"])
    assert exr_equal(local, os.path.join(tmp, "a.exr")), "a preempted job differs from an uninterrupted render"


def test_pause_resume_cancel_priority(tmp, daemons):
    scene = small_cornell(width=64, height=48)
    d = Daemon(tmp, config="max_running: 1\n").start()
    daemons.append(d)
    c = d.client()
    # Priority 10: raising the queued q2 to 7 below must not preempt it. (At 0 it did, and when
    # q2 was then cancelled `run` restarted, so the pause further down met a job the earlier
    # preempt's log line already matched: spp still moved 0.5 s later under load, a flake.)
    run = c.submit(scene, name="run", priority=10, halt_=op.halt(spp=100000))["job"]
    q1 = c.submit(scene, name="q1", halt_=op.halt(spp=2))["job"]
    q2 = c.submit(scene, name="q2", halt_=op.halt(spp=2))["job"]
    wait_spp(c, run, 1)
    # Queued jobs: pause, re-prioritise, cancel.
    assert c.job("pause", q1)["type"] == "ok"
    assert c.job("status", q1)["state"] == "paused"
    assert c.request(lambda id: op.set_priority(id, q2, 7))["type"] == "ok"
    assert c.job("status", q2)["priority"] == 7
    assert c.job("cancel", q2)["type"] == "ok"
    assert c.job("status", q2)["state"] == "cancelled"
    h = c.job("resume", run)
    assert h["type"] == "error" and h["code"] == "invalid_state", h
    h = c.job("cancel", 999)
    assert h["code"] == "unknown_job", h
    # Another user (TCP is anonymous, not the owner) may look but not touch.
    t = d.client(tcp=True)
    h = t.job("pause", run)
    assert h["type"] == "error" and h["code"] == "permission_denied", h
    assert t.job("status", run)["type"] == "job_info"
    # Pause a running job: it stops within a tile's time and keeps its samples.
    t0 = time.monotonic()
    assert c.job("pause", run)["type"] == "ok"
    d.wait_log(rf"job {run}: stopped \(pause\)", timeout=10)
    assert not re.search(rf"job {run}: stopped \(preempt\)", d.log()), "nothing of higher priority was queued"
    stop_s = time.monotonic() - t0
    spp = c.job("status", run)["progress"]["spp"]
    time.sleep(0.5)
    assert c.job("status", run)["progress"]["spp"] == spp and c.job("status", run)["state"] == "paused"
    # Resume it; then cancel it while running: a subscriber sees done (cancelled).
    assert c.job("resume", run)["type"] == "ok"
    wait_state(c, run, {"running"})
    wait_spp(c, run, spp + 1)
    w = d.client()
    sid = w.new_id()
    w.send(op.job_request("subscribe", sid, run))
    t0 = time.monotonic()
    assert c.job("cancel", run)["type"] == "ok"
    while True:
        h, _ = w.recv_for(sid)
        if h["type"] == "done":
            break
    assert h["state"] == "cancelled", h
    d.wait_log(rf"job {run}: stopped \(cancel\)", timeout=10)
    cancel_s = time.monotonic() - t0
    print(f"  pause took effect in {stop_s * 1000:.0f} ms, cancel in {cancel_s * 1000:.0f} ms")
    # The paused queued job resumes and finishes.
    assert c.job("resume", q1)["type"] == "ok"
    wait_state(c, q1, {"done"})
    h = c.job("pause", q1)
    assert h["code"] == "invalid_state", h


def test_running_jobs_share_threads_by_priority(tmp, daemons):
    """Two jobs rendering at once, priorities 10 and 0: weights 2^(10/10) and 1, so the first
    gets two thirds of the thread time and twice the samples per second. Equal priorities split
    evenly (docs/daemon.md, "Scheduling")."""
    scene = small_cornell(width=96, height=96)
    d = Daemon(tmp, config="max_running: 2\n").start()
    daemons.append(d)
    c = d.client()

    def rates(p_hi, p_lo):
        seconds = 3.0
        hi = c.submit(scene, name="hi", priority=p_hi, halt_=op.halt(time_s=seconds))["job"]
        lo = c.submit(scene, name="lo", priority=p_lo, halt_=op.halt(time_s=seconds))["job"]
        a = wait_state(c, hi, {"done"}, timeout=60)
        b = wait_state(c, lo, {"done"}, timeout=60)
        return a["progress"]["samples_per_s"] / b["progress"]["samples_per_s"]

    weighted = rates(10, 0)
    even = rates(3, 3)
    print(f"samples/s ratios: priority 10 against 0 {weighted:.2f}, equal priorities {even:.2f}")
    # The share is charged by each tile's wall time. Under a sanitizer, on 2 cores shared with a
    # neighbouring test, wall time says little about CPU (TSan measured 3.55 once and 0.85 the
    # next time for an expected 2): there the test only runs two shared jobs to their end, for
    # the sanitizer's sake, and the release run checks the proportions.
    if SLOWDOWN == 1:
        assert 1.4 < weighted < 2.8, f"priority 10 against 0: samples/s ratio {weighted:.2f}, expected about 2"
        assert 0.72 < even < 1.38, f"equal priorities: samples/s ratio {even:.2f}, expected about 1"


if __name__ == "__main__":
    t = Test()
    t.run(test_priorities_preemption_fifo)
    t.run(test_pause_resume_cancel_priority)
    t.run(test_running_jobs_share_threads_by_priority)
    t.exit()
