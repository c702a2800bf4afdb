"""`omega batch --slurm` end to end on a real single-host Slurm cluster (tests/support/slurm_cluster.py).

1. --dry-run prints the scripts and sbatch commands and submits nothing.
2. A 3-frame manifest, 4 chunks per frame: the test scancels one running array task; the client must
   resubmit it, replace the merge to depend on the replacement, and every frame's merged output
   must equal its local `omega render --spp N` (1e-6 relative per pixel).
3. A chunk that fails every time: after its retries the frame fails (exit 1), its merge never runs.

Usage: test_slurm_batch.py OMEGA EXR_COMPARE SOURCE_DIR. Fails (never skips) when Slurm cannot run,
with the reason. OMEGA_KEEP_SLURM=1 keeps the cluster's folder (logs) for a look afterwards.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "support"))
from slurm_cluster import SlurmCluster, SlurmUnavailable  # noqa: E402

OMEGA, EXR_COMPARE, SOURCE_DIR = (os.path.abspath(a) for a in sys.argv[1:4])
SPP = 16
SLOW = 4 if os.environ.get("OMEGA_SANITIZER") else 1


def box(fov):
    """The Cornell box at 32x32, with its own fov (so the frames differ)."""
    with open(os.path.join(SOURCE_DIR, "scenes", "cornell-box.yaml")) as f:
        text = f.read()
    text = re.sub(r"film: \{width: \d+, height: \d+", "film: {width: 32, height: 32", text)
    text = re.sub(r"\n  fov: [0-9.]+", f"\n  fov: {fov}", text)
    text = re.sub(r"\n  spp: \d+", "\n  spp: 4", text)  # the manifest's spp must win
    return text


# A stand-in for the omega binary on the nodes. It runs the real omega, except:
# - the first run of chunk $HOLD_CHUNK of a scene matching $HOLD_SCENE writes its Slurm task id to
#   $HOLD_MARK and waits (RUNNING, before rendering) until the test scancels it;
# - a render of chunk $FAIL_CHUNK of a scene matching $FAIL_SCENE always fails.
WRAPPER = r"""#!/bin/bash
if [ "$1" = render ] && [ -n "${HOLD_MARK:-}" ] && [ "${SLURM_ARRAY_TASK_ID:-}" = "$HOLD_CHUNK" ] \
   && [[ "$2" == *"$HOLD_SCENE"* ]] && mkdir "$HOLD_MARK.once" 2>/dev/null; then
  echo "${SLURM_ARRAY_JOB_ID}_${SLURM_ARRAY_TASK_ID}" > "$HOLD_MARK.tmp" && mv "$HOLD_MARK.tmp" "$HOLD_MARK"
  sleep 300
  exit 0   # not reached: the test cancels this task
fi
if [ "$1" = render ] && [ -n "${FAIL_SCENE:-}" ] && [ "${SLURM_ARRAY_TASK_ID:-}" = "$FAIL_CHUNK" ] \
   && [[ "$2" == *"$FAIL_SCENE"* ]]; then
  echo "test: chunk $FAIL_CHUNK fails on purpose" >&2
  exit 1
fi
exec "$REAL_OMEGA" "$@"
"""


def check(cond, what, *context):
    if not cond:
        sys.stderr.write("FAILED: " + what + "\n")
        for c in context:
            sys.stderr.write(str(c) + "\n")
        sys.exit(1)


def write(path, text, mode=0o644):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write(text)
    os.chmod(path, mode)


def queue(cluster, settle=5):
    """The jobs in the queue; waits up to `settle` s for cancelled ones to leave it."""
    deadline = time.monotonic() + settle
    while True:
        r = subprocess.run(["squeue", "-h", "-o", "%i %T %j"], env=cluster.env(), capture_output=True, text=True)
        if not r.stdout.strip() or time.monotonic() > deadline:
            return r.stdout.strip()
        time.sleep(0.2)


def run_batch(cluster, manifest, env, timeout):
    return subprocess.run([OMEGA, "batch", manifest, "--slurm"], env=env, capture_output=True, text=True,
                          timeout=timeout)


def main():
    work = tempfile.mkdtemp(prefix="omega-slurm-batch-")
    os.chmod(work, 0o755)
    try:
        for i, fov in ((1, 19.5), (2, 24), (3, 30)):
            write(os.path.join(work, "scenes", f"box_{i}.yaml"), box(fov))
        write(os.path.join(work, "omega-node"), WRAPPER, 0o755)
        manifest = os.path.join(work, "shots.yaml")
        write(manifest, f"""output_dir: renders
retries: 0            # slurm.retries wins for --slurm
slurm:
  chunks: 4
  retries: 2
  poll_interval: 1
  time_limit: "10"
  omega: omega-node   # relative to the manifest
jobs:
  - scene: scenes/box_{{frame}}.yaml
    frames: [1, 3]
    output: frame_{{frame:02}}.exr
    spp: {SPP}
""")
        t0 = time.monotonic()
        with SlurmCluster() as cluster:
            print(f"cluster up in {cluster.start_s:.1f} s ({cluster.base})", flush=True)
            env = cluster.env()
            env["REAL_OMEGA"] = OMEGA

            # 1. --dry-run: scripts and commands on stdout, nothing submitted, nothing written.
            r = subprocess.run([OMEGA, "batch", manifest, "--slurm", "--dry-run"], env=env, capture_output=True,
                               text=True, timeout=60)
            check(r.returncode == 0, f"--dry-run exited {r.returncode}", r.stderr)
            check(r.stdout.count("#!/bin/bash") == 6, "--dry-run prints a render and a merge script per frame", r.stdout)
            check("--array=0-3" in r.stdout and "--dependency=afterok:ARRAY_JOB_ID" in r.stdout,
                  "--dry-run prints the sbatch commands", r.stdout)
            check(" --samples \"$samples\"" in r.stdout and "samples=12:16" in r.stdout, "chunks of 4 spp", r.stdout)
            check(queue(cluster) == "", "--dry-run submitted jobs", queue(cluster))
            check(not os.path.exists(os.path.join(work, "renders")), "--dry-run wrote files")

            # 2. The farm run, with chunk 2 of frame 2 cancelled while it runs.
            mark = os.path.join(work, "held-task")
            env.update(HOLD_MARK=mark, HOLD_CHUNK="2", HOLD_SCENE="box_2.yaml")
            t1 = time.monotonic()
            proc = subprocess.Popen([OMEGA, "batch", manifest, "--slurm"], env=env, stdout=subprocess.PIPE,
                                    stderr=subprocess.PIPE, text=True)
            try:
                deadline = time.monotonic() + 60 * SLOW
                while not os.path.exists(mark) and time.monotonic() < deadline and proc.poll() is None:
                    time.sleep(0.1)
                check(os.path.exists(mark), "chunk 2 of frame 2 never started", queue(cluster))
                held = open(mark).read().strip()
                state = subprocess.run(["squeue", "-h", "-j", held, "-o", "%T"], env=env, capture_output=True,
                                       text=True).stdout.strip()
                check(state == "RUNNING", f"task {held} is {state!r}, not RUNNING, when cancelled")
                subprocess.run(["scancel", held], env=env, check=True)
                print(f"cancelled running task {held}", flush=True)
                out, err = proc.communicate(timeout=120 * SLOW)
            finally:
                if proc.poll() is None:
                    proc.kill()
                    proc.communicate()
            t2 = time.monotonic()
            sys.stderr.write(err)
            print(out, flush=True)
            check(proc.returncode == 0, f"omega batch --slurm exited {proc.returncode}")
            array2 = held.split("_")[0]
            m = re.search(rf"chunk 2 \(task {held}\) ended CANCELLED.*; resubmitted as job (\d+) \(attempt 2/3\)", err)
            check(m, "the cancelled task was not resubmitted")
            replacement = m.group(1)
            check(re.search(rf"merge job \d+ \(afterok:[0-9_:]*{replacement}_2\b", err),
                  "the new merge job does not depend on the replacement task")
            check(re.search(rf"\[1/3\].*job array \d+: {SPP} spp in 4 chunk\(s\)", err), "frame 1's array line")
            # Frame 2's first merge (afterok of the array with the cancelled task) never ran.
            first_merge = re.search(rf"\[2/3\].*merge job (\d+) \(afterok:{array2}\)", err)
            check(first_merge, "frame 2's first merge job line")
            work2 = os.path.join(work, "renders", ".omega-slurm", "0002-frame_02")
            check(not os.path.exists(os.path.join(work2, f"merge_{first_merge.group(1)}.log")),
                  "the merge that waited on the cancelled task ran")
            rows = [l.split() for l in out.splitlines() if re.match(r"^\d+\s+scenes/", l)]
            # Columns: #, SCENE (two words: the file and frame=N), JOB, STATE, TRIES, SPP, TIME, OUTPUT.
            check(len(rows) == 3 and all(r[4] == "done" and r[6] == str(SPP) for r in rows), "three frames done", out)
            check(rows[1][3] == array2 and rows[1][5] == "2", "frame 2: its array id, 2 tries", out)
            check(rows[0][5] == "1" and rows[2][5] == "1", "frames 1 and 3 took one try", out)
            check("3 of 3 job(s) done, 0 failed" in out, "summary line", out)
            check(not [p for p in os.listdir(work2) if p.endswith(".exr")], "part EXRs kept after the merge")

            # Every merged frame equals its local render of the same spp.
            for i in (1, 2, 3):
                merged = os.path.join(work, "renders", f"frame_{i:02}.exr")
                local = os.path.join(work, f"local_{i}.exr")
                r = subprocess.run([OMEGA, "render", os.path.join(work, "scenes", f"box_{i}.yaml"), "--spp", str(SPP),
                                    "-o", local], capture_output=True, text=True)
                check(r.returncode == 0, f"local render {i}", r.stderr)
                r = subprocess.run([EXR_COMPARE, "--rel-tol", "1e-6", local, merged], capture_output=True, text=True)
                check(r.returncode == 0, f"frame {i}: merged output differs from the local render", r.stderr)

            # 3. A chunk that always fails: the frame fails after its retries and is never merged.
            fail_manifest = os.path.join(work, "fail.yaml")
            write(fail_manifest, """output_dir: renders
slurm: {chunks: 2, retries: 1, poll_interval: 1, omega: omega-node}
jobs: [{scene: scenes/box_3.yaml, output: failing.exr, spp: 8}]
""")
            env = cluster.env()
            env.update(REAL_OMEGA=OMEGA, FAIL_SCENE="box_3.yaml", FAIL_CHUNK="1")
            t3 = time.monotonic()
            r = run_batch(cluster, fail_manifest, env, 90 * SLOW)
            t4 = time.monotonic()
            sys.stderr.write(r.stderr)
            print(r.stdout, flush=True)
            check(r.returncode == 1, f"a frame that cannot render: exit {r.returncode}, not 1")
            check(re.search(r"chunk 1 \(samples 4:8\) failed 2 time\(s\), last as task \d+_1: FAILED exit 1:0 NonZeroExitCode: "
                            r"test: chunk 1 fails on purpose \(log: ", r.stdout),
                  "the summary names the failing chunk", r.stdout)
            check("0 of 1 job(s) done, 1 failed" in r.stdout, "summary line", r.stdout)
            check(not os.path.exists(os.path.join(work, "renders", "failing.exr")), "an incomplete set was merged")
            check(queue(cluster) == "", "jobs left behind by the failed frame", queue(cluster))
        print(f"ok: farm run {t2 - t1:.1f} s, failing run {t4 - t3:.1f} s, total {time.monotonic() - t0:.1f} s",
              flush=True)
    finally:
        if not os.environ.get("OMEGA_KEEP_SLURM"):
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    try:
        main()
    except SlurmUnavailable as e:
        # Not a skip: the farm path must be tested wherever the suite runs.
        sys.stderr.write(f"FAILED: the test Slurm cluster cannot run here: {e}\n")
        sys.exit(1)
