"""metariver for Blender: bake a river over a terrain into a mesh sequence the timeline plays.

Sidebar (N) > metariver: pick the terrain (a grid mesh object, or a heightmap PNG), an
empty that places the water's source, the number of frames, then Bake. Each frame's water
surface becomes one mesh object in the collection "metariver frames", visible on its frame
only (keyed visibility: plays in the viewport, renders, and needs no add-on to open the
.blend). Bodies of the scene's [[bodies]] become one object each, "metariver body <id>",
their location and rotation keyed on every frame (the logs ride the baked river).
Optionally every frame is also written as a binary PLY file. docs/blender.md.

Needs the metariver Python package (python/ of the repository: pip install it, or set the
add-on's preference "Package path" to the folder that holds it).
"""
from __future__ import annotations

import os
import sys

import bpy
import numpy as np

from . import convert

bl_info = {
    "name": "metariver",
    "author": "metariver",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > metariver",
    "description": "Bake a real-time river simulation over a terrain into a mesh sequence",
    "category": "Physics",
}

FRAMES_COLLECTION = "metariver frames"


def import_metariver():
    """The metariver package, from sys.path or the add-on preference's folder."""
    prefs = bpy.context.preferences.addons.get(__name__)
    extra = prefs.preferences.package_path if prefs else ""
    if extra and bpy.path.abspath(extra) not in sys.path:
        sys.path.insert(0, bpy.path.abspath(extra))
    import metariver  # noqa: PLC0415 (imported late: the preference may add its folder)
    return metariver


class MetariverPreferences(bpy.types.AddonPreferences):
    """Where the metariver package is when Blender's Python does not see it."""
    bl_idname = __name__
    package_path: bpy.props.StringProperty(
        name="Package path", subtype="DIR_PATH",
        description="Folder holding the metariver package (e.g. the repository's python/); empty: sys.path")

    def draw(self, context):
        self.layout.prop(self, "package_path")


class MetariverSettings(bpy.types.PropertyGroup):
    """The bake's inputs (Scene.metariver)."""
    terrain: bpy.props.PointerProperty(
        name="Terrain", type=bpy.types.Object, poll=lambda self, obj: obj.type == "MESH",
        description="A grid mesh (vertices on a regular X/Y grid, Z up); its heights become the terrain")
    heightmap: bpy.props.StringProperty(
        name="Heightmap", subtype="FILE_PATH",
        description="A heightmap PNG, used when no terrain object is set")
    area_scale: bpy.props.FloatProperty(
        name="Area scale", min=0.0, default=0.0, description="Metres between heightmap samples; 0: the scene's")
    height_scale: bpy.props.FloatProperty(
        name="Height scale", min=0.0, default=0.0, description="Metres for a heightmap height of 1; 0: the scene's")
    source: bpy.props.PointerProperty(
        name="Source", type=bpy.types.Object, description="An empty whose location is the source's centre; "
        "none: the automatic source at the main channel's head")
    frames: bpy.props.IntProperty(name="Frames", min=1, max=100000, default=120)
    scene_toml: bpy.props.StringProperty(
        name="Scene keys", default="", description="TOML keys over the default scene, e.g. [particles] count = 3000")
    threads: bpy.props.IntProperty(name="Threads", min=0, default=0, description="0: every core")
    ply_dir: bpy.props.StringProperty(
        name="PLY folder", subtype="DIR_PATH", description="Also write frame_NNNN.ply here; empty: none")


def make_world(settings, metariver=None):
    """The metariver.World the settings describe and the metariver-to-Blender transform."""
    metariver = metariver or import_metariver()
    toml = settings.scene_toml.replace("\\n", "\n") or None
    if settings.terrain is not None:
        heights, area_scale, height_scale, to_blender = convert.grid_heights(settings.terrain)
        world = metariver.World(toml=toml, heights=heights, area_scale=area_scale, height_scale=height_scale,
                                threads=settings.threads)
    elif settings.heightmap:
        world = metariver.World(toml=toml, heightmap=bpy.path.abspath(settings.heightmap),
                                area_scale=settings.area_scale, height_scale=settings.height_scale,
                                threads=settings.threads)
        to_blender = convert.Transform()
    else:
        raise ValueError("metariver: set a terrain object or a heightmap file")
    if settings.source is not None:
        world.move_source(to_blender.to_metariver(np.array(settings.source.matrix_world.translation)))
    return world, to_blender


def water_material():
    mat = bpy.data.materials.get("metariver water") or bpy.data.materials.new("metariver water")
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes.get("Principled BSDF")
    if bsdf is not None:
        bsdf.inputs["Base Color"].default_value = (0.05, 0.25, 0.8, 1.0)
        bsdf.inputs["Roughness"].default_value = 0.15
    mat.diffuse_color = (0.05, 0.25, 0.8, 1.0)
    return mat


def key_visibility(obj, frame):
    """obj is visible on `frame` only (keys on the frames around it, constant)."""
    for f, hidden in ((frame - 1, True), (frame, False), (frame + 1, True)):
        obj.hide_viewport = obj.hide_render = hidden
        obj.keyframe_insert("hide_viewport", frame=f)
        obj.keyframe_insert("hide_render", frame=f)
    for fc in obj.animation_data.action.fcurves:
        for kp in fc.keyframe_points:
            kp.interpolation = "CONSTANT"


def terrain_object(coll, world, to_blender):
    """A mesh object of the terrain as the world built it (with its carved channel)."""
    h = world.terrain_heights()
    a = world.terrain.area_scale
    rows, columns = h.shape
    z, x = np.meshgrid(np.arange(rows) * a, np.arange(columns) * a, indexing="ij")
    points = to_blender.points(np.stack([x.ravel(), h.ravel(), z.ravel()], axis=1))
    r, c = np.meshgrid(np.arange(rows - 1), np.arange(columns - 1), indexing="ij")
    i0 = (r * columns + c).ravel()
    quads = np.stack([i0, i0 + columns, i0 + columns + 1, i0, i0 + columns + 1, i0 + 1], axis=1).reshape(-1, 3)
    mesh = convert.surface_mesh("metariver terrain", points, np.zeros_like(points), quads.astype(np.uint32),
                                normals_given=False)
    mat = bpy.data.materials.get("metariver ground") or bpy.data.materials.new("metariver ground")
    mat.diffuse_color = (0.12, 0.08, 0.04, 1.0)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes.get("Principled BSDF")
    if bsdf is not None:
        bsdf.inputs["Base Color"].default_value = (0.12, 0.08, 0.04, 1.0)
    mesh.materials.append(mat)
    obj = bpy.data.objects.new("metariver terrain", mesh)
    coll.objects.link(obj)
    return obj


def key_bodies(coll, world, to_blender, frame, objects, metariver):
    """Each body's pose on `frame`: its object (made at its first frame, in `objects` by
    id) keyed at the body's location and rotation; a body gone is hidden from then on."""
    states = world.bodies()
    seen = set()
    for b in states:
        bid = int(b["id"])
        seen.add(bid)
        obj = objects.get(bid)
        if obj is None:
            mat = bpy.data.materials.get("metariver body") or bpy.data.materials.new("metariver body")
            mat.diffuse_color = (0.45, 0.3, 0.15, 1.0)
            mesh = convert.body_mesh(f"metariver body {bid}", metariver.BODY_SHAPES[int(b["shape"])], b["size"])
            mesh.materials.append(mat)
            obj = bpy.data.objects.new(f"metariver body {bid}", mesh)
            obj.rotation_mode = "QUATERNION"
            coll.objects.link(obj)
            objects[bid] = obj
        obj.location = tuple(float(c) for c in to_blender.points(np.asarray(b["position"], np.float32)[None, :])[0])
        obj.rotation_quaternion = to_blender.quaternion(b["orientation"])
        obj.keyframe_insert("location", frame=frame)
        obj.keyframe_insert("rotation_quaternion", frame=frame)
    for bid, obj in objects.items():
        if bid not in seen and not obj.hide_render:
            obj.hide_viewport = obj.hide_render = True
            obj.keyframe_insert("hide_viewport", frame=frame)
            obj.keyframe_insert("hide_render", frame=frame)


def frames_collection(scene):
    """The collection of baked frames, emptied (a bake replaces the previous one)."""
    coll = bpy.data.collections.get(FRAMES_COLLECTION)
    if coll is None:
        coll = bpy.data.collections.new(FRAMES_COLLECTION)
    if coll.name not in scene.collection.children:
        scene.collection.children.link(coll)
    for obj in list(coll.objects):
        mesh = obj.data
        bpy.data.objects.remove(obj)
        if mesh is not None and mesh.users == 0:
            bpy.data.meshes.remove(mesh)
    return coll


def bake(context, settings):
    """Steps the world settings.frames frames from the scene's start frame; one mesh object
    per frame (and one of the terrain as built, carved channel included). Returns the frames' objects."""
    scene = context.scene
    metariver = import_metariver()
    world, to_blender = make_world(settings, metariver)
    coll = frames_collection(scene)
    mat = water_material()
    dt = 1.0 / (scene.render.fps / scene.render.fps_base)
    dt = min(max(dt, 1e-4), 1.0)
    first = scene.frame_start
    last = first + settings.frames - 1
    ply_dir = bpy.path.abspath(settings.ply_dir) if settings.ply_dir else ""
    if ply_dir:
        os.makedirs(ply_dir, exist_ok=True)
    objects = []
    bodies = {}
    with world:
        terrain_object(coll, world, to_blender)
        for k in range(settings.frames):
            world.step(dt)
            key_bodies(coll, world, to_blender, first + k, bodies, metariver)
            vertices, normals, indices = world.surface()
            frame = first + k
            mesh = convert.surface_mesh(f"metariver.{frame:04d}", to_blender.points(vertices),
                                        to_blender.directions(normals), indices)
            mesh.materials.append(mat)
            obj = bpy.data.objects.new(f"metariver water {frame:04d}", mesh)
            coll.objects.link(obj)
            key_visibility(obj, frame)
            objects.append(obj)
            if ply_dir:
                convert.write_ply(os.path.join(ply_dir, f"frame_{frame:04d}.ply"), vertices, normals, indices)
    scene.frame_end = max(scene.frame_end, last)
    return objects


class METARIVER_OT_bake(bpy.types.Operator):
    """Simulate the river over the terrain and bake its surface, one mesh per frame"""
    bl_idname = "metariver.bake"
    bl_label = "Bake river"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        try:
            objects = bake(context, context.scene.metariver)
        except (ImportError, ValueError, RuntimeError) as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        self.report({"INFO"}, f"metariver: baked {len(objects)} frames")
        return {"FINISHED"}


class METARIVER_PT_panel(bpy.types.Panel):
    """The bake's settings and button in the 3D view's sidebar."""
    bl_label = "metariver"
    bl_idname = "METARIVER_PT_panel"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "metariver"

    def draw(self, context):
        s = context.scene.metariver
        col = self.layout.column()
        col.prop(s, "terrain")
        if s.terrain is None:
            col.prop(s, "heightmap")
            col.prop(s, "area_scale")
            col.prop(s, "height_scale")
        col.prop(s, "source")
        col.prop(s, "frames")
        col.prop(s, "threads")
        col.prop(s, "scene_toml")
        col.prop(s, "ply_dir")
        col.operator(METARIVER_OT_bake.bl_idname, icon="MOD_FLUIDSIM")


CLASSES = (MetariverPreferences, MetariverSettings, METARIVER_OT_bake, METARIVER_PT_panel)


def register():
    """Registers the classes and Scene.metariver."""
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.metariver = bpy.props.PointerProperty(type=MetariverSettings)


def unregister():
    """Removes what register() added."""
    del bpy.types.Scene.metariver
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
