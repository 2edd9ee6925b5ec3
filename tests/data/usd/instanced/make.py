"""Writes leaves.usda, leaves scattered by a UsdGeom PointInstancer as a
particle simulation (Houdini's) writes them, and leaves.points.csv, where
Pixar's own library (pip install usd-core; written with usd-core 26.11)
puts every vertex of every instance: the oracle for
tests/integration/animation_falls.rs.

    python make.py

Three MuJoCo falls of ../../mujoco-falls (every tenth row, time codes
1..241 at 24 a second) are three instances, ids 7 (tumble_thick), 3
(flutter_strip) and 11 (steady_fall), in a y-up stage in centimetres
under an Xform shifted 10 cm; positions float3, orientations quath (half
precision, as Houdini writes them), ids int64. The 4 x 1 cm cards use
prototype `narrow`, whose root Xform is turned 90 degrees about z with
its mesh modelled along y (so the prototype's own transform counts), the
4 x 2 cm card prototype `wide`. The instances are listed in another order
at every odd time code (matched by id). Three more live a part of the
clip or none of it, as particles do: id 99 (tumble_thick, 50 cm aside)
dies after time code 120; id 42 (flutter_strip from its own start, 50 cm
the other way) is born at time code 61; id 21 (steady_fall, 30 cm aside)
is hidden by `invisibleIds` from time code 181 on; id 5 is deactivated
(`inactiveIds`) and never shown. The oracle holds what Pixar's mask
(`ComputeMaskAtTime`) shows. leaves.usdc is the same layer as a crate
file.
"""
import csv, math, os
from pxr import Gf, Sdf, Usd, UsdGeom, Vt

HERE = os.path.dirname(os.path.abspath(__file__))
FALLS = os.path.join(HERE, "..", "..", "mujoco-falls")
INSTANCES = [(7, "tumble_thick", 0), (3, "flutter_strip", 0), (11, "steady_fall", 1)]
# z up in metres -> y up in centimetres: (x, y, z) -> 100 (x, z, -y), a
# turn of -90 degrees about x.
TURN = Gf.Rotation(Gf.Vec3d(1, 0, 0), -90)


def keys(fall):
    rows = list(csv.DictReader(open(os.path.join(FALLS, fall + ".csv"))))
    out = []
    for k in range(0, len(rows), 10):
        r = rows[k]
        p = Gf.Vec3d(float(r["x"]), float(r["y"]), 2.0 + float(r["z"]))
        q = Gf.Quatd(float(r["qw"]), float(r["qx"]), float(r["qy"]), float(r["qz"]))
        out.append((TURN.TransformDir(p) * 100, TURN.GetQuat() * q))
    return out


stage = Usd.Stage.CreateNew(os.path.join(HERE, "leaves.usda"))
UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
UsdGeom.SetStageMetersPerUnit(stage, 0.01)
stage.SetTimeCodesPerSecond(24)
stage.SetStartTimeCode(1)
stage.SetEndTimeCode(241)
world = UsdGeom.Xform.Define(stage, "/World")
world.AddTranslateOp().Set(Gf.Vec3d(10, 0, 0))
inst = UsdGeom.PointInstancer.Define(stage, "/World/leaves")
narrow = UsdGeom.Xform.Define(stage, "/World/leaves/Prototypes/narrow")
narrow.AddRotateZOp().Set(90)
m = UsdGeom.Mesh.Define(stage, "/World/leaves/Prototypes/narrow/card")
# Along y, so that the root's 90 degrees about z lays it along x.
m.CreatePointsAttr([(-0.5, -2, 0), (0.5, -2, 0), (0.5, 2, 0), (-0.5, 2, 0)])
m.CreateFaceVertexCountsAttr([4])
m.CreateFaceVertexIndicesAttr([0, 1, 2, 3])
w = UsdGeom.Mesh.Define(stage, "/World/leaves/Prototypes/wide")
w.CreatePointsAttr([(-2, -1, 0), (2, -1, 0), (2, 1, 0), (-2, 1, 0)])
w.CreateFaceVertexCountsAttr([4])
w.CreateFaceVertexIndicesAttr([0, 1, 2, 3])
inst.CreatePrototypesRel().SetTargets([narrow.GetPath(), w.GetPath()])
falls = {fid: keys(fall) for fid, fall, _ in INSTANCES}
for k in range(241):
    t = 1 + k
    listed = INSTANCES if t % 2 == 0 else list(reversed(INSTANCES))
    if t <= 120:
        listed = listed + [(99, "tumble_thick", 1)]
    if t >= 61:
        listed = [(42, "flutter_strip", 0)] + listed
    listed = listed + [(21, "steady_fall", 1), (5, "tumble_thick", 0)]
    ids, protos, pos, ori = [], [], [], []
    for fid, fall, proto in listed:
        if fid == 42:
            p, q = falls[3][k - 60]
        elif fid == 21:
            p, q = falls[11][k]
            p = p + Gf.Vec3d(-50, 0, 0)
        else:
            p, q = falls.get(fid, falls[7])[k]
        if fid == 99:
            p = p + Gf.Vec3d(50, 0, 0)
        if fid == 21:
            p = p + Gf.Vec3d(0, 0, 30)
        if fid == 5:
            p = p + Gf.Vec3d(0, 0, -30)
        ids.append(fid)
        protos.append(proto)
        pos.append(Gf.Vec3f(p))
        ori.append(Gf.Quath(q.GetReal(), Gf.Vec3h(q.GetImaginary())))
    inst.CreateIdsAttr().Set(Vt.Int64Array(ids), t)
    inst.CreateProtoIndicesAttr().Set(Vt.IntArray(protos), t)
    inst.CreatePositionsAttr().Set(Vt.Vec3fArray(pos), t)
    inst.CreateOrientationsAttr().Set(Vt.QuathArray(ori), t)
    inst.CreateInvisibleIdsAttr().Set(Vt.Int64Array([21] if t >= 181 else []), t)
inst.DeactivateIds([5])
stage.GetRootLayer().Save()
stage.GetRootLayer().Export(os.path.join(HERE, "leaves.usdc"))

# The oracle: every vertex of every instance, world metres, z up.
cache = UsdGeom.XformCache()
with open(os.path.join(HERE, "leaves.points.csv"), "w", newline="") as f:
    out = csv.writer(f)
    out.writerow(["time_code", "id", "vertex", "x", "y", "z"])
    for k in range(241):
        t = 1 + k
        cache.SetTime(t)
        to_world = cache.GetLocalToWorldTransform(inst.GetPrim())
        xforms = inst.ComputeInstanceTransformsAtTime(
            t, t, UsdGeom.PointInstancer.IncludeProtoXform, UsdGeom.PointInstancer.IgnoreMask
        )
        shown = inst.ComputeMaskAtTime(t)
        ids = inst.GetIdsAttr().Get(t)
        protos = inst.GetProtoIndicesAttr().Get(t)
        for i, fid in enumerate(ids):
            if shown and not shown[i]:
                continue
            proto = [m, w][protos[i]]
            # The mesh's own transform below the prototype root (none
            # here); the root's is in xforms[i].
            for v, p in enumerate(proto.GetPointsAttr().Get(t)):
                q = to_world.Transform(xforms[i].Transform(Gf.Vec3d(p)))
                # y up, centimetres -> z up, metres.
                z_up = TURN.GetInverse().TransformDir(q) * 0.01
                out.writerow([t, fid, v] + ["%.9g" % c for c in z_up])
