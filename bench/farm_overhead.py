#!/usr/bin/env python3
"""The worker path's overhead on one machine (docs/farm.md "Scaling, projected"), not part of CI.
In one run, on the same Cornell box job, with one omegad (1 render thread):
  local  omegad renders the job itself (no workers);
  w1     one `omega worker --threads 1` renders it in units;
  w2     two such workers;
  small  one worker on the same job at 64x48, which with w1 splits each per-unit cost into a
         fixed part and a part per pixel (docs/farm.md scales that to 4K).
Each case starts from an idle daemon (workers connected before the submit) and is timed from
`omega submit` to omegad's log line that the job is done. Printed, as ratios of the same run:
w1/local (the whole worker path against local rendering), the split of w1's wall time into
rendering (the worker's own "done in" times), set-up (submit to the first unit's start: asset
fetch, scene build) and per-unit gaps (partial EXR write, transfer, merge, next hand-out),
omegad's CPU per unit (receiving and merging a part), the size of one part, and the 2-worker
speed-up. Repeats each case --repeat times and reports the median.
Usage: python3 bench/farm_overhead.py [--size WxH] [--spp N] [--unit-spp N] [--repeat N] [BUILD_DIR]
(from the repository root after scripts/build; BUILD_DIR defaults to build/)."""
import argparse
import os
import re
import statistics
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--size", default="512x384")
ap.add_argument("--spp", type=int, default=64)
ap.add_argument("--unit-spp", type=int, default=8)
ap.add_argument("--repeat", type=int, default=2)
ap.add_argument("build", nargs="?", default=os.path.join(ROOT, "build"))
args = ap.parse_args()
# The daemon tests' harness takes its binaries from argv (OMEGAD OMEGA EXR_COMPARE SOURCE_DIR).
sys.argv = [sys.argv[0], os.path.join(args.build, "daemon", "omegad"), os.path.join(args.build, "client", "omega"),
            os.path.join(args.build, "tests", "daemon", "omega_exr_compare"), ROOT]
sys.path.insert(0, os.path.join(ROOT, "tests", "daemon"))
from harness import Daemon, cpu_seconds, omega, small_cornell, start_worker, tcp_env, wait_file  # noqa: E402

ALICE, WORKER = "alice-token-0123456789", "worker-token-0123456789"
CONFIG = f"""checkpoint_interval_s: 30
log_level: info
tcp_users:
  alice: {ALICE}
  farm: {{token: {WORKER}, role: worker}}
"""
W, H = (int(x) for x in args.size.split("x"))
SW, SH = 64, 48
SPP, UNIT = args.spp, args.unit_spp
UNITS = SPP // UNIT
assert UNITS * UNIT == SPP, "--spp must be a multiple of --unit-spp"


def run_job(d, scene, alice, workers, logs):
    """Submits the job and waits for its end; returns (wall s, omegad CPU s, submit -> first unit
    start s, sum of the workers' unit render times s)."""
    extra = ["--workers", str(workers), "--unit-spp", str(UNIT)] if workers else []
    start_line = len(d.lines)
    sizes = [os.path.getsize(p) for p in logs]
    cpu0 = cpu_seconds(d.proc.pid)
    t0 = time.monotonic()
    job = int(omega(["submit", scene, "--spp", str(SPP), "-q"] + extra, alice).stdout.split()[-1])
    first = None
    if workers:
        wait_file(logs[0], rf"job {job} unit \d+: samples", 120)  # polls every 20 ms
        first = time.monotonic() - t0
        d.wait_log(rf"job {job}: done on workers: {SPP} spp", 600, start=start_line)
    else:
        d.wait_log(rf"job {job}: done: {SPP} spp", 600, start=start_line)
    wall = time.monotonic() - t0
    cpu = cpu_seconds(d.proc.pid) - cpu0
    render = 0.0
    for p, s in zip(logs, sizes):
        with open(p) as f:
            f.seek(s)
            render += sum(float(x) for x in re.findall(rf"job {job} unit \d+: done in ([0-9.]+) s", f.read()))
    return wall, cpu, first, render


def main():
    load0 = os.getloadavg()
    tmp = tempfile.mkdtemp(prefix="omega-farm-bench-")
    d = Daemon(tmp, config=CONFIG, threads=1).start()
    procs = []
    try:
        alice = tcp_env(d.tcp, "alice", ALICE)
        farm = tcp_env(d.tcp, "farm", WORKER)
        scene = os.path.join(tmp, "scene.yaml")
        with open(scene, "wb") as f:
            f.write(small_cornell(W, H, SPP))
        # The same job on a small film, one worker: with the large one, it splits each per-unit
        # cost into a fixed part and a part per pixel (the part's size is the film's).
        small = os.path.join(tmp, "small.yaml")
        with open(small, "wb") as f:
            f.write(small_cornell(SW, SH, SPP))
        # One part's size: what each unit sends to omegad (double-precision film state; docs/farm.md).
        part = os.path.join(tmp, "part.exr")
        omega(["render", scene, "--samples", f"0:{UNIT}", "-o", part, "-q", "--threads", "1"], alice)
        part_bytes = os.path.getsize(part)
        res = {"local": [], "w1": [], "w2": [], "small": []}
        for r in range(args.repeat):
            res["local"].append(run_job(d, scene, alice, 0, []))
            # Fresh workers for each case, connected before the submit: each pays the asset
            # fetch and scene build once, as a worker that meets a new job does.
            for case, n, sc in (("w1", 1, scene), ("w2", 2, scene), ("small", 1, small)):
                ws = [start_worker(d.tcp, f"r{r}{case}w{i}", tmp, farm) for i in range(n)]
                procs += [p for p, _ in ws]
                for i in range(n):
                    d.wait_log(rf"worker 'conn \d+ \(r{r}{case}w{i}\)'", 30)
                res[case].append(run_job(d, sc, alice, n, [log for _, log in ws]))
                for p, _ in ws:
                    p.kill()
                    p.wait(10)
        load = os.getloadavg()
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.wait(10)
        d.stop()

    def med(case, i):
        return statistics.median(r[i] for r in res[case])

    local, w1, w2 = med("local", 0), med("w1", 0), med("w2", 0)
    render1, first1, cpu1 = med("w1", 3), med("w1", 2), med("w1", 1)
    gaps = w1 - first1 - render1
    print(f"job: Cornell box {W}x{H}, {SPP} spp, {UNITS} units of {UNIT} spp; omegad 1 thread, workers 1 thread each; "
          f"median of {args.repeat}; load average (1, 5, 15 min) before {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f}, "
          f"after {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    print(f"wall s: local {local:.2f}, 1 worker {w1:.2f}, 2 workers {w2:.2f}  "
          f"(each run: local {[round(r[0], 2) for r in res['local']]}, w1 {[round(r[0], 2) for r in res['w1']]}, "
          f"w2 {[round(r[0], 2) for r in res['w2']]})")
    print(f"1 worker / local rendering:            {w1 / local:.3f}")
    print(f"2 workers speed-up over 1 worker:      {w1 / w2:.3f}  (efficiency {w1 / w2 / 2:.3f})")
    print(f"1 worker: rendering {render1:.2f} s, set-up (submit -> first unit) {first1:.2f} s, "
          f"gaps between units {gaps:.2f} s")
    print(f"worker-path overhead / render time:    {(w1 - render1) / render1:.3f}  "
          f"(set-up {first1 / render1:.3f}, per-unit gaps {gaps / render1:.3f} = {gaps / UNITS * 1e3:.1f} ms a unit)")
    print(f"omegad CPU per unit (receive, merge):  {cpu1 / UNITS * 1e3:.1f} ms = {cpu1 / render1:.4f} of render time; "
          f"local job's omegad CPU / its wall {med('local', 1) / local:.3f}")
    sw, scpu, sfirst, srender = (med("small", i) for i in range(4))
    sgaps = sw - sfirst - srender
    dpx = W * H - SW * SH
    gap_px, cpu_px = (gaps - sgaps) / UNITS / dpx, (cpu1 - scpu) / UNITS / dpx
    print(f"same job at {SW}x{SH}, 1 worker: per-unit gap {sgaps / UNITS * 1e3:.1f} ms, omegad CPU per unit "
          f"{scpu / UNITS * 1e3:.1f} ms")
    print(f"per unit, fitted: worker gap {sgaps / UNITS * 1e3 - gap_px * SW * SH * 1e3:.1f} ms + {gap_px * 1e6:.3f} us a pixel; "
          f"omegad CPU {scpu / UNITS * 1e3 - cpu_px * SW * SH * 1e3:.1f} ms + {cpu_px * 1e6:.3f} us a pixel")
    print(f"render rate on one worker thread:      {W * H * SPP / render1 / 1e6:.3f} M pixel samples/s")
    print(f"one part: {part_bytes} bytes = {part_bytes / (W * H):.1f} bytes a pixel")


if __name__ == "__main__":
    main()
