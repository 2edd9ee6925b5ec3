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

Two more put the card under other objects, as animators build a leaf:

- tumble_thick_parented: the keys are on an empty, `carrier`; the card is
  its child, shifted 1 cm along x and turned 30 degrees about z in the
  carrier's frame, and the carrier's keys undo that, so the card's world
  motion is tumble_thick's (.glb and .usda);
- tumble_thick_rigged: a 4 x 1 cm card meshed 4 x 2, skinned to an
  armature of two bones along its length (`root`, `tip`; weights blend
  over the middle centimetre); the armature carries the fall's keys and
  the tip bone bends the card out of its plane by 25 sin(2 pi 1.5 t)
  degrees (.glb with a glTF skin, .usda with UsdSkel). Blender's own
  evaluated vertices at each key, in world metres, go to
  tumble_thick_rigged.vertices.csv (frame, vertex, x, y, z): what the
  animator saw, for the readers to match;
- tumble_thick_curled: the same 4 x 1 cm card, meshed 4 x 2, carrying
  the fall's keys itself and curled by an animated shape key, `curl`
  (the ends lift by 4 mm at full weight, z = 10 x^2; weight
  0.5 + 0.5 sin(2 pi 1.5 t)): glTF writes a morph target, USD a UsdSkel
  BlendShape on a one-joint skeleton. Its evaluated vertices go to
  tumble_thick_curled.vertices.csv as the rigged card's do.

- tumble_thick_takes.glb: a 4 x 1 cm card with two actions, as an
  animator keeps takes: `tumble` (tumble_thick's keys), the active one,
  and `steady` (steady_fall's), stashed in the NLA as Blender does when
  the active action is switched. Blender's glTF exporter writes each as
  an animation of its own, both moving the card.

`python make.py SRC OUT NAME ...` makes only the named ones (the six
falls are `bakes`; `parented`, `rigged`, `curled`, `takes`). With `abc`
among the names, the scenes are written as Blender's Alembic exporter
writes them (NAME.abc, default options: y up, the armature's and the
shape key's deformation baked into the points) and nothing else:
`python make.py SRC OUT abc bakes parented rigged curled` wrote
tumble_thick.abc, tumble_thick_parented.abc, tumble_thick_rigged.abc and
tumble_thick_curled.abc (the rigged and curled cards' evaluated vertices
are the CSVs above).
"""
import bpy, csv, math, os, sys
from mathutils import Quaternion, Vector

src, out = sys.argv[1], sys.argv[2]
ABC = "abc" in sys.argv[3:]
only = [n for n in sys.argv[3:] if n != "abc"]


def wanted(name):
    return not only or name in only
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
    if ABC:
        alembic(name)
        return
    ext = ".glb" if gltf_format == "GLB" else ".gltf"
    bpy.ops.export_scene.gltf(filepath=os.path.join(out, name + ext), export_format=gltf_format)
    if usd:
        bpy.ops.wm.usd_export(filepath=os.path.join(out, name + ".usda"), export_animation=True)


def alembic(name):
    sc = bpy.context.scene
    bpy.ops.wm.alembic_export(filepath=os.path.join(out, name + ".abc"), start=sc.frame_start, end=sc.frame_end)


if wanted("bakes") and ABC:
    bake("tumble_thick", "tumble_thick")
elif wanted("bakes"):
    for fall in ["steady_fall", "glide_ballast", "wobble_card", "flutter_strip", "tumble_thick", "tumble_cardscoef"]:
        bake(fall, fall)
    bake("tumble_thick_modelled_upright", "tumble_thick", upright=True, usd=False)
    bake("tumble_thick_with_ground", "tumble_thick", ground=True, usd=False)
    bake("tumble_thick_separate", "tumble_thick", gltf_format="GLTF_SEPARATE", usd=False)


def keyed(rows):
    """(Blender frame, location, rotation) of every tenth row."""
    for k in range(0, len(rows), 10):
        r = rows[k]
        q = Quaternion((float(r["qw"]), float(r["qx"]), float(r["qy"]), float(r["qz"])))
        yield 1 + k // 10, Vector((float(r["x"]), float(r["y"]), 2.0 + float(r["z"]))), q


def export(name):
    if ABC:
        alembic(name)
        return
    bpy.ops.export_scene.gltf(filepath=os.path.join(out, name + ".glb"), export_format="GLB")
    bpy.ops.wm.usd_export(filepath=os.path.join(out, name + ".usda"), export_animation=True)


def parented():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.fps = 24
    rows = list(csv.DictReader(open(os.path.join(src, "tumble_thick.csv"))))
    me = bpy.data.meshes.new("card")
    me.from_pydata([(-0.02, -0.005, 0), (0.02, -0.005, 0), (0.02, 0.005, 0), (-0.02, 0.005, 0)], [], [(0, 1, 2, 3)])
    ob = bpy.data.objects.new("card", me)
    carrier = bpy.data.objects.new("carrier", None)
    sc.collection.objects.link(ob)
    sc.collection.objects.link(carrier)
    ob.parent = carrier
    ob.rotation_mode = carrier.rotation_mode = "QUATERNION"
    turn, shift = Quaternion((0, 0, 1), math.radians(30)), Vector((0.01, 0, 0))
    ob.location, ob.rotation_quaternion = shift, turn
    frame = 1
    for frame, loc, q in keyed(rows):
        # carrier * child = the fall's pose.
        qc = q @ turn.inverted()
        carrier.rotation_quaternion = qc
        carrier.location = loc - qc @ shift
        carrier.keyframe_insert("location", frame=frame)
        carrier.keyframe_insert("rotation_quaternion", frame=frame)
    sc.frame_start, sc.frame_end = 1, frame
    export("tumble_thick_parented")


def meshed_card():
    """A fresh scene at 24 fps, tumble_thick's rows, and the 4 x 1 cm card
    meshed 4 x 2 (its vertices and object, not yet linked)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.fps = 24
    rows = list(csv.DictReader(open(os.path.join(src, "tumble_thick.csv"))))
    nx, ny = 4, 2
    verts = [(-0.02 + 0.04 * i / nx, -0.005 + 0.01 * j / ny, 0.0) for j in range(ny + 1) for i in range(nx + 1)]
    faces = [(j * (nx + 1) + i, j * (nx + 1) + i + 1, (j + 1) * (nx + 1) + i + 1, (j + 1) * (nx + 1) + i)
             for j in range(ny) for i in range(nx)]
    me = bpy.data.meshes.new("card")
    me.from_pydata(verts, [], faces)
    return sc, rows, verts, bpy.data.objects.new("card", me)


def rigged():
    sc, rows, verts, ob = meshed_card()
    arm = bpy.data.armatures.new("rig")
    rig = bpy.data.objects.new("rig", arm)
    sc.collection.objects.link(ob)
    sc.collection.objects.link(rig)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    root = arm.edit_bones.new("root")
    root.head, root.tail = (-0.02, 0, 0), (0, 0, 0)
    tip = arm.edit_bones.new("tip")
    tip.head, tip.tail, tip.parent = (0, 0, 0), (0.02, 0, 0), root
    bpy.ops.object.mode_set(mode="OBJECT")
    ob.parent = rig
    ob.modifiers.new("rig", "ARMATURE").object = rig
    groups = ob.vertex_groups.new(name="root"), ob.vertex_groups.new(name="tip")
    for v, (x, _, _) in enumerate(verts):
        w = min(1.0, max(0.0, (x + 0.005) / 0.01))
        if w < 1:
            groups[0].add([v], 1 - w, "REPLACE")
        if w > 0:
            groups[1].add([v], w, "REPLACE")
    rig.rotation_mode = "QUATERNION"
    bend = rig.pose.bones["tip"]
    bend.rotation_mode = "QUATERNION"
    frame = 1
    for frame, loc, q in keyed(rows):
        rig.location, rig.rotation_quaternion = loc, q
        rig.keyframe_insert("location", frame=frame)
        rig.keyframe_insert("rotation_quaternion", frame=frame)
        t = (frame - 1) / 24
        # About the bone's own x, which for a bone along +x is world -y:
        # the card bends out of its plane.
        bend.rotation_quaternion = Quaternion((1, 0, 0), math.radians(25 * math.sin(2 * math.pi * 1.5 * t)))
        bend.keyframe_insert("rotation_quaternion", frame=frame)
    sc.frame_start, sc.frame_end = 1, frame
    export("tumble_thick_rigged")
    evaluated(ob, frame, "tumble_thick_rigged.vertices.csv")


def evaluated(ob, frames, name):
    """Blender's own evaluated vertices of `ob` at each key, world metres."""
    if ABC:
        return
    sc = bpy.context.scene
    with open(os.path.join(out, name), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["frame", "vertex", "x", "y", "z"])
        for k in range(1, frames + 1):
            sc.frame_set(k)
            dg = bpy.context.evaluated_depsgraph_get()
            ev = ob.evaluated_get(dg)
            m = ev.to_mesh()
            for i, v in enumerate(m.vertices):
                p = ev.matrix_world @ v.co
                w.writerow([k, i] + ["%.7g" % c for c in p])
            ev.to_mesh_clear()


def curled():
    sc, rows, _, ob = meshed_card()
    sc.collection.objects.link(ob)
    ob.shape_key_add(name="Basis")
    curl = ob.shape_key_add(name="curl")
    for v in curl.data:
        v.co.z = 10 * v.co.x ** 2
    ob.rotation_mode = "QUATERNION"
    frame = 1
    for frame, loc, q in keyed(rows):
        ob.location, ob.rotation_quaternion = loc, q
        ob.keyframe_insert("location", frame=frame)
        ob.keyframe_insert("rotation_quaternion", frame=frame)
        t = (frame - 1) / 24
        curl.value = 0.5 + 0.5 * math.sin(2 * math.pi * 1.5 * t)
        curl.keyframe_insert("value", frame=frame)
    sc.frame_start, sc.frame_end = 1, frame
    export("tumble_thick_curled")
    evaluated(ob, frame, "tumble_thick_curled.vertices.csv")


def takes():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.fps = 24
    me = bpy.data.meshes.new("card")
    me.from_pydata([(-0.02, -0.005, 0), (0.02, -0.005, 0), (0.02, 0.005, 0), (-0.02, 0.005, 0)], [], [(0, 1, 2, 3)])
    ob = bpy.data.objects.new("card", me)
    sc.collection.objects.link(ob)
    ob.rotation_mode = "QUATERNION"
    ob.animation_data_create()
    frame = 1
    for take, fall in [("steady", "steady_fall"), ("tumble", "tumble_thick")]:
        rows = list(csv.DictReader(open(os.path.join(src, fall + ".csv"))))
        action = bpy.data.actions.new(take)
        ob.animation_data.action = action
        for frame, loc, q in keyed(rows):
            ob.location, ob.rotation_quaternion = loc, q
            ob.keyframe_insert("location", frame=frame)
            ob.keyframe_insert("rotation_quaternion", frame=frame)
    # Switching the active action stashes the other in a muted NLA track.
    stash = ob.animation_data.nla_tracks.new()
    stash.name = "[Action Stash]"
    stash.strips.new("steady", 1, bpy.data.actions["steady"])
    stash.mute = True
    sc.frame_start, sc.frame_end = 1, frame
    bpy.ops.export_scene.gltf(filepath=os.path.join(out, "tumble_thick_takes.glb"), export_format="GLB")


if wanted("parented"):
    parented()
if wanted("rigged"):
    rigged()
if wanted("curled"):
    curled()
if wanted("takes"):
    takes()
