#!/usr/bin/env python3
"""Regenerates fuzz/corpus/{frame_decoder,messages,scene_yaml,mitsuba_xml} from the repository: every
example header in docs/protocol.md, the example scenes, and the XML scenes in the importer's tests.
Usage: python3 fuzz/make_seeds.py  (from the repository root). tile_exr seeds come from a real
daemon (tests/daemon) and are committed as they are."""
import hashlib
import os
import re
import struct

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.path.join(ROOT, "fuzz", "corpus")


def put(kind, data):
    d = os.path.join(CORPUS, kind)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, hashlib.sha1(data).hexdigest()[:16]), "wb") as f:
        f.write(data)


doc = open(os.path.join(ROOT, "docs", "protocol.md"), encoding="utf-8").read()
for m in re.finditer(r"^Header: `(\{.*\})`(?: · payload: (\d+) bytes)?$", doc, re.M):
    header = m.group(1).encode()
    payload = b"x" * int(m.group(2) or 0)
    put("messages", header + (b"\0" + payload if payload else b""))
    frame = b"OMG1" + struct.pack("<IQ", len(header), len(payload)) + header + payload
    put("frame_decoder", bytes([7]) + frame + frame)  # first byte: the chunk size
for name in os.listdir(os.path.join(ROOT, "scenes")):
    if name.endswith(".yaml"):
        put("scene_yaml", open(os.path.join(ROOT, "scenes", name), "rb").read())
for src in ("renderer/scene/mitsuba_importer_test.cpp", "tests/integration/mitsuba_cli_test.cpp"):
    text = open(os.path.join(ROOT, src), encoding="utf-8").read()
    for m in re.finditer(r'R"\w*\((.*?)\)\w*"', text, re.S):
        if "<scene" in m.group(1):
            put("mitsuba_xml", m.group(1).encode())
for src in ("renderer/scene/scene_parser_test.cpp",):
    text = open(os.path.join(ROOT, src), encoding="utf-8").read()
    for m in re.finditer(r'R"\w*\((.*?)\)\w*"', text, re.S):
        if "omega:" in m.group(1):
            put("scene_yaml", m.group(1).encode())
