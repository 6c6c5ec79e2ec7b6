#!/usr/bin/env python3
"""Top-down picture of a metariver run without OpenGL: terrain.obj shaded by height
and slope, water surface vertices of one surface_*.obj painted blue. Pure Python
(zlib + struct), no third-party modules.

usage: plot_topdown.py OBJ_DIR [FRAME_OBJ] OUT.png [--scale PIXELS_PER_METRE]
"""
import math
import struct
import sys
import zlib
from pathlib import Path


def read_obj(path):
    vs, fs = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vs.append(tuple(map(float, line.split()[1:4])))
            elif line.startswith("f "):
                fs.append(tuple(int(t.split("/")[0]) - 1 for t in line.split()[1:4]))
    return vs, fs


def write_png(path, w, h, rgb):
    raw = b"".join(b"\x00" + bytes(rgb[y * w * 3:(y + 1) * w * 3]) for y in range(h))
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b"")
    Path(path).write_bytes(png)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    scale = 6.0
    if "--scale" in sys.argv:
        scale = float(sys.argv[sys.argv.index("--scale") + 1])
        args.remove(sys.argv[sys.argv.index("--scale") + 1])
    obj_dir = Path(args[0])
    out = args[-1]
    frame = Path(args[1]) if len(args) == 3 else sorted(obj_dir.glob("surface_*.obj"))[-1]
    tv, tf = read_obj(obj_dir / "terrain.obj")
    xs = [v[0] for v in tv]; zs = [v[2] for v in tv]; ys = [v[1] for v in tv]
    x0, x1, z0, z1 = min(xs), max(xs), min(zs), max(zs)
    y0, y1 = min(ys), max(ys)
    w = int((x1 - x0) * scale) + 1
    h = int((z1 - z0) * scale) + 1
    img = [0] * (w * h * 3)
    # terrain: nearest vertex colour, z up the image (north = +z)
    cols = round((x1 - x0) / (tv[1][0] - tv[0][0])) + 1 if len(tv) > 1 else 1
    step = tv[1][0] - tv[0][0]
    for py in range(h):
        z = z1 - py / scale
        for px in range(w):
            x = x0 + px / scale
            j = min(cols - 1, max(0, round((x - x0) / step)))
            i = min(len(tv) // cols - 1, max(0, round((z - z0) / step)))
            y = tv[i * cols + j][1]
            t = (y - y0) / (y1 - y0 + 1e-9)
            k = (py * w + px) * 3
            img[k:k + 3] = [int(60 + 150 * t), int(90 + 130 * t), int(50 + 90 * t)]
    sv, _ = read_obj(frame)
    for (x, y, z) in sv:
        px = int((x - x0) * scale); py = int((z1 - z) * scale)
        if 0 <= px < w and 0 <= py < h:
            k = (py * w + px) * 3
            img[k:k + 3] = [30, 90, 230]
    write_png(out, w, h, img)
    print(f"wrote {out} ({w}x{h}), {len(sv)} water vertices from {frame.name}")


if __name__ == "__main__":
    main()
