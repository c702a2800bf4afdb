"""Bounded load test on loopback: N clients (default 32) each submit, watch and fetch small jobs
for a fixed time. Checks: no job lost or duplicated (every accepted id is unique, done, and in
`list`; nothing else is), every fetched image equals a local render bit for bit, and the daemon's
peak RSS stays under a bound. Prints jobs/s, p50/p99 time to first tile and peak RSS.
Usage: python3 load_test.py OMEGAD OMEGA EXR_COMPARE SOURCE_DIR [--seconds S] [--clients N]
       [--max-rss-mib M]"""
import argparse
import os
import sys
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "daemon"))
from harness import Daemon, Test, exr_equal, local_render, op, small_cornell  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("paths", nargs=4)
ap.add_argument("--seconds", type=float, default=float(os.environ.get("OMEGA_LOAD_SECONDS", 20)))
ap.add_argument("--clients", type=int, default=32)
ap.add_argument("--max-rss-mib", type=float, default=768)
ARGS = ap.parse_args()
SEEDS = 4  # distinct images, so that local renders stay few
SPP = 2


def rss_kib(pid, field):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    return 0


def percentile(xs, p):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(p / 100 * (len(xs) - 1))))]


def test_load(tmp, daemons):
    scene = small_cornell(width=32, height=32, spp=SPP)
    locals_ = []
    for s in range(SEEDS):
        p = os.path.join(tmp, f"local-{s}.exr")
        local_render(scene, p, SPP, s, tmp)
        locals_.append(p)
    d = Daemon(tmp, threads=2, config="max_running: 2\nlog_level: info\nmax_jobs_per_owner: 100000\n").start()
    daemons.append(d)
    stop_at = time.monotonic() + ARGS.seconds
    lock = threading.Lock()
    accepted, first_tile, images, errors = [], [], [], []
    rss_samples = []

    def client(i):
        try:
            c = d.client(tcp=(i % 2 == 1), timeout=120)
            n = 0
            while time.monotonic() < stop_at:
                seed = (i + n) % SEEDS
                n += 1
                t0 = time.monotonic()
                h = c.submit(scene, name=f"c{i}-{n}", seed=seed, halt_=op.halt(spp=SPP))
                assert h["type"] == "accepted", h
                job = h["job"]
                with lock:
                    accepted.append(job)
                sid = c.new_id()
                c.send(op.job_request("subscribe", sid, job))
                got_tile = None
                while True:
                    f, _ = c.recv_for(sid)
                    if f["type"] == "tile" and got_tile is None:
                        got_tile = time.monotonic() - t0
                    if f["type"] == "done":
                        assert f["state"] == "done", f
                        break
                img = c.job("fetch", job)
                assert img["type"] == "image" and img["spp"] == SPP, img
                path = os.path.join(tmp, f"img-{job}.exr")
                with open(path, "wb") as out:
                    out.write(img["_payload"])
                with lock:
                    first_tile.append(got_tile)
                    images.append((job, seed, path))
            c.close()
        except Exception as e:  # noqa: BLE001
            with lock:
                errors.append((i, repr(e)))

    def sampler():
        while time.monotonic() < stop_at + 5 and d.proc.poll() is None:
            rss_samples.append(rss_kib(d.proc.pid, "VmRSS"))
            time.sleep(0.25)

    t_start = time.monotonic()
    threads = [threading.Thread(target=client, args=(i,)) for i in range(ARGS.clients)]
    st = threading.Thread(target=sampler)
    st.start()
    for t in threads:
        t.start()
    for t in threads:
        t.join(ARGS.seconds + 300)
    elapsed = time.monotonic() - t_start
    peak_kib = rss_kib(d.proc.pid, "VmHWM")
    st.join()
    assert not errors, errors[:5]
    # No job lost or duplicated.
    assert len(accepted) == len(set(accepted)), "a job id was handed out twice"
    listed = d.client().request(lambda id: op.bare("list", id))["jobs"]
    by_id = {j["job"]: j for j in listed}
    assert set(by_id) == set(accepted), (sorted(set(by_id) ^ set(accepted)))[:10]
    assert all(j["state"] == "done" and j["progress"]["spp"] == SPP for j in listed)
    # Every image equals the local render of its seed.
    bad = [job for job, seed, path in images if not exr_equal(locals_[seed], path)]
    assert not bad, f"images differ from local renders: jobs {bad[:10]}"
    ttft = [x for x in first_tile if x is not None]
    print(f"  load: {ARGS.clients} clients, {elapsed:.1f} s, {len(accepted)} jobs, "
          f"{len(accepted) / elapsed:.2f} jobs/s; time to first tile p50 {percentile(ttft, 50) * 1000:.0f} ms, "
          f"p99 {percentile(ttft, 99) * 1000:.0f} ms; daemon peak RSS {peak_kib / 1024:.0f} MiB "
          f"(RSS after warm-up {rss_samples[len(rss_samples) // 4] / 1024:.0f} MiB, at the end "
          f"{rss_samples[-1] / 1024:.0f} MiB)", flush=True)
    assert peak_kib / 1024 < ARGS.max_rss_mib, f"peak RSS {peak_kib / 1024:.0f} MiB over {ARGS.max_rss_mib}"


if __name__ == "__main__":
    sys.argv = [sys.argv[0]] + ARGS.paths
    import harness
    harness.OMEGAD, harness.OMEGA, harness.EXR_COMPARE, harness.SOURCE_DIR = ARGS.paths
    t = Test()
    t.run(test_load)
    t.exit()
