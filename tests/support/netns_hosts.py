"""Stand-in "hosts" for tests that need more than one machine on the network: network namespaces,
each joined to the test's own (root) namespace by a veth pair, with its own address and a default
route through the root side, so that a process started in one (`ip netns exec NS ...`) reaches a
server listening on a root-side veth address over a real route, as from another machine.

Names carry the test's pid (namespaces `omega-PID-I`, interfaces `omPIDhI`/`omPIDwI`, 15
characters at most) so that parallel ctest runs never share one; addresses are /31 pairs in
198.18.0.0/15 (RFC 2544's benchmarking range, which no site routes), a block picked from the pid
and moved past any block already on an interface. Everything is removed on exit of the `with`
block, on SIGTERM (ctest's timeout) and at interpreter exit, whichever comes first.
Needs root and iproute2's `ip`. Raises NamespacesRefused when the kernel refuses a namespace or
a veth pair (an unprivileged container), which callers turn into a skip."""
import atexit
import ipaddress
import os
import re
import signal
import subprocess
import sys

BASE = ipaddress.IPv4Address("198.18.0.0")
SPAN = 1 << 17  # 198.18.0.0/15


class NamespacesRefused(Exception):
    pass


def ip(*args, check=True):
    r = subprocess.run(["ip", *args], capture_output=True, text=True, timeout=30)
    if check and r.returncode != 0:
        raise RuntimeError(f"ip {' '.join(args)} exited {r.returncode}: {r.stderr.strip()}")
    return r


class Host:
    def __init__(self, ns, host_if, ns_if, gateway, addr):
        self.ns, self.host_if, self.ns_if = ns, host_if, ns_if
        self.gateway = gateway  # the root side of the veth: where the host's packets leave to
        self.addr = addr        # the host's own address, which servers see as the peer

    def wrap(self):
        """The command prefix that runs a program on this host."""
        return ["ip", "netns", "exec", self.ns]


class NetnsHosts:
    def __init__(self, count):
        self.count = count
        self.tag = str(os.getpid())
        self.hosts = []
        self._made = []  # (kind, name) in creation order, so that cleanup undoes exactly those

    def _block(self):
        used = set()
        for line in ip("-4", "-o", "addr", "show").stdout.splitlines():
            f = line.split()
            if "inet" in f:
                used.add(ipaddress.IPv4Interface(f[f.index("inet") + 1]).ip)
        size = 2 * self.count
        blocks = SPAN // size
        first = os.getpid() % blocks
        for k in range(blocks):
            start = BASE + ((first + k) % blocks) * size
            if not any(start + i in used for i in range(size)):
                return start
        raise RuntimeError("no free /31 pairs left in 198.18.0.0/15")

    def __enter__(self):
        atexit.register(self.cleanup)
        self._old_term = signal.signal(signal.SIGTERM, self._on_term)
        try:
            r = ip("netns", "add", f"omega-{self.tag}-0", check=False)
            if r.returncode != 0:
                raise NamespacesRefused(f"ip netns add: {r.stderr.strip()}")
            self._made.append(("ns", f"omega-{self.tag}-0"))
            start = self._block()
            for i in range(self.count):
                ns, hv, wv = f"omega-{self.tag}-{i}", f"om{self.tag}h{i}", f"om{self.tag}w{i}"
                if i > 0:
                    ip("netns", "add", ns)
                    self._made.append(("ns", ns))
                r = ip("link", "add", hv, "type", "veth", "peer", "name", wv, "netns", ns, check=False)
                if r.returncode != 0:
                    raise NamespacesRefused(f"ip link add ... type veth: {r.stderr.strip()}")
                self._made.append(("link", hv))
                gw, addr = start + 2 * i, start + 2 * i + 1
                ip("addr", "add", f"{gw}/31", "dev", hv)
                ip("link", "set", hv, "up")
                ip("-n", ns, "addr", "add", f"{addr}/31", "dev", wv)
                ip("-n", ns, "link", "set", wv, "up")
                ip("-n", ns, "link", "set", "lo", "up")
                # Through the root side to every other address, as a host reaches a server on
                # another subnet through its router.
                ip("-n", ns, "route", "add", "default", "via", str(gw))
                self.hosts.append(Host(ns, hv, wv, str(gw), str(addr)))
        except BaseException:
            self.cleanup()
            raise
        return self

    def _on_term(self, signum, frame):
        raise SystemExit(128 + signum)  # unwinds through the caller's finally and __exit__

    def __exit__(self, *exc):
        self.cleanup()
        signal.signal(signal.SIGTERM, self._old_term)
        return False

    def cleanup(self):
        """Removes what this run made (idempotent). Deleting a namespace also deletes the veth end
        inside it, and with it the pair; the root ends are deleted by name in case a process still
        holds a namespace open."""
        while self._made:
            kind, name = self._made.pop()
            if kind == "ns":
                # A process still inside (a worker the caller did not reach after a SIGTERM) keeps
                # the namespace's mount busy, and `ip netns del` would then fail: end it first.
                for pid in ip("netns", "pids", name, check=False).stdout.split():
                    try:
                        os.kill(int(pid), signal.SIGKILL)
                    except (ProcessLookupError, ValueError):
                        pass
            r = ip("link", "del", name, check=False) if kind == "link" else ip("netns", "del", name, check=False)
            if r.returncode != 0 and "Cannot find" not in r.stderr:
                print(f"netns_hosts: could not delete {kind} {name}: {r.stderr.strip()}", file=sys.stderr, flush=True)

    def leftovers(self):
        """Namespaces and interfaces of this run still present (none after cleanup)."""
        names = ip("netns", "list").stdout + ip("-o", "link", "show").stdout
        return [n for h in self.hosts for n in (h.ns, h.host_if)
                if re.search(rf"(^|\s){re.escape(n)}[@:\s]", names, re.M)]
