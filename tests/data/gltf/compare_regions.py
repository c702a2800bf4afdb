# Region means of two linear EXRs of the same size (Omega's render and Cycles's), with Blender's
# Python as the EXR reader (no numpy or OpenImageIO bindings needed):
#
#   blender -b --factory-startup --python tests/data/gltf/compare_regions.py -- OMEGA.exr CYCLES.exr
#
# Prints the whole image's mean RGB and, over a 4 x 3 grid (row 0 at the top), each cell's mean
# luminance (Rec. 709) in both images and their ratio.
import sys

import bpy

a_path, b_path = sys.argv[sys.argv.index("--") + 1:][:2]


def load(path):
    img = bpy.data.images.load(path)
    w, h = img.size
    px = list(img.pixels)  # RGBA, rows bottom-up
    return w, h, [(px[4 * i], px[4 * i + 1], px[4 * i + 2]) for i in range(w * h)]


(w, h, a), (w2, h2, b) = load(a_path), load(b_path)
if (w, h) != (w2, h2):
    sys.exit(f"sizes differ: {w}x{h} and {w2}x{h2}")


def mean(img, x0, x1, y0, y1):
    s = [0.0, 0.0, 0.0]
    for y in range(y0, y1):
        row = (h - 1 - y) * w  # y counts from the top
        for x in range(x0, x1):
            for c in range(3):
                s[c] += img[row + x][c]
    n = (x1 - x0) * (y1 - y0)
    return [v / n for v in s]


def lum(c):
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]


ma, mb = mean(a, 0, w, 0, h), mean(b, 0, w, 0, h)
print(f"whole image mean RGB  A {[round(v, 4) for v in ma]}  B {[round(v, 4) for v in mb]}  "
      f"luminance ratio A/B {lum(ma) / max(lum(mb), 1e-12):.4f}")
for gy in range(3):
    cells = []
    for gx in range(4):
        x0, x1, y0, y1 = gx * w // 4, (gx + 1) * w // 4, gy * h // 3, (gy + 1) * h // 3
        la, lb = lum(mean(a, x0, x1, y0, y1)), lum(mean(b, x0, x1, y0, y1))
        cells.append(f"{la:.4f}/{lb:.4f}={la / max(lb, 1e-12):.3f}")
    print(f"row {gy}: " + "  ".join(cells))
