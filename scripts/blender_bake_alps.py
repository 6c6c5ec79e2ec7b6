"""Bakes 300 frames of the river on the Alps crop through the Blender add-on and renders
frame 300 with Cycles (docs/blender.md, "A real DEM: the Alps"):

    METARIVER_LIBRARY=build/default/src/libmetariver.so blender -b --factory-startup --python scripts/blender_bake_alps.py
"""
import sys, time
from pathlib import Path
import bpy, mathutils
import numpy as np
REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO / "python"), str(REPO / "blender")]
import metariver_blender
metariver_blender.register()
scene = bpy.context.scene
for o in list(scene.collection.objects): bpy.data.objects.remove(o)
s = scene.metariver
s.heightmap = str(REPO / "assets/heightmaps/real/alps.png")
s.area_scale, s.height_scale, s.frames, s.threads = 5.0, 30.0, 300, 2
t0 = time.time(); print("bake", bpy.ops.metariver.bake(), time.time() - t0)
coll = bpy.data.collections[metariver_blender.FRAMES_COLLECTION]
terrain = [o for o in coll.objects if o.name == "metariver terrain"][0]
frames = sorted((o for o in coll.objects if o.name.startswith("metariver water")), key=lambda o: o.name)
print("frames", len(frames), "last tris", len(frames[-1].data.polygons))
scene.frame_set(300)
w = frames[-1]
pts = np.array([w.matrix_world @ v.co for v in w.data.vertices])
tc = pts.mean(axis=0)
bb = np.array([terrain.matrix_world @ mathutils.Vector(c) for c in terrain.bound_box])
size = bb.max(0) - bb.min(0)
print("terrain size", size, "water centre", tc)
cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam")); scene.collection.objects.link(cam)
target = mathutils.Vector(((bb.min(0)[0]+bb.max(0)[0])/2, (bb.min(0)[1]+bb.max(0)[1])/2, bb.min(0)[2]))
cam.location = target + mathutils.Vector((0.35*size[0], -0.9*size[1], 0.8*max(size[0], size[1])))
cam.rotation_euler = (cam.location - target).to_track_quat("Z", "Y").to_euler()
cam.data.clip_end = 10000
scene.camera = cam
sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN")); sun.rotation_euler = (0.7, 0.2, 0.9); scene.collection.objects.link(sun)
world = bpy.data.worlds.new("w"); scene.world = world; world.color = (0.6, 0.7, 0.85)
scene.render.engine = "CYCLES"; scene.cycles.device = "CPU"; scene.cycles.samples = 24; scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y = 800, 500
Path("/tmp/bk").mkdir(exist_ok=True)
scene.render.filepath = "/tmp/bk/alps_frame300.png"
t0 = time.time(); bpy.ops.render.render(write_still=True); print("render", time.time() - t0)
