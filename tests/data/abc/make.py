"""Blender's own reading of Alembic files leafmagic wrote: the oracle for
the Alembic export's layout (tests/integration/export.rs).

    leafmagic scene scenes/ground-blow.toml --seconds 0.5 --export abc --out OUT
    leafmagic scene scenes/rocking-bin.toml --seconds 1 --export abc --out OUT
    cp OUT/ground-blow.abc OUT/rocking-bin.abc .
    python make.py ground-blow.abc ground-blow.blender.csv 30
    python make.py rocking-bin.abc rocking-bin.blender.csv 30

(16 deforming leaves; one rigid bin, whose points are written once under a
matrix per frame.)

(bpy 5.0.1, pip install bpy). Blender imports the archive (its Alembic
importer, default options: y up turned to z up, each Xform and its mesh
one object named as the Xform) into a 30 fps scene and writes every
vertex of every mesh at every frame, world metres, as its depsgraph
evaluates it: object, frame, vertex, x, y, z. Beside it, OUT with
`.uv.csv` for `.csv`: the active UV map Blender made of the archive's
`uv`, per face corner (loop) in its order: object, loop, vertex, u, v.
"""
import bpy, csv, sys

path, out, fps = sys.argv[-3], sys.argv[-2], float(sys.argv[-1])
bpy.ops.wm.read_factory_settings(use_empty=True)
sc = bpy.context.scene
sc.render.fps = int(fps)
bpy.ops.wm.alembic_import(filepath=path)
meshes = [o for o in sc.objects if o.type == "MESH"]
with open(out, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["object", "frame", "vertex", "x", "y", "z"])
    for k in range(sc.frame_start, sc.frame_end + 1):
        sc.frame_set(k)
        dg = bpy.context.evaluated_depsgraph_get()
        for o in meshes:
            ev = o.evaluated_get(dg)
            m = ev.to_mesh()
            for i, v in enumerate(m.vertices):
                p = ev.matrix_world @ v.co
                w.writerow([o.name, k, i] + ["%.7g" % c for c in p])
            ev.to_mesh_clear()
with open(out[: -len(".csv")] + ".uv.csv", "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["object", "loop", "vertex", "u", "v"])
    for o in meshes:
        uv = o.data.uv_layers.active.data
        for l in o.data.loops:
            w.writerow([o.name, l.index, l.vertex_index] + ["%.7g" % c for c in uv[l.index].uv])
