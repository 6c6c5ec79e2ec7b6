#!/usr/bin/env python3
"""Writes the tunneling test's torture terrains as 16-bit grey PNGs (no dependencies):
spikes.png (independent random heights: neighbours differ by up to the full range) and
cliffs.png (terraces with vertical steps), for `metariver run --heightmap`.
Usage: python3 scripts/torture_maps.py OUT_DIR"""
import os, random, struct, sys, zlib


def write_png16(path, w, h, values):
    raw = b"".join(b"\x00" + b"".join(struct.pack(">H", values[r * w + c]) for c in range(w)) for r in range(h))
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(png)
    os.replace(tmp, path)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    os.makedirs(out, exist_ok=True)
    rng = random.Random(5)
    w, h = 33, 29
    write_png16(os.path.join(out, "spikes.png"), w, h, [rng.randrange(65536) for _ in range(w * h)])
    rng = random.Random(9)
    w, h = 41, 33
    def steps(n):
        a, v = 0.0, []
        for _ in range(n):
            if rng.random() < 0.25:
                a += rng.uniform(0.1, 0.4)
            v.append(a)
        return v
    sx, sz = steps(w), steps(h)
    write_png16(os.path.join(out, "cliffs.png"), w, h,
                [int(((sx[c] + sz[r]) % 1.0) * 65535) for r in range(h) for c in range(w)])


if __name__ == "__main__":
    main()
