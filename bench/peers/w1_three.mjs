#!/usr/bin/env node
// metariver peer driver, W1 'metaball isosurface' with three.js's MarchingCubes
// (examples/jsm/objects/MarchingCubes.js from npm three@0.187.0), headless in Node.
// W1 is defined in ../shared/peers/README.md; this file only imports the npm package.
//
// A frame is what a three.js app does every frame: reset() (clear the R^3 field),
// addBall() per ball (accumulate inside each ball's box), update() (polygonize every
// interior cell into a triangle soup with normals). One thread (JavaScript).
//
// three.js must be installed by bench/peers/setup.sh into $METARIVER_PEERS_NODE
// (default <repo>/build/peers-node). Exit 3 when it is not there.
//
// Usage: node bench/peers/w1_three.mjs --cases N:R[,N:R...] [--frames 10] [--warmup 3]
//                                      [--rcoef 0.3] [--sub 12] [--iso 80] [--seed 12345]
// Prints one JSON line per case (keys as ../shared/peers/w1_three_mc.mjs).
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { performance } from 'node:perf_hooks';

const here = path.dirname(fileURLToPath(import.meta.url));
const nodeDir = process.env.METARIVER_PEERS_NODE || path.resolve(here, '../../build/peers-node');

// Check values from the README (seed 12345).
const BALL0 = [0.116322149, 0.113238279, 0.534524636];
const COORD_SUM = { 50: 79.459106, 1000: 1493.437325, 10000: 14935.626684 };

function die(code, msg) {
  process.stderr.write(`w1_three.mjs: ${msg}\n`);
  process.exit(code);
}

function parseArgs(argv) {
  const o = { cases: '', frames: 10, warmup: 3, rcoef: 0.3, sub: 12, iso: 80, seed: 12345 };
  for (let i = 0; i < argv.length; i++) {
    const key = argv[i].startsWith('--') ? argv[i].slice(2) : '';
    if (!(key in o)) die(2, `unknown option ${argv[i]}`);
    if (i + 1 >= argv.length) die(2, `missing value for ${argv[i]}`);
    const v = argv[++i];
    if (key === 'cases') o.cases = v;
    else {
      o[key] = Number(v);
      if (!Number.isFinite(o[key])) die(2, `${argv[i - 1]}: not a number: ${v}`);
    }
  }
  if (!o.cases) die(2, '--cases N:R[,N:R...] is required');
  if (o.frames < 1 || o.warmup < 0) die(2, '--frames must be >= 1, --warmup >= 0');
  const cases = o.cases.split(',').map((c) => {
    const m = /^(\d+):(\d+)$/.exec(c.trim());
    if (!m || +m[1] < 1 || +m[2] < 4) die(2, `--cases: bad case '${c}' (want N:R, N >= 1, R >= 4)`);
    return [+m[1], +m[2]];
  });
  return { ...o, cases };
}

// The shared 32-bit LCG (Numerical Recipes constants); u in [0,1).
function balls(n, seed) {
  let s = seed >>> 0;
  const next = () => { s = (Math.imul(1664525, s) + 1013904223) >>> 0; return s / 4294967296; };
  const b = new Float64Array(3 * n);
  for (let i = 0; i < 3 * n; i++) b[i] = 0.1 + 0.8 * next(); // x, y, z per ball
  return b;
}

function summary(samples) {
  const s = Float64Array.from(samples).sort();
  const n = s.length, mid = n >> 1;
  const med = n % 2 ? s[mid] : 0.5 * (s[mid - 1] + s[mid]);
  const r3 = (x) => Math.round(x * 1000) / 1000;
  return { median: r3(med), min: r3(s[0]), max: r3(s[n - 1]) };
}

function checkBalls(b, n, seed) {
  let sum = 0;
  for (let i = 0; i < 3 * n; i++) sum += b[i];
  const ball0 = [b[0], b[1], b[2]].map((x) => +x.toFixed(9));
  if (seed === 12345) {
    if (ball0.some((x, i) => Math.abs(x - BALL0[i]) > 1e-9))
      die(1, `ball0 ${JSON.stringify(ball0)} != README ${JSON.stringify(BALL0)}`);
    if (n in COORD_SUM && Math.abs(sum - COORD_SUM[n]) > 1e-6)
      die(1, `coord_sum ${sum.toFixed(6)} != README ${COORD_SUM[n]} for N=${n}`);
  }
  return { ball0, coord_sum: +sum.toFixed(6) };
}

async function main() {
  const o = parseArgs(process.argv.slice(2));
  const pkg = path.join(nodeDir, 'node_modules/three/package.json');
  const mcFile = path.join(nodeDir, 'node_modules/three/examples/jsm/objects/MarchingCubes.js');
  if (!fs.existsSync(pkg) || !fs.existsSync(mcFile))
    die(3, `three.js not installed in ${nodeDir}: run bash bench/peers/setup.sh`);
  const version = JSON.parse(fs.readFileSync(pkg, 'utf8')).version;
  const THREE = await import(pathToFileURL(path.join(nodeDir, 'node_modules/three/build/three.module.js')).href);
  const { MarchingCubes } = await import(pathToFileURL(mcFile).href);

  for (const [N, R] of o.cases) {
    const b = balls(N, o.seed);
    const check = checkBalls(b, N, o.seed);
    const r = o.rcoef / Math.cbrt(N);          // surface radius of a lone ball
    const S = (o.iso + o.sub) * r * r;         // kernel strength
    const rsup = Math.sqrt(S / o.sub);         // support radius
    // three.js puts grid index g at ball coordinate g/R; W1 wants g/(R-1): scale positions
    // by k = (R-1)/R and the strength by k^2 (subtract and isolation unchanged).
    const k = (R - 1) / R, Sk = S * k * k;
    const rg = R * Math.sqrt(Sk / o.sub);
    let boxCells = 0;                          // addBall's per-frame work bound
    for (let i = 0; i < N; i++) {
      let v = 1;
      for (let d = 0; d < 3; d++) {
        const c = b[3 * i + d] * k * R;
        v *= Math.max(0, Math.min(R - 1, Math.floor(c + rg)) - Math.max(1, Math.floor(c - rg)));
      }
      boxCells += v;
    }

    let capacity = Math.max(10000, Math.ceil(4 * R * R * Math.cbrt(N)));
    let tris = 0;
    let t = null;
    for (let attempt = 0; attempt < 3; attempt++) {
      const mc = new MarchingCubes(R, new THREE.MeshBasicMaterial(), false, false, capacity);
      mc.isolation = o.iso;
      t = { frame: [], reset: [], addBall: [], update: [] };
      let overflow = false;
      for (let f = 0; f < o.warmup + o.frames; f++) {
        const t0 = performance.now();
        mc.reset();
        const t1 = performance.now();
        for (let i = 0; i < N; i++) mc.addBall(b[3 * i] * k, b[3 * i + 1] * k, b[3 * i + 2] * k, Sk, o.sub);
        const t2 = performance.now();
        mc.update();
        const t3 = performance.now();
        tris = mc.count / 3;
        if (tris >= capacity) { overflow = true; break; }
        if (f >= o.warmup) {
          t.frame.push(t3 - t0); t.reset.push(t1 - t0); t.addBall.push(t2 - t1); t.update.push(t3 - t2);
        }
      }
      if (!overflow) break;
      if (attempt === 2) die(1, `N=${N} R=${R}: output still overflows ${capacity} triangles`);
      capacity = Math.ceil(Math.max(tris, capacity) * 2); // buffers too small: rebuild, measure again
    }

    console.log(JSON.stringify({
      bench: 'W1', peer: 'three.js MarchingCubes', three_version: version, node: process.version,
      N, R, iso: o.iso, sub: o.sub, rcoef: o.rcoef, r_surface: +r.toFixed(6), r_support: +rsup.toFixed(6),
      r_support_cells: +(rsup * (R - 1)).toFixed(2), addBall_box_cells_total: boxCells,
      frames: o.frames, warmup: o.warmup, triangles: tris, threads: 1,
      ms_frame: summary(t.frame), ms_reset: summary(t.reset), ms_addBall: summary(t.addBall),
      ms_update: summary(t.update), ball0: check.ball0, coord_sum: check.coord_sum,
    }));
  }
}

main().catch((e) => die(1, e && e.stack ? e.stack.split('\n')[0] : String(e)));
