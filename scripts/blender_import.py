"""Imports a metariver export folder into Blender and renders one frame to PNG.

    blender -b -P scripts/blender_import.py -- DIR [--frame N] [--range A:B] [--show mesh|vdb|both]
                                               [--render OUT.png] [--size WxH] [--samples N] [--save FILE.blend]

DIR is a folder written by `metariver run|render --export DIR` (docs/export.md); its
export.json says which formats and frames are there. What the script builds:

- the terrain (terrain.ply, .obj or .glb, the first there is), matte;
- the water as a mesh sequence: one object per exported frame (water_NNNNN.ply / .obj /
  .glb), each shown only from its frame to the next exported one (keyframed visibility),
  so playing the timeline plays the river;
- the bodies (a scene with [[bodies]] exported with glb): each body's mesh from the
  bodies_NNNNN.glb of the first exported frame that has it (node body_<id>), its location
  and rotation keyed on every exported frame from the manifest's transforms (the same as
  that frame's glb nodes'), shown from its first frame to its last, so the logs ride the river;
- the water's VDB level set as a volume sequence (water_NNNNN.vdb, grid "surface") with a
  Volume to Mesh modifier on a mesh object, so it renders as a surface too;
- a camera that frames the terrain, a sun and a sky colour; Cycles on the CPU.

metariver files are y-up, metres; Blender is z-up: the OBJ and glTF importers convert,
and PLY objects and the volume object are turned +90 degrees about x (file (x, y, z) ->
Blender (x, -z, y)), which is the same conversion.
Blender's frame numbers are the files' frame numbers. Exit status 0 on success, 1 with a
one-line message on stderr otherwise.
"""

import argparse
import json
import math
import os
import struct
import sys

import bpy
import mathutils


# Rotation of an object whose data is y-up: +90 degrees about x, (x, y, z) -> (x, -z, y).
Y_UP_TO_Z_UP = (math.pi / 2, 0.0, 0.0)


def fail(message):
    print(f"blender_import.py: {message}", file=sys.stderr)
    sys.exit(1)


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="blender -b -P scripts/blender_import.py --")
    p.add_argument("dir", help="export folder (holds export.json)")
    p.add_argument("--frame", type=int, help="frame to render (default: the last exported)")
    p.add_argument("--range", help="FIRST:LAST: import only these frames of the mesh sequence (default: all)")
    p.add_argument("--show", choices=["mesh", "vdb", "both"], help="water to render (default: mesh when a mesh format was exported, else vdb)")
    p.add_argument("--render", help="PNG to write (default DIR/blender_NNNNN.png); '-' renders nothing")
    p.add_argument("--size", default="1280x720", help="image size WxH (default 1280x720)")
    p.add_argument("--samples", type=int, default=32, help="Cycles samples (default 32)")
    p.add_argument("--save", help="also save the scene as this .blend file")
    return p.parse_args(argv)


def clear_scene():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    for block in (bpy.data.meshes, bpy.data.materials, bpy.data.volumes, bpy.data.cameras, bpy.data.lights):
        for item in list(block):
            block.remove(item)


def import_mesh(path):
    """Imports one mesh file (y-up metres) and returns the new objects."""
    before = set(bpy.data.objects)
    ext = os.path.splitext(path)[1].lower()
    if ext == ".obj":
        bpy.ops.wm.obj_import(filepath=path, forward_axis="NEGATIVE_Z", up_axis="Y")
    elif ext == ".ply":
        bpy.ops.import_mesh.ply(filepath=path)  # no axis options in 3.4: turned below
    elif ext == ".glb":
        bpy.ops.import_scene.gltf(filepath=path)  # glTF is y-up: the importer turns it
    else:
        fail(f"{path}: not a mesh format this script imports")
    objs = [o for o in bpy.data.objects if o not in before]
    if ext == ".ply":
        for o in objs:
            o.rotation_euler = Y_UP_TO_Z_UP
    return objs


def material(name, color, roughness, transmission=0.0, alpha=1.0):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes.get("Principled BSDF")
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Transmission"].default_value = transmission
    bsdf.inputs["Alpha"].default_value = alpha
    return m


def assign(objs, mat):
    for o in objs:
        if o.type == "MESH":
            o.data.materials.clear()
            o.data.materials.append(mat)
            for poly in o.data.polygons:
                poly.use_smooth = True


def show_only_between(obj, start, end):
    """Visible (viewport and render) on frames [start, end), hidden before and after."""
    for frame, hidden in ((start - 1, True), (start, False), (end, True)):
        if frame < 0 and hidden:
            continue
        obj.hide_viewport = hidden
        obj.hide_render = hidden
        obj.keyframe_insert("hide_viewport", frame=frame)
        obj.keyframe_insert("hide_render", frame=frame)
    if obj.animation_data and obj.animation_data.action:
        for curve in obj.animation_data.action.fcurves:
            for k in curve.keyframe_points:
                k.interpolation = "CONSTANT"


def read_glb_bodies(path):
    """A bodies_NNNNN.glb's meshes by body id: {id: (vertices, triangles)}, in the body's own
    frame (y up), read here (nodes body_<id>, float VEC3 positions, 16/32-bit indices):
    Debian's Blender glTF importer fails on its numpy (np.bool)."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] != b"glTF":
        fail(f"{path}: not a glb file")
    chunks, at = {}, 12
    while at + 8 <= len(data):
        size, kind = struct.unpack_from("<I4s", data, at)
        chunks[kind] = data[at + 8:at + 8 + size]
        at += 8 + size
    gltf, blob = json.loads(chunks[b"JSON"]), chunks.get(b"BIN\0", b"")

    def read(accessor, fmt, width):
        a = gltf["accessors"][accessor]
        view = gltf["bufferViews"][a["bufferView"]]
        start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
        n = a["count"] * (3 if a["type"] == "VEC3" else 1)  # numbers; `width` of them per item
        flat = struct.unpack_from(f"<{n}{fmt}", blob, start)
        return [flat[i:i + width] for i in range(0, len(flat), width)]

    out = {}
    for node in gltf.get("nodes", []):
        name = node.get("name", "")
        if not name.startswith("body_") or "mesh" not in node:
            continue
        prim = gltf["meshes"][node["mesh"]]["primitives"][0]
        verts = read(prim["attributes"]["POSITION"], "f", 3)
        kind = gltf["accessors"][prim["indices"]]["componentType"]
        tris = read(prim["indices"], "I" if kind == 5125 else "H", 3)
        out[int(name.split("_")[1])] = (verts, tris)
    return out


def import_bodies(folder, manifest, frames, digits, mat):
    """The bodies as keyed objects (see the module's docstring); returns them."""
    if "bodies" not in manifest.get("patterns", {}):
        return []
    entries = [e for e in manifest["frame_files"] if e["frame"] in frames and e.get("bodies")]
    by_id, seen = {}, {}
    for e in entries:
        for b in e["bodies"]:
            seen.setdefault(b["id"], [e["frame"], e["frame"]])[1] = e["frame"]
            if b["id"] in by_id:
                continue
            path = os.path.join(folder, f"bodies_{e['frame']:0{digits}d}.glb")
            if not os.path.isfile(path):
                return []  # exported without glb: no meshes to show
            for bid, (verts, tris) in read_glb_bodies(path).items():  # the frame's bodies; keep the new ones
                if bid in by_id:
                    continue
                mesh = bpy.data.meshes.new(f"body_{bid}")
                mesh.from_pydata([(x, -z, y) for x, y, z in verts], [], tris)  # y-up to z-up
                o = bpy.data.objects.new(f"body_{bid}", mesh)
                o.rotation_mode = "QUATERNION"
                bpy.context.scene.collection.objects.link(o)
                assign([o], mat)
                by_id[bid] = o
    for e in entries:
        for b in e["bodies"]:
            o = by_id.get(b["id"])
            if o is None:
                continue
            x, y, z = b["position"]
            qx, qy, qz, qw = b["orientation"]
            o.location = (x, -z, y)  # y-up to z-up, as the importers turn the meshes
            o.rotation_quaternion = (qw, qx, -qz, qy)
            o.keyframe_insert("location", frame=e["frame"])
            o.keyframe_insert("rotation_quaternion", frame=e["frame"])
    for bid, o in by_id.items():
        show_only_between(o, seen[bid][0], seen[bid][1] + 1)
    return list(by_id.values())


def bounds(objs):
    lo = mathutils.Vector((math.inf,) * 3)
    hi = mathutils.Vector((-math.inf,) * 3)
    for o in objs:
        for corner in o.bound_box:
            w = o.matrix_world @ mathutils.Vector(corner)
            lo = mathutils.Vector(map(min, lo, w))
            hi = mathutils.Vector(map(max, hi, w))
    return lo, hi


def main():
    args = parse_args()
    folder = os.path.abspath(args.dir)
    manifest_path = os.path.join(folder, "export.json")
    if not os.path.isfile(manifest_path):
        fail(f"{folder}: no export.json (write the folder with metariver run --export DIR)")
    with open(manifest_path) as f:
        manifest = json.load(f)
    formats = manifest["formats"]
    frames = [entry["frame"] for entry in manifest["frame_files"]]
    if not frames:
        fail(f"{manifest_path}: no frames were exported")
    mesh_ext = next((e for e in ("ply", "obj", "glb") if e in formats), None)
    show = args.show or ("mesh" if mesh_ext else "vdb")
    if show in ("mesh", "both") and not mesh_ext:
        fail(f"--show {show}: the export has no mesh format (formats: {', '.join(formats)})")
    if show in ("vdb", "both") and "vdb" not in formats:
        fail(f"--show {show}: the export has no vdb files (formats: {', '.join(formats)})")
    first, last = frames[0], frames[-1]
    if args.range:
        try:
            a, b = (int(x) for x in args.range.split(":"))
        except ValueError:
            fail(f"--range: expected FIRST:LAST (got '{args.range}')")
        frames = [f for f in frames if a <= f <= b]
        if not frames:
            fail(f"--range {args.range}: no exported frame in it (exported: {first}..{last})")
    frame = args.frame if args.frame is not None else frames[-1]
    if frame not in frames:
        fail(f"--frame {frame}: not an exported frame in the range (exported: {frames[0]}..{frames[-1]}, "
             f"every {manifest['frames']['every']})")

    clear_scene()
    scene = bpy.context.scene
    scene.render.fps = max(1, round(manifest["frame_rate"]))
    scene.frame_start, scene.frame_end = frames[0], frames[-1]

    terrain_mat = material("terrain", (0.15, 0.18, 0.10), 0.95)
    water_mat = material("water", (0.05, 0.28, 0.50), 0.08, transmission=0.3)
    scenery = []
    for ext in ("ply", "obj", "glb"):
        path = os.path.join(folder, f"terrain.{ext}")
        if os.path.isfile(path):
            terrain = import_mesh(path)
            assign(terrain, terrain_mat)
            scenery += terrain
            break

    digits = len(manifest["patterns"]["water"].split("_")[1].split(".")[0])
    if show in ("mesh", "both"):
        water = bpy.data.collections.new("water sequence")
        scene.collection.children.link(water)
        for k, f in enumerate(frames):
            objs = import_mesh(os.path.join(folder, f"water_{f:0{digits}d}.{mesh_ext}"))
            assign(objs, water_mat)
            end = frames[k + 1] if k + 1 < len(frames) else f + 1
            for o in objs:
                o.name = f"water_{f:0{digits}d}"
                for c in list(o.users_collection):
                    c.objects.unlink(o)
                water.objects.link(o)
                show_only_between(o, f, end)
            if not scenery:
                scenery += objs

    bodies = import_bodies(folder, manifest, frames, digits, material("body", (0.45, 0.3, 0.15), 0.8))

    if show in ("vdb", "both"):
        vol = bpy.data.volumes.new("water_vdb")
        vol.filepath = os.path.join(folder, f"water_{frames[0]:0{digits}d}.vdb")
        vol.is_sequence = True
        # Blender reads file number (scene frame - frame_start + 1) + frame_offset.
        vol.frame_start = frames[0]
        vol.frame_offset = frames[0] - 1
        vol.frame_duration = frames[-1] - frames[0] + 1
        vol.sequence_mode = "CLIP"
        vol_obj = bpy.data.objects.new("water_vdb", vol)
        vol_obj.rotation_euler = Y_UP_TO_Z_UP
        vol_obj.hide_render = True  # rendered through the surface below
        scene.collection.objects.link(vol_obj)
        surface = bpy.data.objects.new("water_vdb_surface", bpy.data.meshes.new("water_vdb_surface"))
        scene.collection.objects.link(surface)
        mod = surface.modifiers.new("Volume to Mesh", "VOLUME_TO_MESH")
        mod.object = vol_obj
        mod.grid_name = "surface"
        mod.resolution_mode = "GRID"
        mod.threshold = 0.0
        mod.use_smooth_shade = True
        surface.data.materials.append(water_mat if show == "vdb" else material("water vdb", (0.5, 0.15, 0.1), 0.3))

    if not scenery:
        fail(f"{folder}: nothing to frame (no terrain and no mesh water)")
    lo, hi = bounds(scenery)
    centre = (lo + hi) / 2
    size = max((hi - lo).x, (hi - lo).y, 1.0)
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    cam.data.lens = 35
    cam.data.clip_end = size * 10
    # From the +x side, a little downstream of the middle, looking down about 35 degrees.
    cam.location = centre + mathutils.Vector((0.85 * size, -0.45 * size, 0.75 * size))
    cam.rotation_euler = (centre - cam.location).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(cam)
    scene.camera = cam
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy = 3.0
    sun.rotation_euler = (math.radians(40), math.radians(10), math.radians(30))
    scene.collection.objects.link(sun)
    world = scene.world or bpy.data.worlds.new("world")
    scene.world = world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.55, 0.68, 0.85, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.8

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.samples
    scene.cycles.use_denoising = False  # Debian's Blender is built without OpenImageDenoise
    try:
        w, h = (int(x) for x in args.size.lower().split("x"))
    except ValueError:
        fail(f"--size: expected WIDTHxHEIGHT (got '{args.size}')")
    scene.render.resolution_x, scene.render.resolution_y = w, h
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.frame_set(frame)

    if args.save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(args.save))
    if args.render != "-":
        out = os.path.abspath(args.render or os.path.join(folder, f"blender_{frame:0{digits}d}.png"))
        scene.render.filepath = out
        bpy.ops.render.render(write_still=True)
        if not os.path.isfile(out):
            fail(f"{out}: Blender wrote no image")
        print(f"blender_import.py: {len(frames)} water frames ({show}) from {folder}; rendered frame {frame} to {out}")
    print(f"blender_import.py: {len(bodies)} bodies keyed on the exported frames")


if __name__ == "__main__":
    main()
