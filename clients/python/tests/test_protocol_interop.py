#!/usr/bin/env python3
"""Interop: frames built by the Python client package's codec (clients/python/src/omega/codec.py,
written from docs/protocol.md) must survive omega_frame_echo (C++ decode, typed decode, re-encode)
byte for byte, and must equal the hex dumps printed in docs/protocol.md. Client-to-daemon messages
come from the package's builders; the daemon's replies, which the package only reads, are built
here from the documented field order with its encode_frame, and read back with its Decoder.

usage: test_protocol_interop.py PATH/TO/omega_frame_echo PATH/TO/docs/protocol.md
"""
import hashlib
import json
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src"))
from omega import codec as op  # noqa: E402

MESH = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
EXR = b"\x76\x2f\x31\x01\x02\x00\x00\x00"
NONCE = "8f3a" * 16
SCENE = b"omega: 1\nshapes:\n  - {type: mesh, file: meshes/tri.obj}\n"


def reply(type, id, **fields):
    """A daemon-to-client frame: keyword order is the documented field order."""
    return op.encode_frame({"type": type, "id": id, **fields})


def examples():
    """The messages of docs/protocol.md's examples, in the order the page shows them."""
    sha = hashlib.sha256(MESH).hexdigest()
    prog = {"pass": 3, "spp": 12, "elapsed_s": 4.25, "rel_error": 0.031, "samples_per_s": 1.5e6}
    info = {"job": 42, "name": "cornell", "state": "running", "priority": 5, "owner": "alice",
            "halt": op.halt(spp=64), "progress": prog}
    done_prog = {k: v for k, v in prog.items() if k != "rel_error"}
    return [
        ("hello", op.hello(1, "omega/0.1")),
        ("welcome (unix socket, peer credentials)",
         reply("welcome", 1, version=1, server="omegad/0.1", auth="peer", user="1000")),
        ("welcome (TCP, HMAC challenge)",
         reply("welcome", 1, version=1, server="omegad/0.1", auth="hmac-sha256", nonce=NONCE)),
        ("auth", op.auth(2, "alice", op.auth_mac(b"s3cret", NONCE, "alice"))),
        ("ok", op.bare("ok", 2)),
        ("error", reply("error", 3, code="scene_invalid", message="scene.yaml:4: sensor.fov: expected a number")),
        ("ping", op.bare("ping", 4)),
        ("pong", op.bare("pong", 4)),
        ("bye", op.bare("bye", 0)),
        ("submit", op.submit(5, SCENE, name="bunny", halt_=op.halt(spp=64, time_s=30), seed=7, integrator="bdpt",
                             assets=[op.asset_ref("meshes/tri.obj", sha, len(MESH))])),
        ("need_assets", reply("need_assets", 5, missing=[sha])),
        ("asset", op.asset(5, MESH)),
        ("accepted", reply("accepted", 5, job=42)),
        ("status", op.job_request("status", 6, 42)),
        ("job_info", reply("job_info", 6, **info)),
        ("list", op.bare("list", 7)),
        ("job_list", reply("job_list", 7, jobs=[info])),
        ("cancel", op.job_request("cancel", 8, 42)),
        ("pause", op.job_request("pause", 9, 42)),
        ("resume", op.job_request("resume", 10, 42)),
        ("set_priority", op.set_priority(11, 42, -3)),
        ("delete", op.job_request("delete", 12, 42)),
        ("subscribe", op.job_request("subscribe", 13, 42)),
        ("unsubscribe", op.job_request("unsubscribe", 14, 42)),
        ("tile", op.encode_frame({"type": "tile", "id": 13, "job": 42, "rect": [32, 0, 64, 32], "pass": 3,
                                  "spp": 12, "version": 3}, EXR)),
        ("progress", reply("progress", 13, job=42, state="running", progress=prog)),
        ("done", reply("done", 13, job=42, state="done", progress=done_prog)),
        ("fetch", op.job_request("fetch", 15, 42)),
        ("image", op.encode_frame({"type": "image", "id": 15, "job": 42, "pass": 3, "spp": 12, "width": 512,
                                   "height": 512}, EXR)),
        ("work_request", op.encode_frame({"type": "work_request", "id": 1, "threads": 4, "name": "node17:4242"})),
        ("work_unit", op.encode_frame({"type": "work_unit", "id": 1, "job": 42, "unit": 3, "begin": 48, "end": 64,
                                       "seed": 7, "name": "bunny", "integrator": "bdpt",
                                       "assets": [op.asset_ref("meshes/tri.obj", sha, len(MESH))]}, SCENE)),
        ("asset_request", op.encode_frame({"type": "asset_request", "id": 2, "job": 42, "sha256": sha})),
        ("unit_result", op.encode_frame({"type": "unit_result", "id": 3, "job": 42, "unit": 3, "begin": 48, "end": 64,
                                         "time_s": 2.5, "samples_per_s": 1.2e6}, EXR)),
        ("unit_stop", op.encode_frame({"type": "unit_stop", "id": 0, "job": 42, "unit": 3, "reason": "cancelled"})),
    ]


def doc_dumps(path):
    """{title: bytes} from the '#### title' headings and the hexdump blocks under them."""
    text = open(path, encoding="utf-8").read()
    text = text[text.index("\n## Examples\n"):]
    out = {}
    for m in re.finditer(r"^#### (.+?)\n(.*?)^```\n(.*?)^```", text, re.S | re.M):
        data = bytearray()
        for line in m.group(3).splitlines():
            hexpart = line[10:58]  # between the offset and the |ascii| column
            data += bytes(int(t, 16) for t in hexpart.split())
        out[m.group(1)] = bytes(data)
    return out


def echo(tool, data):
    return subprocess.run([tool], input=data, capture_output=True, timeout=60)


def main():
    tool, doc = sys.argv[1], sys.argv[2]
    failures = []
    dumps = doc_dumps(doc)
    stream = b""
    for title, frame in examples():
        if dumps.get(title) != frame:
            failures.append(f"{title}: Python bytes differ from the docs hex dump")
        r = echo(tool, frame)
        if r.returncode != 0 or r.stdout != frame:
            failures.append(f"{title}: echo changed the frame (rc {r.returncode}, {r.stderr.decode()!r})")
        stream += frame

    # Everything at once, and the decoder in Python reading what C++ wrote.
    r = echo(tool, stream)
    if r.stdout != stream:
        failures.append("multi-frame stream did not round-trip")
    dec = op.Decoder()
    got = []
    for i in range(0, len(r.stdout), 7):  # an awkward split on purpose
        dec.feed(r.stdout[i:i + 7])
        got += list(dec.frames())
    want = []
    for _, f in examples():
        _, hlen, plen = op.PRELUDE.unpack_from(f)
        want.append((json.loads(f[16:16 + hlen]), f[16 + hlen:]))
    if got != want or dec.buffered:
        failures.append("Python decoder read back the wrong frames")

    # The package's decoder names stream failures as the docs do.
    for data, code in [(b"GET / HTTP/1.1\r\n\r\n", "bad_magic"), (b"OMX", "bad_magic"),
                       (op.PRELUDE.pack(op.MAGIC, 2, 1 << 60) + b"{}", "payload_too_large"),
                       (op.PRELUDE.pack(op.MAGIC, 1 << 21, 0), "header_too_large"),
                       (op.PRELUDE.pack(op.MAGIC, 2, 0) + b"[]", "header_not_mapping"),
                       (op.PRELUDE.pack(op.MAGIC, 2, 0) + b"\xff{", "header_not_utf8")]:
        d = op.Decoder()
        d.feed(data)
        try:
            list(d.frames())
            failures.append(f"Python decoder accepted {data[:20]!r}")
        except op.FrameError as e:
            if e.code != code:
                failures.append(f"Python decoder: {e.code} for {data[:20]!r}, expected {code}")

    # Errors reach stderr with the names the docs give them.
    for data, want in [
        (b"GET / HTTP/1.1\r\n\r\n", "frame_error bad_magic"),
        (op.encode_frame({"type": "launch", "id": 1}), "frame_error unknown_type"),
        (op.PRELUDE.pack(op.MAGIC, 2, 1 << 60) + b"{}", "frame_error payload_too_large"),
        (op.bare("ping", 1)[:-1], "frame_error truncated"),
        (op.encode_frame({"type": "status", "id": 1, "job": "x"}), "decode_error wrong_type"),
    ]:
        r = echo(tool, data)
        if r.returncode != 1 or not r.stderr.decode().startswith(want):
            failures.append(f"expected {want!r}, got rc {r.returncode} {r.stderr.decode()!r}")

    # Unicode and escapes survive as the canonical form defines them.
    tricky = reply("error", 9, code="internal", message="tab\there \"q\" \\ é 🎨 \x01")
    r = echo(tool, tricky)
    if r.stdout != tricky:
        failures.append(f"string escaping differs: {r.stdout!r} vs {tricky!r}")

    for f in failures:
        print("FAIL:", f)
    print(f"{len(examples())} examples checked, {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
