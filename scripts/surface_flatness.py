#!/usr/bin/env python3
"""Flatness of still water on a surface OBJ (`metariver run --obj-dir`): issue 11's measure.

Upward-facing vertices (vertex normal within 60 degrees of +y) whose x and z lie in the
inner 60 % of the x / z range of all upward-facing vertices (the pool's top, without its
shore). For them: the normal's tilt from +y (RMS and 95th percentile, degrees), from the
OBJ's vertex normals (what the renderer shades with) and from area-weighted face normals
of the positions (what the geometry says), and the standard deviation of their heights.
Pure Python, no third-party modules.

usage: surface_flatness.py SURFACE.obj [--inner 0.6] [--up-cos 0.5] [--json]
"""
import json
import math
import sys


def read_obj(path):
    vs, ns, fs = [], [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vs.append(tuple(map(float, line.split()[1:4])))
            elif line.startswith("vn "):
                ns.append(tuple(map(float, line.split()[1:4])))
            elif line.startswith("f "):
                fs.append(tuple(int(t.split("/")[0]) - 1 for t in line.split()[1:4]))
    return vs, ns, fs


def face_normals(vs, fs):
    acc = [[0.0, 0.0, 0.0] for _ in vs]
    for a, b, c in fs:
        pa, pb, pc = vs[a], vs[b], vs[c]
        u = (pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2])
        v = (pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2])
        n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        for i in (a, b, c):
            acc[i][0] += n[0]
            acc[i][1] += n[1]
            acc[i][2] += n[2]
    out = []
    for n in acc:
        l = math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
        out.append((n[0] / l, n[1] / l, n[2] / l) if l > 0 else (0.0, 0.0, 0.0))
    return out


def tilt_stats(normals, sel):
    t = sorted(math.degrees(math.acos(max(-1.0, min(1.0, normals[i][1] / max(1e-12, math.sqrt(sum(c * c for c in normals[i]))))))) for i in sel)
    if not t:
        return float("nan"), float("nan")
    rms = math.sqrt(sum(x * x for x in t) / len(t))
    return rms, t[min(len(t) - 1, int(0.95 * len(t)))]


def main(argv):
    args = [a for a in argv[1:]]
    inner, up_cos, as_json = 0.6, 0.5, False
    if "--json" in args:
        args.remove("--json")
        as_json = True
    for flag in ("--inner", "--up-cos"):
        if flag in args:
            k = args.index(flag)
            val = float(args[k + 1])
            del args[k:k + 2]
            if flag == "--inner":
                inner = val
            else:
                up_cos = val
    if len(args) != 1:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    vs, ns, fs = read_obj(args[0])
    if len(ns) != len(vs):
        print("the OBJ has no vertex normals", file=sys.stderr)
        return 2
    fn = face_normals(vs, fs)
    up = [i for i in range(len(vs)) if ns[i][1] > up_cos]
    if not up:
        print("no upward-facing vertex", file=sys.stderr)
        return 1
    x0, x1 = min(vs[i][0] for i in up), max(vs[i][0] for i in up)
    z0, z1 = min(vs[i][2] for i in up), max(vs[i][2] for i in up)
    m = 0.5 * (1.0 - inner)
    xa, xb = x0 + m * (x1 - x0), x1 - m * (x1 - x0)
    za, zb = z0 + m * (z1 - z0), z1 - m * (z1 - z0)
    sel = [i for i in up if xa <= vs[i][0] <= xb and za <= vs[i][2] <= zb]
    ys = [vs[i][1] for i in sel]
    mean = sum(ys) / len(ys)
    std = math.sqrt(sum((y - mean) ** 2 for y in ys) / len(ys))
    rms, p95 = tilt_stats(ns, sel)
    frms, fp95 = tilt_stats(fn, sel)
    r = {"obj": args[0], "vertices": len(vs), "triangles": len(fs), "selected": len(sel),
         "tilt_rms_deg": round(rms, 3), "tilt_p95_deg": round(p95, 3),
         "face_tilt_rms_deg": round(frms, 3), "face_tilt_p95_deg": round(fp95, 3),
         "height_mean_m": round(mean, 4), "height_std_m": round(std, 4)}
    if as_json:
        print(json.dumps(r))
    else:
        print(f"{args[0]}: {len(sel)} vertices (upward, inner {inner:.0%}): tilt RMS {rms:.2f} deg "
              f"(p95 {p95:.2f}), face-normal tilt RMS {frms:.2f} (p95 {fp95:.2f}), "
              f"height mean {mean:.3f} m, std {std:.4f} m")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
