"""omegad with `executor: slurm` (docs/farm.md "Workers under Slurm") on a real single-host Slurm
cluster (tests/support/slurm_cluster.py): a job with `workers: 2` makes omegad sbatch a 2-task
array of `omega worker`s, recorded in its SQLite store; one more worker is started by hand and
kill -9'ed mid-unit. The result must equal `omega merge` of the same units rendered locally bit
for bit (and `omega render --spp N` within 1e-6), units must have been rendered by the Slurm
workers, a Slurm worker that Slurm ends (scancel of its task) must be replaced while the job has
work left, and omegad must scancel its Slurm jobs when the job is done.
Usage: test_daemon_slurm.py OMEGAD OMEGA EXR_COMPARE SOURCE_DIR. Fails (never skips) when Slurm
cannot run, with the reason."""
import os
import re
import signal
import sqlite3
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "support"))
sys.path.insert(0, os.path.join(HERE, "..", "daemon"))
from slurm_cluster import SlurmCluster, SlurmUnavailable  # noqa: E402
from harness import (ALICE, OMEGA, WORKER, Daemon, Test, check_units_merge, free_port, omega, small_cornell, start_worker,  # noqa: E402
                     tcp_env, wait_file)

SANITIZED = bool(os.environ.get("OMEGA_SANITIZER"))
W, H, UNIT, UNITS = (48, 32, 8, 12) if SANITIZED else (160, 120, 48, 14)
SPP = UNIT * UNITS


def test_slurm_workers(tmp, daemons):
    with SlurmCluster() as cluster:
        os.environ["SLURM_CONF"] = cluster.conf  # omegad runs sbatch, squeue and scancel with it
        token = os.path.join(tmp, "farm.token")
        fd = os.open(token, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        os.write(fd, (WORKER + "\n").encode())
        os.close(fd)
        port = free_port()
        addr = f"tcp:127.0.0.1:{port}"
        config = f"""tcp_users:
  alice: {ALICE}
  farm: {{token_file: {token}, role: worker}}
executor: slurm
slurm:
  omega: {OMEGA}
  connect: {addr}
  user: farm
  token_file: {token}
  threads: 1
  poll_s: 1
  idle_exit_s: 30
"""
        d = Daemon(tmp, config=config, tcp_port=port, threads=1).start()
        daemons.append(d)
        scene = os.path.join(tmp, "scene.yaml")
        with open(scene, "wb") as f:
            f.write(small_cornell(W, H, SPP))
        alice = tcp_env(addr, "alice", ALICE)
        job = int(omega(["submit", scene, "--spp", str(SPP), "--workers", "2", "--unit-spp", str(UNIT), "-q"],
                        alice).stdout.split()[-1])
        m = d.wait_log(rf"job {job}: Slurm job (\d+): 2 worker\(s\) submitted", 30)
        slurm_id = m.group(1)
        db = sqlite3.connect(os.path.join(d.state_dir, "jobs.sqlite"))
        rows = db.execute("SELECT job, tasks FROM slurm_jobs WHERE slurm_id = ?", (slurm_id,)).fetchall()
        db.close()
        assert rows == [(job, 2)], rows
        # The script Slurm runs names the token file, never the token.
        script = open(os.path.join(d.state_dir, "slurm", f"job-{job}.sh")).read()
        assert WORKER not in script and token in script, script

        # One worker by hand, kill -9'ed in the middle of its second unit.
        hand, log = start_worker(addr, "hand", tmp, dict(os.environ, OMEGA_USER="farm", OMEGA_TOKEN_FILE=token))
        try:
            wait_file(log, r"(?s)unit \d+: done.*unit (\d+): samples", 60)
            hand.send_signal(signal.SIGKILL)
            hand.wait(10)
        finally:
            if hand.poll() is None:
                hand.kill()
        d.wait_log(rf"job {job}: unit \d+ \(samples \d+:\d+\) back to the queue: conn \d+ \(hand\) left", 30)
        # Slurm ends the array's tasks (as a node failure or a preemption would): omegad starts
        # others. Both tasks, not one: with one left alive it could finish every unit before
        # omegad's next squeue poll (poll_s 1) saw the other gone, and no replacement would be
        # needed (a race the ASan run lost once). With none alive the job can only finish on
        # replacements; squeue may report the two ended in one poll or in two.
        d.wait_log(rf"job {job}: unit \d+ \(samples \d+:\d+\) to conn \d+ \((slurm-{slurm_id}_\d)\)", 60)
        subprocess.run(["scancel", slurm_id], env=cluster.env(), check=True, timeout=30)
        d.wait_log(rf"job {job}: [12] of its Slurm workers ended with work left; starting [12] more", 30)
        m = d.wait_log(rf"job {job}: Slurm job (?!{slurm_id}:)(\d+): [12] worker\(s\) submitted", 30)
        d.wait_log(rf"job {job}: done on workers: {SPP} spp", 120)
        slurm_workers = set(re.findall(rf"job {job}: unit \d+ \(samples \d+:\d+\) done by conn \d+ \((slurm-\d+_\d)\)",
                                       d.log()))
        assert any(not w.startswith(f"slurm-{slurm_id}_") for w in slurm_workers), \
            "no unit was rendered by a replacement Slurm worker:\n" + d.log()[-3000:]
        assert slurm_workers, "no unit was rendered by a Slurm worker:\n" + d.log()[-3000:]
        print(f"units rendered by Slurm workers {sorted(slurm_workers)} and by hand", flush=True)
        d.wait_log(rf"job {job}: scancel [0-9 ]*{m.group(1)}[0-9 ]* \(job done\)", 10)
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            q = subprocess.run(["squeue", "-h", "-o", "%i %T"], env=cluster.env(), capture_output=True, text=True)
            if not q.stdout.strip():
                break
            time.sleep(0.5)
        assert not q.stdout.strip(), "Slurm jobs left after the job ended: " + q.stdout

        check_units_merge(tmp, scene, job, alice, UNIT, UNITS)


if __name__ == "__main__":
    t = Test()
    try:
        t.run(test_slurm_workers)
    except SlurmUnavailable as e:
        sys.stderr.write(f"FAILED: the test Slurm cluster cannot run here: {e}\n")
        sys.exit(1)
    t.exit()
