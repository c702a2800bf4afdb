#!/usr/bin/env python3
"""The package's EXR reader (omega.exr, needs numpy) against what omegad sends and against files
built here from the OpenEXR layout. test_client.py runs it in process when its interpreter has
numpy, else under another python3 that has it.

usage: decode_check.py SPP IMAGE.exr [X0,Y0,X1,Y1=TILE.exr ...]   (prints OK or raises)
"""
import os
import struct
import sys
import zlib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src"))
import numpy as np  # noqa: E402

from omega import exr  # noqa: E402


def attr(name, type_name, value):
    return name.encode() + b"\0" + type_name.encode() + b"\0" + struct.pack("<i", len(value)) + value


def handmade(compression, width=5, height=19):
    """A scanline EXR with a FLOAT, a HALF and a UINT channel, written from the file layout:
    per chunk of lines, per line, each channel's samples in name order."""
    ys, xs = np.mgrid[0:height, 0:width]
    planes = {"A": (ys * 10 + xs).astype(np.float32) / 4, "B": (xs - ys).astype(np.float16),
              "C": (ys * 1000 + xs).astype(np.uint32)}
    chlist = b""
    for name, ptype in (("A", 2), ("B", 1), ("C", 0)):
        chlist += name.encode() + b"\0" + struct.pack("<iBBBBii", ptype, 0, 0, 0, 0, 1, 1)
    chlist += b"\0"
    x0, y0 = 3, 7
    header = (b"\x76\x2f\x31\x01" + struct.pack("<I", 2) + attr("channels", "chlist", chlist)
              + attr("compression", "compression", bytes([compression]))
              + attr("dataWindow", "box2i", struct.pack("<4i", x0, y0, x0 + width - 1, y0 + height - 1))
              + attr("displayWindow", "box2i", struct.pack("<4i", 0, 0, 63, 63))
              + attr("lineOrder", "lineOrder", b"\0") + attr("omega.spp", "int", struct.pack("<i", 42)) + b"\0")
    per = {0: 1, 3: 16}[compression]
    chunks = []
    for row in range(0, height, per):
        raw = b"".join(planes[n][r].tobytes() for r in range(row, min(row + per, height)) for n in "ABC")
        body = raw
        if compression == 3:  # ZIP: split even/odd bytes, delta + 128, deflate
            b = np.frombuffer(raw, np.uint8)
            t = np.concatenate([b[0::2], b[1::2]])
            d = t.copy()
            d[1:] = t[1:] - t[:-1] + np.uint8(128)
            body = zlib.compress(d.tobytes())
            if len(body) >= len(raw):  # as OpenEXR does: stored raw when deflate does not help
                body = raw
        chunks.append(struct.pack("<ii", y0 + row, len(body)) + body)
    table_end = len(header) + 8 * len(chunks)
    offsets, pos = [], table_end
    for c in chunks:
        offsets.append(pos)
        pos += len(c)
    return header + struct.pack(f"<{len(chunks)}Q", *offsets) + b"".join(chunks), planes, (x0, y0)


def check_handmade():
    for compression in (0, 3):
        data, planes, (x0, y0) = handmade(compression)
        img = exr.decode(data)
        assert img.data_window == (x0, y0, x0 + 5, y0 + 19), img.data_window
        assert img.attributes["omega.spp"] == 42
        for n, want in planes.items():
            got = img.channels[n]
            assert got.shape == want.shape and np.array_equal(got, want.astype(got.dtype)), (compression, n)
    for bad in (b"", b"not an exr", handmade(0)[0][:-3]):
        try:
            exr.decode(bad)
            raise AssertionError("a broken EXR decoded")
        except exr.ExrError:
            pass


def check_daemon_files(spp, image_path, tiles):
    with open(image_path, "rb") as f:
        img = exr.decode(f.read())
    x0, y0, x1, y1 = img.data_window
    rgb, var = img.rgb, img.variance
    assert rgb.shape == (y1 - y0, x1 - x0, 3) and rgb.dtype == np.float32, rgb.shape
    assert np.isfinite(rgb).all() and (rgb >= 0).all() and 0.01 < rgb.mean() < 10, rgb.mean()
    assert var is not None and (var >= 0).all()
    assert img.attributes["omega.spp"] == spp, img.attributes
    # Red wall on the left, green on the right (what garbled bytes would not give).
    assert rgb[:, :x1 // 8, 0].mean() > 3 * rgb[:, :x1 // 8, 1].mean()
    assert rgb[:, -x1 // 8:, 1].mean() > 1.5 * rgb[:, -x1 // 8:, 0].mean()
    canvas = np.full_like(rgb, np.nan)
    for rect, path in tiles:
        with open(path, "rb") as f:
            t = exr.decode(f.read())
        assert t.data_window == rect and t.header.display_window == (0, 0, x1, y1), (t.data_window, rect)
        canvas[rect[1]:rect[3], rect[0]:rect[2]] = t.rgb
    assert np.array_equal(canvas, rgb), "the tiles do not assemble into the image"


def main(argv):
    spp, image = int(argv[0]), argv[1]
    tiles = []
    for arg in argv[2:]:
        rect, path = arg.split("=", 1)
        tiles.append((tuple(int(v) for v in rect.split(",")), path))
    check_handmade()
    check_daemon_files(spp, image, tiles)
    print("OK")


if __name__ == "__main__":
    main(sys.argv[1:])
