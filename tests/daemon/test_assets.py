"""Scenes with image files go through the daemon: `omega submit` uploads every bitmap texture and
the envmap image the scene names (a YAML scene and a Mitsuba XML scene), and the images a .glb
embeds, and the fetched image equals, bit for bit, `omega render` of the same scene with the same
seed and spp."""
import os
import shutil
import signal
import struct
import subprocess
import sys

from harness import (ALICE, HERE, OMEGA, SOURCE_DIR, WORKER, Daemon, Test, check_units_merge, exr_equal, omega,
                     start_worker, tcp_env, wait_state)

SPP, SEED = 8, 5


def write(path, data):
    with open(path, "wb") as f:
        f.write(data)


def pfm(width, height, fn):
    """A colour PFM (little-endian floats, rows stored bottom first), fn(x, y) -> (r, g, b) with
    y = 0 the top row."""
    rows = []
    for y in reversed(range(height)):
        rows.append(b"".join(struct.pack("<3f", *fn(x, y)) for x in range(width)))
    return f"PF\n{width} {height}\n-1.0\n".encode() + b"".join(rows)


def sky(x, y):
    if x == 5 and y == 2:
        return (40.0, 35.0, 30.0)  # a small sun
    return (0.4 + 0.05 * y, 0.5 + 0.04 * y, 0.9) if y < 4 else (0.2, 0.15, 0.1)


def checks(x, y):
    return (0.8, 0.2, 0.1) if (x + y) % 2 else (0.1, 0.6, 0.8)


# A textured floor, a bump-mapped and a masked rectangle (each with its own image, one of them in
# a subfolder), lit by an envmap; seen from above at a slant.
YAML_SCENE = b"""omega: 1
integrator: {type: path, max_depth: 4}
sensor:
  type: perspective
  fov: 50
  to_world: {look_at: {origin: [0, 2.5, 2.5], target: [0, 0, 0], up: [0, 1, 0]}}
  film: {width: 40, height: 32}
materials:
  floor: {type: diffuse, reflectance: {type: bitmap, file: tex/checks.pfm, filter: nearest}}
  bumpy: {type: diffuse, reflectance: 0.6, bump: {type: bitmap, file: height.pfm}, bump_scale: 0.05}
  leaf: {type: diffuse, reflectance: 0.5, opacity: {type: bitmap, file: alpha.pfm}}
shapes:
  - {type: rectangle, material: floor, to_world: [{scale: 2}, {rotate: {axis: [1, 0, 0], angle: -90}}]}
  - {type: rectangle, material: bumpy,
     to_world: [{scale: 0.5}, {rotate: {axis: [1, 0, 0], angle: -90}}, {translate: [-0.7, 0.3, 0]}]}
  - {type: rectangle, material: leaf, to_world: [{scale: 0.5}, {translate: [0.7, 0.5, 0]}]}
lights:
  - {type: envmap, file: sky.pfm, scale: 1.5, to_world: {rotate: {axis: [0, 1, 0], angle: 40}}}
"""

XML_SCENE = b"""<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="4"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="0, 2.5, 2.5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="32"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse">
            <texture type="bitmap" name="reflectance"><string name="filename" value="tex/checks.pfm"/></texture>
        </bsdf>
    </shape>
    <emitter type="envmap">
        <string name="filename" value="sky.pfm"/>
        <float name="scale" value="1.5"/>
    </emitter>
</scene>
"""


def make_files(scene_dir):
    os.makedirs(os.path.join(scene_dir, "tex"))
    write(os.path.join(scene_dir, "tex", "checks.pfm"), pfm(8, 8, checks))
    write(os.path.join(scene_dir, "sky.pfm"), pfm(16, 8, sky))
    write(os.path.join(scene_dir, "height.pfm"), pfm(8, 8, lambda x, y: ((x * y) % 3 / 3.0,) * 3))
    write(os.path.join(scene_dir, "alpha.pfm"), pfm(8, 8, lambda x, y: (1.0 if (x - 4) ** 2 + (y - 4) ** 2 < 9 else 0.0,) * 3))


def submit_and_compare(tmp, d, scene_path, expect_assets, label, spp=SPP):
    local = os.path.join(tmp, label + "-local.exr")
    subprocess.run([OMEGA, "render", scene_path, "--spp", str(spp), "--seed", str(SEED), "-o", local, "--threads", "2",
                    "-q"], check=True, timeout=120, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    # From another folder: the client resolves the scene's files against the scene's own folder.
    r = subprocess.run([OMEGA, "submit", scene_path, "--host", d.unix, "--spp", str(spp), "--seed", str(SEED)],
                       capture_output=True, text=True, timeout=120, cwd=tmp)
    assert r.returncode == 0, r.stderr
    assert f"{expect_assets} asset(s), {expect_assets} sent" in r.stderr, r.stderr
    # glTF's approximations are warned (by name); nothing else is.
    warnings = [w for w in r.stderr.splitlines() if "warning" in w and ".glb: " not in w]
    assert not warnings, r.stderr
    job = int(r.stdout.strip())
    c = d.client()
    info = wait_state(c, job, {"done", "failed"})
    assert info["state"] == "done", info
    fetched = c.job("fetch", job)
    assert fetched["type"] == "image", fetched
    p = os.path.join(tmp, label + "-fetched.exr")
    write(p, fetched["_payload"])
    assert exr_equal(local, p) and exr_equal(p, local), f"{label}: fetched image differs from the local render"
    c.close()


def test_yaml_scene_with_textures_and_envmap(tmp, daemons):
    scene_dir = os.path.join(tmp, "scene")
    make_files(scene_dir)
    path = os.path.join(scene_dir, "scene.yaml")
    write(path, YAML_SCENE)
    d = Daemon(tmp).start()
    daemons.append(d)
    # checks, height, alpha and the sky: four files, each sent once.
    submit_and_compare(tmp, d, path, 4, "yaml")


def test_textured_jobs_under_the_units_confinement(tmp, daemons):
    """omegad.service and omega-worker.service set MemoryDenyWriteExecute=yes and
    SystemCallFilter=@system-service. A textured job makes omegad (and a worker) dlopen the image
    module and, with it, OpenImageIO's ~250 libraries: none of them may need a writable and
    executable mapping (text relocations, an executable stack), and nothing omegad or a worker
    does (threads, SQLite, sockets, the module) may make a call the filter kills for, or the
    job would fail in production and in no other test. Both run here under the kernel's forms
    of the two settings (mdwe_exec.py, seccomp_exec.py), as the units start them."""
    wrap = [sys.executable, os.path.join(HERE, "mdwe_exec.py"),
            sys.executable, os.path.join(HERE, "seccomp_exec.py"), "@system-service"]
    # Both settings survive execve: what the wrappers set is what omegad runs under. A call the
    # group leaves out (ptrace) kills the process with SIGSYS; MDWE is reported on.
    probe = subprocess.run(wrap + [sys.executable, "-c", "import ctypes; print(ctypes.CDLL(None).prctl(66, 0, 0, 0, 0))"],
                           capture_output=True, text=True, timeout=30)
    assert probe.returncode == 0 and probe.stdout.strip() == "1", probe.stdout + probe.stderr
    probe = subprocess.run(wrap + [sys.executable, "-c", "import ctypes; ctypes.CDLL(None).syscall(101, 0, 0, 0, 0)"],
                           capture_output=True, text=True, timeout=30)
    assert probe.returncode == -signal.SIGSYS, (probe.returncode, probe.stderr)
    scene_dir = os.path.join(tmp, "scene")
    make_files(scene_dir)
    path = os.path.join(scene_dir, "scene.yaml")
    write(path, YAML_SCENE)
    # LeakSanitizer (preset asan) stops the threads with ptrace for its check at exit, which
    # @system-service leaves out: the check would hang the exit. The other tests check leaks.
    asan = os.environ.get("ASAN_OPTIONS")
    env = dict(os.environ, ASAN_OPTIONS=(asan + ":" if asan else "") + "detect_leaks=0")
    d = Daemon(tmp, wrap=wrap, env=env,
               config=f"tcp_users:\n  alice: {ALICE}\n  farm: {{token: {WORKER}, role: worker}}\n").start()
    daemons.append(d)
    submit_and_compare(tmp, d, path, 4, "confined")
    # The same scene as a worker job: the worker receives the four images and decodes them.
    alice = tcp_env(d.tcp, "alice", ALICE)
    unit, units = 4, 2
    job = int(omega(["submit", path, "--spp", str(unit * units), "--workers", "1", "--unit-spp", str(unit), "-q"],
                    alice).stdout.split()[-1])
    worker, log = start_worker(d.tcp, "confined", tmp, tcp_env(d.tcp, "farm", WORKER), wrap=wrap)
    try:
        d.wait_log(rf"job {job}: done on workers: {unit * units} spp", 120)
    finally:
        worker.kill()
        worker.wait(10)
    assert worker.returncode != -signal.SIGSYS, open(log).read()
    check_units_merge(tmp, path, job, alice, unit, units)
    # systemctl stop: the drain, the last checkpoint and SQLite's close run under the filter too.
    assert d.terminate() == 0, d.log()[-3000:]


def test_mitsuba_scene_with_texture_and_envmap(tmp, daemons):
    scene_dir = os.path.join(tmp, "scene")
    make_files(scene_dir)
    path = os.path.join(scene_dir, "scene.xml")
    write(path, XML_SCENE)
    d = Daemon(tmp).start()
    daemons.append(d)
    submit_and_compare(tmp, d, path, 2, "xml")


def test_glb_scene_with_embedded_textures(tmp, daemons):
    # Blender's .glb carries its two images inside; the checker is a base colour texture, which
    # travels as the file `omega import` would write (blender_scene_textures/checker.png), from
    # the client's memory: no such file exists beside the scene. The roughness image only gives
    # its mean at import. The .glb itself is the other asset.
    scene_dir = os.path.join(tmp, "scene")
    os.makedirs(scene_dir)
    path = os.path.join(scene_dir, "blender_scene.glb")
    shutil.copy(os.path.join(SOURCE_DIR, "tests", "data", "gltf", "blender_scene.glb"), path)
    d = Daemon(tmp).start()
    daemons.append(d)
    submit_and_compare(tmp, d, path, 2, "glb", spp=2)
    assert not os.path.exists(os.path.join(scene_dir, "blender_scene_textures"))


if __name__ == "__main__":
    t = Test()
    t.run(test_yaml_scene_with_textures_and_envmap)
    t.run(test_textured_jobs_under_the_units_confinement)
    t.run(test_mitsuba_scene_with_texture_and_envmap)
    t.run(test_glb_scene_with_embedded_textures)
    t.exit()
