#!/usr/bin/env python3
"""seccomp_exec.py GROUP COMMAND [ARGS...]: run COMMAND under the system call filter systemd
builds for `SystemCallFilter=GROUP` with `SystemCallArchitectures=native` (x86-64), as
omegad.service and omega-worker.service ask (GROUP: @system-service).

The groups come from `systemd-analyze syscall-filter` of the systemd installed here, expanded
as systemd expands them. Like systemd (v250 and later), a call the group leaves out kills the
process with SIGSYS, and a call systemd does not know (newer than its tables) fails with ENOSYS,
so that glibc falls back as it would under the unit. Numbers come from the kernel headers. The
filter is a plain BPF program loaded with prctl(PR_SET_SECCOMP), and survives execve."""
import ctypes
import errno
import os
import re
import struct
import subprocess
import sys

PR_SET_NO_NEW_PRIVS, PR_SET_SECCOMP, SECCOMP_MODE_FILTER = 38, 22, 2
AUDIT_ARCH_X86_64 = 0xC000003E
RET_KILL_PROCESS, RET_ERRNO, RET_ALLOW = 0x80000000, 0x00050000, 0x7FFF0000
LD_W_ABS, JEQ_K, RET_K = 0x20, 0x15, 0x06  # BPF_LD|BPF_W|BPF_ABS, BPF_JMP|BPF_JEQ|BPF_K, BPF_RET|BPF_K
UNISTD = "/usr/include/x86_64-linux-gnu/asm/unistd_64.h"


def groups():
    """{'@name': [members]} from `systemd-analyze syscall-filter`."""
    out = subprocess.run(["systemd-analyze", "syscall-filter"], capture_output=True, text=True, check=True).stdout
    table, current = {}, None
    for line in out.splitlines():
        if line.startswith("@"):
            current = table.setdefault(line.strip(), [])
        elif line.startswith(" ") and current is not None and not line.strip().startswith("#") and line.strip():
            current.append(line.strip())
        elif not line.strip() or line.startswith("#"):
            current = None
    return table


def expand(name, table, seen=None):
    seen = set() if seen is None else seen
    if name in seen:
        return set()
    seen.add(name)
    calls = set()
    for m in table[name]:
        calls |= expand(m, table, seen) if m.startswith("@") else {m}
    return calls


def numbers():
    with open(UNISTD) as f:
        return {m.group(1): int(m.group(2)) for m in re.finditer(r"#define __NR_(\w+) (\d+)", f.read())}


def program(group):
    table, nr = groups(), numbers()
    allowed = {nr[c] for c in expand(group, table) if c in nr}
    known = {nr[c] for g in table for c in table[g] if c in nr}
    insns = [(LD_W_ABS, 0, 0, 4), (JEQ_K, 1, 0, AUDIT_ARCH_X86_64), (RET_K, 0, 0, RET_KILL_PROCESS),
             (LD_W_ABS, 0, 0, 0)]
    # Two instructions per call: a jump past the next when the number differs, a return when
    # it matches (BPF's jump offsets are 8 bits, too short to reach one shared return).
    for n in sorted(allowed):
        insns += [(JEQ_K, 0, 1, n), (RET_K, 0, 0, RET_ALLOW)]
    for n in sorted(set(nr.values()) - known):
        insns += [(JEQ_K, 0, 1, n), (RET_K, 0, 0, RET_ERRNO | errno.ENOSYS)]
    insns.append((RET_K, 0, 0, RET_KILL_PROCESS))
    return b"".join(struct.pack("HBBI", *i) for i in insns), len(insns)


def main():
    group, argv = sys.argv[1], sys.argv[2:]
    code, count = program(group)
    buf = ctypes.create_string_buffer(code, len(code))

    class Fprog(ctypes.Structure):
        _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]

    prog = Fprog(count, ctypes.addressof(buf))
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0 or \
            libc.prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, ctypes.byref(prog), 0, 0) != 0:
        e = ctypes.get_errno()
        sys.stderr.write(f"seccomp_exec: cannot load the filter: {os.strerror(e)}\n")
        sys.exit(126)
    os.execvp(argv[0], argv)


if __name__ == "__main__":
    main()
