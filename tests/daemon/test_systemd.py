"""systemd: `systemd-analyze verify` passes on the units (with ExecStart pointing at the built
omegad, since /usr/bin/omegad is not installed here), and omegad started through
systemd-socket-activate serves on the socket it was handed. Fails when the tools are absent
(scripts/install-deps installs them): a skip in CI would assert nothing."""
import os
import shutil
import subprocess
import sys
import time

from harness import OMEGA, OMEGAD, Daemon, Test, op, small_cornell, wait_state

UNITS = sys.argv[5] if len(sys.argv) > 5 else None


def test_units_verify(tmp, daemons):
    tool = shutil.which("systemd-analyze")
    assert tool, "systemd-analyze is not installed (scripts/install-deps installs the systemd package)"
    for name in ("omegad.service", "omegad.socket"):
        with open(os.path.join(UNITS, name)) as f:
            text = f.read().replace("/usr/bin/omegad", OMEGAD)
        with open(os.path.join(tmp, name), "w") as f:
            f.write(text)
    r = subprocess.run([tool, "verify", os.path.join(tmp, "omegad.service"), os.path.join(tmp, "omegad.socket")],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout + r.stderr
    # The worker's unit (docs/farm.md "Workers"), with ExecStart at the built omega.
    with open(os.path.join(UNITS, "omega-worker.service")) as f:
        text = f.read().replace("/usr/bin/omega ", OMEGA + " ")
    with open(os.path.join(tmp, "omega-worker.service"), "w") as f:
        f.write(text)
    r = subprocess.run([tool, "verify", os.path.join(tmp, "omega-worker.service")], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0, r.stdout + r.stderr
    for key in ("MemoryDenyWriteExecute=yes", "SystemCallFilter=@system-service", "CapabilityBoundingSet=",
                "NoNewPrivileges=yes", "ProtectSystem=strict"):
        assert key in text, "omega-worker.service lacks " + key
    text = open(os.path.join(UNITS, "omegad.service")).read()
    for key in ("Type=notify", "WatchdogSec=", "StateDirectory=omega", "RuntimeDirectory=omega", "NoNewPrivileges=yes",
                "ProtectSystem=strict", "User=omega"):
        assert key in text, key


def test_socket_activation(tmp, daemons):
    tool = shutil.which("systemd-socket-activate")
    assert tool, "systemd-socket-activate is not installed (scripts/install-deps installs the systemd package)"
    d = Daemon(tmp)
    daemons.append(d)
    sock = os.path.join(tmp, "activated.sock")
    # systemd-socket-activate listens, and starts omegad on the first connection with the socket as fd 3.
    # It passes omegad a clean environment: forward the sanitizers' options (presets asan/tsan),
    # or a TSan build would run without its suppressions.
    env = [a for v in ("ASAN_OPTIONS", "UBSAN_OPTIONS", "TSAN_OPTIONS", "LSAN_OPTIONS") if v in os.environ
           for a in ("-E", v)]
    args = [tool, "-l", sock, *env, OMEGAD, "--config", d.config_path, "--state-dir", d.state_dir, "--threads", "2"]
    d.proc = subprocess.Popen(args, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    import threading
    threading.Thread(target=d._pump, args=(d.proc,), daemon=True).start()
    deadline = time.monotonic() + 20
    while not os.path.exists(sock):
        assert time.monotonic() < deadline, "systemd-socket-activate did not create the socket"
        time.sleep(0.05)
    c = op.Client("unix:" + sock)
    assert c.welcome[0]["type"] == "welcome"
    d.wait_log(r"omegad ready: listening on unix:.*activated.sock \(systemd\)")
    h = c.submit(small_cornell(width=32, height=32), name="activated", halt_=op.halt(spp=2))
    assert h["type"] == "accepted", h
    wait_state(c, h["job"], {"done"})


if __name__ == "__main__":
    t = Test()
    t.run(test_units_verify)
    t.run(test_socket_activation)
    t.exit()
