#!/usr/bin/python3
"""metariver peer driver, W1 'metaball isosurface' with VTK 9.1 (Debian python3-vtk9).

numpy builds the W1 field (../shared/peers/README.md) once per case; VTK then extracts the
ISO surface from that ready field, and only the extraction (filter.Update()) is timed:
  fe:T  vtkFlyingEdges3D with T SMP threads (vtkSMPTools.Initialize(T); Debian's VTK uses TBB)
  mc    vtkMarchingCubes (a serial filter)
Both with ComputeNormals on, gradients and scalars off (positions + normals, as three.js).

Run with Debian's /usr/bin/python3 (a pyenv python does not see python3-vtk9).
Exit 3 when VTK or numpy is missing (install: bash bench/peers/setup.sh).

Usage: /usr/bin/python3 bench/peers/w1_vtk.py --cases N:R[,N:R...] [--configs fe:2,fe:1,mc]
                                              [--reps 7] [--warmup 1] [--rcoef 0.3] [--seed 12345]
Prints one JSON line per case and configuration (keys as ../shared/peers/w1_vtk.py).
"""
import argparse
import math
import json
import statistics
import sys
import time

try:
    import numpy as np
    from vtkmodules.vtkCommonCore import vtkSMPTools, vtkVersion
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkFiltersCore import vtkFlyingEdges3D, vtkMarchingCubes
    from vtkmodules.util.numpy_support import numpy_to_vtk
except ImportError as e:  # not installed: the bench reports it and goes on
    print(f"w1_vtk.py: {e}: run bash bench/peers/setup.sh (and use /usr/bin/python3)", file=sys.stderr)
    sys.exit(3)

# Check values from the README (seed 12345).
BALL0 = (0.116322149, 0.113238279, 0.534524636)
COORD_SUM = {50: 79.459106, 1000: 1493.437325, 10000: 14935.626684}


def fail(msg, code=1):
    print(f"w1_vtk.py: {msg}", file=sys.stderr)
    sys.exit(code)


def w1_balls(n, seed):
    """The shared 32-bit LCG; x, y, z per ball = 0.1 + 0.8 * next() in that order."""
    s = seed & 0xFFFFFFFF
    out = np.empty(3 * n)
    for i in range(3 * n):
        s = (1664525 * s + 1013904223) & 0xFFFFFFFF
        out[i] = 0.1 + 0.8 * (s / 4294967296.0)
    return out.reshape(n, 3)


def check_balls(balls, n, seed):
    total = float(balls.sum())
    if seed == 12345:
        if any(abs(a - b) > 1e-9 for a, b in zip(balls[0], BALL0)):
            fail(f"ball0 {list(balls[0])} != README {list(BALL0)}")
        if n in COORD_SUM and abs(total - COORD_SUM[n]) > 1e-6:
            fail(f"coord_sum {total:.6f} != README {COORD_SUM[n]} for N={n}")
    return round(total, 6)


def w1_field(balls, R, r, iso, sub, chunk=512):
    """f(p) = sum_b max(0, S / (|p - c_b|^2 + 1e-6) - sub), S = (iso + sub) r^2, at p = (i, j, k) h,
    h = 1/(R-1); float32, x fastest (VTK's point order). Each ball only touches the samples in
    its support box: per chunk of balls, the per-axis squared distances of a K^3 box are
    combined by broadcasting, and the positive kernel values are scatter-added (bincount)."""
    h = 1.0 / (R - 1)
    S = (iso + sub) * r * r
    rsup = math.sqrt(S / sub)
    K = int(math.floor(2.0 * rsup / h)) + 2          # samples per axis a support box can touch
    step = np.arange(K)
    field = np.zeros(R * R * R)
    for c0 in range(0, len(balls), chunk):
        c = balls[c0:c0 + chunk]                      # (b, 3)
        first = np.ceil((c - rsup) / h).astype(np.int64)
        ix = first[:, :, None] + step                 # (b, 3, K) sample indices per axis
        inside = (ix >= 0) & (ix < R)
        d2 = np.where(inside, (ix * h - c[:, :, None]) ** 2, np.inf)
        dx, dy, dz = d2[:, 0], d2[:, 1], d2[:, 2]
        val = S / (dz[:, :, None, None] + dy[:, None, :, None] + dx[:, None, None, :] + 1e-6) - sub
        keep = val > 0.0
        ixc = np.clip(ix, 0, R - 1)
        lin = (ixc[:, 2, :, None, None] * R + ixc[:, 1, None, :, None]) * R + ixc[:, 0, None, None, :]
        field += np.bincount(lin[keep], weights=val[keep], minlength=R * R * R)
    return field.astype(np.float32)


def parse_cases(text):
    cases = []
    for c in text.split(','):
        try:
            n, r = (int(v) for v in c.split(':'))
        except ValueError:
            fail(f"--cases: bad case '{c}' (want N:R)", 2)
        if n < 1 or r < 4:
            fail(f"--cases: bad case '{c}' (N >= 1, R >= 4)", 2)
        cases.append((n, r))
    return cases


def parse_configs(text):
    configs = []
    for c in text.split(','):
        if c == 'mc':
            configs.append(('mc', 1))
        elif c.startswith('fe:') and c[3:].isdigit() and int(c[3:]) >= 1:
            configs.append(('fe', int(c[3:])))
        else:
            fail(f"--configs: bad entry '{c}' (fe:THREADS or mc)", 2)
    return configs


def stats(xs):
    return {'median': round(statistics.median(xs), 3), 'min': round(min(xs), 3), 'max': round(max(xs), 3)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--cases', required=True)
    ap.add_argument('--configs', default='fe:2,fe:1,mc')
    ap.add_argument('--reps', type=int, default=7)
    ap.add_argument('--warmup', type=int, default=1)
    ap.add_argument('--rcoef', type=float, default=0.3)
    ap.add_argument('--sub', type=float, default=12.0)
    ap.add_argument('--iso', type=float, default=80.0)
    ap.add_argument('--seed', type=int, default=12345)
    a = ap.parse_args()
    if a.reps < 1 or a.warmup < 0:
        fail('--reps must be >= 1, --warmup >= 0', 2)
    cases, configs = parse_cases(a.cases), parse_configs(a.configs)
    version = vtkVersion.GetVTKVersion()

    for n, R in cases:
        balls = w1_balls(n, a.seed)
        coord_sum = check_balls(balls, n, a.seed)
        r = a.rcoef * n ** (-1.0 / 3.0)
        t0 = time.perf_counter()
        field = w1_field(balls, R, r, a.iso, a.sub)
        field_ms = (time.perf_counter() - t0) * 1e3
        h = 1.0 / (R - 1)
        image = vtkImageData()
        image.SetDimensions(R, R, R)
        image.SetOrigin(0.0, 0.0, 0.0)
        image.SetSpacing(h, h, h)
        scalars = numpy_to_vtk(field, deep=0)  # zero copy; `field` outlives the filters
        scalars.SetName('f')
        image.GetPointData().SetScalars(scalars)

        for kind, threads in configs:
            if kind == 'fe':
                vtkSMPTools.Initialize(threads)
                flt = vtkFlyingEdges3D()
                smp_threads = vtkSMPTools.GetEstimatedNumberOfThreads()
            else:
                flt = vtkMarchingCubes()
                smp_threads = 1
            flt.SetInputData(image)
            flt.SetValue(0, a.iso)
            flt.ComputeNormalsOn()
            flt.ComputeGradientsOff()
            flt.ComputeScalarsOff()
            times = []
            for i in range(a.warmup + a.reps):
                flt.Modified()
                t0 = time.perf_counter()
                flt.Update()
                dt = (time.perf_counter() - t0) * 1e3
                if i >= a.warmup:
                    times.append(dt)
            mesh = flt.GetOutput()
            print(json.dumps({
                'bench': 'W1', 'peer': 'VTK ' + flt.GetClassName(), 'vtk_version': version,
                'smp_backend': vtkSMPTools.GetBackend(), 'smp_threads': smp_threads,
                'N': n, 'R': R, 'iso': a.iso, 'sub': a.sub, 'rcoef': a.rcoef, 'r_surface': round(r, 6),
                'reps': a.reps, 'triangles': mesh.GetNumberOfPolys(), 'points': mesh.GetNumberOfPoints(),
                'ms_extract': stats(times),
                'ms_numpy_field': {'median': round(field_ms, 3), 'min': round(field_ms, 3), 'max': round(field_ms, 3)},
                'field_sum': round(float(field.sum(dtype=np.float64)), 1),
                'coord_sum': coord_sum,
            }), flush=True)


if __name__ == '__main__':
    main()
