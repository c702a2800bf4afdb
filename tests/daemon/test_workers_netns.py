"""Workers on other hosts (docs/farm.md "Workers"): two worker "hosts" are network namespaces
joined to this one by veth pairs (tests/support/netns_hosts.py); omegad listens on the root side
of the first veth, and `omega worker --connect tcp:ADDR:PORT` runs in each namespace with HMAC
auth (role worker), the second host reaching the daemon through its default route. A job with
`workers: 2` must be rendered by both hosts (omegad logs each worker's peer address, which must
be the namespace's own), and its result must equal `omega merge` of the same units rendered
locally bit for bit and `omega render --spp N` within 1e-6 (harness.check_units_merge). A worker
with a wrong token is refused over the veth.
Skips (exit 77) only when the kernel refuses network namespaces or veth pairs.
Usage: python3 test_workers_netns.py OMEGAD OMEGA EXR_COMPARE SOURCE_DIR"""
import os
import re
import subprocess
import sys

from harness import (ALICE, OMEGA, WORKER, Daemon, Test, check_units_merge, free_port, omega, small_cornell, start_worker,
                     tcp_env)

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from netns_hosts import NamespacesRefused, NetnsHosts  # noqa: E402

CONFIG = f"""tcp_users:
  alice: {ALICE}
  farm: {{token: {WORKER}, role: worker}}
"""
# A tiny film and few spp: the test is about the network path, which the unit size does not change;
# four units so that each host takes at least one whichever finishes first.
W, H, UNIT, UNITS = 48, 32, 16, 4
SPP = UNIT * UNITS


HOSTS = NetnsHosts(2)


def test_workers_on_two_hosts(tmp, daemons):
    a, b = HOSTS.hosts
    port = free_port()
    server = f"tcp:{a.gateway}:{port}"
    d = Daemon(tmp, config=CONFIG, threads=1, listen=[server]).start()
    daemons.append(d)
    assert f"tcp:{a.gateway}:{port}" in d.wait_log(r"omegad ready: .*").group(0), d.log()
    farm = tcp_env(server, "farm", WORKER)
    workers = []
    try:
        for name, host in (("hostA", a), ("hostB", b)):
            workers.append(start_worker(server, name, tmp, farm, wrap=host.wrap())[0])
        # Both connected before the job exists, so that the first units go to both. The peer
        # address proves each came over its own veth, not through loopback.
        for name, host in (("hostA", a), ("hostB", b)):
            d.wait_log(rf"connection \d+ \({re.escape(host.addr)}:\d+\): worker 'conn \d+ \({name}\)' with 1 thread", 30)
        # The same address with a wrong token: refused over the veth as over loopback.
        r = subprocess.run(b.wrap() + [OMEGA, "worker", "--connect", server, "--once", "--threads", "1",
                                       "--cache", os.path.join(tmp, "cache-bad")],
                           env=tcp_env(server, "farm", "wrong-token-0123456789"), capture_output=True, text=True,
                           timeout=60)
        assert r.returncode != 0 and "authentication failed" in r.stderr, (r.returncode, r.stderr)
        d.wait_log(rf"connection \d+ \({re.escape(b.addr)}:\d+\): authentication failed for user 'farm'", 10)
        scene = os.path.join(tmp, "scene.yaml")
        with open(scene, "wb") as f:
            f.write(small_cornell(W, H, SPP))
        alice = tcp_env(d.tcp, "alice", ALICE)
        job = int(omega(["submit", scene, "--spp", str(SPP), "--workers", "2", "--unit-spp", str(UNIT), "-q"],
                        alice).stdout.split()[-1])
        d.wait_log(rf"job {job}: done on workers: {SPP} spp", 60)
        done_by = set(re.findall(rf"job {job}: unit \d+ \(samples \d+:\d+\) done by conn \d+ \((host[AB])\)", d.log()))
        assert done_by == {"hostA", "hostB"}, f"units done by {done_by}, not both hosts:\n" + d.log()[-3000:]
    finally:
        for p in workers:
            if p.poll() is None:
                p.kill()
                p.wait(10)
    check_units_merge(tmp, scene, job, alice, UNIT, UNITS)


if __name__ == "__main__":
    try:
        HOSTS.__enter__()
    except NamespacesRefused as e:
        print(f"SKIP: the kernel refuses network namespaces or veth pairs here ({e}); "
              "the across-hosts worker test needs root in a namespace-capable kernel", flush=True)
        sys.exit(77)
    t = Test()
    try:
        t.run(test_workers_on_two_hosts)
    finally:
        HOSTS.__exit__(None, None, None)
    left = HOSTS.leftovers()
    if left:
        print(f"FAIL: namespaces or interfaces left after cleanup: {left}", flush=True)
        sys.exit(1)
    t.exit()
