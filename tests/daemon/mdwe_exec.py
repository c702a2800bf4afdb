"""mdwe_exec.py COMMAND ARGS...: runs COMMAND with Linux's memory-deny-write-execute on
(prctl PR_SET_MDWE, Linux 6.3+), the kernel's form of systemd's MemoryDenyWriteExecute=yes,
which omegad.service sets: no mapping may be writable and executable at once, or become
executable later. The setting survives execve, so COMMAND runs under it from its first
instruction, as a service does. Exits 2, naming why, when the kernel refuses it."""
import ctypes
import os
import sys

PR_SET_MDWE, PR_GET_MDWE, PR_MDWE_REFUSE_EXEC_GAIN = 65, 66, 1

libc = ctypes.CDLL(None, use_errno=True)
if libc.prctl(PR_SET_MDWE, PR_MDWE_REFUSE_EXEC_GAIN, 0, 0, 0) != 0:
    sys.stderr.write(f"mdwe_exec: PR_SET_MDWE: {os.strerror(ctypes.get_errno())}\n")
    sys.exit(2)
if libc.prctl(PR_GET_MDWE, 0, 0, 0, 0) != PR_MDWE_REFUSE_EXEC_GAIN:
    sys.stderr.write("mdwe_exec: PR_GET_MDWE does not report the setting\n")
    sys.exit(2)
os.execv(sys.argv[1], sys.argv[1:])
