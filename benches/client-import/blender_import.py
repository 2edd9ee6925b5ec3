"""Imports one file into an empty Blender scene (bpy, Blender as a Python
module) and prints what a user gets, as one JSON line: the import time, the
objects, shape keys and keyframes Blender built, the scene's frame rate and
range, and the world position of every vertex of every mesh object at the
frames asked for (evaluated: shape keys, modifiers and object animation).

    python blender_import.py FILE.glb|FILE.usda|FILE.usdc [--frames 1,151,301]
        [--pc2-dir DIR] [--save out.blend]

The scene is set to 30 fps before a glTF import (glTF has no frame rate;
Blender converts its key times with the scene's). A USD import takes the
rate and range from the stage. With --pc2-dir, each imported mesh object
named NAME gets instead the OBJ + PC2 cache of leafmagic's PC2 export
(DIR/NAME.obj, DIR/NAME.pc2) through a Mesh Cache modifier."""
import json
import os
import sys
import time

import bpy


def arg(name, default=None):
    if name in sys.argv:
        return sys.argv[sys.argv.index(name) + 1]
    return default


path = sys.argv[1]
frames = [int(f) for f in arg("--frames", "1").split(",")]
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.fps = 30
started = time.perf_counter()
if path.endswith(".glb"):
    bpy.ops.import_scene.gltf(filepath=path)
elif path.endswith(".pc2dir"):
    d = path[: -len(".pc2dir")]
    for f in sorted(os.listdir(d)):
        if f.endswith(".obj"):
            bpy.ops.wm.obj_import(filepath=os.path.join(d, f), up_axis="Z", forward_axis="Y")
            obj = bpy.context.selected_objects[0]
            m = obj.modifiers.new("cache", "MESH_CACHE")
            m.cache_format = "PC2"
            m.filepath = os.path.join(d, f[:-4] + ".pc2")
else:
    bpy.ops.wm.usd_import(filepath=path)
elapsed = time.perf_counter() - started

meshes = [o for o in scene.objects if o.type == "MESH"]
shape_keys = sum(len(o.data.shape_keys.key_blocks) - 1 for o in meshes if o.data.shape_keys)
keyframes = 0
for a in bpy.data.actions:
    # Blender 4.4+ keeps an action's curves in layered channel bags.
    layers = getattr(a, "layers", None)
    if layers:
        curves = [c for layer in layers for strip in layer.strips for bag in strip.channelbags for c in bag.fcurves]
    else:
        curves = a.fcurves
    keyframes += sum(len(c.keyframe_points) for c in curves)
out = {
    "file": path,
    "import_s": elapsed,
    "objects": len(scene.objects),
    "meshes": len(meshes),
    "shape_keys": shape_keys,
    "keyframes": keyframes,
    "fps": scene.render.fps / scene.render.fps_base,
    "frame_start": scene.frame_start,
    "frame_end": scene.frame_end,
    "positions": {},
}
for f in frames:
    scene.frame_set(f)
    graph = bpy.context.evaluated_depsgraph_get()
    per = {}
    for o in meshes:
        e = o.evaluated_get(graph)
        m = e.matrix_world
        per[o.name] = [list(m @ v.co) for v in e.to_mesh().vertices]
        e.to_mesh_clear()
    out["positions"][str(f)] = per
save = arg("--save")
if save:
    bpy.ops.wm.save_as_mainfile(filepath=save)
    out["blend_bytes"] = os.path.getsize(save)
print("RESULT " + json.dumps(out))
