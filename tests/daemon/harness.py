"""Shared helpers for omegad's black-box tests: start a real daemon on a temp Unix socket and a
free loopback port, talk to it with omega_proto.Client, and compare EXRs with omega_exr_compare.
Standard library only. Usage of a test: python3 test_x.py OMEGAD OMEGA EXR_COMPARE SOURCE_DIR"""
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "python"))
import omega_proto as op  # noqa: E402

OMEGAD, OMEGA, EXR_COMPARE, SOURCE_DIR = (sys.argv[1:5] + [None] * 4)[:4]


def small_cornell(width=80, height=48, spp=16):
    """The Cornell box at a small size (the scene's own text, with the film and spp replaced)."""
    with open(os.path.join(SOURCE_DIR, "scenes", "cornell-box.yaml")) as f:
        text = f.read()
    text = re.sub(r"film: \{width: \d+, height: \d+", f"film: {{width: {width}, height: {height}", text)
    text = re.sub(r"\n  spp: \d+", f"\n  spp: {spp}", text)
    return text.encode()


# TCP tokens of the test users (tcp_users in a test's config) and of the workers' user.
ALICE, BOB, WORKER = "alice-token-0123456789", "bob-token-0123456789", "worker-token-0123456789"


class Daemon:
    def __init__(self, workdir, threads=2, config="", state_dir=None, name="omegad", tcp_port=0, listen=(), wrap=(),
                 env=None):
        self.workdir = workdir
        self.state_dir = state_dir or os.path.join(workdir, "state")
        self.sock = os.path.join(workdir, name + ".sock")
        self.config_path = os.path.join(workdir, name + ".yaml")
        # The test's own top-level keys replace these defaults: omegad refuses a key given twice
        # (it used to read the first, so e.g. bench_daemon.py's checkpoint_interval_s was ignored).
        own = {line.split(":", 1)[0] for line in config.splitlines() if line[:1] not in ("", " ", "-", "#")}
        base = {"checkpoint_interval_s": "0", "drain_timeout_s": "20", "log_level": "debug"}
        with open(self.config_path, "w") as f:
            f.write("".join(f"{k}: {v}\n" for k, v in base.items() if k not in own) + config)
        self.threads = threads
        self.tcp_port = tcp_port  # 0: any free port; a fixed one lets clients reconnect after a restart
        self.listen = list(listen)  # more --listen addresses (e.g. a veth's, for workers in a netns)
        self.wrap = list(wrap)  # a command that execs omegad (mdwe_exec.py, seccomp_exec.py): same pid, its settings
        self.env = env  # omegad's environment (None: this process's)
        self.lines = []
        self.lock = threading.Lock()
        self.proc = None
        self.tcp = None

    @property
    def unix(self):
        return "unix:" + self.sock

    def start(self, timeout=30):
        self.lines = []
        args = self.wrap + [OMEGAD, "--config", self.config_path, "--state-dir", self.state_dir,
                "--listen", self.unix, "--listen", f"tcp:127.0.0.1:{self.tcp_port}", "--threads", str(self.threads)]
        for a in self.listen:
            args += ["--listen", a]
        self.proc = subprocess.Popen(args, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True, env=self.env)
        threading.Thread(target=self._pump, args=(self.proc,), daemon=True).start()
        m = self.wait_log(r"omegad ready: listening on .*tcp:([0-9.]+:\d+)", timeout)
        self.tcp = "tcp:" + m.group(1)
        return self

    def _pump(self, proc):
        for line in proc.stderr:
            with self.lock:
                self.lines.append(line.rstrip("\n"))
            if os.environ.get("OMEGAD_TEST_VERBOSE"):
                sys.stderr.write("  omegad| " + line)

    def log(self):
        with self.lock:
            return "\n".join(self.lines)

    def wait_log(self, pattern, timeout=30, start=0):
        timeout *= SLOWDOWN
        deadline = time.monotonic() + timeout
        rx = re.compile(pattern)
        while time.monotonic() < deadline:
            with self.lock:
                for line in self.lines[start:]:
                    m = rx.search(line)
                    if m:
                        return m
            if self.proc.poll() is not None and not self.proc.stderr.closed:
                time.sleep(0.2)
                with self.lock:
                    if not any(rx.search(l) for l in self.lines[start:]):
                        raise AssertionError(f"omegad exited ({self.proc.returncode}) before logging /{pattern}/:\n" + self.log())
            time.sleep(0.05)
        raise AssertionError(f"omegad did not log /{pattern}/ within {timeout} s:\n" + self.log()[-4000:])

    def client(self, tcp=False, **kw):
        return op.Client(self.tcp if tcp else self.unix, **kw)

    def kill9(self):
        self.proc.send_signal(signal.SIGKILL)
        self.proc.wait(10)

    def terminate(self, timeout=30):
        self.proc.send_signal(signal.SIGTERM)
        return self.proc.wait(timeout)

    def stop(self):
        if self.proc and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGKILL)
            self.proc.wait(10)


def free_port():
    """A loopback TCP port that was free a moment ago."""
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def local_render(scene_bytes, out, spp, seed=0, workdir=None, integrator=None):
    path = os.path.join(workdir, "local-scene.yaml")
    with open(path, "wb") as f:
        f.write(scene_bytes)
    extra = ["--integrator", integrator] if integrator else []
    subprocess.run([OMEGA, "render", path, "--spp", str(spp), "--seed", str(seed), "-o", out, "--threads", "2", "-q"] + extra,
                   check=True, timeout=120, stdout=subprocess.DEVNULL)


def exr_equal(full, part, layers=(), attrs=()):
    extra = [a for l in layers for a in ("--layer", l)] + [a for n in attrs for a in ("--attr", n)]
    r = subprocess.run([EXR_COMPARE] + extra + [full, part], capture_output=True, text=True, timeout=60)
    if r.returncode != 0:
        sys.stderr.write(r.stderr)
    return r.returncode == 0


# Sanitizer builds run 5-15x slower, and CI runs two daemon tests at once: waits for progress
# scale by this factor so that a slow machine fails only a real stall.
SLOWDOWN = 4 if os.environ.get("OMEGA_SANITIZER") else 1


def wait_spp(c, job, at_least, timeout=60):
    deadline = time.monotonic() + timeout * SLOWDOWN
    h = None
    while time.monotonic() < deadline:
        h = c.job("status", job)
        if h["progress"]["spp"] >= at_least:
            return h
        time.sleep(0.05)
    raise AssertionError(f"job {job} stuck below {at_least} spp after {timeout * SLOWDOWN} s (last: {h})")


def wait_state(c, job, states, timeout=60):
    timeout *= SLOWDOWN
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        h = c.job("status", job)
        assert h["type"] == "job_info", h
        if h["state"] in states:
            return h
        time.sleep(0.05)
    raise AssertionError(f"job {job} did not reach {states} in {timeout} s (last: {h})")


def watch(c, job, timeout=120):
    """Subscribes and collects frames until done. Returns (tiles by rect, progress list, done)."""
    sid = c.new_id()
    c.send(op.job_request("subscribe", sid, job))
    h, _ = c.recv_for(sid)
    assert h["type"] == "ok", h
    tiles, progress = {}, []
    deadline = time.monotonic() + timeout
    while True:
        h, p = c.recv_for(sid, timeout=max(0.1, deadline - time.monotonic()))
        if h["type"] == "tile":
            key = tuple(h["rect"])
            if key not in tiles or tiles[key][0]["version"] <= h["version"]:
                tiles[key] = (h, p)
        elif h["type"] == "progress":
            progress.append(h)
        elif h["type"] == "done":
            return tiles, progress, h
        else:
            raise AssertionError(f"unexpected frame {h}")


def cpu_seconds(pid, tid=None):
    """User + system CPU time of a live process (or of its thread `tid`): what it spent, whatever
    else shares the cores."""
    with open(f"/proc/{pid}/stat" if tid is None else f"/proc/{pid}/task/{tid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def tcp_env(addr, user, token):
    """The environment of an `omega` client that logs in over TCP as USER with TOKEN (the token
    travels in the environment, never on the command line, which ps shows)."""
    return dict(os.environ, OMEGA_HOST=addr, OMEGA_USER=user, OMEGA_TOKEN=token)


def omega(args, env, check=True, timeout=120):
    """Runs the omega client; with check, a non-zero exit fails the test with its stderr."""
    r = subprocess.run([OMEGA] + args, env=env, capture_output=True, text=True, timeout=timeout)
    if check and r.returncode != 0:
        raise AssertionError(f"omega {' '.join(args)} exited {r.returncode}: {r.stderr}")
    return r


def wait_file(path, pattern, timeout):
    """Waits until a log file (a worker's stderr) matches PATTERN; returns the match."""
    deadline = time.monotonic() + timeout * SLOWDOWN
    while time.monotonic() < deadline:
        with open(path) as f:
            m = re.search(pattern, f.read())
        if m:
            return m
        time.sleep(0.02)
    with open(path) as f:
        raise AssertionError(f"{path}: no /{pattern}/ within {timeout * SLOWDOWN} s:\n{f.read()[-3000:]}")


def start_worker(addr, name, tmp, env, wrap=()):
    """`omega worker --connect ADDR` with one thread and its own cache, its stderr in
    TMP/worker-NAME.log. WRAP prefixes the command (e.g. `ip netns exec NS`). Returns (proc, log)."""
    log = os.path.join(tmp, f"worker-{name}.log")
    with open(log, "w") as lf:
        p = subprocess.Popen(list(wrap) + [OMEGA, "worker", "--connect", addr, "--threads", "1", "--name", name,
                                           "--cache", os.path.join(tmp, "cache-" + name)],
                             env=env, stdout=subprocess.DEVNULL, stderr=lf)
    return p, log


def merge_units_locally(tmp, scene, env, unit, units):
    """`omega merge` of the job's units rendered here with `omega render --samples A:B`: the
    image a worker job's result must equal bit for bit. Returns its path."""
    parts = []
    for i in range(units):
        p = os.path.join(tmp, f"part{i}.exr")
        omega(["render", scene, "--samples", f"{i * unit}:{(i + 1) * unit}", "-o", p, "-q", "--threads", "2"], env)
        parts.append(p)
    merged = os.path.join(tmp, "merged.exr")
    omega(["merge"] + parts + ["-o", merged, "-q"], env)
    return merged


def check_units_merge(tmp, scene, job, env, unit, units):
    """The worker tests' verdict (docs/farm.md "Workers"): the job's result equals `omega merge`
    of the same sample ranges rendered locally bit for bit, and `omega render --spp` of the whole
    range within the merge bound (1e-6 relative)."""
    out = os.path.join(tmp, "out.exr")
    omega(["fetch", str(job), "-o", out], env)
    merged = merge_units_locally(tmp, scene, env, unit, units)
    r = subprocess.run([EXR_COMPARE, merged, out], capture_output=True, text=True)
    assert r.returncode == 0, "result differs from omega merge of the same units: " + r.stdout + r.stderr
    local = os.path.join(tmp, "local.exr")
    omega(["render", scene, "--spp", str(unit * units), "-o", local, "-q", "--threads", "2"], env)
    r = subprocess.run([EXR_COMPARE, "--rel-tol", "1e-6", local, out], capture_output=True, text=True)
    assert r.returncode == 0, "result differs from omega render --spp beyond 1e-6: " + r.stdout + r.stderr


SANITIZER_REPORT = re.compile(r"WARNING: ThreadSanitizer|ERROR: AddressSanitizer|ERROR: LeakSanitizer|runtime error: ")


def sanitizer_report(log):
    """The first sanitizer report in a daemon's log (the presets asan/tsan), or None. A report
    fails the test even when the daemon carried on (UBSan) or the test did not notice it exit."""
    m = SANITIZER_REPORT.search(log)
    return log[max(0, m.start() - 200):m.start() + 6000] if m else None


class Test:
    """Runs named test functions in order with a fresh temp dir each; prints a summary."""

    def __init__(self):
        self.failures = 0

    def run(self, fn):
        tmp = tempfile.mkdtemp(prefix="omegad-test-")
        t0 = time.monotonic()
        daemons = []
        try:
            fn(tmp, daemons)
            for d in daemons:
                report = sanitizer_report(d.log())
                if report:
                    raise AssertionError("omegad logged a sanitizer report:\n" + report)
            print(f"PASS {fn.__name__} ({time.monotonic() - t0:.1f} s)", flush=True)
        except Exception:
            import traceback
            self.failures += 1
            print(f"FAIL {fn.__name__}", flush=True)
            traceback.print_exc()
            for d in daemons:
                print("---- omegad log ----\n" + d.log()[-6000:], flush=True)
        finally:
            for d in daemons:
                d.stop()
            shutil.rmtree(tmp, ignore_errors=True)

    def exit(self):
        sys.exit(1 if self.failures else 0)
