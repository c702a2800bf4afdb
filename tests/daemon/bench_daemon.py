"""Measurements (not a CTest test): time from submit to first tile on the Cornell box, and
render throughput with 0, 1 and 8 watchers against a plain `omega render`.
Usage: python3 bench_daemon.py OMEGAD OMEGA EXR_COMPARE SOURCE_DIR [SIZE SPP]"""
import os
import re
import subprocess
import sys
import tempfile
import threading
import time

from harness import Daemon, OMEGA, cpu_seconds, op, small_cornell, wait_state, watch

SIZE = int(sys.argv[5]) if len(sys.argv) > 5 else 256
SPP = int(sys.argv[6]) if len(sys.argv) > 6 else 64
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


def throughput(d, watchers):
    c = d.client()
    cpu0 = cpu_seconds(d.proc.pid)
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
    return SIZE * SIZE * SPP / e, e, cpu_seconds(d.proc.pid) - cpu0


def main():
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
