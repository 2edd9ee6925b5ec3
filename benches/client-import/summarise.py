"""Summarises benches/client-import.sh's JSON results: import times (median,
min, max over runs) and what each client built, and the largest distance
between the vertices a client evaluates and the simulation's (the PC2 cache
of the same export: f32 positions per frame, z up).
    python summarise.py blender|three WORK_DIR RUNS"""
import json
import os
import statistics
import struct
import sys

kind, work, runs = sys.argv[1], sys.argv[2], int(sys.argv[3])


def pc2(name):
    """Samples of WORK/pc2/NAME.pc2 as [sample][vertex] = (x, y, z)."""
    with open(os.path.join(work, "pc2", name + ".pc2"), "rb") as f:
        b = f.read()
    _, _, n, _, _, s = struct.unpack("<12sii ffi", b[:32])
    v = struct.unpack("<%df" % (3 * n * s), b[32:])
    return [[v[3 * (k * n + i): 3 * (k * n + i) + 3] for i in range(n)] for k in range(s)]


def object_name(blender_name):
    n = blender_name
    for suffix in ("-mesh", "_mesh"):
        if n.endswith(suffix):
            n = n[: -len(suffix)]
    return n.replace("_", "-")


cache = {}


def error(positions_by_frame, convert=lambda p: p, offset=0, fps=30.0, seconds=False):
    """Largest distance to the simulation over the given frames/times."""
    worst = 0.0
    for key, per in positions_by_frame.items():
        sample = round(float(key) * fps) if seconds else int(key) - offset
        for name, pts in per.items():
            ref_name = object_name(name)
            if not os.path.exists(os.path.join(work, "pc2", ref_name + ".pc2")):
                continue
            if ref_name not in cache:
                cache[ref_name] = pc2(ref_name)
            ref = cache[ref_name]
            s = min(max(sample, 0), len(ref) - 1)
            for p, q in zip(pts, ref[s]):
                p = convert(p)
                worst = max(worst, sum((a - b) ** 2 for a, b in zip(p, q)) ** 0.5)
    return worst


def stats(xs):
    return "%.2f s (median of %d; %.2f–%.2f)" % (statistics.median(xs), len(xs), min(xs), max(xs))


if kind == "blender":
    for f in ["hundred-leaves.glb", "hundred-leaves.usda", "hundred-leaves.usdc", "pc2.pc2dir"]:
        rs = []
        for r in range(1, runs + 1):
            p = os.path.join(work, "blender-%s-%d.json" % (f, r))
            if os.path.exists(p) and os.path.getsize(p) > 0:
                rs.append(json.load(open(p)))
        if not rs:
            print("%-22s no result (import failed)" % f)
            continue
        r = rs[0]
        errs = {o: error(r["positions"], offset=o) for o in (0, 1)}
        best = min(errs, key=errs.get)
        blend = r.get("blend_bytes")
        print("%-22s import %s; %d objects (%d meshes), %d shape keys, %d keyframes; scene %g fps, "
              "frames %d–%d; .blend %s; vertices within %.1e m of the simulation (frame F = sample F−%d)"
              % (f, stats([x["import_s"] for x in rs]), r["objects"], r["meshes"], r["shape_keys"],
                 r["keyframes"], r["fps"], r["frame_start"], r["frame_end"],
                 "%.1f MB" % (blend / 1e6) if blend else "-", errs[best], best))
else:
    rs = []
    for r in range(1, runs + 1):
        p = os.path.join(work, "three-%d.json" % r)
        if os.path.exists(p):
            rs.extend(json.loads(l) for l in open(p) if l.strip())
    for f in sorted({x["file"] for x in rs}):
        xs = [x for x in rs if x["file"] == f]
        x = xs[0]
        frames = x["frames"]
        yup = lambda p: (p[0], -p[2], p[1])
        per = {str(fr["t"]): {x["names"][0]: fr["positions"]} for fr in frames}
        e = error(per, convert=yup, seconds=True) if "hundred" in f else None
        print("%-20s load %s, first frame %s; %d meshes, %d tracks, %.1f s clip; GL errors %s; "
              "pixels drawn at t = %s: %s%s; names %s, scene %s"
              % (f, stats([y["load_ms"] / 1000 for y in xs]), stats([y["first_frame_ms"] / 1000 for y in xs]),
                 x["meshes"], x["tracks"], x["duration"], [fr["glError"] for fr in frames],
                 [fr["t"] for fr in frames], [fr["drawn_pixels"] for fr in frames],
                 "; first mesh within %.1e m of the simulation" % e if e is not None else "",
                 x["names"], x["scene"]))
        if x["logs"]:
            print("   console:", x["logs"])
