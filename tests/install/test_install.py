#!/usr/bin/env python3
"""`cmake --install` into a scratch prefix, then the installed programs as a user runs them:
omega finds its image module in PREFIX/lib/omega for a textured render and for `compare`, and
without it fails alone, naming where it looked and never the build tree. The installed systemd
units start PREFIX/bin's programs and pass `systemd-analyze verify` as installed, and a prefix
with a blank gets no units (ExecStart= would split the path).

Usage: test_install.py CMAKE BUILD_DIR
"""
import os
import shutil
import stat
import struct
import subprocess
import sys
import tempfile
import zlib


def png(path, w, h, rgb):
    """An 8-bit RGB PNG, every pixel `rgb`."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    rows = b"".join(b"\0" + bytes(rgb) * w for _ in range(h))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


SCENE = """omega: 1
integrator: {type: path, max_depth: 3}
sensor:
  type: perspective
  fov: 40
  to_world: {look_at: {origin: [0, 0, -3], target: [0, 0, 0], up: [0, 1, 0]}}
  film: {width: 16, height: 12}
materials:
  tex: {type: diffuse, reflectance: %s}
shapes:
  - {type: sphere, center: [0, 0, 0], radius: 1, material: tex}
lights:
  - {type: point, position: [0, 2, -3], intensity: [10, 10, 10]}
"""


def run(cmd, env=None):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, timeout=120)
    return r.returncode, r.stdout


def check_units(prefix, check):
    """The installed units name this prefix's programs and docs, and systemd accepts them."""
    units = os.path.join(prefix, "lib", "systemd", "system")
    for name, program in (("omegad.service", "omegad"), ("omega-worker.service", "omega")):
        with open(os.path.join(units, name)) as f:
            text = f.read()
        check(f"\nExecStart={prefix}/bin/{program} " in text, f"{name} does not start PREFIX/bin/{program}", text)
        docs = [l.split("=file:", 1)[1] for l in text.splitlines() if l.startswith("Documentation=file:")]
        check(docs and all(d.startswith(prefix + "/") and os.path.isfile(d) for d in docs),
              f"{name} documents files not installed under PREFIX: {docs}")
    tool = shutil.which("systemd-analyze")
    check(tool, "systemd-analyze is not installed (scripts/install-deps installs the systemd package)")
    if tool:
        # verify fails when an ExecStart= program does not exist: the units as installed, no edits.
        code, out = run([tool, "verify"] + [os.path.join(units, n) for n in
                                            ("omegad.service", "omegad.socket", "omega-worker.service")])
        check(code == 0, "systemd-analyze verify refuses the installed units", out)


def main():
    cmake, build = sys.argv[1], os.path.realpath(sys.argv[2])
    failures = []

    def check(ok, what, detail=""):
        if not ok:
            failures.append(what + ("\n" + detail if detail else ""))

    with tempfile.TemporaryDirectory() as tmp:
        prefix = os.path.join(tmp, "prefix")
        code, out = run([cmake, "--install", build, "--prefix", prefix])
        if code != 0:
            print("cmake --install failed:\n" + out)
            return 1
        omega = os.path.join(prefix, "bin", "omega")
        module = os.path.join(prefix, "lib", "omega", "libomega_images.so")
        for path in (omega, os.path.join(prefix, "bin", "omegad"), module,
                     os.path.join(prefix, "lib", "systemd", "system", "omegad.service"),
                     os.path.join(prefix, "lib", "systemd", "system", "omegad.socket"),
                     os.path.join(prefix, "lib", "systemd", "system", "omega-worker.service"),
                     os.path.join(prefix, "share", "doc", "omega", "daemon.md"),
                     os.path.join(prefix, "lib", "sysusers.d", "omega.conf")):
            check(os.path.isfile(path), "not installed: " + path)
        if failures:
            print("\n".join(failures))
            return 1
        check_units(prefix, check)
        # image_library.cpp refuses a module that others could replace.
        check(os.stat(module).st_mode & (stat.S_IWGRP | stat.S_IWOTH) == 0, "module installed group/other-writable")

        # OMEGA_IMAGE_LIBRARY would decide alone where to look: the test is about the default.
        env = {k: v for k, v in os.environ.items() if k != "OMEGA_IMAGE_LIBRARY"}
        png(os.path.join(tmp, "red.png"), 4, 4, (200, 30, 30))
        textured = os.path.join(tmp, "textured.yaml")
        with open(textured, "w") as f:
            f.write(SCENE % "{type: bitmap, file: red.png}")
        plain = os.path.join(tmp, "plain.yaml")
        with open(plain, "w") as f:
            f.write(SCENE % "[0.5, 0.5, 0.5]")
        image = os.path.join(tmp, "out.exr")

        code, out = run([omega, "render", textured, "-o", image, "--spp", "2", "-q"], env)
        check(code == 0 and os.path.isfile(image), "installed omega could not render a textured scene", out)
        code, out = run([omega, "compare", image, image], env)
        check(code == 0 and "RMSE 0 " in out, "installed omega compare failed", out)

        # Without its module the installed omega must not fall back to the build tree's copy.
        os.remove(module)
        code, out = run([omega, "render", textured, "-o", image, "--spp", "2", "-q"], env)
        check(code != 0, "textured render succeeded without the installed module", out)
        check("cannot load the image library" in out, "no message naming the image library", out)
        check(os.path.join(prefix, "bin", "..", "lib", "omega", "libomega_images.so") in out,
              "the message does not name PREFIX/lib/omega", out)
        check(build not in out, "the installed program looked in the build tree", out)
        code, out = run([omega, "render", plain, "-o", image, "--spp", "2", "-q"], env)
        check(code == 0, "an untextured render needs the image module", out)

        blank = os.path.join(tmp, "with blank")
        code, out = run([cmake, "--install", build, "--prefix", blank])
        check(code == 0 and os.path.isfile(os.path.join(blank, "bin", "omegad")),
              "cmake --install into a prefix with a blank failed", out)
        check(not os.path.exists(os.path.join(blank, "lib", "systemd", "system", "omegad.service"))
              and "contains a blank" in out, "units installed into a prefix with a blank, or no warning", out)

    print("\n".join(failures) if failures else "ok: installed omega uses PREFIX/lib/omega and nothing else")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
