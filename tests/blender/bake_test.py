"""Headless test of the Blender add-on (ctest label blender):

    blender -b --factory-startup --python tests/blender/bake_test.py -- OUT_DIR

Registers blender/metariver_blender from this checkout (the package from python/, the
library from METARIVER_LIBRARY), builds a grid terrain, places the source with an empty,
bakes 40 frames, and checks that every baked frame's mesh has the vertex and triangle
counts of the same world stepped directly through the package, that the PLY files say the
same, that each frame is visible on its own frame only, that a log of the scene's
[[bodies]] arrives as an object keyed on every frame at the twin's body poses and moves,
and that a Cycles render of a frame shows the water (blue pixels over a brown ground, not a
uniform image).
Exits 0 on success, 1 with the failures listed.
"""
import os
import sys
import time
from pathlib import Path

import bpy
import numpy as np

REPO = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(REPO / "python"), str(REPO / "blender")]
OUT = Path(sys.argv[sys.argv.index("--") + 1]) if "--" in sys.argv else Path("/tmp/metariver_blender_test")
OUT.mkdir(parents=True, exist_ok=True)
FRAMES = 40
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def grid_terrain(rows=72, columns=40, height=12.0):
    """A valley falling along -Y (metariver +z), one vertex per sample, 1 m apart."""
    z = np.linspace(0.0, 1.0, rows)[:, None]
    x = np.linspace(-1.0, 1.0, columns)[None, :]
    h = 0.05 + 0.45 * (1.0 - z) + 0.45 * np.abs(x)
    r, c = np.meshgrid(np.arange(rows), np.arange(columns), indexing="ij")
    verts = np.stack([c.ravel() + 5.0, (rows - 1 - r).ravel() - 3.0, (h * height).ravel()], axis=1)
    faces = [(i * columns + j, (i + 1) * columns + j, (i + 1) * columns + j + 1, i * columns + j + 1)
             for i in range(rows - 1) for j in range(columns - 1)]
    mesh = bpy.data.meshes.new("valley")
    mesh.from_pydata(verts.tolist(), [], faces)
    obj = bpy.data.objects.new("valley", mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj, h


def setup_render(scene, target):
    cam_data = bpy.data.cameras.new("cam")
    cam = bpy.data.objects.new("cam", cam_data)
    scene.collection.objects.link(cam)
    cam.location = (target[0] + 30.0, target[1] - 70.0, target[2] + 50.0)
    direction = cam.location.copy()
    direction -= __import__("mathutils").Vector(target)
    cam.rotation_euler = direction.to_track_quat("Z", "Y").to_euler()
    scene.camera = cam
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.rotation_euler = (0.6, 0.2, 0.8)
    scene.collection.objects.link(sun)
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 8
    scene.cycles.use_denoising = False  # Debian's Blender has no OpenImageDenoise
    scene.render.resolution_x, scene.render.resolution_y = 320, 240
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"


def check_bodies(scene, coll, poses, to_blender):
    """The log: one object keyed on every frame, at the twin's poses, moving."""
    logs = [o for o in coll.objects if o.name.startswith("metariver body")]
    check(len(logs) == 1 and all(p is not None for p in poses), f"one body object ({[o.name for o in logs]})")
    if len(logs) != 1:
        return
    log = logs[0]
    action = log.animation_data.action if log.animation_data else None
    keyed = {fc.data_path for fc in action.fcurves} if action else set()
    check({"location", "rotation_quaternion"} <= keyed, f"its location and rotation are keyed ({sorted(keyed)})")
    counts = [len(fc.keyframe_points) for fc in action.fcurves] if action else [0]
    check(min(counts) == FRAMES, f"keyed on every frame ({min(counts)} keys of {FRAMES})")
    worst = 0.0
    for k in (0, FRAMES // 2, FRAMES - 1):
        scene.frame_set(scene.frame_start + k)
        at, q = poses[k]
        worst = max(worst, float(np.abs(np.array(log.location) - at[0]).max()),
                    float(np.abs(np.array(log.rotation_quaternion) - np.array(to_blender.quaternion(q[0]))).max()))
    check(worst < 1e-4, f"its poses are the simulation's (largest difference {worst:.2g})")
    moved = float(np.linalg.norm(poses[-1][0][0] - poses[0][0][0]))
    check(moved > 0.5, f"the log moves ({moved:.2f} m over {FRAMES} frames)")
    print(f"body: {log.name}, keyed on {min(counts)} frames, moved {moved:.2f} m")


def main():
    import metariver_blender
    from metariver_blender import convert

    import metariver

    metariver_blender.register()
    scene = bpy.context.scene
    scene.frame_start = 1
    terrain, h = grid_terrain()
    source = bpy.data.objects.new("source", None)
    scene.collection.objects.link(source)
    # metariver (x, z) = (20, 8): Blender (5 + 20, 68 - 8), 1.5 m over the ground
    source.location = (25.0, 60.0, h[8, 20] * 12.0 + 1.5)
    s = scene.metariver
    s.terrain, s.source, s.frames, s.threads = terrain, source, FRAMES, 2
    # a log dropped 1 m over the valley's middle, upstream of the source: it slides and floats down
    log_y = h[12, 20] * 12.0 + 1.0
    s.scene_toml = ("[particles]\\ncount = 1500\\n[[bodies]]\\nshape = \"box\"\\nsize = [1.2, 0.4, 0.4]\\n"
                    f"density = 500.0\\nposition = [20.0, {log_y:.3f}, 12.0]")
    s.ply_dir = str(OUT / "ply")
    bpy.context.view_layer.update()

    t0 = time.time()
    result = bpy.ops.metariver.bake()
    print(f"bake: {result} in {time.time() - t0:.1f} s")
    check(result == {"FINISHED"}, "the bake operator finished")
    coll = bpy.data.collections[metariver_blender.FRAMES_COLLECTION]
    frames = sorted((o for o in coll.objects if o.name.startswith("metariver water")), key=lambda o: o.name)
    check(len(frames) == FRAMES, f"{FRAMES} frame objects ({len(frames)})")

    # the twin: the same settings' world stepped directly through the package
    world, to_blender = metariver_blender.make_world(s, metariver)
    dt = 1.0 / (scene.render.fps / scene.render.fps_base)
    mismatches = 0
    poses = []
    with world:
        for k, obj in enumerate(frames):
            world.step(dt)
            b = world.bodies()
            poses.append((to_blender.points(b["position"]), b["orientation"].copy()) if len(b) else None)
            st = world.stats
            ply = convert.read_ply_counts(str(OUT / "ply" / f"frame_{k + 1:04d}.ply"))
            got = (len(obj.data.vertices), len(obj.data.polygons))
            if got != (st.surface_vertices, st.surface_triangles) or ply != got:
                mismatches += 1
                print(f"  frame {k + 1}: baked {got}, PLY {ply}, simulation "
                      f"{(st.surface_vertices, st.surface_triangles)}")
    check(mismatches == 0, f"every frame's vertex and triangle counts equal the simulation's ({mismatches} differ)")
    check(len(frames[-1].data.polygons) > 100, f"the last frame has water ({len(frames[-1].data.polygons)} triangles)")

    check_bodies(scene, coll, poses, to_blender)

    scene.frame_set(20)
    visible = [o.name for o in frames if not o.hide_render and not o.hide_viewport]
    check(visible == ["metariver water 0020"], f"frame 20 shows its own mesh only ({visible})")

    lo, hi = np.array(terrain.bound_box[0]), np.array(terrain.bound_box[6])
    setup_render(scene, ((lo[0] + hi[0]) / 2 + 5.0, (lo[1] + hi[1]) / 2 - 3.0, 4.0))
    terrain.hide_render = True  # the add-on's terrain object shows the carved channel
    png = OUT / "frame_0020.png"
    scene.render.filepath = str(png)
    t0 = time.time()
    bpy.ops.render.render(write_still=True)
    print(f"render: {png} in {time.time() - t0:.1f} s")
    check(png.is_file() and png.stat().st_size > 1000, f"{png} written")
    img = bpy.data.images.load(str(png))
    px = np.array(img.pixels[:], np.float32).reshape(-1, 4)[:, :3]
    check(float(px.std()) > 0.03, f"the render is not uniform (std {px.std():.3f})")
    blue = (px[:, 2] > px[:, 0] + 0.1) & (px[:, 2] > px[:, 1])
    check(blue.mean() > 0.01, f"water shows: {100 * blue.mean():.1f} % blue pixels")


try:
    main()
except Exception as exc:  # noqa: BLE001 (any error fails the test with its traceback)
    import traceback
    traceback.print_exc()
    failures.append(f"exception: {exc}")
print("metariver blender test:", "FAILED: " + "; ".join(failures) if failures else "passed")
sys.stdout.flush()
os._exit(1 if failures else 0)
