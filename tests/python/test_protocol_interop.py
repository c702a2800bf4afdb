#!/usr/bin/env python3
"""Interop: frames built by the Python codec (tests/python/omega_proto.py, written from
docs/protocol.md) must survive omega_frame_echo (C++ decode, typed decode, re-encode) byte for
byte, and must equal the hex dumps printed in docs/protocol.md.

usage: test_protocol_interop.py PATH/TO/omega_frame_echo PATH/TO/docs/protocol.md
"""
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omega_proto as op  # noqa: E402

MESH = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
EXR = b"\x76\x2f\x31\x01\x02\x00\x00\x00"
NONCE = "8f3a" * 16
SCENE = b"omega: 1\nshapes:\n  - {type: mesh, file: meshes/tri.obj}\n"


def examples():
    """The messages of docs/protocol.md's examples, in the order the page shows them."""
    sha = op.hashlib.sha256(MESH).hexdigest()
    prog = op.progress_info(3, 12, 4.25, 1.5e6, rel_error=0.031)
    info = op.job_info_fields(42, "cornell", "running", 5, "alice", op.halt(spp=64), prog)
    return [
        ("hello", op.hello(1, "omega/0.1")),
        ("welcome (unix socket, peer credentials)", op.welcome(1, 1, "omegad/0.1", "peer", user="1000")),
        ("welcome (TCP, HMAC challenge)", op.welcome(1, 1, "omegad/0.1", "hmac-sha256", nonce=NONCE)),
        ("auth", op.auth(2, "alice", op.auth_mac(b"s3cret", NONCE, "alice"))),
        ("ok", op.bare("ok", 2)),
        ("error", op.error(3, "scene_invalid", "scene.yaml:4: sensor.fov: expected a number")),
        ("ping", op.bare("ping", 4)),
        ("pong", op.bare("pong", 4)),
        ("bye", op.bare("bye", 0)),
        ("submit", op.submit(5, SCENE, name="bunny", halt_=op.halt(spp=64, time_s=30), seed=7,
                             integrator="bdpt", assets=[("meshes/tri.obj", MESH)])),
        ("need_assets", op.need_assets(5, [sha])),
        ("asset", op.asset(5, MESH)),
        ("accepted", op.encode_frame({"type": "accepted", "id": 5, "job": 42})),
        ("status", op.job_request("status", 6, 42)),
        ("job_info", op.job_info(6, info)),
        ("list", op.bare("list", 7)),
        ("job_list", op.job_list(7, [info])),
        ("cancel", op.job_request("cancel", 8, 42)),
        ("pause", op.job_request("pause", 9, 42)),
        ("resume", op.job_request("resume", 10, 42)),
        ("set_priority", op.set_priority(11, 42, -3)),
        ("delete", op.job_request("delete", 12, 42)),
        ("subscribe", op.job_request("subscribe", 13, 42)),
        ("unsubscribe", op.job_request("unsubscribe", 14, 42)),
        ("tile", op.tile(13, 42, (32, 0, 64, 32), 3, 12, 3, EXR)),
        ("progress", op.progress(13, 42, "running", prog)),
        ("done", op.done(13, 42, "done", op.progress_info(3, 12, 4.25, 1.5e6))),
        ("fetch", op.job_request("fetch", 15, 42)),
        ("image", op.image(15, 42, 3, 12, 512, 512, EXR)),
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
    for i in range(0, len(r.stdout), 7):  # an awkward split on purpose
        dec.feed(r.stdout[i:i + 7])
    got = []
    dec.feed(b"")
    got = list(dec.frames())
    if [h["type"] for h, _ in got] != [op.json.loads(f[16:16 + op.PRELUDE.unpack_from(f)[1]])["type"]
                                       for _, f in examples()]:
        failures.append("Python decoder read back the wrong frames")

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
    tricky = op.error(9, "internal", "tab\there \"q\" \\ é 🎨 \x01")
    r = echo(tool, tricky)
    if r.stdout != tricky:
        failures.append(f"string escaping differs: {r.stdout!r} vs {tricky!r}")

    for f in failures:
        print("FAIL:", f)
    print(f"{len(examples())} examples checked, {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
