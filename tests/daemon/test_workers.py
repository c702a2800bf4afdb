"""Workers under omegad (docs/farm.md "Workers"): a job with `workers: 2` rendered by two
`omega worker`s started by hand over TCP with HMAC auth; one worker is kill -9'ed mid-unit and
omegad itself is kill -9'ed mid-job and restarted on the same port. The result must equal
`omega merge` of the same sample ranges rendered locally, bit for bit, and the local
`omega render --spp N` within the merge bound of docs/farm.md (1e-6 relative). A worker's
credentials (role worker) may take units only: no submit, status, fetch or cancel.
Usage: python3 test_workers.py OMEGAD OMEGA EXR_COMPARE SOURCE_DIR"""
import os
import re
import signal
import subprocess
import time

from harness import (ALICE, BOB, EXR_COMPARE, SLOWDOWN, WORKER, Daemon, Test, check_units_merge, free_port, merge_units_locally, omega, op,
                     small_cornell, start_worker, tcp_env, wait_file, wait_state)

CONFIG = f"""tcp_users:
  alice: {ALICE}
  bob: {BOB}
  farm: {{token: {WORKER}, role: worker}}
"""
SANITIZED = bool(os.environ.get("OMEGA_SANITIZER"))
# Units of about a second on one thread (a smaller film under a sanitizer, which renders ~6x slower),
# so that a worker killed right after it starts a unit dies in the middle of it.
W, H, UNIT, UNITS = (64, 48, 64, 6) if SANITIZED else (120, 90, 96, 6)
SPP = UNIT * UNITS


def login(d, user, token):
    c = d.client(tcp=True)
    w = c.welcome[0]
    h = c.request(lambda id: op.auth(id, user, op.auth_mac(token.encode(), w["nonce"], user)))
    assert h["type"] == "ok", h
    return c


def test_workers_exact_through_deaths(tmp, daemons):
    port = free_port()
    d = Daemon(tmp, config=CONFIG, tcp_port=port, threads=1).start()
    daemons.append(d)
    addr = d.tcp
    scene = os.path.join(tmp, "scene.yaml")
    with open(scene, "wb") as f:
        f.write(small_cornell(W, H, SPP))
    alice = tcp_env(addr, "alice", ALICE)
    farm = tcp_env(addr, "farm", WORKER)
    job = int(omega(["submit", scene, "--spp", str(SPP), "--workers", "2", "--unit-spp", str(UNIT), "-q"],
                    alice).stdout.split()[-1])
    workers = []
    try:
        a, a_log = start_worker(addr, "A", tmp, farm)
        b, b_log = start_worker(addr, "B", tmp, farm)
        workers += [a, b]
        # A dies by kill -9 in the middle of its second unit: that unit goes back to the queue.
        wait_file(a_log, r"unit \d+: done", 60)
        m = wait_file(a_log, r"(?s)unit \d+: done.*unit (\d+): samples", 60)
        a.send_signal(signal.SIGKILL)
        a.wait(10)
        d.wait_log(rf"job {job}: unit {m.group(1)} \(samples \d+:\d+\) back to the queue: conn \d+ \(A\) left", 30)
        # omegad dies by kill -9 with units done and units out; it comes back on the same port.
        d.wait_log(rf"job {job}: unit \d+ \(samples \d+:\d+\) done by conn \d+ \(B\)", 60)
        d.kill9()
        d.start()
        d.wait_log(rf"job {job}: on workers \(2 wanted\), \d+ unit\(s\) recorded, [1-9]\d* done", 30)
        # B reconnects by itself; A2 replaces A. A watcher sees the merged image grow.
        a2, _ = start_worker(addr, "A2", tmp, farm)
        workers.append(a2)
        w = login(d, "alice", ALICE)
        sid = w.new_id()
        w.send(op.job_request("subscribe", sid, job))
        tiles, done = 0, None
        deadline = time.monotonic() + 120 * SLOWDOWN
        while done is None and time.monotonic() < deadline:
            h, _ = w.recv_for(sid, timeout=max(0.1, deadline - time.monotonic()))
            if h["type"] == "tile":
                tiles += 1
            elif h["type"] == "done":
                done = h
        assert done and done["state"] == "done" and done["progress"]["spp"] == SPP, done
        assert tiles > 0, "the watcher saw no tile of the merged image"
        d.wait_log(rf"job {job}: done on workers: {SPP} spp", 10)
        assert re.search(r"conn \d+ \(B\)", d.log()) and re.search(r"conn \d+ \(A2\)", d.log())
        # `omega status` names the workers of the job.
        st = omega(["status", str(job)], alice).stdout
        assert "units done" in st and "(A2)" in st, st
    finally:
        for p in workers:
            if p.poll() is None:
                p.kill()
                p.wait(10)

    # Every unit counted once: each range was recorded done exactly once in this daemon life or
    # the last, so the result equals the local merge of the same ranges bit for bit.
    check_units_merge(tmp, scene, job, alice, UNIT, UNITS)

    # A worker's credentials give units only: never another user's job, nor any control.
    for args in (["cancel", str(job)], ["fetch", str(job), "-o", os.path.join(tmp, "x.exr")],
                 ["status", str(job)], ["submit", scene, "--spp", "1"]):
        r = omega(args, farm, check=False)
        assert r.returncode == 3 and "permission_denied" in r.stderr and "is a worker" in r.stderr, (args, r.stderr)
    # And an ordinary user's credentials take no units.
    r = omega(["worker", "--once", "--threads", "1", "--cache", os.path.join(tmp, "cache-bob")],
              tcp_env(addr, "bob", BOB), check=False)
    assert r.returncode == 3 and "may not take work units" in r.stderr, r.stderr
    # Nothing was merged twice: one "done by" line per unit in the daemon's logs after the restart
    # plus the units already done before it.
    h = omega(["status", str(job)], alice).stdout
    assert re.search(rf"progress\s+{SPP}/{SPP} spp", h), h


def test_cancel_and_pause_reach_workers(tmp, daemons):
    d = Daemon(tmp, config=CONFIG, threads=1).start()
    daemons.append(d)
    addr = d.tcp
    scene = os.path.join(tmp, "scene.yaml")
    with open(scene, "wb") as f:
        f.write(small_cornell(W, H, 4096))
    alice = tcp_env(addr, "alice", ALICE)
    big = UNIT * 64
    job = int(omega(["submit", scene, "--spp", str(big), "--workers", "1", "--unit-spp", str(UNIT * 4), "-q"],
                    alice).stdout.split()[-1])
    p, log = start_worker(addr, "C", tmp, tcp_env(addr, "farm", WORKER))
    try:
        wait_file(log, rf"job {job} unit 0: samples", 30)
        omega(["pause", str(job)], alice)
        wait_file(log, rf"job {job} unit 0: stopped by the daemon", 30)
        wait_state(login(d, "alice", ALICE), job, ["paused"], 10)
        omega(["resume", str(job)], alice)
        wait_file(log, rf"(?s)stopped by the daemon.*job {job} unit 0: samples", 30)
        # A higher-priority job's units go out first: the next unit after it arrives is its own,
        # although the first job has units left.
        hi = int(omega(["submit", scene, "--spp", str(UNIT), "--workers", "1", "--unit-spp", str(UNIT),
                        "--priority", "5", "-q"], alice).stdout.split()[-1])
        wait_file(log, rf"job {hi} unit 0: done", 60)
        after = d.log().split(f"job {hi} accepted", 1)[1]
        first = re.search(r"job (\d+): unit \d+ \(samples \d+:\d+\) to conn", after)
        assert first and int(first.group(1)) == hi, after[:3000]
        omega(["cancel", str(job)], alice)
        wait_file(log, rf"job {job} unit \d+: stopped by the daemon", 30)
        d.wait_log(rf"job {hi}: done on workers: {UNIT} spp", 30)
        h = omega(["status", str(job)], alice).stdout
        assert "cancelled" in h, h
    finally:
        p.kill()
        p.wait(10)


def test_aovs_and_breakdown_fold_exactly(tmp, daemons):
    """A worker job with light path expression outputs and a breakdown: the workers' units carry
    both, and the daemon folds them as `omega merge` does, bit for bit (they were dropped before)."""
    d = Daemon(tmp, config=CONFIG, threads=1).start()
    daemons.append(d)
    addr = d.tcp
    unit, units = 8, 3
    scene = os.path.join(tmp, "scene.yaml")
    text = small_cornell(40, 30, unit * units).decode()
    text, n = re.subn(r"(film: \{width: \d+, height: \d+)", r'\1, aov: {direct: "L D E"}, breakdown: {length: 4}', text)
    assert n == 1, text
    with open(scene, "w") as f:
        f.write(text)
    alice = tcp_env(addr, "alice", ALICE)
    job = int(omega(["submit", scene, "--spp", str(unit * units), "--workers", "1", "--unit-spp", str(unit), "-q"],
                    alice).stdout.split()[-1])
    p, _ = start_worker(addr, "D", tmp, tcp_env(addr, "farm", WORKER))
    try:
        info = wait_state(login(d, "alice", ALICE), job, {"done", "failed"}, 120)
        assert info["state"] == "done", info
    finally:
        p.kill()
        p.wait(10)
    out = os.path.join(tmp, "out.exr")
    omega(["fetch", str(job), "-o", out], alice)
    merged = merge_units_locally(tmp, scene, alice, unit, units)
    r = subprocess.run([EXR_COMPARE, "--layer", "aov.direct", "--layer", "aov.direct.var", "--attr", "omega.breakdown",
                        "--attr", "omega.breakdown_state", merged, out], capture_output=True, text=True)
    assert r.returncode == 0, "the job's AOV or breakdown differs from omega merge of its units: " + r.stdout + r.stderr


if __name__ == "__main__":
    t = Test()
    t.run(test_aovs_and_breakdown_fold_exactly)
    t.run(test_workers_exact_through_deaths)
    t.run(test_cancel_and_pause_reach_workers)
    t.exit()
