"""Bakes the six MuJoCo falls of ../mujoco-falls/ into Blender animations and
exports them as Blender's own glTF and USD exporters write them: what a
client who keyframed (or simulated) a falling card in Blender sends.

Run with Blender's Python module (pip install bpy; written with bpy 5.0.1):

    python make.py ../mujoco-falls OUT_DIR

For each fall NAME.csv (240 Hz) it keys every tenth row on Blender frames
1, 2, ... at 24 fps (location and quaternion rotation, Blender is z up like
the files) of a 4 x 1 cm or 4 x 2 cm card (the README's sizes), starting
2 m above the ground, and writes NAME.glb (glTF binary, default options)
and NAME.usda (USD text, animation on). Three variants of tumble_thick
check what a modeller may do differently:

- tumble_thick_modelled_upright: the card's mesh lies in its local
  xz-plane and the object carries the turn that lays it flat, so the world
  motion is the same but the node's frame is not the card's;
- tumble_thick_with_ground: a static 1 m ground plane beside the card;
- tumble_thick_separate: glTF written as .gltf + .bin (GLTF_SEPARATE).
"""
import bpy, csv, math, os, sys
from mathutils import Quaternion

src, out = sys.argv[-2], sys.argv[-1]
os.makedirs(out, exist_ok=True)
WIDTH = {"flutter_strip": 0.01, "tumble_thick": 0.01}


def bake(name, fall, upright=False, ground=False, gltf_format="GLB", usd=True):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.fps = 24
    rows = list(csv.DictReader(open(os.path.join(src, fall + ".csv"))))
    L, W = 0.04, WIDTH.get(fall, 0.02)
    corners = [(-L / 2, -W / 2), (L / 2, -W / 2), (L / 2, W / 2), (-L / 2, W / 2)]
    if upright:
        verts = [(x, 0.0, y) for x, y in corners]  # local xz-plane
        fix = Quaternion((1, 0, 0), math.radians(-90))  # lays it in xy
    else:
        verts = [(x, y, 0.0) for x, y in corners]
        fix = Quaternion()
    me = bpy.data.meshes.new("card")
    me.from_pydata(verts, [], [(0, 1, 2, 3)])
    ob = bpy.data.objects.new("card", me)
    sc.collection.objects.link(ob)
    if ground:
        g = bpy.data.meshes.new("ground")
        g.from_pydata([(-0.5, -0.5, 0), (0.5, -0.5, 0), (0.5, 0.5, 0), (-0.5, 0.5, 0)], [], [(0, 1, 2, 3)])
        sc.collection.objects.link(bpy.data.objects.new("ground", g))
    ob.rotation_mode = "QUATERNION"
    frame = 0
    for k in range(0, len(rows), 10):
        r = rows[k]
        frame = 1 + k // 10
        q = Quaternion((float(r["qw"]), float(r["qx"]), float(r["qy"]), float(r["qz"])))
        ob.location = (float(r["x"]), float(r["y"]), 2.0 + float(r["z"]))
        ob.rotation_quaternion = q @ fix
        ob.keyframe_insert("location", frame=frame)
        ob.keyframe_insert("rotation_quaternion", frame=frame)
    sc.frame_start, sc.frame_end = 1, frame
    ext = ".glb" if gltf_format == "GLB" else ".gltf"
    bpy.ops.export_scene.gltf(filepath=os.path.join(out, name + ext), export_format=gltf_format)
    if usd:
        bpy.ops.wm.usd_export(filepath=os.path.join(out, name + ".usda"), export_animation=True)


for fall in ["steady_fall", "glide_ballast", "wobble_card", "flutter_strip", "tumble_thick", "tumble_cardscoef"]:
    bake(fall, fall)
bake("tumble_thick_modelled_upright", "tumble_thick", upright=True, usd=False)
bake("tumble_thick_with_ground", "tumble_thick", ground=True, usd=False)
bake("tumble_thick_separate", "tumble_thick", gltf_format="GLTF_SEPARATE", usd=False)
