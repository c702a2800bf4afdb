#!/usr/bin/env python3
"""The package installs offline, as docs/python.md says: `pip install --no-build-isolation
--no-index` with setuptools as the build backend, into a fresh --target folder, and imports from
there (not from the source tree). pip builds in the folder it is given, so it gets a copy.

The interpreter is this one when it has pip, setuptools and wheel (setuptools < 70.1 needs wheel
to build one), else Debian's /usr/bin/python3, where scripts/install-deps puts python3-pip,
python3-setuptools and python3-wheel.

usage: test_install.py SOURCE_DIR
"""
import os
import shutil
import subprocess
import sys
import tempfile

CHECK = """
import sys, omega
from omega import assets, codec, connection, errors, exr, jobs
assert omega.__file__.startswith(sys.argv[1]), omega.__file__
assert codec.hello(1, "omega/0.1")[:4] == b"OMG1" and callable(omega.connect)
print(omega.__version__)
"""


def can_build(exe):
    # setuptools first: importing pip before it trips Debian's distutils shim.
    r = subprocess.run([exe, "-c", "import setuptools, importlib.util\nassert importlib.util.find_spec('pip')\n"
                        "try:\n import wheel\nexcept ImportError:\n from setuptools.command import bdist_wheel"],
                       capture_output=True, timeout=60)
    return r.returncode == 0


def main():
    src = os.path.join(sys.argv[1], "clients", "python")
    exe = next((e for e in (sys.executable, "/usr/bin/python3") if os.path.exists(e) and can_build(e)), None)
    if exe is None:
        print("FAIL: no python3 with pip, setuptools and wheel (scripts/install-deps installs them)")
        return 1
    tmp = tempfile.mkdtemp(prefix="omega-pip-")
    try:
        copy = os.path.join(tmp, "src")
        shutil.copytree(src, copy, ignore=shutil.ignore_patterns("__pycache__", "build", "*.egg-info"))
        target = os.path.join(tmp, "target")
        # No configuration or index of any kind: what an offline machine has.
        env = {k: v for k, v in os.environ.items() if not k.startswith("PIP_")}
        env.update(PIP_CONFIG_FILE=os.devnull, PIP_DISABLE_PIP_VERSION_CHECK="1", PYTHONNOUSERSITE="1")
        r = subprocess.run([exe, "-m", "pip", "install", "--no-build-isolation", "--no-index", "--target", target,
                            copy], env=env, capture_output=True, text=True, timeout=180)
        if r.returncode != 0:
            print(f"FAIL: pip install with {exe}:\n{r.stdout}\n{r.stderr}")
            return 1
        env["PYTHONPATH"] = target
        r = subprocess.run([exe, "-c", CHECK, target], env=env, cwd=tmp, capture_output=True, text=True, timeout=60)
        if r.returncode != 0:
            print(f"FAIL: import from {target}:\n{r.stdout}\n{r.stderr}")
            return 1
        print(f"PASS: installed with {exe} and imported omega {r.stdout.strip()} from {target}")
        return 0
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
