"""The live job page (docs/web.md) in a real browser: Debian's chromium, headless, driven by
puppeteer-core (tests/web/browser.mjs). A real omegad with two TCP users, a real `omega view`
bridge, and the page as a user sees it:

- `--listen` off loopback is refused, and so is a WebSocket upgrade from a foreign Origin;
- a wrong token is refused (the page shows auth_failed, and nothing is listed);
- the job list names the jobs as `omega list` does, with controls only on the user's own jobs;
- an open running job receives float tiles to its end; the canvas then equals the EXR fetched
  over the protocol after the same tone map (exposure +0.5), within 8-bit rounding, and holds no
  NaN; the error view differs; the download is the fetched file;
- the priority field and clicks on pause, resume, pause and cancel act on the job (each checked
  via the protocol);
- over the daemon's Unix socket, a wrong access key is refused and the printed one logs in as
  the uid running `omega view`, with no controls on others' jobs;
- a screenshot is kept in the build tree (its path is printed).

Usage: python3 test_web.py OMEGAD OMEGA EXR_COMPARE SOURCE_DIR ARTEFACT_DIR"""
import json
import os
import re
import shutil
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "daemon"))
sys.path.insert(0, os.path.join(HERE, "..", "..", "clients", "python", "src"))
from harness import OMEGA, SOURCE_DIR, Daemon, Test, op, small_cornell, wait_spp, wait_state  # noqa: E402
try:
    import numpy as np
except ImportError:  # Debian's python3-numpy serves /usr/bin/python3, maybe not the python3 on PATH
    if os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") and os.path.exists("/usr/bin/python3"):
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    raise
from omega import exr as omega_exr  # noqa: E402  (the Python client's EXR reader, with numpy)

ARTEFACTS = os.path.abspath(sys.argv[5] if len(sys.argv) > 5 else os.getcwd())
ALICE, BOB = "alice-web-token-0123456789", "bob-web-token-0123456789"
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"


def login(d, user, token):
    c = d.client(tcp=True)
    w = c.welcome[0]
    h = c.request(lambda id: op.auth(id, user, op.auth_mac(token.encode(), w["nonce"], user)))
    assert h["type"] == "ok", h
    return c


def submit(c, name, halt, priority=0):
    h = c.submit(small_cornell(64, 48, 1 << 20), name=name, priority=priority, halt_=halt)
    assert h["type"] == "accepted", h
    return h["job"]


class Browser:
    def __init__(self):
        self.proc = subprocess.Popen(["node", os.path.join(HERE, "browser.mjs"), CHROMIUM], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True, cwd=HERE)

    def __call__(self, cmd, **kw):
        self.proc.stdin.write(json.dumps(dict(cmd=cmd, **kw)) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise AssertionError(f"the browser driver exited ({self.proc.poll()}) during {cmd}")
        out = json.loads(line)
        if "error" in out:
            raise AssertionError(f"browser {cmd} {kw}: {out['error']}")
        return out.get("value")

    def close(self):
        try:
            self.proc.stdin.write('{"cmd": "quit"}\n')
            self.proc.stdin.flush()
            self.proc.wait(15)
        except Exception:
            self.proc.kill()


class View:
    """`omega view --host ADDR --listen 127.0.0.1:0`; url is the page, key the printed access key."""

    def __init__(self, host):
        self.proc = subprocess.Popen([OMEGA, "view", "--host", host, "--listen", "127.0.0.1:0", "--list-interval", "0.3"],
                                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.lines = []
        first, second = self.proc.stdout.readline(), self.proc.stdout.readline()
        m = re.search(r"serving (http://127\.0\.0\.1:\d+/)", first)
        assert m, f"omega view printed {first!r}"
        self.url = m.group(1)
        m = re.search(r"#key=([0-9a-f]{32})$", second.strip())
        assert m, f"omega view printed {second!r}"
        self.key = m.group(1)
        threading.Thread(target=lambda: self.lines.extend(self.proc.stdout), daemon=True).start()

    def stop(self):
        self.proc.terminate()
        rc = self.proc.wait(15)
        assert rc == 0, f"omega view exited {rc}: {''.join(self.lines)}"


def upgrade_status(url, origin):
    """The HTTP status of a WebSocket upgrade of /ws sent with this Origin (0: closed unanswered)."""
    import http.client
    host = url.split("/")[2]
    c = http.client.HTTPConnection(host, timeout=10)
    try:
        c.request("GET", "/ws", headers={"Upgrade": "websocket", "Connection": "Upgrade", "Origin": origin,
                                        "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ==", "Sec-WebSocket-Version": "13"})
        return c.getresponse().status
    except (http.client.RemoteDisconnected, ConnectionError):
        return 0
    finally:
        c.close()


def tone_map(rgb, exposure, gamma):
    """tonemap.js, mode "gamma": round(255 * clamp(v * 2^exposure, 0, 1) ^ (1/gamma))."""
    x = rgb.astype(np.float64) * 2.0 ** exposure
    x = np.clip(np.nan_to_num(x, nan=0.0), 0.0, 1.0)
    return np.floor(255.0 * x ** (1.0 / gamma) + 0.5).astype(np.int32)


def canvas_rgba(b):
    """The canvas's RGBA8 as numpy (h, w, 4), read back by getImageData."""
    v = b("eval", js="""(() => { const c = document.getElementById('image');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height);
        let s = ''; for (let i = 0; i < d.data.length; i += 8192) s += String.fromCharCode(...d.data.subarray(i, i + 8192));
        return {w: c.width, h: c.height, b64: btoa(s)}; })()""")
    import base64
    return np.frombuffer(base64.b64decode(v["b64"]), dtype=np.uint8).reshape(v["h"], v["w"], 4)


def test_job_page(tmp, daemons):
    t0 = time.monotonic()
    d = Daemon(tmp, threads=1, config=f"tcp_users: {{alice: {ALICE}, bob: {BOB}}}\n").start()
    daemons.append(d)
    alice, bob = login(d, "alice", ALICE), login(d, "bob", BOB)
    theirs = submit(bob, "bobs-frame", halt=op.halt(spp=4), priority=-5)  # someone else's: no controls
    r = subprocess.run([OMEGA, "view", "--host", d.tcp, "--listen", "0.0.0.0:0"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "loopback only" in r.stderr, (r.returncode, r.stderr)
    view = View(d.tcp)
    # A foreign web page may not open the WebSocket (its Origin is not the page's own).
    assert upgrade_status(view.url, view.url.rstrip("/")) == 101
    assert upgrade_status(view.url, "http://evil.example") != 101
    b = Browser()
    unix_view = None
    try:
        b("goto", url=view.url)
        # A wrong token: refused, nothing listed.
        b("type", selector="#user", text="alice")
        b("type", selector="#token", text="not-the-token-0123456789")
        b("click", selector="#login-button")
        msg = b("wait", js="!document.getElementById('login-error').hidden && document.getElementById('login-error').textContent")
        assert msg.startswith("auth_failed"), msg
        assert b("eval", js="document.getElementById('list').hidden") is True
        assert b("eval", js="document.querySelectorAll('#jobs tbody tr').length") == 0

        # The right one: the jobs listed, named as `omega list` names them; controls on alice's only.
        # Her job is submitted now, so that it still renders when the page opens it (max_running 1).
        b("type", selector="#token", text=ALICE)
        b("click", selector="#login-button")
        b("wait", js=f"document.querySelector('#jobs tr[data-job=\"{theirs}\"]')")
        live = submit(alice, "web-live", halt=op.halt(time_s=6.0), priority=5)
        b("wait", js=f"document.querySelector('#jobs tr[data-job=\"{live}\"]')")
        rows = b("eval", js="[...document.querySelectorAll('#jobs tbody tr')].map(r => [...r.cells].map(c => c.textContent))")
        listed = subprocess.run([OMEGA, "list", "--host", d.tcp], capture_output=True, text=True, timeout=30,
                                env=dict(os.environ, OMEGA_USER="alice", OMEGA_TOKEN=ALICE)).stdout
        assert sorted(int(r[0]) for r in rows) == sorted([live, theirs]), rows
        for r in rows:
            assert re.search(rf"^{r[0]}\s+\S+\s+{r[2]}\s+{r[3]}\s+.*\s{re.escape(r[6])}$", listed, re.M), (r, listed)
        assert b("eval", js=f"!!document.querySelector('button.cancel[data-job=\"{live}\"]')") is True
        assert b("eval", js=f"!!document.querySelector('button[data-job=\"{theirs}\"]')") is False

        # The running job: float tiles arrive and the image fills in, pass after pass, to the end.
        b("click", selector=f"#jobs tr[data-job=\"{live}\"] td:nth-child(7)")
        b("wait", js="window.omegaView.tiles >= 1", timeout=30)
        assert b("eval", js="document.getElementById('image').width") == 64
        b("wait", js="document.getElementById('job-status').dataset.state === 'done'", timeout=60)
        tiles = b("eval", js="window.omegaView.tiles")
        assert tiles >= 8, f"only {tiles} tiles: the 4 rects did not each arrive at least twice while rendering"
        assert b("eval", js="window.omegaView.curve.length") >= 2  # the error curve grew
        b("eval", js="(() => { const e = document.getElementById('exposure'); e.value = '0.5';"
                     " e.dispatchEvent(new Event('input')); return 1; })()")
        h = alice.job("fetch", live)
        assert h["type"] == "image", h
        img = omega_exr.decode(h["_payload"])
        x0, y0, x1, y1 = img.data_window
        want = tone_map(img.rgb, 0.5, 2.2)
        got = canvas_rgba(b)[y0:y1, x0:x1, :3].astype(np.int32)
        assert got.shape == want.shape, (got.shape, want.shape)
        diff = int(np.abs(got - want).max())
        assert diff <= 1, f"canvas differs from the fetched EXR by up to {diff} (8-bit)"
        assert want.max() > 0 and want.min() < 255, "the fetched image is flat"
        assert b("eval", js="window.omegaView.film.rgb.every(Number.isFinite) && window.omegaView.film.vr.every(Number.isFinite)")
        warnings = b("eval", js="document.getElementById('warnings').textContent")
        assert "waiting" not in warnings and warnings, warnings
        # The relative-error view paints something else (false colour from the variances).
        b("eval", js="(() => { const m = document.getElementById('mode'); m.value = 'error';"
                     " m.dispatchEvent(new Event('input')); return 1; })()")
        assert int(np.abs(canvas_rgba(b)[y0:y1, x0:x1, :3].astype(np.int32) - want).max()) > 1
        b("eval", js="(() => { const m = document.getElementById('mode'); m.value = 'gamma';"
                     " m.dispatchEvent(new Event('input')); return 1; })()")
        # The download: the page receives the current EXR, the very bytes of the fetch.
        b("click", selector="#download")
        size = b("wait", js="window.omegaView.lastExr && window.omegaView.lastExr.size")
        assert size == len(h["_payload"]), (size, len(h["_payload"]))
        b("hover", selector="#image")
        os.makedirs(ARTEFACTS, exist_ok=True)
        shot = os.path.join(ARTEFACTS, "web_job_page.png")
        b("screenshot", path=shot)

        # Priority, pause, resume, pause and cancel from the page; each checked via the protocol.
        hold = submit(alice, "web-hold", halt=op.halt(spp=1 << 20))
        b("click", selector="#back")
        wait_state(alice, hold, ["running"], timeout=30)
        b("wait", js=f"document.querySelector('button.pause[data-job=\"{hold}\"]')")
        # Priority, typed into the row's field (applied on change), checked via the protocol.
        b("type", selector=f"input.priority[data-job=\"{hold}\"]", text="7")
        b("eval", js="(() => { const e = document.activeElement; e.dispatchEvent(new Event('change')); e.blur(); return 1; })()")
        deadline = time.monotonic() + 20
        while alice.job("status", hold)["priority"] != 7:
            assert time.monotonic() < deadline, "set_priority from the page did not arrive"
            time.sleep(0.1)
        b("wait", js=f"document.querySelector('#jobs tr[data-job=\"{hold}\"]').cells[2].textContent === '7'")
        b("click", selector=f"button.pause[data-job=\"{hold}\"]")
        wait_state(alice, hold, ["paused"], timeout=30)
        b("wait", js=f"document.querySelector('button.resume[data-job=\"{hold}\"]')")
        b("click", selector=f"button.resume[data-job=\"{hold}\"]")
        wait_state(alice, hold, ["running", "queued"], timeout=30)
        b("wait", js=f"document.querySelector('button.pause[data-job=\"{hold}\"]')")
        b("click", selector=f"button.pause[data-job=\"{hold}\"]")
        wait_state(alice, hold, ["paused"], timeout=30)
        b("wait", js=f"document.querySelector('button.cancel[data-job=\"{hold}\"]') && "
                     f"document.querySelector('#jobs tr[data-job=\"{hold}\"]').cells[1].textContent === 'paused'")
        b("click", selector=f"button.cancel[data-job=\"{hold}\"]")
        wait_state(alice, hold, ["cancelled"], timeout=30)
        b("wait", js=f"document.querySelector('#jobs tr[data-job=\"{hold}\"]').cells[1].textContent === 'cancelled'")
        assert bob.job("status", theirs)["state"] in ("queued", "running", "done"), "bob's job was touched"

        # Over the daemon's Unix socket the page proves itself with the access key omega view
        # printed; it then acts as the uid running omega view, which owns none of these jobs.
        unix_view = View(d.unix)
        b("goto", url=unix_view.url)
        b("type", selector="#token", text="0" * 32)
        b("click", selector="#login-button")
        msg = b("wait", js="!document.getElementById('login-error').hidden && document.getElementById('login-error').textContent")
        assert msg.startswith("auth_failed"), msg
        b("type", selector="#token", text=unix_view.key)
        b("click", selector="#login-button")
        who = b("wait", js="!document.getElementById('list').hidden && document.getElementById('who').textContent")
        assert who.startswith(f"{os.getuid()} @"), who
        b("wait", js=f"document.querySelector('#jobs tr[data-job=\"{live}\"]')")
        assert b("eval", js="document.querySelectorAll('#jobs button').length") == 0
        print(f"screenshot: {shot} ({tiles} tiles; {time.monotonic() - t0:.1f} s)", flush=True)
    finally:
        b.close()
        view.stop()
        if unix_view:
            unix_view.stop()


if __name__ == "__main__":
    t = Test()
    t.run(test_job_page)
    t.exit()
