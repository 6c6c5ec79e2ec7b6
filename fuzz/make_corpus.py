#!/usr/bin/env python3
"""Writes the fuzzers' seed corpus, fuzz/corpus/<target>/: small valid files of every
kind each loader accepts and broken ones it must refuse (truncated, bad CRC, bad
header, oversized, wrong type). Python's standard library only (PNG by hand); the JPEG
seeds come from the ffmpeg program (progressive ones from jpegtran) when they are there.
Run from anywhere:
    python3 fuzz/make_corpus.py
"""
import os
import shutil
import struct
import subprocess
import tempfile
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(HERE, "corpus")


def chunk(kind, data, crc=None):
    c = zlib.crc32(kind + data) & 0xFFFFFFFF if crc is None else crc
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", c)


def png(width, height, color_type=0, depth=8, rows=None, extra=(), interlace=0, idat_split=1, palette=None):
    """A PNG; `rows` are the raw scanlines (without filter bytes), filter 0 (or 1..4 cycling)."""
    channels = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}[color_type]
    bpp = max(1, channels * depth // 8)
    row_bytes = (width * channels * depth + 7) // 8
    if rows is None:
        rows = [bytes((x * 37 + y * 11) % 256 for x in range(row_bytes)) for y in range(height)]
    raw = b""
    if interlace == 0:
        for y, r in enumerate(rows):
            f = y % 5
            out = bytearray(r)
            if f == 1:  # sub
                out = bytearray(r[i] - (r[i - bpp] if i >= bpp else 0) & 0xFF for i in range(len(r)))
            elif f == 2 and y > 0:  # up
                out = bytearray(r[i] - rows[y - 1][i] & 0xFF for i in range(len(r)))
            else:
                f = 0
            raw += bytes([f]) + bytes(out)
    else:  # Adam7, byte-aligned pixels only
        passes = [(0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2), (0, 1, 1, 2)]
        for x0, y0, dx, dy in passes:
            xs = range(x0, width, dx)
            if not xs:
                continue
            for y in range(y0, height, dy):
                raw += b"\x00" + b"".join(rows[y][x * bpp:(x + 1) * bpp] for x in xs)
    z = zlib.compress(raw, 9)
    ihdr = struct.pack(">IIBBBBB", width, height, depth, color_type, 0, 0, interlace)
    out = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr)
    if palette is not None:
        out += chunk(b"PLTE", palette)
    for e in extra:
        out += e
    step = max(1, (len(z) + idat_split - 1) // idat_split)
    for i in range(0, len(z), step):
        out += chunk(b"IDAT", z[i:i + step])
    return out + chunk(b"IEND", b"")


def write(target, name, data):
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def png_seeds():
    s = {}
    grad = [bytes((x * 16 + y) % 256 for x in range(17)) for y in range(17)]
    s["gray8_17x17.png"] = png(17, 17, rows=grad)
    s["gray8_2x2.png"] = png(2, 2)
    s["gray16_9x7.png"] = png(9, 7, depth=16)
    s["rgb8_5x5.png"] = png(5, 5, color_type=2)
    s["rgba8_4x6.png"] = png(4, 6, color_type=6, idat_split=3)
    s["rgba16_3x3.png"] = png(3, 3, color_type=6, depth=16)
    s["gray_alpha_4x4.png"] = png(4, 4, color_type=4)
    s["palette_4x4.png"] = png(4, 4, color_type=3, palette=bytes(range(48)))
    s["gray1_8x8.png"] = png(8, 8, depth=1)
    s["gray4_6x3.png"] = png(6, 3, depth=4)
    s["interlaced_9x9.png"] = png(9, 9, interlace=1)
    s["text_chunk_3x3.png"] = png(3, 3, extra=[chunk(b"tEXt", b"Comment\x00metariver seed")])
    good = s["gray8_2x2.png"]
    s["broken_truncated_in_idat.png"] = s["gray8_17x17.png"][:60]
    s["broken_truncated_in_iend.png"] = good[:-2]
    s["broken_bad_crc_ihdr.png"] = good[:29] + b"\x00\x00\x00\x00" + good[33:]
    s["broken_signature.png"] = b"\x89PNX" + good[4:]
    s["broken_1x1.png"] = png(1, 1)
    s["broken_huge_header.png"] = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 100000, 100000, 8, 0, 0, 0, 0)) + chunk(b"IDAT", zlib.compress(b"\x00" * 64)) + chunk(b"IEND", b"")
    s["broken_idat_not_zlib.png"] = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 4, 4, 8, 0, 0, 0, 0)) + chunk(b"IDAT", b"not zlib data") + chunk(b"IEND", b"")
    s["broken_short_idat.png"] = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 64, 64, 8, 0, 0, 0, 0)) + chunk(b"IDAT", zlib.compress(b"\x00" * 10)) + chunk(b"IEND", b"")
    s["broken_no_ihdr.png"] = b"\x89PNG\r\n\x1a\n" + chunk(b"IEND", b"")
    s["broken_chunk_length.png"] = b"\x89PNG\r\n\x1a\n" + b"\xff\xff\xff\xf0IHDR" + b"\x00" * 20
    s["broken_empty.png"] = b""
    return s


def jpeg_seeds():
    s = {}
    ffmpeg = shutil.which("ffmpeg")
    if not ffmpeg:
        print("make_corpus: no ffmpeg, no JPEG seeds")
        return s
    with tempfile.TemporaryDirectory() as tmp:
        for name, args in [("color_8x8.jpg", ["-f", "lavfi", "-i", "testsrc=size=8x8", "-pix_fmt", "yuvj420p"]),
                           ("color_16x9.jpg", ["-f", "lavfi", "-i", "testsrc=size=16x9", "-pix_fmt", "yuvj444p"]),
                           ("gray_7x5.jpg", ["-f", "lavfi", "-i", "testsrc=size=7x5", "-pix_fmt", "gray"])]:
            out = os.path.join(tmp, name)
            subprocess.run([ffmpeg, "-v", "error", "-y", *args, "-frames:v", "1", "-q:v", "8", out], check=True)
            with open(out, "rb") as f:
                s[name] = f.read()
        jpegtran = shutil.which("jpegtran")  # Debian libjpeg-turbo-progs: progressive variants
        if jpegtran:
            for name in ["color_16x9.jpg", "gray_7x5.jpg"]:
                src, out = os.path.join(tmp, name), os.path.join(tmp, "progressive_" + name)
                subprocess.run([jpegtran, "-progressive", "-outfile", out, src], check=True)
                with open(out, "rb") as f:
                    s["progressive_" + name] = f.read()
    if "color_8x8.jpg" in s:
        s["broken_truncated.jpg"] = s["color_8x8.jpg"][: len(s["color_8x8.jpg"]) // 2]
    return s


SCENES = {
    "minimal.toml": 'name = "tiny"\n',
    "empty.toml": "",
    "river_all_tables.toml": '''name = "river"
solver = "pbf"
surface = true
[terrain]
source = "valley"
width = 33
height = 33
seed = 3
area_scale = 1.5
height_scale = 20.0
paper_row_orientation = true
condition = "fill"
[particles]
count = 2000
spawn_center = "channel"
spawn_half_extent = [1.0, 0.5, 1.0]
initial_velocity = [0.0, 0.0, 0.5]
auto_height = 1.0
source_shape = "disc"
flow_rate = 100.0
litres_per_particle = 2.0
[pbf]
spacing = 0.25
kernel_radius = 0.5
iterations = 4
relaxation = 100.0
scorr_k = 0.001
scorr_n = 4
scorr_dq = 0.2
xsph = 0.01
vorticity = 0.0
[sink]
kind = "edges"
[collision]
mode = "robust"
query = "heightfield"
damping = 0.5
offset = 0.05
radius = 0.1
bvh_leaf_triangles = 8
[integrator]
dt = 0.004
substeps = 4
[forces]
gravity = 9.81
[field]
kernel = "poly6"
bounds = "terrain"
radius = 0.6
resolution = 4.0
bounds_offset = 1.0
threshold = 0.5
''',
    "springs_paper.toml": '''name = "paper"
solver = "springs"
seed = 7
[terrain]
source = "strict"
width = 17
height = 17
[particles]
count = 20
spawn_center = [8.0, 7.0, 15.0]
spawn_half_extent = [2.0, 1.0, 0.2]
spawn_interval = 80
[springs]
stiffness = 2.0
min_distance = 3.0
max_distance = 5.0
mode = "pairs"
[collision]
mode = "paper"
damping = 0.7
offset = 0.07
[field]
kernel = "radius_over_r"
bounds = "particles"
radius = 2.0
resolution = 2.0
bounds_offset = 4.0
threshold = 0.54
''',
    "bullet.toml": '''solver = "bullet"
[terrain]
source = "bowl"
[particles]
count = 40
spawn_interval = 8
[bullet]
terrain = "heightfield"
sphere_radius = 0.5
mass = 1.0
friction = 0.5
restitution = 0.1
particle_collisions = true
dt = 0.01
max_substeps = 4
solver_iterations = 10
ccd = true
sleep = false
springs = true
''',
    "file_terrain.toml": '[terrain]\nheightmap = "maps/nile.png"\narea_scale = 1\n',
    "sink_box.toml": '[sink]\nkind = "box"\nmin = [0, -10, 0]\nmax = [4, 10, 4]\n',
    "broken_syntax.toml": "[particles\ncount = 3\n",
    "broken_unknown_key.toml": "[particles]\ncounts = 3\n",
    "broken_out_of_range.toml": "[pbf]\nspacing = 1e-6\n",
    "broken_nan.toml": "[forces]\ngravity = nan\n",
    "broken_inf.toml": "[collision]\nradius = inf\n",
    "broken_huge_float.toml": "[field]\nresolution = 1e300\n",
    "broken_wrong_type.toml": 'seed = "one"\n[terrain]\nwidth = 2.5\n',
    "broken_table_as_value.toml": 'terrain = 3\n',
    "broken_bullet_with_pbf.toml": 'solver = "bullet"\n[pbf]\nspacing = 0.5\n',
    "broken_springs_with_bullet.toml": 'solver = "springs"\n[bullet]\nmass = 2.0\n',
    "broken_pbf_with_springs.toml": 'solver = "pbf"\n[springs]\nstiffness = 2.0\n',
    "springs_carve_spacing.toml": 'solver = "springs"\n[terrain]\ncondition = "carve"\n[pbf]\nspacing = 0.25\n',
    "broken_interval_with_rate.toml": '[particles]\nflow_rate = 50.0\nspawn_interval = 4\n',
    "broken_field_without_surface.toml": 'surface = false\n[field]\nthreshold = 0.3\n',
    "broken_seed_with_pbf.toml": 'seed = 3\n',
    "broken_springs_distance_without_stiffness.toml": 'solver = "springs"\n[springs]\nstiffness = 0.0\nmin_distance = 3.0\n',
    "broken_inline_tables.toml": 'particles = { count = 10, spawn_center = [1, 2] }\n',
    "broken_deep_array.toml": "x = " + "[" * 40 + "]" * 40 + "\n",
    "broken_utf8.toml": b'name = "\xff\xfe"\n',
}

CLI = {
    "run_default": "run\n--frames\n300",
    "run_all": "run\n--preset\ndefault\n--frames\n10\n--dt\n0.016\n--collision\nrobust\n--stats\ns.json\n--obj-dir\nobjs\n--obj-every\n5\n--area-scale\n2\n--height-scale\n30",
    "run_seed": "run\n--preset\npaper-bowl\n--frames\n10\n--seed\n3",
    "run_scene": "run\n--scene\nnone.toml\n--heightmap\nnone.png\n--real-scale",
    "run_bad_preset": "run\n--preset\nnope",
    "run_preset_and_scene": "run\n--preset\ndefault\n--scene\nx.toml",
    "run_bad_number": "run\n--frames\nten",
    "render_all": "render\n--preset\npaper-bowl\n--frames\n3\n--size\n320x200\n--out\nout/f\n--camera\n35,40,30,1,2,3\n--orbit\n90\n--warmup\n2\n--steps\n2\n--water\ngouraud\n--particles\n--bvh\n3\n--texture\nt.png\n--stats\nr.json",
    "render_camera": "render\n--camera\n35,-95,0",
    "view": "view\n--preset\npaper-nile\n--size\n640x480\n--dt\n0.02\n--frames\n5\n--screenshot\ns.png",
    "bench": "bench\n--scenario\nw1\n--balls\n100\n--res\n32\n--frames\n3\n--threads\n1\n--json\nb.json",
    "help": "--help",
    "version_then_run_options": "--version\n--preset\ndefault\n--frames\n10",
    "run_help": "run\n--help",
    "unknown_command": "fly\n--frames\n1",
    "no_command": "",
    "equals_form": "run\n--frames=5\n--seed=1\n--area-scale=1e400",
    # found by CI's fuzz run: CLI11 took "--version=" (the NUL ends the argument) for --version
    "version_empty_value": "--version=\x00\x00\x00?-)p\nrun\n--frames\n2",
    "help_with_value": "run\n--help=all",
}


def main():
    if os.path.isdir(CORPUS):
        shutil.rmtree(CORPUS)
    pngs = png_seeds()
    for name, data in pngs.items():
        write("png_heightmap", name, data)
    jpegs = jpeg_seeds()
    # image: the first byte picks the channel count (fuzz/image_fuzz.cpp)
    for i, (name, data) in enumerate(list(pngs.items()) + list(jpegs.items())):
        write("image", name, bytes([i % 4]) + data)
    write("image", "broken_bmp.bmp", b"\x03BM" + b"\x00" * 60)
    write("image", "broken_gif.gif", b"\x03GIF89a" + b"\x01\x00\x01\x00" + b"\x00" * 20)
    for name, text in SCENES.items():
        write("scene_toml", name, text.encode("utf-8", "surrogateescape") if isinstance(text, str) else text)
    for name, text in CLI.items():
        write("cli", name, text.encode())


if __name__ == "__main__":
    main()
