//! USD export (issue 21) checked with Pixar's own library: the files
//! `leafmagic` writes (`.usda`), and their `.usdc` conversions by Pixar's
//! `Sdf.Layer.Export`, are opened by `pxr.Usd` (PyPI `usd-core`, installed
//! into the target directory on first use; skipped with a message where it
//! cannot be installed), pass every validator of `UsdValidation` (what
//! `usdchecker` runs in usd-core 26), carry the stage metadata, one material
//! per class, UVs and normals, and their points, composed through the Xforms
//! as USD composes them, are the simulation's at every time code.

use leafmagic::formats::clip::Clip;
use leafmagic::formats::clip::render_mesh::{ObjMesh, RenderMesh};
use leafmagic::formats::usd;
use leafmagic::leaf::LeafSpec;
use leafmagic::output::export;
use leafmagic::sim::scene::Scene;
use nalgebra::Vector3;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

type V3 = Vector3<f64>;

/// The pinned usd-core release the tests use.
const USD_CORE: &str = "usd-core==26.11";

/// A Python with `pxr` (usd-core) importable, set up once per target
/// directory, or why there is none.
pub fn pixar_python() -> Result<PathBuf, String> {
    crate::common::venv_python("usd-core-venv", "pxr.Usd", USD_CORE)
}

/// Reads each file with pxr and reports, as JSON, the compliance checker's
/// findings, the stage metadata, and per geometry prim its composed world
/// points at every time code, UVs, normals, material and custom attributes.
const READ_PY: &str = r#"
import json, sys
from pxr import Usd, UsdGeom, UsdShade, UsdValidation, Sdf, Gf

validators = UsdValidation.ValidationContext(
    UsdValidation.ValidationRegistry().GetOrLoadAllValidators())
files = []
for f in sys.argv[1:]:
    files.append(f)
    # The binary encoding, written by Pixar's library from ours.
    c = f[:-len(".usda")] + ".usdc"
    assert Sdf.Layer.FindOrOpen(f).Export(c)
    files.append(c)
out = []
for f in files:
    stage = Usd.Stage.Open(f)
    issues = ["%s %s: %s" % (e.GetType(), e.GetName(), e.GetMessage())
              for e in validators.Validate(stage)]
    start, end = stage.GetStartTimeCode(), stage.GetEndTimeCode()
    r = {"file": f, "issues": issues, "up": UsdGeom.GetStageUpAxis(stage),
         "mpu": UsdGeom.GetStageMetersPerUnit(stage), "tcps": stage.GetTimeCodesPerSecond(),
         "fps": stage.GetFramesPerSecond(), "start": start, "end": end,
         "default": str(stage.GetDefaultPrim().GetPath()), "objects": []}
    for prim in stage.Traverse():
        if not (prim.IsA(UsdGeom.Mesh) or prim.IsA(UsdGeom.BasisCurves)):
            continue
        parent = prim.GetParent()
        g = UsdGeom.PointBased(prim)
        frames = []
        for t in range(int(start), int(end) + 1):
            m = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(t)
            frames.append([list(m.Transform(Gf.Vec3d(p))) for p in g.GetPointsAttr().Get(t)])
        o = {"path": str(prim.GetPath()), "type": prim.GetTypeName(), "frames": frames,
             "name": parent.GetAttribute("leafmagic:name").Get(),
             "class": parent.GetAttribute("leafmagic:class").Get(),
             "features": {a.GetName(): a.Get() for a in parent.GetAttributes()
                          if a.GetName().startswith("leafmagic:features:")},
             "xform_samples": len(parent.GetAttribute("xformOp:translate").GetTimeSamples())}
        mat, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        o["material"] = str(mat.GetPath()) if mat else None
        if mat:
            shader = mat.ComputeSurfaceSource()[0]
            o["color"] = list(shader.GetInput("diffuseColor").Get())
        if prim.IsA(UsdGeom.Mesh):
            mesh = UsdGeom.Mesh(prim)
            st = UsdGeom.PrimvarsAPI(prim).GetPrimvar("st")
            o["st"] = [list(x) for x in st.Get()]
            o["st_interpolation"] = st.GetInterpolation()
            o["normals"] = [len(mesh.GetNormalsAttr().Get(t)) for t in (start, end)]
            o["normals_interpolation"] = mesh.GetNormalsInterpolation()
            o["faces"] = len(mesh.GetFaceVertexCountsAttr().Get())
        r["objects"].append(o)
    out.append(r)
print(json.dumps(out))
"#;

fn scratch(name: &str) -> PathBuf {
    super::common::scratch("usd", name)
}

/// One of everything that is exported differently (as in export.rs): a
/// deforming leaf, a tumbling rigid box, a rope, ground and wind.
const MIXED: &str = r#"
name = "mixed"
duration = 1.0
frame_rate = 60
[ground]
height = 0.0
static_friction = 0.5
kinetic_friction = 0.4
[[wind]]
kind = "uniform"
velocity = [0.4, 0.0, 0.0]
[[leaf]]
name = "leaf"
leaf = "a"
position = [0.0, 0.0, 1.0]
tilt_deg = 20.0
[[rigid]]
name = "box"
shape = "box"
size = [0.2, 0.1, 0.05]
mass = 0.1
position = [0.5, 0.0, 0.6]
angular_velocity = [1.0, 2.0, 3.0]
[[fixed]]
name = "anchor"
position = [-0.5, 0.0, 1.5]
[[rope]]
name = "rope"
from = "anchor"
to = "box:0"
segments = 4
mass = 0.01
stiffness = 50.0
slack = 0.3
"#;

/// A render mesh for a leaf: each simulated rest triangle split in four,
/// every vertex lifted off the surface by up to 1.5 mm, UVs over the
/// outline; in the leaf's body frame.
pub fn fine_mesh(rest: &[V3], triangles: &[[u32; 3]]) -> ObjMesh {
    let (lo, hi) = rest.iter().fold(
        (V3::repeat(f64::INFINITY), V3::repeat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    );
    let mut m = ObjMesh {
        positions: vec![],
        uvs: vec![],
        triangles: vec![],
    };
    for t in triangles {
        let [a, b, c] = t.map(|i| rest[i as usize]);
        let n = (b - a).cross(&(c - a)).normalize();
        let start = m.positions.len() as u32;
        for p in [a, b, c, (a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0] {
            let k = m.positions.len() as f64;
            m.positions.push(p + n * (0.0015 * (k * 0.7).sin()));
            m.uvs
                .push([(p.x - lo.x) / (hi.x - lo.x), (p.y - lo.y) / (hi.y - lo.y)]);
        }
        let [a, b, c, ab, bc, ca] = [0, 1, 2, 3, 4, 5].map(|i| start + i);
        m.triangles
            .extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    m
}

/// A bred-leaf-style clip: leaf b dropped for `seconds`, optionally dressed
/// with [`fine_mesh`].
pub fn leaf_clip(seconds: f64, dressed: bool) -> Clip {
    let model = LeafSpec::load("b").unwrap().model().unwrap();
    let mut leaf = export::drop_clip("leaf-b", "spinner", &model, seconds, 30.0).unwrap();
    leaf.features = vec![("descent_m_s".into(), 0.75), ("net_turns".into(), 3.0)];
    if dressed {
        let body = leaf.body.clone().unwrap();
        let mesh = fine_mesh(&body.rest, &leaf.triangles);
        leaf.render = Some(RenderMesh::bind("fine", &mesh, &body.rest, &leaf.triangles).unwrap());
    }
    export::side_by_side("leaf-b", vec![leaf], 30.0, 0.0).unwrap()
}

fn mixed_clip() -> Clip {
    let scene = Scene::from_toml(MIXED, "mixed.toml", Path::new(".")).unwrap();
    let run = scene.run(None).unwrap();
    export::from_scene_run(&scene, &run, 30.0).unwrap()
}

#[test]
fn usd_files_open_in_pixars_library_comply_and_hold_the_simulation() {
    let dir = scratch("pxr");
    let clips = [mixed_clip(), leaf_clip(3.0, false), leaf_clip(3.0, true)];
    let mut files = Vec::new();
    for (i, clip) in clips.iter().enumerate() {
        let f = dir.join(format!("clip{i}.usda"));
        usd::write_usd(clip, &f, clip.fps).unwrap();
        files.push((i, f.clone()));
        files.push((i, f.with_extension("usdc")));
    }
    let text = std::fs::read_to_string(&files[0].1).unwrap();
    assert!(text.starts_with("#usda 1.0"), "{}", &text[..40]);
    let python = match pixar_python() {
        Ok(p) => p,
        Err(why) => {
            crate::common::missing_tool("usd_files_open_in_pixars_library...", &why);
            return;
        }
    };
    let script = dir.join("read.py");
    std::fs::write(&script, READ_PY).unwrap();
    let o = Command::new(&python)
        .arg(&script)
        .args(files.iter().step_by(2).map(|(_, f)| f))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: Vec<Value> = serde_json::from_slice(&o.stdout).unwrap();
    for ((i, f), r) in files.iter().zip(&report) {
        let clip = &clips[*i];
        let f = f.display();
        assert_eq!(r["file"], f.to_string().as_str());
        assert_eq!(
            r["issues"].as_array().unwrap().len(),
            0,
            "{f}: {:#}",
            r["issues"]
        );
        assert_eq!(r["up"], "Z", "{f}");
        assert_eq!(r["mpu"], 1.0, "{f}");
        assert_eq!(r["tcps"], 30.0, "{f}");
        assert_eq!(r["fps"], 30.0, "{f}");
        assert_eq!(r["start"], 0.0, "{f}");
        assert_eq!(r["end"], (clip.frames - 1) as f64, "{f}");
        let objects = r["objects"].as_array().unwrap();
        assert_eq!(objects.len(), clip.objects.len(), "{f}");
        let mut worst = 0.0f64;
        for (o, u) in clip.objects.iter().zip(objects) {
            assert_eq!(u["name"], o.name.as_str(), "{f}");
            let frames = u["frames"].as_array().unwrap();
            assert_eq!(frames.len(), clip.frames, "{f} {}", o.name);
            assert_eq!(u["xform_samples"], clip.frames, "{f}: the Xform moves");
            for (k, fr) in frames.iter().enumerate() {
                let want = o.shown_positions(k);
                let got = fr.as_array().unwrap();
                assert_eq!(got.len(), want.len(), "{f} {} frame {k}", o.name);
                for (a, b) in want.iter().zip(got) {
                    let b = V3::new(
                        b[0].as_f64().unwrap(),
                        b[1].as_f64().unwrap(),
                        b[2].as_f64().unwrap(),
                    );
                    worst = worst.max((a - b).norm());
                }
            }
            let rgb = leafmagic::formats::clip::look::colour(o);
            let colour: Vec<f32> = u["color"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap() as f32)
                .collect();
            assert_eq!(colour, rgb, "{f} {}: display colour of its class", o.name);
            let want_material = format!(
                "/{}/Looks/{}",
                usd::identifier(&format!("{}_scene", clip.name)),
                usd::identifier(&leafmagic::formats::clip::look::material_name(o))
            );
            assert_eq!(u["material"], want_material.as_str(), "{f}");
            if u["type"] == "Mesh" {
                assert_eq!(u["st_interpolation"], "vertex");
                assert_eq!(u["normals_interpolation"], "vertex");
                let st = u["st"].as_array().unwrap();
                let n = o.shown_positions(0).len();
                assert_eq!(st.len(), n);
                assert_eq!(u["normals"], serde_json::json!([n, n]));
                let uv: Vec<f64> = st
                    .iter()
                    .flat_map(|t| [t[0].as_f64().unwrap(), t[1].as_f64().unwrap()])
                    .collect();
                assert!(
                    uv.iter().all(|x| (-1e-6..=1.0 + 1e-6).contains(x)),
                    "{f}: UVs in 0 … 1"
                );
            } else {
                assert_eq!(o.kind, "rope", "{f}: only ropes are curves");
            }
            if !o.label.is_empty() {
                assert_eq!(u["class"], o.label.as_str());
                assert_eq!(u["features"]["leafmagic:features:descent_m_s"], 0.75);
            }
        }
        eprintln!("{f}: Pixar's library reads every point within {worst:.2e} m of the simulation");
        assert!(worst <= 1e-5, "{f}: {worst}");
    }
}
