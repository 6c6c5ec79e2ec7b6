#!/usr/bin/env python3
"""Writes test terrains as 16-bit grey PNGs (no dependencies), for `metariver run
--heightmap`: the tunneling test's torture terrains, spikes.png (independent random
heights: neighbours differ by up to the full range) and cliffs.png (terraces with
vertical steps), and random smooth maps random_WxH.png (value noise, four octaves) of
odd sizes from 2 x 2 to 1000 x 700.
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
    random_maps(out)


def value_noise(w, h, seed):
    rng = random.Random(seed)
    out = [0.0] * (w * h)
    amp, total = 1.0, 0.0
    for octave in range(4):
        cells = 2 ** (octave + 1)
        g = [[rng.random() for _ in range(cells + 2)] for _ in range(cells + 2)]
        for r in range(h):
            y = r / max(h - 1, 1) * cells
            y0 = int(y); fy = y - y0
            fy = fy * fy * (3 - 2 * fy)
            for c in range(w):
                x = c / max(w - 1, 1) * cells
                x0 = int(x); fx = x - x0
                fx = fx * fx * (3 - 2 * fx)
                a = g[y0][x0] * (1 - fx) + g[y0][x0 + 1] * fx
                b = g[y0 + 1][x0] * (1 - fx) + g[y0 + 1][x0 + 1] * fx
                out[r * w + c] += amp * (a * (1 - fy) + b * fy)
        total += amp
        amp *= 0.5
    lo, hi = min(out), max(out)
    span = (hi - lo) or 1.0
    return [int((v - lo) / span * 65535) for v in out]


def random_maps(out):
    for i, (w, h) in enumerate([(2, 2), (17, 9), (100, 61), (257, 129), (1000, 700)]):
        write_png16(os.path.join(out, f"random_{w}x{h}.png"), w, h, value_noise(w, h, 100 + i))


if __name__ == "__main__":
    main()
