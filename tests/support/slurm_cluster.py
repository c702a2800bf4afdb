"""A real single-host Slurm cluster on loopback for tests: munged, slurmctld and slurmd of Debian
12's slurm-wlm, with every file (config, munge key and socket, state, spool, logs) in a temp dir
and free non-default ports, so a host's own Slurm (if any) is neither used nor disturbed.

    with SlurmCluster() as c:
        subprocess.run(["sbatch", ...], env=c.env())

Starting takes about 1-2 s; stopping about 1-3 s. Needs root: SlurmUser and SlurmdUser are root
(slurmd must be able to start job steps as the submitting user) and munged's key must be owned by
the user it runs as. Runs in a container without systemd: the daemons run in the foreground as
children of this process, proctrack/linuxproc and task/none avoid cgroups. Standard library only.

Cleanup: stop() (also on an exception in the with block) cancels every job, shuts the daemons down
and removes the folder. If the test process is SIGKILLed (a ctest timeout), the daemons still get
SIGTERM (PR_SET_PDEATHSIG), but a job step that was running (slurmstepd and its processes) lives
on until its own command ends.
"""
import ctypes
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time

PROGRAMS = ["munged", "mungekey", "slurmctld", "slurmd", "sinfo", "sbatch", "squeue", "scontrol", "scancel"]


class SlurmUnavailable(RuntimeError):
    """Slurm cannot run here; the message says exactly why (tests fail with it, never skip)."""


def _which(program):
    """PATH, then the sbin folders: the daemons live in /usr/sbin, which a non-login PATH may lack."""
    return shutil.which(program) or shutil.which(program, path="/usr/sbin:/sbin:/usr/local/sbin")


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _die_with_parent():
    """preexec_fn: the daemon gets SIGTERM when this process dies, even by SIGKILL (a ctest timeout),
    so no munged or slurmctld outlives a test that could not run its cleanup."""
    PR_SET_PDEATHSIG = 1
    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


def _tail(path, n=15):
    try:
        with open(path, errors="replace") as f:
            return "".join(f.readlines()[-n:])
    except OSError as e:
        return f"({e})"


class SlurmCluster:
    def __init__(self, base=None, keep=False, start_timeout=30):
        self.keep = keep or bool(os.environ.get("OMEGA_KEEP_SLURM"))
        self.base = base or tempfile.mkdtemp(prefix="omega-slurm-")
        self.start_timeout = start_timeout
        self.node = socket.gethostname().split(".")[0]
        self.conf = os.path.join(self.base, "etc", "slurm.conf")
        self.munge_socket = os.path.join(self.base, "munge", "munge.socket.2")
        self.procs = {}  # name -> Popen, in start order

    def env(self, base=None):
        """The environment for Slurm's commands (and the jobs they submit): our slurm.conf."""
        e = dict(os.environ if base is None else base)
        e["SLURM_CONF"] = self.conf
        return e

    def log(self, name):
        return os.path.join(self.base, "log", name + ".log")

    # ------------------------------------------------------------------ setup

    def _check_host(self):
        if os.geteuid() != 0:
            raise SlurmUnavailable("the test Slurm cluster needs root (SlurmUser=root starts job steps "
                                   f"as the submitting user); running as uid {os.geteuid()}")
        missing = [p for p in PROGRAMS if not _which(p)]
        if missing:
            raise SlurmUnavailable(f"missing programs {', '.join(missing)} (scripts/install-deps installs "
                                   "munge, slurmctld, slurmd, slurm-client)")
        if len(self.munge_socket) >= 100:  # sun_path is 108 bytes with the NUL
            raise SlurmUnavailable(f"temp dir path too long for munge's socket: {self.munge_socket}")
        # slurmctld checks that its host name is SlurmctldHost, and slurmd and srun look the node
        # name up; a container's host name may not resolve at all.
        try:
            socket.gethostbyname(self.node)
        except OSError:
            with open("/etc/hosts", "a") as f:
                f.write(f"127.0.0.1 {self.node}\n")

    def _write_config(self):
        for d in ("etc", "munge", "state", "spool", "log", "run"):
            os.makedirs(os.path.join(self.base, d), exist_ok=True)
        # munged refuses a socket folder that is group/world-writable or not world-searchable.
        os.chmod(os.path.join(self.base, "munge"), 0o755)
        os.chmod(self.base, 0o755)
        key = os.path.join(self.base, "munge", "munge.key")
        subprocess.run([_which("mungekey"), "-c", "-k", key], check=True, capture_output=True)
        os.chmod(key, 0o600)
        # The node's line from slurmd -C (the real CPUs, sockets, memory): a node that registers
        # with fewer resources than slurm.conf claims is drained as "Low CPUs"/"Low RealMemory".
        hw = subprocess.run([_which("slurmd"), "-C"], check=True, capture_output=True, text=True).stdout.splitlines()[0]
        hw = "NodeName=" + self.node + " " + hw.split(" ", 1)[1]
        self.ctld_port, self.slurmd_port = _free_port(), _free_port()
        b = self.base
        with open(self.conf, "w") as f:
            f.write(f"""ClusterName=omegatest
SlurmctldHost={self.node}(127.0.0.1)
SlurmctldPort={self.ctld_port}
SlurmdPort={self.slurmd_port}
CommunicationParameters=NoCtldInAddrAny,NoInAddrAny
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={self.munge_socket}
SlurmUser=root
SlurmdUser=root
StateSaveLocation={b}/state
SlurmdSpoolDir={b}/spool
SlurmctldPidFile={b}/run/slurmctld.pid
SlurmdPidFile={b}/run/slurmd.pid
SlurmctldLogFile={self.log('slurmctld')}
SlurmdLogFile={self.log('slurmd')}
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0
MailProg=/bin/true
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MinJobAge=600
{hw} NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=test Nodes={self.node} Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
""")

    # ------------------------------------------------------------------ start / stop

    def _spawn(self, name, args):
        out = open(self.log(name + ".stdio"), "w")
        self.procs[name] = subprocess.Popen([_which(args[0])] + args[1:], stdout=out, stderr=subprocess.STDOUT, env=self.env(),
                                            stdin=subprocess.DEVNULL, preexec_fn=_die_with_parent)
        out.close()

    def start(self):
        self._check_host()
        self._write_config()
        t0 = time.monotonic()
        self._spawn("munged", ["munged", "--foreground", "--force", f"--socket={self.munge_socket}",
                               f"--key-file={self.base}/munge/munge.key",
                               f"--pid-file={self.base}/run/munged.pid", f"--log-file={self.log('munged')}",
                               f"--seed-file={self.base}/munge/munged.seed"])
        self._wait(lambda: os.path.exists(self.munge_socket), "munged's socket", "munged")
        # -i: ignore state a previous run left (there is none in a fresh dir, but be explicit).
        self._spawn("slurmctld", ["slurmctld", "-D", "-i"])
        self._spawn("slurmd", ["slurmd", "-D", "-N", self.node])

        def idle():
            r = subprocess.run(["sinfo", "-h", "-n", self.node, "-o", "%t"], env=self.env(),
                               capture_output=True, text=True)
            return r.stdout.strip() == "idle"
        self._wait(idle, "the node to register idle", "slurmctld", "slurmd")
        self.start_s = time.monotonic() - t0
        return self

    def _wait(self, ready, what, *logs):
        deadline = time.monotonic() + self.start_timeout
        while time.monotonic() < deadline:
            for name, p in self.procs.items():
                if p.poll() is not None:
                    raise SlurmUnavailable(f"{name} exited with status {p.returncode} while waiting for {what}:\n"
                                           + _tail(self.log(name + ".stdio")) + _tail(self.log(name)))
            if ready():
                return
            time.sleep(0.1)
        detail = "".join(f"--- {n}.log:\n{_tail(self.log(n))}" for n in logs)
        raise SlurmUnavailable(f"timed out after {self.start_timeout} s waiting for {what}\n{detail}")

    def stop(self):
        if "slurmctld" in self.procs and self.procs["slurmctld"].poll() is None:
            # Jobs first, so no slurmstepd outlives its slurmd; then the daemons themselves.
            subprocess.run(["scancel", "--full", "--partition=test"], env=self.env(), capture_output=True, timeout=10)
            subprocess.run(["scontrol", "shutdown"], env=self.env(), capture_output=True, timeout=10)
        for name in reversed(list(self.procs)):
            p = self.procs[name]
            if name == "munged":  # scontrol shutdown stops the Slurm daemons, not munged
                p.send_signal(signal.SIGTERM)
            try:
                p.wait(timeout=5)
            except subprocess.TimeoutExpired:
                p.send_signal(signal.SIGTERM)
                try:
                    p.wait(timeout=5)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()
        self.procs = {}
        if not self.keep:
            shutil.rmtree(self.base, ignore_errors=True)

    def __enter__(self):
        try:
            return self.start()
        except BaseException:
            self.keep = bool(self.procs)  # the daemons' logs explain the failure
            self.stop()
            raise

    def __exit__(self, *exc):
        if exc[0] is not None:
            self.keep = self.keep or bool(os.environ.get("OMEGA_KEEP_SLURM_ON_FAILURE"))
        self.stop()
        return False
