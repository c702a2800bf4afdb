"""What a submit sends: the scene YAML plus the files it names, each by SHA-256 and size
(docs/protocol.md, "Submit exchange"; the C++ client's client/asset_scan.cpp).

The standard library has no YAML parser, so the scene is scanned as text for `file:` keys (block
or flow style, plain or quoted values; comments and block scalars skipped). Every `file:` value
that names an existing regular file is sent, which covers what the C++ client sends (mesh shapes,
bitmap textures of any material parameter, an envmap light's image). A clean relative name (`meshes/bunny.obj`) is kept; any other
(absolute, or climbing out with `..`) becomes `assets/<first 16 hex of sha256>/<basename>` and
only that value is rewritten in the text, so the rest of the scene travels byte for byte. The
files a mesh names inside itself (an OBJ's `mtllib`, a glTF's relative `buffers[].uri` and
`images[].uri`) travel beside it under the same relative names. A `file:` naming nothing is
left alone: omegad refuses the scene with `scene_invalid` and the line.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
import struct
import urllib.parse
import warnings
from dataclasses import dataclass, field


@dataclass
class Asset:
    name: str    # as the (possibly rewritten) scene names it: relative, '/'-separated
    path: str    # where the bytes are on this machine
    sha256: str
    size: int


@dataclass
class Scene:
    path: str
    name: str    # the file's stem: names the job
    yaml: bytes  # the submit payload
    assets: list[Asset] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)


def clean_relative(name: str) -> bool:
    """What the protocol accepts as an asset name as is: relative, '/'-separated, no empty, '.'
    or '..' component, no backslash or NUL."""
    if not name or name.startswith("/") or "\\" in name or "\0" in name:
        return False
    return all(part not in ("", ".", "..") for part in name.split("/"))


def sha256_file(path: str) -> tuple[str, int]:
    h = hashlib.sha256()
    size = 0
    with open(path, "rb") as f:
        while chunk := f.read(1 << 20):
            h.update(chunk)
            size += len(chunk)
    return h.hexdigest(), size


# ---- finding `file:` values in YAML text ----

_TOKEN_BEFORE = " \t\n{[,"
_KEY = re.compile(r"""(file|"file"|'file')[ \t]*:""")


def _skip_quoted(text: str, i: int) -> int:
    """i at an opening quote; returns the index after the closing one (or len(text))."""
    q = text[i]
    i += 1
    while i < len(text):
        c = text[i]
        if q == '"' and c == "\\":
            i += 2
            continue
        if c == q:
            if q == "'" and text[i + 1:i + 2] == "'":  # '' is an escaped quote
                i += 2
                continue
            return i + 1
        i += 1
    return i


def _unquote(raw: str) -> str | None:
    if raw.startswith("'"):
        return raw[1:-1].replace("''", "'")
    try:  # a YAML double-quoted scalar is JSON for every escape a path needs
        v = json.loads(raw)
        return v if isinstance(v, str) else None
    except ValueError:
        return None


def _line_indent(text: str, i: int) -> int:
    start = text.rfind("\n", 0, i) + 1
    n = start
    while n < len(text) and text[n] == " ":
        n += 1
    return n - start


def _skip_block_scalar(text: str, i: int) -> int:
    """i at `|` or `>`: skips the indicator line and every following line indented deeper than
    the line holding the indicator (blank lines included)."""
    indent = _line_indent(text, i)
    nl = text.find("\n", i)
    if nl < 0:
        return len(text)
    j = nl + 1
    while j < len(text):
        end = text.find("\n", j)
        end = len(text) if end < 0 else end
        line = text[j:end]
        if line.strip() and len(line) - len(line.lstrip(" ")) <= indent:
            return j
        j = end + 1
    return len(text)


def find_file_values(text: str) -> list[tuple[int, int, str]]:
    """(start, end, value) of every `file:` value, end exclusive; quotes are inside the span."""
    out = []
    depth = 0  # flow collection nesting: plain scalars end at , ] } inside one
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        at_token = i == 0 or text[i - 1] in _TOKEN_BEFORE
        if c == "#" and at_token:
            nl = text.find("\n", i)
            i = n if nl < 0 else nl
            continue
        if not at_token:
            if c in "]}" and depth:
                depth -= 1
            i += 1
            continue
        if c in "\"'":
            m = _KEY.match(text, i)
            if not m:
                i = _skip_quoted(text, i)
                continue
        elif c in "{[":
            depth += 1
            i += 1
            continue
        elif c in "]}":
            depth = max(0, depth - 1)
            i += 1
            continue
        elif c in "|>" and i > 0 and text[i - 1] in " \t":
            i = _skip_block_scalar(text, i)
            continue
        m = _KEY.match(text, i)
        if not m or (m.end() < n and text[m.end()] not in " \t\n\r" and m.group(1) == "file"):
            i += 1
            continue
        j = m.end()
        while j < n and text[j] in " \t":
            j += 1
        if j >= n or text[j] in "\r\n#|>&*!":
            # No value on the line, a block scalar, an anchor, an alias or a tag: not a path we
            # can rewrite in place; omegad reads the scene as it is.
            i = j
            continue
        if text[j] in "\"'":
            end = _skip_quoted(text, j)
            value = _unquote(text[j:end])
        else:
            end = j
            stops = ",]}\n\r" if depth else "\n\r"
            while end < n and text[end] not in stops and not (text[end] == "#" and text[end - 1] in " \t"):
                end += 1
            while end > j and text[end - 1] in " \t":
                end -= 1
            value = text[j:end]
        if value:
            out.append((j, end, value))
        i = end
    return out


# ---- files a mesh names inside itself ----

def _obj_refs(data: bytes) -> list[list[str]]:
    """Each `mtllib` line's candidates: the whole rest of the line, then its words."""
    refs = []
    for line in data.decode("utf-8", "surrogateescape").splitlines():
        s = line.strip()
        if s.startswith("mtllib") and s[6:7] in (" ", "\t"):
            rest = s[6:].strip()
            if rest:
                refs.append([rest] + (rest.split() if len(rest.split()) > 1 else []))
    return refs


def _gltf_json(data: bytes, binary: bool):
    if binary:  # .glb: 12-byte header, then the JSON chunk first
        if len(data) < 20 or data[:4] != b"glTF":
            return None
        length, kind = struct.unpack_from("<II", data, 12)
        if kind != 0x4E4F534A:
            return None
        data = data[20:20 + length]
    try:
        return json.loads(data.decode("utf-8"))
    except ValueError:
        return None


def _gltf_refs(data: bytes, binary: bool) -> list[list[str]]:
    doc = _gltf_json(data, binary)
    refs = []
    if not isinstance(doc, dict):
        return refs
    for key in ("buffers", "images"):
        items = doc.get(key)
        for item in items if isinstance(items, list) else []:
            uri = item.get("uri") if isinstance(item, dict) else None
            # data: URIs are inline; anything with a scheme is not a file beside the mesh.
            if isinstance(uri, str) and uri and not re.match(r"^[A-Za-z][A-Za-z0-9+.-]*:", uri):
                refs.append([urllib.parse.unquote(uri)])
    return refs


def inner_refs(path: str) -> list[list[str]]:
    """The files a mesh file names, as written in it (each a list of candidate spellings)."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in (".obj", ".gltf", ".glb"):
        return []
    with open(path, "rb") as f:
        data = f.read()
    return _obj_refs(data) if ext == ".obj" else _gltf_refs(data, ext == ".glb")


# ---- the scene ----

def scan_scene(scene_path: str) -> Scene:
    """Reads a scene and hashes every file it names. Raises OSError for an unreadable file."""
    scene_path = os.fspath(scene_path)
    with open(scene_path, "rb") as f:
        raw = f.read()
    # surrogateescape: bytes that are not UTF-8 travel unchanged (omegad reports them).
    text = raw.decode("utf-8", "surrogateescape")
    scene = Scene(path=scene_path, name=os.path.splitext(os.path.basename(scene_path))[0], yaml=raw)
    base = os.path.dirname(scene_path) or "."
    by_name: dict[str, Asset] = {}

    def add(a: Asset):
        if a.name not in by_name:  # the same file named twice is sent once
            by_name[a.name] = a
            scene.assets.append(a)

    def add_inner(mesh: Asset, written: str):
        mesh_dir = os.path.dirname(mesh.path)
        name_dir = os.path.dirname(mesh.name)
        for candidates in inner_refs(mesh.path):
            found = [c for c in candidates[:1] if os.path.isfile(os.path.join(mesh_dir, c))] or \
                    [c for c in candidates[1:] if os.path.isfile(os.path.join(mesh_dir, c))]
            for ref in found:
                p = os.path.normpath(os.path.join(mesh_dir, ref))
                rel = os.path.relpath(p, mesh_dir).replace(os.sep, "/")
                if os.path.isabs(ref) or not clean_relative(rel):
                    scene.warnings.append(f"{scene_path}: mesh '{written}' names '{ref}' outside its own folder; "
                                          "it is not sent, and omegad will refuse the mesh")
                    continue
                sha, size = sha256_file(p)
                add(Asset(f"{name_dir}/{rel}" if name_dir else rel, p, sha, size))

    rewrites = []
    for start, end, written in find_file_values(text):
        p = os.path.normpath(written if os.path.isabs(written) else os.path.join(base, written))
        if not os.path.isfile(p):
            continue
        sha, size = sha256_file(p)
        if clean_relative(written):
            name = written
        else:
            name = f"assets/{sha[:16]}/{os.path.basename(p)}"
            rewrites.append((start, end, json.dumps(name, ensure_ascii=False)))
        a = Asset(name, p, sha, size)
        add(a)
        add_inner(a, written)
    for start, end, new in reversed(rewrites):
        text = text[:start] + new + text[end:]
    if rewrites:
        scene.yaml = text.encode("utf-8", "surrogateescape")
    for w in scene.warnings:
        warnings.warn(w, stacklevel=3)
    return scene
