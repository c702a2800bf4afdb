"""A small OpenEXR reader for what omegad sends: single-part scanline files, compression NONE,
ZIPS or ZIP (omegad writes images with ZIP, streamed tiles with NONE), channels HALF, FLOAT or
UINT without subsampling. Anything else raises ExrError. The header is read with the standard library; pixels need numpy (zlib does the
inflating, numpy the predictor and the byte interleaving that OpenEXR's ZIP adds).
"""
from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass, field

MAGIC = b"\x76\x2f\x31\x01"
_COMPRESSION = {0: "none", 1: "rle", 2: "zips", 3: "zip", 4: "piz", 5: "pxr24", 6: "b44", 7: "b44a",
                8: "dwaa", 9: "dwab"}
_LINES_PER_CHUNK = {"none": 1, "zips": 1, "zip": 16}
_PIXEL_TYPES = {0: ("uint", 4, "<u4"), 1: ("half", 2, "<f2"), 2: ("float", 4, "<f4")}
# Version flags that make a file something other than one scanline image.
_TILED, _NON_IMAGE, _MULTIPART = 0x200, 0x800, 0x1000


class ExrError(ValueError):
    pass


@dataclass
class Header:
    attributes: dict            # name -> value (int, float, str, tuple; raw bytes for other types)
    channels: list              # (name, pixel type name, byte size, numpy dtype), in file order
    compression: str
    data_window: tuple          # (x0, y0, x1, y1), half-open like the protocol's tile rect
    display_window: tuple       # (x0, y0, x1, y1), half-open
    end: int                    # offset of the line offset table


@dataclass
class ExrImage:
    header: Header
    channels: dict = field(default_factory=dict)  # name -> numpy array (height, width)

    @property
    def attributes(self) -> dict:
        return self.header.attributes

    @property
    def data_window(self) -> tuple:
        return self.header.data_window

    def stack(self, names) -> "numpy.ndarray":  # noqa: F821
        import numpy as np
        return np.stack([self.channels[n] for n in names], axis=-1)

    @property
    def rgb(self):
        """float32 array (height, width, 3) of the data window."""
        return self.stack(("R", "G", "B"))

    @property
    def variance(self):
        """The per-pixel variance of the estimate (var.R, var.G, var.B) as (height, width, 3), or None."""
        names = ("var.R", "var.G", "var.B")
        return self.stack(names) if all(n in self.channels for n in names) else None


class _Reader:
    def __init__(self, data: bytes, pos: int = 0):
        self.data, self.pos = data, pos

    def take(self, n: int) -> bytes:
        if n < 0 or self.pos + n > len(self.data):
            raise ExrError("truncated EXR header")
        b = self.data[self.pos:self.pos + n]
        self.pos += n
        return b

    def cstr(self) -> str:
        end = self.data.find(b"\0", self.pos)
        if end < 0 or end - self.pos > 255:
            raise ExrError("bad name in EXR header")
        s = self.data[self.pos:end].decode("latin-1")
        self.pos = end + 1
        return s

    def unpack(self, fmt: str):
        s = struct.Struct(fmt)
        return s.unpack(self.take(s.size))


def _channels(value: bytes) -> list:
    r = _Reader(value)
    out = []
    while r.pos < len(value) and value[r.pos] != 0:
        name = r.cstr()
        ptype, _linear, _r1, _r2, _r3, xs, ys = r.unpack("<iBBBBii")
        if ptype not in _PIXEL_TYPES:
            raise ExrError(f"channel {name}: unknown pixel type {ptype}")
        if xs != 1 or ys != 1:
            raise ExrError(f"channel {name} is subsampled")
        out.append((name,) + _PIXEL_TYPES[ptype])
    return out


def _attribute(type_name: str, value: bytes):
    try:
        if type_name == "int":
            return struct.unpack("<i", value)[0]
        if type_name == "float":
            return struct.unpack("<f", value)[0]
        if type_name == "double":
            return struct.unpack("<d", value)[0]
        if type_name == "string":
            return value.decode("utf-8", "replace")
        if type_name in ("box2i", "v2i", "v3i"):
            return struct.unpack(f"<{len(value) // 4}i", value)
        if type_name in ("box2f", "v2f", "v3f"):
            return struct.unpack(f"<{len(value) // 4}f", value)
        if type_name in ("compression", "lineOrder"):
            return value[0]
    except (struct.error, IndexError):
        raise ExrError(f"bad {type_name} attribute") from None
    return value


def read_header(data: bytes) -> Header:
    """Parses the header alone (no numpy needed)."""
    if len(data) < 8 or data[:4] != MAGIC:
        raise ExrError("not an OpenEXR file")
    version = struct.unpack_from("<I", data, 4)[0]
    if version & 0xFF != 2:
        raise ExrError(f"unsupported OpenEXR version {version & 0xFF}")
    if version & (_TILED | _NON_IMAGE | _MULTIPART):
        raise ExrError("tiled, deep and multi-part EXR files are not supported")
    r = _Reader(data, 8)
    attrs, channels = {}, None
    while True:
        name = r.cstr()
        if not name:
            break
        type_name = r.cstr()
        (size,) = r.unpack("<i")
        value = r.take(size)
        if name == "channels" and type_name == "chlist":
            channels = _channels(value)
            attrs[name] = [c[0] for c in channels]
        else:
            attrs[name] = _attribute(type_name, value)
    for key in ("dataWindow", "displayWindow", "compression"):
        if key not in attrs:
            raise ExrError(f"EXR header lacks {key}")
    if not channels:
        raise ExrError("EXR header lacks channels")
    compression = _COMPRESSION.get(attrs["compression"], str(attrs["compression"]))
    x0, y0, x1, y1 = attrs["dataWindow"]
    dx0, dy0, dx1, dy1 = attrs["displayWindow"]
    if x1 < x0 or y1 < y0:
        raise ExrError("empty data window")
    return Header(attrs, channels, compression, (x0, y0, x1 + 1, y1 + 1), (dx0, dy0, dx1 + 1, dy1 + 1), r.pos)


def _unzip(chunk: bytes, expected: int):
    import numpy as np
    try:
        raw = zlib.decompress(chunk)
    except zlib.error as e:
        raise ExrError(f"bad ZIP chunk: {e}") from None
    if len(raw) != expected:
        raise ExrError("ZIP chunk has the wrong size")
    # Undo the predictor (each byte stored as the difference to the previous, +128), then the
    # split of the bytes into two halves (even positions first, odd second).
    t = np.frombuffer(raw, dtype=np.uint8).copy()
    t[1:] -= np.uint8(128)
    t = np.cumsum(t, dtype=np.uint8)
    out = np.empty_like(t)
    half = (len(t) + 1) // 2
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    return out


def decode(data: bytes) -> ExrImage:
    """Every channel of the data window as a numpy array (height, width): float32 for HALF and
    FLOAT channels, uint32 for UINT. Raises ExrError for a file it cannot read."""
    import numpy as np
    data = bytes(data)
    h = read_header(data)
    if h.compression not in _LINES_PER_CHUNK:
        raise ExrError(f"EXR compression {h.compression} is not supported (omegad writes none or zip)")
    x0, y0, x1, y1 = h.data_window
    width, height = x1 - x0, y1 - y0
    per_chunk = _LINES_PER_CHUNK[h.compression]
    chunks = (height + per_chunk - 1) // per_chunk
    line_bytes = width * sum(c[2] for c in h.channels)
    if h.end + 8 * chunks > len(data):
        raise ExrError("truncated EXR offset table")
    offsets = struct.unpack_from(f"<{chunks}Q", data, h.end)
    planes = {c[0]: np.empty((height, width), dtype=np.float32 if c[1] != "uint" else np.uint32)
              for c in h.channels}
    seen = set()
    for off in offsets:
        if off + 8 > len(data):
            raise ExrError("EXR chunk offset out of range")
        y, size = struct.unpack_from("<ii", data, off)
        row = y - y0
        if row < 0 or row >= height or row % per_chunk or row in seen or size < 0 or off + 8 + size > len(data):
            raise ExrError("bad EXR chunk")
        seen.add(row)
        lines = min(per_chunk, height - row)
        expected = lines * line_bytes
        body = data[off + 8:off + 8 + size]
        if size < expected and h.compression != "none":
            block = _unzip(body, expected)
        elif size == expected:
            block = np.frombuffer(body, dtype=np.uint8)  # stored raw: compression did not help
        else:
            raise ExrError("EXR chunk has the wrong size")
        block = block.reshape(lines, line_bytes)
        col = 0
        for name, _type, nbytes, dtype in h.channels:  # per line: each channel's samples in turn
            span = width * nbytes
            values = np.ascontiguousarray(block[:, col:col + span]).view(dtype).reshape(lines, width)
            planes[name][row:row + lines] = values
            col += span
    if len(seen) != chunks:
        raise ExrError("EXR chunks missing")
    return ExrImage(h, planes)
