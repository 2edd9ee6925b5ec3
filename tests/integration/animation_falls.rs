//! Falls read from animation files (glTF) as clients send them: Blender's
//! own exports of the six MuJoCo falls (`tests/data/blender/`, made by its
//! `make.py` with Blender's Python module), and leafmagic's own exports.
//! The oracle is the fall the file was made from: the same keys, the same
//! normal, the same class.

use leafmagic::formats::clip::{Clip, ClipObject, Motion};
use leafmagic::formats::fall::{self, read_fall};
use leafmagic::formats::{alembic, gltf, usd};
use leafmagic::leaf::AeroSpec;
use leafmagic::leaf::LeafSpec;
use leafmagic::leaf::plates::{PlateShape, plate};
use leafmagic::motion::classify::{Classification, classify};
use leafmagic::motion::trajectory::Trajectory;
use leafmagic::output::export;
use leafmagic::sim::drop::{DropParams, drop_leaf};
use nalgebra::Vector3;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

type V3 = Vector3<f64>;

/// The MuJoCo falls Blender baked (one file each).
use crate::corpus::MUJOCO as FALLS;

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(rel)
}

fn leafmagic() -> Command {
    Command::new(env!("CARGO_BIN_EXE_leafmagic"))
}

/// Whether `leafmagic ARGS` succeeds, and what it prints to stderr.
fn run<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> (bool, String) {
    let o = leafmagic().args(args).output().unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// What `leafmagic ARGS` prints to stderr, asserting it fails.
fn refusal<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> String {
    let (ok, err) = run(args);
    assert!(!ok, "did not fail: {err}");
    err
}

fn scratch(name: &str) -> PathBuf {
    super::common::scratch("anim", name)
}

/// A one-object clip at `fps` (as many frames as the object has), written
/// as `dir/file` (.glb or .usda by its extension).
fn written(dir: &Path, file: &str, object: ClipObject, fps: f64) -> (Clip, PathBuf) {
    let frames = match &object.motion {
        Motion::Rigid { translation, .. } => translation.len(),
        Motion::Deforming { frames } => frames.len(),
    };
    let clip = Clip {
        name: file.to_string(),
        fps,
        frames,
        objects: vec![object],
        ground: None,
        wind: vec![],
        aero_law: String::new(),
        warnings: vec![],
    };
    let path = dir.join(file);
    if file.ends_with(".usda") {
        usd::write_usd(&clip, &path, clip.fps).unwrap();
    } else {
        gltf::write_glb(&clip, &path).unwrap();
    }
    (clip, path)
}

/// Classifies two falls (each with its chord) and asserts the same class
/// and regime; returns both classifications.
fn same_class(
    what: &str,
    (a, size_a): (&Trajectory, f64),
    (b, size_b): (&Trajectory, f64),
) -> (Classification, Classification) {
    let (ca, cb) = (classify(a, size_a), classify(b, size_b));
    assert_eq!(
        (ca.class, ca.regime),
        (cb.class, cb.regime),
        "{what}: {:?} | {:?}",
        ca.reason,
        cb.reason
    );
    (ca, cb)
}

/// How far apart two positions may be after a round through f32 (what
/// glTF stores): a few units in the last place of the larger.
fn f32_close(a: &V3, b: &V3) -> bool {
    (a - b).norm() <= 4.0 * f32::EPSILON as f64 * a.norm().max(b.norm()) + 1e-7
}

/// Blender keyed every tenth row of each 240 Hz MuJoCo fall on its 24 fps
/// frames, 2 m up, and exported glTF as it does by default (y up, keys from
/// frame 1 at 1/24 s, the card's node carrying the pose). Read back, each
/// key is the MuJoCo row it came from (to f32), the card's normal and long
/// axis are MuJoCo's body z and x (up to sign: a mesh does not say which
/// face is the top), and the class and regime are those of the 240 Hz CSV.
#[test]
fn blender_bakes_read_as_the_falls_they_were_made_from() {
    for name in FALLS {
        let fall = read_fall(&data(&format!("blender/{name}.glb")), None).unwrap();
        let csv = Trajectory::read_csv(&data(&format!("mujoco-falls/{name}.csv"))).unwrap();
        assert_eq!(fall.object, "card", "{name}");
        assert_eq!(fall.rate_hz, 24.0, "{name}");
        let t = &fall.trajectory;
        assert_eq!(t.len(), 241, "{name}: a key per Blender frame");
        let lift = V3::new(0.0, 0.0, 2.0);
        for k in 0..t.len() {
            assert!((t.time[k] - k as f64 / 24.0).abs() < 1e-12);
            let want = csv.position[10 * k] + lift;
            assert!(
                f32_close(&t.position[k], &want),
                "{name} key {k}: {} against {want}",
                t.position[k]
            );
            for axis in [V3::z(), V3::x()] {
                let got = t.orientation[k] * axis;
                let want = csv.orientation[10 * k] * axis;
                // Blender keys and evaluates its curves in f32: 1e-5 rad.
                assert!(
                    got.cross(&want).norm() < 1e-4 && got.dot(&want).abs() > 0.99,
                    "{name} key {k}: body axis {axis:?} {got} against {want}"
                );
            }
        }
        same_class(name, (t, 0.04), (&csv, 0.04));
    }
}

/// Blender's Alembic export of the same bake (`make.py abc bakes`: y up,
/// the card an Xform `card` over a PolyMesh `card`, a matrix per key) reads
/// as the fall it was made from: each key the MuJoCo row to f32, the
/// card's normal MuJoCo's body z, the same class; and the glTF and the
/// Alembic file place every vertex alike at every key.
#[test]
fn blender_s_alembic_reads_as_the_fall_it_was_made_from() {
    let file = "blender/tumble_thick.abc";
    let fall = read_fall(&data(file), None).unwrap();
    let csv = Trajectory::read_csv(&data("mujoco-falls/tumble_thick.csv")).unwrap();
    assert_eq!(fall.object, "card/card");
    assert_eq!(fall.rate_hz, 24.0);
    let t = &fall.trajectory;
    assert_eq!(t.len(), 241);
    for k in 0..t.len() {
        let want = csv.position[10 * k] + V3::new(0.0, 0.0, 2.0);
        assert!(
            f32_close(&t.position[k], &want),
            "key {k}: {} against {want}",
            t.position[k]
        );
        let (got, want) = (
            t.orientation[k] * V3::z(),
            csv.orientation[10 * k] * V3::z(),
        );
        assert!(
            got.cross(&want).norm() < 1e-4,
            "key {k}: normal {got} against {want}"
        );
    }
    same_class(file, (t, 0.04), (&csv, 0.04));
    let (abc, glb) = (keys_of(file), keys_of("blender/tumble_thick.glb"));
    assert_eq!(abc.frames, glb.frames);
    for k in 0..abc.frames {
        same_points(
            &format!("{file} key {k}"),
            &abc.objects[0].positions(k),
            &glb.objects[0].positions(k),
            1e-5,
        );
    }
    // One animation in an Alembic archive: --animation is refused.
    let path = data(file);
    let err = refusal(&["classify", "--animation", "take", path.to_str().unwrap()]);
    assert!(
        err.contains("an Alembic archive holds one animation"),
        "{err}"
    );
    // Alembic carries no unit: --scale says what one is (0.01 for a Maya
    // file in centimetres), where glTF and USD say their own.
    let describe = |args: &[&str]| -> Value {
        let o = leafmagic()
            .args(["describe", "--json"])
            .args(args)
            .arg(&path)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let (metres, halves) = (describe(&[]), describe(&["--scale", "0.5"]));
    let size = |v: &Value| v["size_m"].as_f64().unwrap();
    assert!((size(&halves) - 0.5 * size(&metres)).abs() < 1e-15);
    assert_eq!(halves["class"], metres["class"]);
}

/// What a modeller may do differently gives the same fall: the card
/// modelled standing in its local xz-plane (the node's frame is not the
/// card's), a static ground beside it (left out), the file written as
/// .gltf + .bin.
#[test]
fn the_modeller_s_frame_a_static_ground_and_separate_buffers_change_nothing() {
    let base = read_fall(&data("blender/tumble_thick.glb"), None).unwrap();
    for file in [
        "blender/tumble_thick_modelled_upright.glb",
        "blender/tumble_thick_with_ground.glb",
        "blender/tumble_thick_separate.gltf",
    ] {
        let fall = read_fall(&data(file), None).unwrap();
        assert_eq!(fall.trajectory.len(), base.trajectory.len(), "{file}");
        assert_eq!(
            fall.still,
            if file.contains("ground") {
                vec!["ground".to_string()]
            } else {
                Vec::<String>::new()
            }
        );
        for k in 0..fall.trajectory.len() {
            assert!(
                f32_close(&fall.trajectory.position[k], &base.trajectory.position[k]),
                "{file} key {k}"
            );
            let n = fall.trajectory.orientation[k] * V3::z();
            let m = base.trajectory.orientation[k] * V3::z();
            assert!(
                n.cross(&m).norm() < 1e-5,
                "{file} key {k}: normal {n} against {m}"
            );
        }
    }
}

/// Every vertex of `got` within `tol` m of a vertex of `want` and every
/// vertex of `want` within `tol` of one of `got`: the same points,
/// whatever order and duplication an exporter gave them (Blender's glTF
/// exporter splits vertices where face normals differ).
fn same_points(what: &str, got: &[V3], want: &[V3], tol: f64) {
    for (a, b, side) in [(got, want, "read"), (want, got, "expected")] {
        for p in a {
            let nearest = b
                .iter()
                .map(|q| (p - q).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(
                nearest < tol,
                "{what}: {side} vertex {p} is {nearest} m from the other side's"
            );
        }
    }
}

/// The clip a glTF or USD file reads as, at its own keys.
fn keys_of(file: &str) -> Clip {
    let path = data(file);
    if file.ends_with(".abc") {
        alembic::read_abc(&std::fs::read(&path).unwrap(), file).unwrap()
    } else if file.ends_with(".usda") {
        usd::read_usda_keys(&std::fs::read_to_string(&path).unwrap(), file).unwrap()
    } else {
        fall::read_clip(&path, None).unwrap()
    }
}

/// The card's name as each format names it: glTF and USD by its mesh,
/// Alembic by its path (`PARENTS/card/card`: the object's Xform, then its
/// mesh).
fn card_name(file: &str, parents: &str) -> String {
    if file.ends_with(".abc") {
        format!("{parents}card/card")
    } else {
        "card".to_string()
    }
}

/// A card under an animated parent, as Blender writes an object parented
/// to an empty: the keys are on the empty `carrier`, the card is its child
/// shifted and turned in the carrier's frame, and the carrier's keys undo
/// that. Both Blender's glTF (a child node) and its USD (nested Xforms)
/// read as the unparented card's fall, vertex for vertex, under the card's
/// name.
#[test]
fn a_card_under_an_animated_parent_reads_as_the_card_s_fall() {
    let base = keys_of("blender/tumble_thick.glb");
    for file in [
        "blender/tumble_thick_parented.glb",
        "blender/tumble_thick_parented.usda",
        "blender/tumble_thick_parented.abc",
    ] {
        let clip = keys_of(file);
        assert_eq!(clip.objects.len(), 1, "{file}: only the card has a mesh");
        assert_eq!(clip.objects[0].name, card_name(file, "carrier/"), "{file}");
        assert_eq!(clip.frames, base.frames, "{file}");
        for k in 0..clip.frames {
            same_points(
                &format!("{file} key {k}"),
                &clip.objects[0].positions(k),
                &base.objects[0].positions(k),
                1e-5,
            );
        }
    }
}

/// The vertices Blender's depsgraph evaluated at each key (`make.py`'s
/// `evaluated`), world metres, one list per key.
fn blender_vertices(file: &str) -> Vec<Vec<V3>> {
    let mut blender: Vec<Vec<V3>> = Vec::new();
    let mut r = csv::Reader::from_path(data(file)).unwrap();
    for row in r.records() {
        let row = row.unwrap();
        let f: usize = row[0].parse().unwrap();
        let p = V3::new(
            row[2].parse().unwrap(),
            row[3].parse().unwrap(),
            row[4].parse().unwrap(),
        );
        if blender.len() < f {
            blender.push(Vec::new());
        }
        blender[f - 1].push(p);
    }
    assert_eq!(blender.len(), 241, "{file}");
    blender
}

/// A card curled by an animated shape key, as an animator shapes a leaf
/// without bones: the card carries the fall's keys and a shape key lifts
/// its ends by up to 4 mm, weighted 0.5 + 0.5 sin(2π 1.5 t). Blender's glTF
/// (a morph target and its weights channel) and its USD (a UsdSkel
/// BlendShape on a one-joint skeleton whose animation holds only the
/// weights) both read, at every key, as the vertices Blender evaluated
/// (`blender/tumble_thick_curled.vertices.csv`) to f32; the curl is there,
/// and the fall keeps the flat card's class.
#[test]
fn a_card_curled_by_a_shape_key_reads_as_blender_shapes_it() {
    let blender = blender_vertices("blender/tumble_thick_curled.vertices.csv");
    for file in [
        "blender/tumble_thick_curled.glb",
        "blender/tumble_thick_curled.usda",
        "blender/tumble_thick_curled.abc",
    ] {
        let clip = keys_of(file);
        assert_eq!(clip.objects.len(), 1, "{file}");
        assert_eq!(clip.objects[0].name, card_name(file, ""), "{file}");
        assert_eq!(clip.frames, 241, "{file}");
        let mut most_curled = 0.0f64;
        for (k, want) in blender.iter().enumerate() {
            let got = clip.objects[0].positions(k);
            same_points(&format!("{file} key {k}"), &got, want, 1e-5);
            // The ends' lift off the flat card's plane: through the
            // middle column (vertices 2, 7, 12 of the 5 × 3 grid, which the
            // curl leaves), along the card's length (the two ends of a
            // row, lifted alike).
            let n = (want[4] - want[0]).cross(&(want[12] - want[2])).normalize();
            most_curled = want
                .iter()
                .map(|p| (p - want[2]).dot(&n).abs())
                .fold(most_curled, f64::max);
        }
        assert!(
            (most_curled - 4e-3).abs() < 2e-4,
            "{file}: the ends lift {most_curled} m at most, not 4 mm"
        );
        let fall = read_fall(&data(file), None).unwrap();
        let flat = read_fall(&data("blender/tumble_thick.glb"), None).unwrap();
        same_class(file, (&fall.trajectory, 0.04), (&flat.trajectory, 0.04));
    }
}

/// A card bent by an armature, as an animator rigs a leaf: skinned to two
/// bones along its length, the armature carrying the fall and the tip bone
/// bending the card out of its plane. Blender's glTF (a skin: joints,
/// inverse bind matrices, JOINTS_0/WEIGHTS_0) and its USD (UsdSkel: a
/// Skeleton, a SkelAnimation, joint indices and weights) both read, at
/// every key, as the vertices Blender itself evaluated (its depsgraph's,
/// `blender/tumble_thick_rigged.vertices.csv`), to f32; the bend is there
/// (the card is not flat at the bend's peaks), and the fall keeps the
/// class of the unbent card's.
#[test]
fn a_card_bent_by_bones_reads_as_blender_poses_it() {
    let blender = blender_vertices("blender/tumble_thick_rigged.vertices.csv");
    for file in [
        "blender/tumble_thick_rigged.glb",
        "blender/tumble_thick_rigged.usda",
        "blender/tumble_thick_rigged.abc",
    ] {
        let clip = keys_of(file);
        assert_eq!(clip.objects.len(), 1, "{file}: the armature has no mesh");
        assert_eq!(clip.objects[0].name, card_name(file, "rig/"), "{file}");
        assert_eq!(clip.frames, 241, "{file}");
        let mut most_bent = 0.0f64;
        for (k, want) in blender.iter().enumerate() {
            let got = clip.objects[0].positions(k);
            // The exported keys are Blender's f32 curves: 1e-5 m at 2 m.
            same_points(&format!("{file} key {k}"), &got, want, 1e-5);
            // How far the card is from flat: the largest distance of a
            // vertex from the plane of the root half's first three.
            let n = (want[1] - want[0]).cross(&(want[5] - want[0])).normalize();
            most_bent = want
                .iter()
                .map(|p| (p - want[0]).dot(&n).abs())
                .fold(most_bent, f64::max);
        }
        // 25° over the tip's 1.5 cm (the blend over the middle centimetre
        // softens it): millimetres out of the plane.
        assert!(
            most_bent > 3e-3,
            "{file}: the card bends only {most_bent} m"
        );
        let fall = read_fall(&data(file), None).unwrap();
        let unbent = read_fall(&data("blender/tumble_thick.glb"), None).unwrap();
        same_class(file, (&fall.trajectory, 0.04), (&unbent.trajectory, 0.04));
    }
}

/// UsdSkel posed as Pixar's library poses it. `usd/skinned_leaf.usda` is
/// written by hand to exercise what Blender's file does not: the skeleton
/// under a moving Xform and turned by its own op, an animation of two of
/// three joints in its own order (the third at rest), rotations slerped
/// between samples, a mesh under an Xform that skinning ignores, with its
/// own joint order, two influences a vertex and a geomBindTransform, and a
/// mesh bound rigidly (constant interpolation). pxr's skinning query
/// poses each mesh at every time code the reader samples; leafmagic's
/// reading matches it to f32 (pxr skins in single precision), in metres
/// and z up.
#[test]
fn usd_skinning_matches_pixar_s() {
    let python = match crate::usd::pixar_python() {
        Ok(p) => p,
        Err(why) => {
            crate::common::missing_tool("usd_skinning_matches_pixar_s", &why);
            return;
        }
    };
    let layer = data("usd/skinned_leaf.usda");
    let clip = keys_of("usd/skinned_leaf.usda");
    // Samples at time codes 0, 2.5, 5 and 10, 10 codes a second: a frame
    // every 2.5 codes.
    assert_eq!(clip.fps, 4.0);
    assert_eq!(clip.frames, 5);
    let codes: Vec<String> = (0..clip.frames)
        .map(|k| format!("{}", 2.5 * k as f64))
        .collect();
    // Each skinned mesh's points posed by pxr's skinning query at each
    // time code, in world space through the Skeleton's transform.
    // (`UsdSkel.BakeSkinning` would do for keys of the animation itself,
    // but bakes only at those: between them it interpolates the points.)
    let pose = r#"
import json, sys
from pxr import Usd, UsdSkel, UsdGeom, Gf, Vt
stage = Usd.Stage.Open(sys.argv[1])
codes = [float(x) for x in sys.argv[2].split(",")]
cache, out = UsdSkel.Cache(), {}
for prim in stage.Traverse():
    if not prim.IsA(UsdSkel.Root):
        continue
    root = UsdSkel.Root(prim)
    cache.Populate(root, Usd.PrimDefaultPredicate)
    for b in cache.ComputeSkelBindings(root, Usd.PrimDefaultPredicate):
        skel = cache.GetSkelQuery(b.GetSkeleton())
        for q in b.GetSkinningTargets():
            frames = []
            for t in codes:
                points = Vt.Vec3fArray(UsdGeom.Mesh(q.GetPrim()).GetPointsAttr().Get(t))
                assert q.ComputeSkinnedPoints(skel.ComputeSkinningTransforms(t), points, t)
                world = UsdGeom.XformCache(t).GetLocalToWorldTransform(b.GetSkeleton().GetPrim())
                frames.append([list(world.Transform(Gf.Vec3d(p))) for p in points])
            out[q.GetPrim().GetName()] = frames
print(json.dumps(out))
"#;
    let o = Command::new(python)
        .args(["-c", pose])
        .arg(&layer)
        .arg(codes.join(","))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let pixar: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(clip.objects.len(), 2);
    for object in &clip.objects {
        // Objects are named by the Xform above a lone mesh: both meshes
        // share one, so each keeps its own name.
        let frames = pixar[&object.name]
            .as_array()
            .unwrap_or_else(|| panic!("{}", object.name));
        for (k, want) in frames.iter().enumerate() {
            let got = object.positions(k);
            let want = want.as_array().unwrap();
            assert_eq!(got.len(), want.len());
            for (i, (g, w)) in got.iter().zip(want).enumerate() {
                let w: Vec<f64> = w
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap())
                    .collect();
                // centimetres, y up → metres, z up.
                let w = V3::new(w[0], -w[2], w[1]) * 0.01;
                assert!(
                    f32_close(g, &w) || (g - w).norm() < 2e-7,
                    "{} code {} vertex {i}: {g} against pxr's {w}",
                    object.name,
                    codes[k]
                );
            }
        }
    }
}

/// Blender's exports after gltfpack 0.25 (`tests/data/gltfpack/`, its
/// defaults but keys at 24 Hz: KHR_mesh_quantization, positions as 16-bit
/// integers moved into an unnamed child node whose scale dequantises
/// them, rotations as normalised 16-bit integers, weights as 8-bit ones):
/// the plain and the rigged card read as Blender's own files do, under the
/// card's name, within what gltfpack's quantisation keeps (14-bit
/// positions over the 4.1 cm card, 2.5 µm; 12-bit rotations, 2.4e-4 rad,
/// 5 µm at the card's tip; so 2e-5 m), with the same class.
#[test]
fn gltfpack_s_quantised_files_read_as_blender_s() {
    for (packed, original) in [
        ("gltfpack/tumble_thick.glb", "blender/tumble_thick.glb"),
        (
            "gltfpack/tumble_thick_rigged.glb",
            "blender/tumble_thick_rigged.glb",
        ),
    ] {
        let (q, b) = (keys_of(packed), keys_of(original));
        assert_eq!((q.fps, q.frames), (b.fps, b.frames), "{packed}");
        assert_eq!(q.objects.len(), 1, "{packed}");
        assert_eq!(q.objects[0].name, "card", "{packed}");
        for k in 0..q.frames {
            same_points(
                &format!("{packed} key {k}"),
                &q.objects[0].positions(k),
                &b.objects[0].positions(k),
                2e-5,
            );
        }
        let (fq, fb) = (
            read_fall(&data(packed), None).unwrap(),
            read_fall(&data(original), None).unwrap(),
        );
        same_class(packed, (&fq.trajectory, 0.04), (&fb.trajectory, 0.04));
    }
}

/// The same fall, in the CLI: `classify --json` of the .glb names the
/// object and the chord it took from the mesh (the 4 × 1 cm card's
/// diagonal), with the class of the CSV; `compare` of the two is close.
#[test]
fn the_cli_reads_a_glb_as_it_reads_a_csv() {
    let glb = data("blender/tumble_thick.glb");
    let o = leafmagic()
        .args(["classify", "--json"])
        .arg(&glb)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["class"], "spinner");
    assert_eq!(v["regime"], "tumble");
    assert_eq!(v["object"], "card");
    let chord = v["size_m"].as_f64().unwrap();
    assert!((chord - 0.04f64.hypot(0.01)).abs() < 1e-7, "{chord}");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("241 keys at 24 Hz"), "{stderr}");
    let o = leafmagic()
        .args(["compare", "--json", "--size", "0.04"])
        .arg(&glb)
        .arg(data("mujoco-falls/tumble_thick.csv"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["same_class"], true);
    let d = v["distance"].as_f64().unwrap();
    assert!(d < 0.1, "a 24 fps bake of a fall is {d} from the fall");
}

/// leafmagic's own exports read back: a rigid plate (node poses) to f32 of
/// the drop's 240 Hz record at the exported frames, its centre being the
/// uniform plate's centroid; prototype A (a mass-spring leaf, morph
/// targets) with the class of its drop.
#[test]
fn leafmagic_s_own_exports_read_back_as_their_drops() {
    let dir = scratch("own");
    let fps = 30.0;
    // A 2 × 6 cm strip let go at a tilt: it turns, so the frame matters.
    let model = plate(PlateShape::Rectangle, 0.02, 3.0, 0.07, AeroSpec::unsteady())
        .unwrap()
        .model()
        .unwrap();
    let tilt = [30.0, 10.0];
    let object = export::drop_clip_released("strip", "", &model, 4.0, fps, tilt).unwrap();
    let (clip, path) = written(&dir, "strip.glb", object, fps);
    let fall = read_fall(&path, None).unwrap();
    let drop = drop_leaf(
        &model,
        &DropParams {
            seconds: 4.0,
            tilt_deg: tilt,
            ..DropParams::default()
        },
    )
    .unwrap();
    assert_eq!(fall.rate_hz, fps);
    for k in 0..fall.trajectory.len() {
        let want = drop.trajectory.position[8 * k];
        assert!(f32_close(&fall.trajectory.position[k], &want), "frame {k}");
        let n = fall.trajectory.orientation[k] * V3::z();
        let m = drop.trajectory.orientation[8 * k] * V3::z();
        assert!(
            n.cross(&m).norm() < 1e-5,
            "frame {k}: normal {n} against {m}"
        );
        let x = fall.trajectory.orientation[k] * V3::x();
        let l = drop.trajectory.orientation[8 * k] * V3::x();
        assert!(
            x.cross(&l).norm() < 1e-5,
            "frame {k}: long axis {x} against {l}"
        );
    }
    same_class(
        "strip",
        (&fall.trajectory, fall.chord),
        (&drop.trajectory, model.chord()),
    );
    // The same clip as leafmagic's USD (an Xform per object, time-sampled
    // translate and orient, the mesh's points in its frame): the same fall.
    let (_, usd_path) = written(&dir, "strip.usda", clip.objects[0].clone(), fps);
    let from_usd = read_fall(&usd_path, None).unwrap();
    assert_eq!(from_usd.object, "strip");
    assert_eq!(from_usd.trajectory.len(), fall.trajectory.len());
    for k in 0..fall.trajectory.len() {
        assert!(
            f32_close(
                &from_usd.trajectory.position[k],
                &fall.trajectory.position[k]
            ),
            "frame {k}"
        );
        let n = from_usd.trajectory.orientation[k] * V3::z();
        let m = fall.trajectory.orientation[k] * V3::z();
        assert!(
            n.cross(&m).norm() < 1e-5,
            "frame {k}: normal {n} against {m}"
        );
    }

    let (_, leaf) = LeafSpec::load_with_model("a").unwrap();
    let object = export::drop_clip("leaf-a", "", &leaf, 10.0, fps).unwrap();
    let (_, path) = written(&dir, "a.glb", object, fps);
    let fall = read_fall(&path, None).unwrap();
    let drop = drop_leaf(&leaf, &DropParams::default()).unwrap();
    let (a, b) = same_class(
        "prototype A",
        (&fall.trajectory, fall.chord),
        (&drop.trajectory, leaf.chord()),
    );
    let (da, db) = (
        a.features.mean_descent_speed_m_s,
        b.features.mean_descent_speed_m_s,
    );
    assert!((da / db - 1.0).abs() < 0.02, "descent {da} against {db}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad or ambiguous animation files are refused by name, with what to do.
#[test]
fn ambiguous_or_broken_animation_files_are_refused_clearly() {
    let dir = scratch("bad");
    let (_, leaf) = LeafSpec::load_with_model("a").unwrap();
    let a = export::drop_clip("leaf-a", "", &leaf, 1.0, 30.0).unwrap();
    let mut b = a.clone();
    b.name = "leaf-b".into();
    b.translate(V3::new(0.2, 0.0, 0.0));
    let two = Clip {
        name: "two".into(),
        fps: 30.0,
        frames: 31,
        objects: vec![a, b],
        ground: None,
        wind: vec![],
        aero_law: String::new(),
        warnings: vec![],
    };
    let path = dir.join("two.glb");
    gltf::write_glb(&two, &path).unwrap();
    let p = path.to_str().unwrap();
    let (ok, err) = run(&["classify", p]);
    assert!(!ok);
    assert!(
        err.contains(p)
            && err.contains("`leaf-a`")
            && err.contains("`leaf-b`")
            && err.contains("--object"),
        "{err}"
    );
    let (ok, err) = run(&["classify", p, "--object", "leaf-b"]);
    assert!(ok, "{err}");
    let (ok, err) = run(&["classify", p, "--object", "leaf-c"]);
    assert!(
        !ok && err.contains("--object leaf-c") && err.contains("`leaf-a`"),
        "{err}"
    );
    let csv = data("mujoco-falls/tumble_thick.csv");
    let (ok, err) = run(&["classify", csv.to_str().unwrap(), "--object", "card"]);
    assert!(!ok && err.contains("CSV record"), "{err}");
    // Files that are not what their name says, or need what is not here:
    // (file, bytes, what the error must say besides the file's name).
    let rigged = std::fs::read_to_string(data("blender/tumble_thick_rigged.usda")).unwrap();
    let bound = "rel skel:skeleton = </root/rig/rig>";
    assert!(rigged.contains(bound));
    // The .gltf + .bin card, edited: a required extension added, or what
    // the fuzz harness found that once panicked or hung the reader.
    let edited = |edit: &dyn Fn(&mut Value)| {
        let text = std::fs::read_to_string(data("blender/tumble_thick_separate.gltf")).unwrap();
        let mut json: Value = serde_json::from_str(&text).unwrap();
        edit(&mut json);
        serde_json::to_vec(&json).unwrap()
    };
    let requiring = |ext: &str| {
        edited(&|json: &mut Value| {
            json["extensionsUsed"] = serde_json::json!([ext]);
            json["extensionsRequired"] = serde_json::json!([ext]);
        })
    };
    let usd_edited = |from: &str, to: &str| {
        let text = std::fs::read_to_string(data("blender/tumble_thick_parented.usda")).unwrap();
        assert!(text.contains(from), "{from}");
        text.replacen(from, to, 1).into_bytes()
    };
    // Beside its .bin, in a folder of its own (`lonely.gltf` must not find it).
    std::fs::create_dir_all(dir.join("ext")).unwrap();
    std::fs::copy(
        data("blender/tumble_thick_separate.bin"),
        dir.join("ext/tumble_thick_separate.bin"),
    )
    .unwrap();
    // The rigged card's crate file with eight bytes at `at` set to 0xff.
    let damaged = |at: usize| {
        let mut b = std::fs::read(data("usd/composed/tumble_thick_rigged.usdc")).unwrap();
        b[at..at + 8].fill(0xff);
        b
    };
    let cases: [(&str, Vec<u8>, &str); 20] = [
        (
            "junk.glb",
            b"t,x,y,z\n0,0,0,0\n".to_vec(),
            "not a valid glTF",
        ),
        (
            // A .gltf whose .bin did not come with it.
            "lonely.gltf",
            std::fs::read(data("blender/tumble_thick_separate.gltf")).unwrap(),
            "tumble_thick_separate.bin",
        ),
        // Binary, packaged and composed USD (read through openusd in a
        // child process, src/output/export/usd_stage.rs).
        (
            "bake.usdc",
            b"PXR-USDC\x00\x00\x00\x00".to_vec(),
            "failed to parse USDC layer",
        ),
        (
            "pack.usdz",
            b"PK\x03\x04\x00\x00".to_vec(),
            "failed to open USDZ archive",
        ),
        (
            "shot.usda",
            b"#usda 1.0\n(\n    subLayers = [@anim.usda@]\n)\n".to_vec(),
            "it does not compose: unresolved sublayer @anim.usda@",
        ),
        // Damaged crate files, found by the fuzz harness: openusd 0.6
        // indexed past a table, and asked for 17 TB (which aborts).
        (
            "indexed.usdc",
            damaged(20728),
            "the USD library (openusd) failed on it: index out of bounds",
        ),
        (
            "greedy.usdc",
            damaged(2589),
            "stopped on it (signal: 6 (SIGABRT): memory allocation of 17592186044400 bytes failed)",
        ),
        (
            // Skinned to a skeleton the layer does not hold.
            "unbound.usda",
            rigged
                .replace(bound, "rel skel:skeleton = </root/rig/gone>")
                .into_bytes(),
            "bound to the skeleton `/root/rig/gone`, which is not in the layer",
        ),
        (
            // UsdSkel blend shapes named without the shapes themselves.
            "shapes.usda",
            rigged
                .replace(
                    bound,
                    &format!("uniform token[] skel:blendShapes = [\"cup\"]\n{bound}"),
                )
                .into_bytes(),
            "mesh `card`: 1 skel:blendShapes but 0 skel:blendShapeTargets",
        ),
        (
            // Inbetween shapes, which would be read wrong if ignored.
            "inbetween.usda",
            std::fs::read_to_string(data("blender/tumble_thick_curled.usda"))
                .unwrap()
                .replacen(
                    "uniform int[] pointIndices",
                    "uniform vector3f[] inbetweens:half = [(0, 0, 1)] (\n weight = 0.5\n )\n uniform int[] pointIndices",
                    1,
                )
                .into_bytes(),
            "blend shape `curl` has the inbetween shape `inbetweens:half`, which this reader does not apply",
        ),
        (
            // gltfpack -c: meshopt-compressed buffers.
            "packed.glb",
            std::fs::read(data("gltfpack/tumble_thick_meshopt.glb")).unwrap(),
            "EXT_meshopt_compression (meshopt-compressed buffers), which leafmagic does not decode",
        ),
        (
            "ext/draco.gltf",
            requiring("KHR_draco_mesh_compression"),
            "KHR_draco_mesh_compression (Draco-compressed geometry), which leafmagic does not decode",
        ),
        (
            // Instancing would place copies this reader does not know of.
            "ext/instanced.gltf",
            requiring("EXT_mesh_gpu_instancing"),
            "EXT_mesh_gpu_instancing, which leafmagic does not read",
        ),
        // Found by the fuzz harness (tests/integration/fuzz.rs): each
        // panicked inside the gltf crate, or hung an eigen-solver, before.
        (
            "ext/no-node.gltf",
            edited(&|j: &mut Value| {
                j["animations"][0]["channels"][0]["target"]["node"] = 99.into()
            }),
            "channels[0].target.node: Index out of bounds",
        ),
        (
            "ext/no-path.gltf",
            edited(&|j: &mut Value| {
                j["animations"][0]["channels"][0]["target"]["path"] = "spin".into()
            }),
            "channels[0].target.path: Invalid value",
        ),
        (
            "ext/no-position.gltf",
            edited(&|j: &mut Value| {
                j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 99.into()
            }),
            "attributes[\"POSITION\"]: Index out of bounds",
        ),
        (
            "ext/float-indices.gltf",
            edited(&|j: &mut Value| {
                let i = j["meshes"][0]["primitives"][0]["indices"].as_u64().unwrap() as usize;
                j["accessors"][i]["componentType"] = 5126.into();
            }),
            "(indices): component type F32, where glTF allows [U8, U16, U32]",
        ),
        (
            "ext/short-keys.gltf",
            edited(&|j: &mut Value| {
                let i = j["animations"][0]["samplers"][1]["output"]
                    .as_u64()
                    .unwrap() as usize;
                j["accessors"][i]["count"] = 100.into();
            }),
            "sampler 1: 241 key times and 400 values, not 4 a key",
        ),
        (
            "far.usda",
            usd_edited("108: (-0.28798091411590576,", "108: (-1e308,"),
            "more than 1e6 m from the origin",
        ),
        (
            // Time codes a second so few that the keys span 1e32 s.
            "forever.usda",
            usd_edited("timeCodesPerSecond = 24", "timeCodesPerSecond = 1e-30"),
            "more than the 1000000 this reader samples",
        ),
    ];
    for (file, bytes, want) in cases {
        let path = dir.join(file);
        std::fs::write(&path, bytes).unwrap();
        let (ok, err) = run(&["classify", path.to_str().unwrap()]);
        assert!(!ok && err.contains(file) && err.contains(want), "{err}");
    }
    // A required extension of looks alone (KTX2 textures) is left unread.
    let path = dir.join("ext/ktx2.gltf");
    std::fs::write(&path, requiring("KHR_texture_basisu")).unwrap();
    let (ok, err) = run(&["classify", path.to_str().unwrap()]);
    assert!(ok, "{err}");
    // Nothing moves: every frame the first.
    let mut held = two.objects[0].clone();
    if let Motion::Deforming { frames } = &mut held.motion {
        let first = frames[0].clone();
        frames.iter_mut().for_each(|f| *f = first.clone());
    }
    let still = Clip {
        objects: vec![held],
        ..two
    };
    let path = dir.join("still.glb");
    gltf::write_glb(&still, &path).unwrap();
    let (ok, err) = run(&["classify", path.to_str().unwrap()]);
    assert!(!ok && err.contains("nothing in it moves"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `breed --like` takes a glTF example: described at its mesh's chord
/// (not the prototype's), its target the .glb's class, and the run keeps
/// the fall read from it as its example.
#[test]
fn breed_like_takes_a_gltf_example() {
    let dir = scratch("like");
    let glb = data("blender/tumble_thick.glb");
    let run = dir.join("run");
    let o = leafmagic()
        .args(["breed", "--create-only", "--like"])
        .arg(&glb)
        .arg("--out")
        .arg(&run)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let toml: toml::Table =
        toml::from_str(&std::fs::read_to_string(run.join("run.toml")).unwrap()).unwrap();
    let like = &toml["settings"]["like"];
    assert_eq!(like["class"].as_str(), Some("spinner"), "{like}");
    let size = like["size_m"].as_float().unwrap();
    assert!((size - 0.04f64.hypot(0.01)).abs() < 1e-7, "{size}");
    let kept = Trajectory::read_csv(&run.join("example.csv")).unwrap();
    let read = read_fall(&glb, None).unwrap().trajectory;
    assert_eq!(kept.time, read.time);
    assert_eq!(kept.position, read.position);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Blender's USD export of the same falls (`NAME.usda`: an Xform with
/// `translate`, Euler `rotateXYZ` in degrees and `scale` time-sampled per
/// frame, the card a Mesh under it) reads as its glTF export does: every
/// vertex of every key within f32 of the .glb's, so the same fall.
#[test]
fn blender_usd_reads_as_its_gltf() {
    for name in FALLS {
        let usd = usd::read_usda_keys(
            &std::fs::read_to_string(data(&format!("blender/{name}.usda"))).unwrap(),
            name,
        )
        .unwrap();
        let glb = gltf::read_gltf_keys(
            &std::fs::read(data(&format!("blender/{name}.glb"))).unwrap(),
            name,
            None,
            None,
        )
        .unwrap();
        assert_eq!(usd.fps, 24.0);
        assert_eq!(usd.frames, glb.frames, "{name}");
        let (u, g) = (&usd.objects[0], &glb.objects[0]);
        assert_eq!(u.name, "card");
        for k in 0..usd.frames {
            let (pu, pg) = (u.positions(k), g.positions(k));
            // Same corners, maybe in another order.
            for p in &pu {
                let nearest = pg
                    .iter()
                    .map(|q| (p - q).norm())
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    nearest < 1e-5,
                    "{name} key {k}: {p} is {nearest} m from the glb's corners"
                );
            }
        }
        let a = read_fall(&data(&format!("blender/{name}.usda")), None).unwrap();
        let b = read_fall(&data(&format!("blender/{name}.glb")), None).unwrap();
        same_class(name, (&a.trajectory, 0.04), (&b.trajectory, 0.04));
    }
}

/// USD as pipelines store it: binary crate files (`.usdc`, and a `.usd`
/// holding one), a USDZ package, and a shot composed of layers (a sublayer
/// retimed by offset 10 and scale ½, a reference to a crate-file asset
/// that holds its mesh by payload, a variant selection that scales it 2×,
/// an xformOpOrder inherited from a class, an inactive prim). Each reads
/// as its text: the Blender and hand-written layers they were made from,
/// and for the shot, what Pixar's own library flattens it to
/// (`shot.flat.usda`, by `tests/data/usd/composed/make.py`, usd-core 26.11).
/// The descriptors of the fall must be the same numbers, to the bit.
#[test]
fn crate_files_packages_and_composed_stages_read_as_their_text() {
    let describe = |file: &str, object: Option<&str>| {
        let mut cmd = leafmagic();
        cmd.args(["describe", "--json"]).arg(data(file));
        if let Some(o) = object {
            cmd.args(["--object", o]);
        }
        let o = cmd.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{file}: {err}");
        let mut json: Value = serde_json::from_slice(&o.stdout).unwrap();
        json.as_object_mut().unwrap().remove("file");
        (json, err)
    };
    for (binary, text, object) in [
        (
            "usd/composed/tumble_thick.usdz",
            "blender/tumble_thick.usda",
            None,
        ),
        (
            "usd/composed/tumble_thick_crate.usd",
            "blender/tumble_thick.usda",
            None,
        ),
        (
            "usd/composed/tumble_thick_rigged.usdc",
            "blender/tumble_thick_rigged.usda",
            None,
        ),
        (
            "usd/composed/skinned_leaf.usdc",
            "usd/skinned_leaf.usda",
            Some("blade"),
        ),
        (
            "usd/composed/shot.usda",
            "usd/composed/shot.flat.usda",
            None,
        ),
    ] {
        let (got, _) = describe(binary, object);
        let (want, _) = describe(text, object);
        assert_eq!(got, want, "{binary} against {text}");
    }
    // The composition did act: the keys run at twice Blender's 24 Hz (the
    // sublayer's scale ½) and the card is twice its size (the variant).
    let (_, note) = describe("usd/composed/shot.usda", None);
    assert!(note.contains("object `leaf`, 241 keys at 48 Hz"), "{note}");
    let chord = |note: &str| -> f64 {
        let at = note.find("chord ").unwrap() + 6;
        note[at..].split(' ').next().unwrap().parse().unwrap()
    };
    let (_, blender) = describe("blender/tumble_thick.usda", None);
    assert!(
        (chord(&note) / chord(&blender) - 2.0).abs() < 0.01,
        "{note} / {blender}"
    );
}

/// An object with several takes, as an animator keeps them: Blender writes
/// the active action (`tumble`, tumble_thick's keys) and the one it stashed
/// when the animator switched (`steady`, steady_fall's) as two glTF
/// animations of the same card (`blender/tumble_thick_takes.glb`). Read
/// together they were one fall of neither (the first channel of each
/// property won); now the file is refused naming both, and `--animation`
/// reads (or `preview` plays) the one it names, by name or index, as the
/// fall it holds.
#[test]
fn a_file_with_several_takes_is_read_by_the_one_named() {
    let takes = data("blender/tumble_thick_takes.glb");
    for (pick, original) in [
        ("tumble", "blender/tumble_thick.glb"),
        ("1", "blender/tumble_thick.glb"),
        ("steady", "blender/steady_fall.glb"),
    ] {
        let got = fall::read_fall_of(&takes, None, Some(pick)).unwrap();
        let want = read_fall(&data(original), None).unwrap();
        let (g, w) = (&got.trajectory, &want.trajectory);
        assert_eq!(g.time, w.time, "{pick}");
        for k in 0..g.len() {
            assert!(
                (g.position[k] - w.position[k]).norm() < 1e-12,
                "{pick} key {k}"
            );
            assert!(
                g.orientation[k].angle_to(&w.orientation[k]) < 1e-9,
                "{pick} key {k}"
            );
        }
    }
    let file = takes.to_str().unwrap();
    let (ok, err) = run(&["classify", file]);
    assert!(
        !ok && err.contains(
            "tumble_thick_takes.glb: 2 of its animations move node `card` (`steady`, `tumble`): name the one to read with --animation NAME"
        ),
        "{err}"
    );
    let (ok, err) = run(&["classify", file, "--animation", "walk"]);
    assert!(
        !ok && err
            .contains("--animation walk: no animation of that name; it holds `steady`, `tumble`"),
        "{err}"
    );
    // Each side of a comparison its own take.
    let (ok, err) = run(&["compare", file, file, "--animation", "tumble,steady"]);
    assert!(ok, "{err}");
    // A preview plays the take it is given, and refuses to mix them.
    let dir = scratch("takes");
    let html = dir.join("takes.html");
    let html = html.to_str().unwrap();
    let (ok, err) = run(&["preview", file, "--out", html]);
    assert!(!ok && err.contains("--animation NAME"), "{err}");
    let (ok, err) = run(&["preview", file, "--out", html, "--animation", "tumble"]);
    assert!(ok && std::path::Path::new(html).is_file(), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
    // Not for a USD stage, which holds one, nor for a CSV record.
    for other in ["blender/tumble_thick.usda", "mujoco-falls/tumble_thick.csv"] {
        let (ok, err) = run(&[
            "classify",
            data(other).to_str().unwrap(),
            "--animation",
            "tumble",
        ]);
        assert!(!ok && err.contains("--animation tumble"), "{err}");
    }
}

/// Leaves scattered by a UsdGeom PointInstancer, as a particle simulation
/// writes them (`usd/instanced/leaves.usda`, by its `make.py`: MuJoCo
/// falls as instances of two prototypes, y up in centimetres under a
/// shifted parent, half-precision orientations, ids listed in another
/// order at every other time code, a prototype root with its own turn; one
/// instance dies half way, one is born a quarter of the way in, one is
/// hidden for the last quarter and one is deactivated). Every vertex of
/// every instance reads where Pixar's library places it, over the life
/// its mask shows (`leaves.points.csv`: `ComputeInstanceTransformsAtTime`,
/// `ComputeMaskAtTime` and the instancer's world transform) at every key
/// (below, how close), the deactivated instance is not read, the crate
/// file reads to the same bits as the text, and each instance keeps the
/// class of the fall it was made from.
#[test]
fn a_point_instancer_s_leaves_read_where_pixar_places_them() {
    let file = "usd/instanced/leaves.usda";
    let clip = usd::read_usda_keys(&std::fs::read_to_string(data(file)).unwrap(), file).unwrap();
    let lives: std::collections::BTreeMap<&str, (usize, usize)> = clip
        .objects
        .iter()
        .map(|o| (o.name.as_str(), (o.first_frame, o.frame_count())))
        .collect();
    // Each life: its first key and how many keys it holds, of 241.
    let expected: std::collections::BTreeMap<&str, (usize, usize)> = [
        ("leaves[11]", (0, 241)),
        ("leaves[21]", (0, 180)),
        ("leaves[3]", (0, 241)),
        ("leaves[42]", (60, 181)),
        ("leaves[7]", (0, 241)),
        ("leaves[99]", (0, 120)),
    ]
    .into_iter()
    .collect();
    assert_eq!(lives, expected);
    assert_eq!(clip.frames, 241);
    let mut want: std::collections::HashMap<(usize, String), Vec<V3>> = Default::default();
    let mut r = csv::Reader::from_path(data("usd/instanced/leaves.points.csv")).unwrap();
    for row in r.records() {
        let row = row.unwrap();
        let key = (
            row[0].parse::<usize>().unwrap() - 1,
            format!("leaves[{}]", &row[1]),
        );
        let p = V3::new(
            row[3].parse().unwrap(),
            row[4].parse().unwrap(),
            row[5].parse().unwrap(),
        );
        want.entry(key).or_default().push(p);
    }
    // Pixar shows each instance at exactly the keys of its life.
    for (name, &(first, count)) in &expected {
        let shown: Vec<usize> = (0..clip.frames)
            .filter(|&k| want.contains_key(&(k, name.to_string())))
            .collect();
        assert_eq!(shown, (first..first + count).collect::<Vec<_>>(), "{name}");
    }
    assert!(!want.keys().any(|(_, name)| name == "leaves[5]"));
    // Pixar turns each instance by its half-precision quaternion as
    // stored, |q| within 1e-3 of 1 (0.99951 at code 2 for id 11), which
    // scales the card by |q|²; leafmagic normalises it, as a rigid leaf
    // is turned. So each vertex is within 3e-5 m (2.2 cm from the centre
    // times 1e-3), and the centres, which the scale leaves, within 1e-6 m.
    let centre = |ps: &[V3]| ps.iter().sum::<V3>() / ps.len() as f64;
    for o in &clip.objects {
        for k in 0..o.frame_count() {
            let expected = &want[&(o.first_frame + k, o.name.clone())];
            let got = o.positions(k);
            assert_eq!(got.len(), expected.len());
            for (g, w) in got.iter().zip(expected) {
                assert!((g - w).norm() < 3e-5, "{} key {k}: {g} against {w}", o.name);
            }
            let (g, w) = (centre(&got), centre(expected));
            assert!(
                (g - w).norm() < 1e-7 + 2e-7 * w.norm(),
                "{} key {k}: centre {g} against {w}",
                o.name
            );
        }
    }
    // The crate file (read in leafmagic's child process, so through the
    // binary): each instance describes to the same bytes as in the text.
    let crate_file = data("usd/instanced/leaves.usdc");
    for o in &clip.objects {
        let describe = |path: &Path| {
            let out = leafmagic()
                .args(["describe", "--json", "--object", &o.name])
                .arg(path)
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let mut v: Value = serde_json::from_slice(&out.stdout).unwrap();
            v.as_object_mut().unwrap().remove("file");
            (v, String::from_utf8_lossy(&out.stderr).into_owned())
        };
        let ((crate_out, crate_err), (text_out, _)) =
            (describe(&crate_file), describe(&data(file)));
        assert_eq!(crate_out, text_out, "{}", o.name);
        assert_eq!(
            crate_err.contains("it appears 2.50 s after the file's first key"),
            o.name == "leaves[42]",
            "{crate_err}"
        );
    }
    let err = refusal(&["classify", crate_file.to_str().unwrap()]);
    assert!(
        err.contains("`leaves[42]` (deforming, 2.50–10.00 s of 10.00 s)"),
        "{err}"
    );
    assert!(!err.contains("leaves[5]"), "{err}");
    for (id, fall) in [(42, "flutter_strip"), (21, "steady_fall")] {
        let object = format!("leaves[{id}]");
        let read = read_fall(&data(file), Some(&object)).unwrap();
        let original = Trajectory::read_csv(&data(&format!("mujoco-falls/{fall}.csv"))).unwrap();
        same_class(&object, (&read.trajectory, 0.04), (&original, 0.04));
    }
    for (id, fall) in [
        (7, "tumble_thick"),
        (3, "flutter_strip"),
        (11, "steady_fall"),
    ] {
        let object = format!("leaves[{id}]");
        let read = read_fall(&data(file), Some(&object)).unwrap();
        let original = Trajectory::read_csv(&data(&format!("mujoco-falls/{fall}.csv"))).unwrap();
        same_class(&object, (&read.trajectory, 0.04), (&original, 0.04));
    }
}

/// The page data of a `preview` page: its JSON, and per object its name,
/// label, first clip frame and vertex positions per frame of its life.
struct PageObject {
    name: String,
    label: String,
    first: usize,
    frames: Vec<Vec<V3>>,
}

fn page_objects(html: &Path) -> (Value, Vec<PageObject>) {
    use base64::Engine as _;
    let page = std::fs::read_to_string(html).unwrap();
    let start = page.find("id=\"leafmagic-data\"").unwrap();
    let start = start + page[start..].find('>').unwrap() + 1;
    let end = start + page[start..].find("</script>").unwrap();
    let data: Value = serde_json::from_str(&page[start..end].replace("<\\/", "</")).unwrap();
    let objects = data["objects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| {
            let n = o["n"].as_u64().unwrap() as usize;
            let bytes = base64::engine::general_purpose::STANDARD
                .decode(o["pos"].as_str().unwrap())
                .unwrap();
            let floats: Vec<f64> = bytes
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64)
                .collect();
            PageObject {
                name: o["name"].as_str().unwrap().to_string(),
                label: o["label"].as_str().unwrap().to_string(),
                first: o["first"].as_u64().unwrap() as usize,
                frames: floats
                    .chunks_exact(3 * n)
                    .map(|f| {
                        f.chunks_exact(3)
                            .map(|c| V3::new(c[0], c[1], c[2]))
                            .collect()
                    })
                    .collect(),
            }
        })
        .collect();
    (data, objects)
}

/// What `leafmagic classify FILE [--object NAME] [MORE]` names the fall: its
/// class, as the page labels it.
fn class_of(file: &Path, object: Option<&str>, more: &[&str]) -> String {
    let o = leafmagic()
        .arg("classify")
        .arg(file)
        .args(object.map(|o| ["--object", o]).into_iter().flatten())
        .arg("--json")
        .args(more)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    v["class"].as_str().unwrap().to_string()
}

/// `preview` plays every animation file `classify` reads (glTF, USD text
/// and crate, Alembic): each object over its own life (a PointInstancer's
/// leaves born, killed, hidden), and each fall the file does not label
/// labelled with the class `classify --object` gives it, at the file's own
/// keys, even where the page samples a .glb at another rate.
#[test]
fn preview_plays_every_animation_file_with_its_falls_classified() {
    let dir = scratch("preview-files");
    for file in [
        "usd/instanced/leaves.usda",
        "usd/instanced/leaves.usdc",
        "blender/tumble_thick.abc",
        "blender/tumble_thick_separate.gltf",
        "blender/tumble_thick_with_ground.glb",
        "blender/flutter_strip.usda",
        "particles/leaves.abc",
        "particles/dying.abc",
    ] {
        let path = data(file);
        let html = dir.join(file.replace('/', "_") + ".html");
        let o = leafmagic()
            .arg("preview")
            .arg(&path)
            .arg("--out")
            .arg(&html)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let said = String::from_utf8_lossy(&o.stdout);
        // A crate file is read by a child `leafmagic` process, which this
        // test binary is not: its text twin stands for it (the instancer's
        // test holds them the same).
        let twin = if file.ends_with(".usdc") {
            path.with_extension("usda")
        } else {
            path.clone()
        };
        let keys = fall::read_clip(&twin, None).unwrap();
        let (data, objects) = page_objects(&html);
        let mut classified = 0;
        for (index, (page, read)) in objects.iter().zip(&keys.objects).enumerate() {
            assert_eq!(page.name, read.name);
            if page.name == "ground" {
                assert_eq!(page.label, "", "{file}: the still ground is not a fall");
                continue;
            }
            assert_eq!(
                page.label,
                class_of(&path, Some(&page.name), &[]),
                "{file}: {}",
                page.name
            );
            classified += 1;
            if file.ends_with(".glb") {
                continue; // sampled from 0 at 30 fps, not at its keys
            }
            // Over its own life, vertex for vertex as read (float32).
            assert_eq!(
                (page.first, page.frames.len()),
                (read.first_frame, read.frame_count())
            );
            // A particle's page holds its centre and its size.
            let marker = data["objects"][index]["marker"].as_f64();
            if read.is_marker() {
                let size = fall::chord(&read.positions(0));
                assert!((marker.unwrap() - size).abs() < 1e-12 * size);
            } else {
                assert_eq!(marker, None);
            }
            for (k, frame) in page.frames.iter().enumerate() {
                let at = if read.is_marker() {
                    vec![read.centre(k)]
                } else {
                    read.positions(k)
                };
                assert_eq!(frame.len(), at.len());
                for (a, b) in frame.iter().zip(at) {
                    assert!(
                        (a - b).norm() <= 1e-6 * (1.0 + b.norm()),
                        "{file} {}",
                        page.name
                    );
                }
            }
        }
        assert_eq!(
            data["frames"].as_u64().unwrap() as usize,
            if file.ends_with(".glb") {
                302
            } else {
                keys.frames
            }
        );
        assert!(
            said.contains(&format!("classified {classified} fall")),
            "{file}: {said}"
        );
    }
    // The instancer's leaves: one born at 2.5 s, one dead from 4.96 s.
    let leaves = data("usd/instanced/leaves.usda");
    let html = dir.join("leaves-12.html");
    let (ok, err) = run(&[
        "preview",
        leaves.to_str().unwrap(),
        "--out",
        html.to_str().unwrap(),
        "--fps",
        "12",
    ]);
    assert!(ok, "{err}");
    let (data12, objects) = page_objects(&html);
    assert_eq!(data12["frames"], 121);
    let keys = fall::read_clip(&leaves, None).unwrap();
    let born = objects.iter().find(|o| o.name == "leaves[42]").unwrap();
    let read = keys
        .objects
        .iter()
        .find(|o| o.name == "leaves[42]")
        .unwrap();
    // 2.5 s: frame 60 of 24 Hz, frame 30 of 12 Hz; every other key.
    assert_eq!((read.first_frame, born.first), (60, 30));
    for (k, frame) in born.frames.iter().enumerate() {
        for (a, b) in frame.iter().zip(read.positions(2 * k)) {
            assert!((a - b).norm() <= 1e-6 * (1.0 + b.norm()));
        }
    }
    let died = objects.iter().find(|o| o.name == "leaves[99]").unwrap();
    assert_eq!((died.first, died.frames.len()), (0, 60)); // to 4.92 s of 4.96

    // Alembic carries no unit: --scale says it, for the page and the labels.
    let abc = data("blender/tumble_thick.abc");
    let cm = dir.join("cm.html");
    let (ok, err) = run(&[
        "preview",
        abc.to_str().unwrap(),
        "--out",
        cm.to_str().unwrap(),
        "--scale",
        "0.01",
    ]);
    assert!(ok, "{err}");
    let (_, scaled) = page_objects(&cm);
    let (_, metres) = page_objects(&dir.join("blender_tumble_thick.abc.html"));
    assert_eq!(
        scaled[0].label,
        class_of(&abc, Some(&scaled[0].name), &["--scale", "0.01"])
    );
    for (a, b) in scaled[0]
        .frames
        .iter()
        .flatten()
        .zip(metres[0].frames.iter().flatten())
    {
        assert!((a - b * 0.01).norm() <= 1e-6 * b.norm() * 0.01 + 1e-9);
    }
    for (args, want) in [
        (
            vec!["preview", leaves.to_str().unwrap(), "--scale", "0.01"],
            "--scale 0.01: applies to an Alembic archive",
        ),
        (
            vec!["preview", abc.to_str().unwrap(), "--scale=-1"],
            "--scale must be a positive number",
        ),
        (
            vec!["preview", dir.to_str().unwrap(), "--scale", "0.01"],
            "--scale applies to an animation file",
        ),
        (
            vec!["preview", abc.to_str().unwrap(), "--animation", "tumble"],
            "--animation tumble: a USD stage or an Alembic archive holds one",
        ),
    ] {
        let err = refusal(&args);
        assert!(err.contains(want), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `preview` plays a recorded fall (a CSV, as `classify` reads it): a
/// square plate of diagonal `--size` posed by the record's orientation, or
/// a marker where the record has a path only (a real square tracked on
/// video), each labelled with the class `classify` gives it with the same
/// flags, beside the record's whole path drawn still.
#[test]
fn preview_plays_a_recorded_fall_as_its_plate_or_its_path() {
    let dir = scratch("preview-records");
    // MuJoCo's tumbling card: 240 Hz, orientation and all.
    let mujoco = data("mujoco-falls/tumble_thick.csv");
    let html = dir.join("tumble.html");
    let (ok, err) = run(&[
        "preview",
        mujoco.to_str().unwrap(),
        "--out",
        html.to_str().unwrap(),
        "--size",
        "0.04",
    ]);
    assert!(ok, "{err}");
    let (page, objects) = page_objects(&html);
    // 240 Hz is more than a page needs: 120 frames a second over its 10 s.
    assert_eq!(
        (page["fps"].as_f64(), page["frames"].as_u64()),
        (Some(120.0), Some(1201))
    );
    let plate = &objects[0];
    assert_eq!(plate.label, class_of(&mujoco, None, &["--size", "0.04"]));
    let record = Trajectory::read_csv(&mujoco).unwrap();
    let at = record.resampled(120.0);
    for (k, corners) in plate.frames.iter().enumerate() {
        // Its centre where the record puts it, its diagonals the chord,
        // its normal the record's body z.
        // Float32 on the page: 40 m down, a few micrometres.
        let tol = 2e-7 * (1.0 + at.position[k].norm());
        let centre = corners.iter().sum::<V3>() / 4.0;
        assert!((centre - at.position[k]).norm() < tol, "frame {k}");
        for diagonal in [corners[2] - corners[0], corners[3] - corners[1]] {
            assert!((diagonal.norm() - 0.04).abs() < 4.0 * tol, "frame {k}");
        }
        let normal = (corners[1] - corners[0])
            .cross(&(corners[2] - corners[0]))
            .normalize();
        assert!(
            normal.dot(&(at.orientation[k] * V3::z())) > 1.0 - 1e-5,
            "frame {k}"
        );
    }
    // Its path, still: the record's samples, one frame.
    let path = &objects[1];
    assert_eq!(page["objects"][1]["still"], true);
    assert_eq!(path.frames.len(), 1);
    // Its 2,401 samples, every other one kept (at most 2,000 points).
    let n = record.time.len();
    assert_eq!((n, path.frames[0].len()), (2401, 1201));
    for (j, p) in path.frames[0].iter().enumerate() {
        let q = record.position[2 * j];
        assert!((p - q).norm() < 2e-7 * (1.0 + q.norm()));
    }

    // A real square tracked on video: a path only, so a marker.
    let square = data("real-falls/squares/square_003.csv");
    let html = dir.join("square.html");
    let (ok, err) = run(&[
        "preview",
        square.to_str().unwrap(),
        "--out",
        html.to_str().unwrap(),
        "--size",
        "0.069",
    ]);
    assert!(ok, "{err}");
    let (page, objects) = page_objects(&html);
    assert_eq!(page["fps"].as_f64(), Some(98.0));
    assert_eq!(page["objects"][0]["kind"], "marker");
    assert_eq!(page["objects"][0]["tris"].as_array().map(Vec::len), Some(0));
    assert_eq!(
        objects[0].label,
        class_of(&square, None, &["--size", "0.069"])
    );

    // Flags that do not apply, refused by name.
    let glb = data("blender/tumble_thick.glb");
    for (args, want) in [
        (
            vec!["preview", glb.to_str().unwrap(), "--size", "0.04"],
            "--size applies to a CSV record",
        ),
        (
            vec!["preview", glb.to_str().unwrap(), "--up", "y"],
            "--up applies to a CSV record",
        ),
        (
            vec!["preview", square.to_str().unwrap(), "--animation", "tumble"],
            "--animation tumble: ",
        ),
        (
            vec!["preview", square.to_str().unwrap(), "--size", "0"],
            "--size",
        ),
    ] {
        let err = refusal(&args);
        assert!(err.contains(want), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The preview of a `breed --like` run shows the example the run was bred
/// toward beside its best leaves: the example's own motion (from the copy
/// the run keeps), labelled with the class the run recorded for it, one
/// place left of the first leaf and released at the leaves' height.
#[test]
fn a_like_run_s_preview_shows_its_example_beside_its_leaves() {
    let dir = scratch("like-preview");
    let run_dir = dir.join("run");
    let example = data("mujoco-falls/tumble_thick.csv");
    let (ok, err) = run(&[
        "breed",
        "--like",
        example.to_str().unwrap(),
        "--size",
        "0.04",
        "--generations",
        "1",
        "--population",
        "8",
        "--out",
        run_dir.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let html = dir.join("page.html");
    let (ok, err) = run(&[
        "preview",
        run_dir.to_str().unwrap(),
        "--out",
        html.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let (page, objects) = page_objects(&html);
    assert_eq!(objects.len(), 6, "the five best and the example");
    let centre = |f: &[V3]| f.iter().sum::<V3>() / f.len() as f64;
    let ex = &objects[0];
    assert_eq!(ex.name, "example");
    assert_eq!(ex.label, class_of(&example, None, &["--size", "0.04"]));
    // Its motion is the example's, at the page's 30 fps, from its release.
    let record = Trajectory::read_csv(&run_dir.join("example.csv"))
        .unwrap()
        .resampled(30.0);
    let frames = page["frames"].as_u64().unwrap() as usize;
    assert_eq!(ex.frames.len(), record.time.len().min(frames));
    let start = centre(&ex.frames[0]);
    for (k, f) in ex.frames.iter().enumerate() {
        let moved = centre(f) - start;
        let want = record.position[k] - record.position[0];
        assert!(
            (moved - want).norm() < 1e-5 * (1.0 + want.norm()),
            "frame {k}"
        );
    }
    // Left of the row, about one place before its first leaf (each leaf's
    // centre sits near its place, off by its shape), at its height.
    let leaves: Vec<V3> = objects[1..].iter().map(|o| centre(&o.frames[0])).collect();
    let mean_gap = (leaves[4].x - leaves[0].x) / 4.0;
    let gap = leaves[0].x - start.x;
    assert!(
        gap > 0.5 * mean_gap && gap < 1.5 * mean_gap,
        "the example {gap} m left of the first leaf, the leaves {mean_gap} m apart"
    );
    assert!(start.y.abs() < 1e-6 && (start.z - leaves[0].z).abs() < 1e-6);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `preview A B ...` puts several falls side by side on one page to compare
/// them by eye: each labelled as `classify` labels it, all played at the
/// highest of their rates, each released at one height in a place of its
/// own along x; the flags apply to the inputs they fit, and a directory
/// among several is refused.
#[test]
fn preview_of_several_files_puts_their_falls_side_by_side() {
    let dir = scratch("preview-several");
    let record = data("mujoco-falls/tumble_thick.csv");
    let glb = data("blender/tumble_thick.glb");
    let abc = data("blender/tumble_thick.abc");
    let html = dir.join("page.html");
    let (ok, err) = run(&[
        "preview",
        record.to_str().unwrap(),
        glb.to_str().unwrap(),
        abc.to_str().unwrap(),
        "--size",
        "0.04",
        "--out",
        html.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let (page, objects) = page_objects(&html);
    assert_eq!(page["grid"], true);
    // The record's 240 Hz, capped at 120; the files' 24 and 30 below it.
    assert_eq!(page["fps"].as_f64(), Some(120.0));
    let names: Vec<&str> = objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "tumble_thick",
            "tumble_thick-2/card",
            "tumble_thick-3/card/card"
        ]
    );
    assert_eq!(
        objects[0].label,
        class_of(&record, None, &["--size", "0.04"])
    );
    assert_eq!(objects[1].label, class_of(&glb, None, &[]));
    assert_eq!(objects[2].label, class_of(&abc, None, &[]));
    // Released at one height, left to right in the order given.
    let centre = |f: &[V3]| f.iter().sum::<V3>() / f.len() as f64;
    let starts: Vec<V3> = objects.iter().map(|o| centre(&o.frames[0])).collect();
    for s in &starts {
        assert!(s.z.abs() < 1e-6 && s.y.abs() < 1e-6, "{s}");
    }
    assert!(starts[0].x < starts[1].x && starts[1].x < starts[2].x);
    // The record's fall as it moves, from its release, at 120 fps.
    let at = Trajectory::read_csv(&record).unwrap().resampled(120.0);
    for (k, f) in objects[0].frames.iter().enumerate().step_by(60) {
        let moved = centre(f) - starts[0];
        let want = at.position[k] - at.position[0];
        assert!(
            (moved - want).norm() < 1e-5 * (1.0 + want.norm()),
            "frame {k}"
        );
    }
    for (args, want) in [
        (
            vec![
                "preview",
                glb.to_str().unwrap(),
                abc.to_str().unwrap(),
                "--size",
                "0.04",
            ],
            "--size applies to a CSV record (a .csv fall); none of the inputs is one",
        ),
        (
            vec!["preview", glb.to_str().unwrap(), dir.to_str().unwrap()],
            "a directory; several inputs are compared as files",
        ),
    ] {
        let err = refusal(&args);
        assert!(err.contains(want), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
