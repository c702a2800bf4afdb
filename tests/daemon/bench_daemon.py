"""Measurements (not a CTest test): time from submit to first tile on the Cornell box, and
render throughput with 0, 1 and 8 watchers against a plain `omega render`.
Usage: python3 bench_daemon.py OMEGAD OMEGA EXR_COMPARE SOURCE_DIR [SIZE SPP [ROUNDS]]

With ROUNDS (> 0), the watchers' cost is measured apart from the cores they would otherwise
take: omegad renders with one thread pinned to CPU 0 (taskset), this process and its watchers
run on CPU 1, and ROUNDS rounds of jobs with 0, 1 and 8 watchers follow each other
(pinned_rounds). On a machine this small, watchers that share omegad's cores slow it by taking
cores, not by what serving them costs, and two unpinned runs without any watcher differ by
several percent; the median of the rounds' ratios, with their range, resolves a few percent."""
import os
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time

from harness import Daemon, OMEGA, cpu_seconds, op, small_cornell, wait_state, watch

SIZE = int(sys.argv[5]) if len(sys.argv) > 5 else 256
SPP = int(sys.argv[6]) if len(sys.argv) > 6 else 64
ROUNDS = int(sys.argv[7]) if len(sys.argv) > 7 else 0
THREADS = 2


def first_tile(d, size, spp):
    c = d.client()
    scene = small_cornell(width=size, height=size, spp=spp)
    t0 = time.monotonic()
    a = c.submit(scene, name=f"cornell{size}", halt_=op.halt(spp=spp))
    t_acc = time.monotonic() - t0
    sid = c.new_id()
    c.send(op.job_request("subscribe", sid, a["job"]))
    while True:
        h, _ = c.recv_for(sid, timeout=120)
        if h["type"] == "tile":
            break
    t_tile = time.monotonic() - t0
    c.job("cancel", a["job"])
    return t_acc, t_tile


def loop_cpu_seconds(pid):
    """CPU time of omegad's main thread, which runs the event loop (sends frames to watchers)."""
    return cpu_seconds(pid, tid=pid)


def throughput(d, watchers, loop=None, busy=False):
    """Samples/s, render seconds and omegad's CPU seconds of one job; `loop` gets its event
    loop's CPU seconds; `busy` keeps CPU 1 spinning through the job."""
    c = d.client()
    spin = subprocess.Popen(["taskset", "-c", "1", sys.executable, "-c", "while True: pass"]) if busy else None
    cpu0 = cpu_seconds(d.proc.pid)
    loop0 = loop_cpu_seconds(d.proc.pid)
    scene = small_cornell(width=SIZE, height=SIZE, spp=SPP)
    a = c.submit(scene, name="tp", halt_=op.halt(spp=SPP))
    job = a["job"]
    ws = []
    for _ in range(watchers):
        w = d.client()
        t = threading.Thread(target=watch, args=(w, job, 600))
        t.start()
        ws.append(t)
    info = wait_state(c, job, {"done"}, timeout=600)
    for t in ws:
        t.join()
    e = info["progress"]["elapsed_s"]
    if spin:
        spin.kill()
        spin.wait()
    if loop is not None:
        loop.append(loop_cpu_seconds(d.proc.pid) - loop0)
    return SIZE * SIZE * SPP / e, e, cpu_seconds(d.proc.pid) - cpu0


def pinned_rounds():
    """ROUNDS rounds of four jobs, in rotating order, on a one-thread omegad pinned to CPU 0: with
    0, 1 and 8 watchers, and with none but CPU 1 kept busy by a spinning process (the control:
    what merely sharing the machine costs). 1 against 0 adds encoding the tiles (only a watched
    job encodes them) and the event loop's work per tile; 8 against 1 the fan-out to more
    connections. CPU times are clock ticks (10 ms)."""
    os.sched_setaffinity(0, {1})  # this process and its watcher threads: CPU 1 only
    tmp = tempfile.mkdtemp(prefix="omegad-bench-pinned-")
    d = Daemon(tmp, threads=1, wrap=["taskset", "-c", "0"],
               config="max_running: 1\ncheckpoint_interval_s: 30\nlog_level: info\n").start()
    kinds = (("0 watchers", 0, False), ("1 watcher", 1, False), ("8 watchers", 8, False),
             ("0 watchers, CPU 1 busy", 0, True))
    try:
        throughput(d, 0)  # warm-up: page cache, allocator, the first job's set-up
        runs = {k[0]: [] for k in kinds}
        for i in range(ROUNDS):
            for j in range(len(kinds)):
                name, watchers, busy = kinds[(i + j) % len(kinds)]
                loop = []
                rate, _, cpu = throughput(d, watchers, loop, busy)
                runs[name].append((rate, cpu))
                print(f"pinned round {i}, {name}: {rate / 1e3:.0f}k samples/s, omegad CPU {cpu:.2f} s, "
                      f"of which its event loop {loop[0]:.2f} s")
        base = runs[kinds[0][0]]
        for name, _, _ in kinds[1:]:
            # Per round, > 1 when the job cost more than the round's 0-watcher job.
            slower = sorted(a[0] / b[0] for a, b in zip(base, runs[name]))
            cpu = sorted(b[1] / a[1] for a, b in zip(base, runs[name]))
            print(f"pinned, {name} against 0 watchers: render time per sample {statistics.median(slower):.3f} "
                  f"({slower[0]:.3f}-{slower[-1]:.3f}), omegad CPU per job {statistics.median(cpu):.3f} "
                  f"({cpu[0]:.3f}-{cpu[-1]:.3f}), medians of {len(cpu)} rounds")
    finally:
        d.stop()


def main():
    if ROUNDS > 0:
        pinned_rounds()
        return
    tmp = tempfile.mkdtemp(prefix="omegad-bench-")
    d = Daemon(tmp, threads=THREADS, config="max_running: 1\ncheckpoint_interval_s: 30\nlog_level: info\n").start()
    try:
        for size in (256, 1024):
            acc, tile = first_tile(d, size, 64)
            print(f"cornell {size}x{size}: submit->accepted {acc * 1000:.0f} ms, submit->first tile {tile * 1000:.0f} ms")
        path = os.path.join(tmp, "scene.yaml")
        with open(path, "wb") as f:
            f.write(small_cornell(width=SIZE, height=SIZE, spp=SPP))
        t0 = time.monotonic()
        out = subprocess.run([OMEGA, "render", path, "--spp", str(SPP), "--threads", str(THREADS), "-q",
                              "-o", os.path.join(tmp, "l.exr")], check=True, capture_output=True, text=True)
        wall = time.monotonic() - t0
        m = re.search(r"in ([0-9.]+) s", out.stdout)
        local_s = float(m.group(1))
        print(f"omega render {SIZE}x{SIZE} {SPP} spp: {SIZE * SIZE * SPP / local_s / 1e3:.0f}k samples/s "
              f"(render {local_s:.2f} s, wall {wall:.2f} s incl. start-up and EXR write)")
        # Watchers here are Python processes on the same cores, so wall-clock rates understate
        # omegad; its own CPU time per job is the cost of serving them (the measure).
        base_cpu = None
        for w in (0, 1, 8, 0, 8):
            rate, e, cpu = throughput(d, w)
            if w == 0 and base_cpu is None:
                base_cpu = cpu
            print(f"omegad {SIZE}x{SIZE} {SPP} spp, {w} watcher(s): {rate / 1e3:.0f}k samples/s (render {e:.2f} s), "
                  f"omegad CPU {cpu:.2f} s = {cpu / base_cpu:.3f} of the first 0-watcher run")
    finally:
        d.stop()


if __name__ == "__main__":
    main()
