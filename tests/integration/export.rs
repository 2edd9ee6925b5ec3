//! Export and preview (issue 5): the .glb layout against the glTF 2.0
//! specification and the Khronos validator, PC2 byte for byte against its
//! specification and the OBJ in the same vertex order, resampling exact for
//! linear motion, the HTML page drawn by headless Chromium at two times.

use leafmagic::formats::clip::{self, Clip, ClipObject, DEFAULT_FPS, Motion};
use leafmagic::formats::{ExportError, Format, alembic, gltf, pc2, usd};
use leafmagic::leaf::LeafSpec;
use leafmagic::output::export;
use leafmagic::sim::scene::Scene;
use nalgebra::Vector3;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

type V3 = Vector3<f64>;

fn leafmagic() -> Command {
    Command::new(env!("CARGO_BIN_EXE_leafmagic"))
}

fn scratch(name: &str) -> PathBuf {
    super::common::scratch("export", name)
}

/// A scene with one of everything that is exported differently: a
/// deforming leaf (morph targets), a tumbling rigid box (TRS channels), a
/// rope (lines), a fixed point (not exported), ground and wind (extras).
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

[[wind]]
kind = "line_vortex"
point = [0.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
circulation = 0.5
core_radius = 0.2

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

fn mixed_clip(fps: f64) -> Clip {
    let scene = Scene::from_toml(MIXED, "mixed.toml", Path::new(".")).unwrap();
    let run = scene.run(None).unwrap();
    export::from_scene_run(&scene, &run, fps).unwrap()
}

/// The GLB's parts: (JSON document, BIN chunk), after checking the
/// container layout of the glTF 2.0 specification §4.4 byte for byte.
fn split_glb(bytes: &[u8]) -> (Value, Vec<u8>) {
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as usize;
    assert_eq!(&bytes[0..4], b"glTF", "magic");
    assert_eq!(u32_at(4), 2, "container version");
    assert_eq!(u32_at(8), bytes.len(), "header length = file length");
    let json_len = u32_at(12);
    assert_eq!(&bytes[16..20], b"JSON", "first chunk is JSON");
    assert_eq!(json_len % 4, 0, "JSON chunk padded to 4 bytes");
    let json_bytes = &bytes[20..20 + json_len];
    let text = std::str::from_utf8(json_bytes).unwrap();
    // Padding of the JSON chunk is spaces (0x20), which JSON ignores.
    assert!(
        json_bytes[text.trim_end().len()..]
            .iter()
            .all(|&b| b == b' ')
    );
    let bin_at = 20 + json_len;
    let bin_len = u32_at(bin_at);
    assert_eq!(
        &bytes[bin_at + 4..bin_at + 8],
        b"BIN\0",
        "second chunk is BIN"
    );
    assert_eq!(bin_len % 4, 0, "BIN chunk padded to 4 bytes");
    assert_eq!(
        bin_at + 8 + bin_len,
        bytes.len(),
        "nothing after the BIN chunk"
    );
    let doc: Value = serde_json::from_str(text.trim_end()).unwrap();
    (doc, bytes[bin_at + 8..].to_vec())
}

/// Little-endian unsigned integers of `component_type` (5121, 5123, 5125)
/// from `count` tightly packed elements at `offset` of `view`.
fn uints(
    doc: &Value,
    bin: &[u8],
    view: usize,
    offset: usize,
    component_type: u64,
    count: usize,
) -> Vec<u32> {
    let view = &doc["bufferViews"][view];
    let size = match component_type {
        5121 => 1,
        5123 => 2,
        5125 => 4,
        t => panic!("unexpected index component type {t}"),
    };
    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize + offset;
    assert!(
        start + size * count
            <= view["byteOffset"].as_u64().unwrap_or(0) as usize
                + view["byteLength"].as_u64().unwrap() as usize
    );
    (0..count)
        .map(|i| {
            let b = &bin[start + size * i..start + size * (i + 1)];
            b.iter().rev().fold(0u32, |x, &y| (x << 8) | y as u32)
        })
        .collect()
}

/// `n` tightly packed little-endian f32 at `offset` of `view`.
fn view_floats(doc: &Value, bin: &[u8], view: usize, offset: usize, n: usize) -> Vec<f32> {
    let view = &doc["bufferViews"][view];
    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize + offset;
    assert!(
        start + 4 * n
            <= view["byteOffset"].as_u64().unwrap_or(0) as usize
                + view["byteLength"].as_u64().unwrap() as usize
    );
    (0..n)
        .map(|i| f32::from_le_bytes(bin[start + 4 * i..start + 4 * i + 4].try_into().unwrap()))
        .collect()
}

/// An accessor's floats (tightly packed f32, as we write them), with sparse
/// substitution (glTF 2.0 §3.6.2.3): the base data is the buffer view, or
/// zeros without one, and `sparse.values[i]` replaces element
/// `sparse.indices[i]`; the indices must strictly increase.
fn floats(doc: &Value, bin: &[u8], accessor: usize) -> Vec<f32> {
    let a = &doc["accessors"][accessor];
    assert_eq!(a["componentType"], 5126, "FLOAT");
    let width = match a["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" => 4,
        t => panic!("unexpected type {t}"),
    };
    let count = a["count"].as_u64().unwrap() as usize;
    let offset = a["byteOffset"].as_u64().unwrap_or(0) as usize;
    let mut v = match a["bufferView"].as_u64() {
        Some(view) => view_floats(doc, bin, view as usize, offset, count * width),
        None => {
            assert!(
                a["sparse"].is_object(),
                "accessor {accessor}: no bufferView and not sparse"
            );
            vec![0.0; count * width]
        }
    };
    if let Some(sparse) = a["sparse"].as_object() {
        let n = sparse["count"].as_u64().unwrap() as usize;
        assert!(
            n >= 1 && n <= count,
            "accessor {accessor}: sparse.count {n}"
        );
        let ix = &sparse["indices"];
        let indices = uints(
            doc,
            bin,
            ix["bufferView"].as_u64().unwrap() as usize,
            ix["byteOffset"].as_u64().unwrap_or(0) as usize,
            ix["componentType"].as_u64().unwrap(),
            n,
        );
        assert!(
            indices.windows(2).all(|w| w[0] < w[1]),
            "accessor {accessor}: sparse indices strictly increasing"
        );
        assert!((*indices.last().unwrap() as usize) < count);
        let vs = &sparse["values"];
        let values = view_floats(
            doc,
            bin,
            vs["bufferView"].as_u64().unwrap() as usize,
            vs["byteOffset"].as_u64().unwrap_or(0) as usize,
            n * width,
        );
        for (i, &k) in indices.iter().enumerate() {
            let k = k as usize;
            v[k * width..(k + 1) * width].copy_from_slice(&values[i * width..(i + 1) * width]);
        }
    }
    v
}

#[test]
fn glb_layout_accessors_targets_and_quaternions_follow_the_specification() {
    let clip = mixed_clip(30.0);
    assert_eq!(clip.frames, 31, "1 s at 30 fps, t = 0 included");
    assert_eq!(
        clip.objects.len(),
        3,
        "leaf, box, rope; the fixed point is not exported"
    );
    let bytes = gltf::glb_bytes(&clip).unwrap();
    let (doc, bin) = split_glb(&bytes);
    assert_eq!(doc["asset"]["version"], "2.0");
    assert_eq!(
        doc["buffers"][0]["byteLength"].as_u64().unwrap() as usize,
        bin.len()
    );
    for v in doc["bufferViews"].as_array().unwrap() {
        let o = v["byteOffset"].as_u64().unwrap_or(0);
        assert_eq!(o % 4, 0, "every view starts on a 4-byte boundary");
        assert!(o + v["byteLength"].as_u64().unwrap() <= bin.len() as u64);
    }
    // Every accessor with min/max (positions, morph targets, times) holds
    // exactly those extremes, per component.
    let mut checked = 0;
    for (i, a) in doc["accessors"].as_array().unwrap().iter().enumerate() {
        let (Some(min), Some(max)) = (a["min"].as_array(), a["max"].as_array()) else {
            continue;
        };
        let w = min.len();
        let v = floats(&doc, &bin, i);
        for d in 0..w {
            let lo = v
                .iter()
                .skip(d)
                .step_by(w)
                .copied()
                .fold(f32::INFINITY, f32::min);
            let hi = v
                .iter()
                .skip(d)
                .step_by(w)
                .copied()
                .fold(f32::NEG_INFINITY, f32::max);
            assert_eq!(min[d].as_f64().unwrap() as f32, lo, "accessor {i} min[{d}]");
            assert_eq!(max[d].as_f64().unwrap() as f32, hi, "accessor {i} max[{d}]");
        }
        checked += 1;
    }
    let nodes = doc["nodes"].as_array().unwrap();
    let node = |name: &str| nodes.iter().position(|n| n["name"] == name).unwrap();
    let mesh_of = |n: usize| &doc["meshes"][nodes[n]["mesh"].as_u64().unwrap() as usize];
    // Deforming leaf and rope: three morph targets per particle and one
    // offset, however many frames (sparse: one vertex each but the offset),
    // named for Blender and three.js.
    let mut targets_total = 0;
    for name in ["leaf", "rope"] {
        let o = clip.objects.iter().find(|o| o.name == name).unwrap();
        let mesh = mesh_of(node(name));
        let targets = mesh["primitives"][0]["targets"].as_array().unwrap();
        let n = o.vertex_count();
        assert_eq!(targets.len(), 3 * n + 1, "{name}: 3 per particle + offset");
        assert_eq!(mesh["weights"].as_array().unwrap().len(), targets.len());
        let names = mesh["extras"]["targetNames"].as_array().unwrap();
        assert_eq!(names[0], "particle0.x");
        assert_eq!(names[5], "particle1.z");
        assert_eq!(names[3 * n], "offset");
        for (k, t) in targets.iter().enumerate() {
            let a = &doc["accessors"][t["POSITION"].as_u64().unwrap() as usize];
            let moved = if k < 3 * n { 1 } else { n };
            assert_eq!(a["sparse"]["count"], moved, "{name}: target {k}");
            assert!(a["bufferView"].is_null());
        }
        targets_total += targets.len();
    }
    assert!(mesh_of(node("box"))["primitives"][0]["targets"].is_null());
    assert_eq!(
        checked,
        2 * 2 + 1 + targets_total + 1,
        "POSITION and NORMAL of leaf and box, POSITION of the rope, every target, the times"
    );
    assert_eq!(
        mesh_of(node("rope"))["primitives"][0]["mode"],
        1,
        "rope drawn as LINES"
    );
    // Leaf and box have normals and UVs in 0 … 1.
    for name in ["leaf", "box"] {
        let attrs = &mesh_of(node(name))["primitives"][0]["attributes"];
        let uv = floats(&doc, &bin, attrs["TEXCOORD_0"].as_u64().unwrap() as usize);
        assert!(uv.iter().all(|x| (0.0..=1.0).contains(x)), "{name}: {uv:?}");
        assert!(
            uv.contains(&0.0) && uv.contains(&1.0),
            "{name}: spans its outline"
        );
        let n = floats(&doc, &bin, attrs["NORMAL"].as_u64().unwrap() as usize);
        for v in n.chunks(3) {
            let norm = v.iter().map(|x| (*x as f64).powi(2)).sum::<f64>().sqrt();
            assert!((norm - 1.0).abs() < 1e-6, "{name}: normal {v:?}");
        }
    }
    // Names: scene, nodes and meshes all differ.
    assert_eq!(doc["scenes"][0]["name"], "mixed-scene");
    for (k, n) in nodes.iter().enumerate() {
        assert_eq!(
            mesh_of(k)["name"],
            format!("{}-mesh", n["name"].as_str().unwrap())
        );
    }
    // Channels: times k/fps; every object's origin moves (translation and
    // rotation), the deforming ones' weights; rotations unit.
    let anim = &doc["animations"][0];
    let samplers = anim["samplers"].as_array().unwrap();
    let mut paths = Vec::new();
    for ch in anim["channels"].as_array().unwrap() {
        let s = &samplers[ch["sampler"].as_u64().unwrap() as usize];
        assert_eq!(s["interpolation"], "LINEAR");
        let t = floats(&doc, &bin, s["input"].as_u64().unwrap() as usize);
        assert_eq!(t.len(), clip.frames);
        for (k, x) in t.iter().enumerate() {
            assert_eq!(*x, (k as f64 / 30.0) as f32);
        }
        let out = floats(&doc, &bin, s["output"].as_u64().unwrap() as usize);
        let path = ch["target"]["path"].as_str().unwrap().to_string();
        let n = ch["target"]["node"].as_u64().unwrap() as usize;
        match path.as_str() {
            "rotation" => {
                assert_eq!(out.len(), 4 * clip.frames);
                for q in out.chunks(4) {
                    let norm = q.iter().map(|x| (*x as f64).powi(2)).sum::<f64>().sqrt();
                    assert!((norm - 1.0).abs() < 1e-6, "rotation key not unit: {norm}");
                }
                // Leaf and box turn as they move; a rope (points on a line
                // at rest) has no rotation to fit, its frame does not turn.
                if n == node("rope") {
                    assert!(out.chunks(4).all(|q| q == [0.0, 0.0, 0.0, 1.0]));
                } else {
                    assert_ne!(out[..4], out[out.len() - 4..], "node {n}");
                }
            }
            "weights" => {
                let k = doc["meshes"][nodes[n]["mesh"].as_u64().unwrap() as usize]["weights"]
                    .as_array()
                    .unwrap()
                    .len();
                assert_eq!(out.len(), k * clip.frames, "targets × frames");
                // In 0 … 1, the range of a Blender shape key; each degree
                // of freedom spans it; the offset is always 1.
                assert!(out.iter().all(|w| (0.0..=1.0).contains(w)));
                for j in 0..k - 1 {
                    let w: Vec<f32> = out.iter().skip(j).step_by(k).copied().collect();
                    let lo = w.iter().copied().fold(f32::INFINITY, f32::min);
                    let hi = w.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                    assert!(
                        lo == 0.0 && (hi == 1.0 || hi == 0.0),
                        "target {j}: {lo} … {hi}"
                    );
                }
                assert!(out.iter().skip(k - 1).step_by(k).all(|&w| w == 1.0));
            }
            "translation" => assert_eq!(out.len(), 3 * clip.frames),
            p => panic!("unexpected channel {p}"),
        }
        paths.push((n, path));
    }
    paths.sort();
    let mut want = Vec::new();
    for name in ["leaf", "box", "rope"] {
        want.push((node(name), "translation".to_string()));
        want.push((node(name), "rotation".to_string()));
        if name != "box" {
            want.push((node(name), "weights".to_string()));
        }
    }
    want.sort();
    assert_eq!(paths, want);
    // Ground, wind and the frame range travel in the scene's extras.
    let extras = &doc["scenes"][0]["extras"]["leafmagic"];
    assert_eq!(extras["ground"], 0.0);
    assert_eq!(extras["wind"].as_array().unwrap().len(), 2);
    assert_eq!(extras["fps"], 30.0);
    assert_eq!(extras["frames"], 31);
}

/// What a glTF client shows of every node at key `k`, decoded from the
/// document as the specification defines it (§3.7.2.1 morph targets:
/// base + Σ wᵢ targetᵢ; §3.5.3 node transform T · R · S), in simulator
/// axes: `(node name, vertex positions)`.
fn client_positions(doc: &Value, bin: &[u8], k: usize) -> Vec<(String, Vec<V3>)> {
    let anim = &doc["animations"][0];
    let samplers = anim["samplers"].as_array().unwrap();
    let key = |node: usize, path: &str| -> Option<Vec<f32>> {
        let ch = anim["channels"].as_array().unwrap().iter().find(|c| {
            c["target"]["node"].as_u64() == Some(node as u64) && c["target"]["path"] == path
        })?;
        let s = &samplers[ch["sampler"].as_u64().unwrap() as usize];
        let times = floats(doc, bin, s["input"].as_u64().unwrap() as usize);
        let out = floats(doc, bin, s["output"].as_u64().unwrap() as usize);
        let width = out.len() / times.len();
        Some(out[k * width..(k + 1) * width].to_vec())
    };
    let z_up = |p: [f64; 3]| V3::new(p[0], -p[2], p[1]);
    doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let mesh = &doc["meshes"][n["mesh"].as_u64().unwrap() as usize];
            let prim = &mesh["primitives"][0];
            let base = floats(
                doc,
                bin,
                prim["attributes"]["POSITION"].as_u64().unwrap() as usize,
            );
            let mut p: Vec<f64> = base.iter().map(|&x| x as f64).collect();
            if let Some(targets) = prim["targets"].as_array() {
                let w = key(i, "weights").unwrap();
                for (t, w) in targets.iter().zip(w) {
                    let d = floats(doc, bin, t["POSITION"].as_u64().unwrap() as usize);
                    p.iter_mut()
                        .zip(d)
                        .for_each(|(x, d)| *x += w as f64 * d as f64);
                }
            }
            let fixed = |name: &str, default: Vec<f64>| -> Vec<f64> {
                n[name]
                    .as_array()
                    .map_or(default, |a| a.iter().map(|x| x.as_f64().unwrap()).collect())
            };
            let t = key(i, "translation")
                .map(|v| v.iter().map(|&x| x as f64).collect())
                .unwrap_or_else(|| fixed("translation", vec![0.0; 3]));
            let r = key(i, "rotation")
                .map(|v| v.iter().map(|&x| x as f64).collect())
                .unwrap_or_else(|| fixed("rotation", vec![0.0, 0.0, 0.0, 1.0]));
            let q = nalgebra::UnitQuaternion::new_normalize(nalgebra::Quaternion::new(
                r[3], r[0], r[1], r[2],
            ));
            let t = nalgebra::Vector3::new(t[0], t[1], t[2]);
            let world = p
                .chunks(3)
                .map(|v| {
                    let y_up = t + q * nalgebra::Vector3::new(v[0], v[1], v[2]);
                    z_up([y_up.x, y_up.y, y_up.z])
                })
                .collect();
            (n["name"].as_str().unwrap().to_string(), world)
        })
        .collect()
}

/// The largest distance over every frame and vertex between what a client
/// shows of `clip`'s .glb and the simulation (each object's shown mesh).
fn client_error(clip: &Clip) -> f64 {
    let (doc, bin) = split_glb(&gltf::glb_bytes(clip).unwrap());
    let mut worst = 0.0f64;
    for k in 0..clip.frames {
        for (o, (name, shown)) in clip.objects.iter().zip(client_positions(&doc, &bin, k)) {
            assert_eq!(o.name, name);
            let want = o.shown_positions(k);
            assert_eq!(want.len(), shown.len());
            for (a, b) in want.iter().zip(&shown) {
                worst = worst.max((a - b).norm());
            }
        }
    }
    worst
}

#[test]
fn a_client_evaluating_the_glb_shows_the_simulation_at_every_frame() {
    // Node TRS × (base + Σ w · targets), decoded from the bytes: within
    // 1e-5 m of the simulated vertices at every frame (f32 keys; the leaf
    // falls a metre, the rope swings), here and for a bred-leaf-style fall.
    let clip = mixed_clip(30.0);
    let e = client_error(&clip);
    eprintln!("mixed scene, 31 frames: largest client error {e:.2e} m");
    assert!(e <= 1e-5, "{e}");
    let model = LeafSpec::load("b").unwrap().model().unwrap();
    let leaf = export::drop_clip("leaf-b", "spinner", &model, 10.0, 30.0).unwrap();
    let single = export::side_by_side("leaf-b", vec![leaf], 30.0, 0.0).unwrap();
    let e = client_error(&single);
    eprintln!("leaf b, 10 s fall, 301 frames: largest client error {e:.2e} m");
    assert!(e <= 1e-5, "{e}");
    // Dressed with a finer render mesh lifted off the surface: its vertices
    // as bound (Σ bᵢ pᵢ + h n) are what the client shows, to the same bound.
    let dressed = super::usd::leaf_clip(10.0, true);
    let r = dressed.objects[0].render.as_ref().unwrap();
    assert!(
        r.bindings.iter().any(|b| b.offset.abs() > 1e-3),
        "offsets along the normal"
    );
    let e = client_error(&dressed);
    eprintln!(
        "leaf b with a {}-vertex render mesh, 301 frames: largest client error {e:.2e} m",
        r.vertex_count()
    );
    assert!(e <= 1e-5, "{e}");
}

#[test]
fn glb_reads_back_to_the_exported_positions_at_every_frame() {
    // Through the glTF semantics (TRS of the node applied to the mesh;
    // base + Σ weight × target): every vertex at every frame within f32
    // rounding of what was exported, in the simulator's z-up axes.
    let clip = mixed_clip(30.0);
    let back = gltf::from_glb_bytes(&gltf::glb_bytes(&clip).unwrap(), "mixed", None, None).unwrap();
    assert_eq!(back.frames, clip.frames);
    assert_eq!(back.fps, 30.0, "the frame rate travels in the extras");
    assert_eq!(back.ground, Some(0.0));
    assert_eq!(back.wind, clip.wind);
    for (a, b) in clip.objects.iter().zip(&back.objects) {
        assert_eq!(a.name, b.name);
        assert_eq!(a.kind, b.kind);
        assert_eq!(a.triangles, b.triangles);
        assert_eq!(a.segments, b.segments);
        assert_eq!(
            matches!(a.motion, Motion::Rigid { .. }),
            matches!(b.motion, Motion::Rigid { .. })
        );
        for k in 0..clip.frames {
            for (p, q) in a.positions(k).iter().zip(b.positions(k)) {
                assert!(
                    (p - q).norm() < 2e-6,
                    "{} frame {k}: {p:?} vs {q:?}",
                    a.name
                );
            }
        }
    }
}

#[test]
fn resampling_reproduces_a_linear_motion_exactly() {
    // A rigid box coasting in free space (no gravity, no wind, no spin):
    // its centre moves as x0 + v t; recorded at 60 Hz, exported at 30 and
    // at 24 fps (keys between recorded frames), the keys are that line.
    let text = r#"
name = "coast"
duration = 2.0
frame_rate = 60
gravity = [0.0, 0.0, 0.0]
[[rigid]]
name = "box"
shape = "box"
size = [0.2, 0.1, 0.05]
mass = 0.1
position = [0.25, -0.5, 2.0]
velocity = [0.75, 0.5, -1.25]
"#;
    let scene = Scene::from_toml(text, "coast.toml", Path::new(".")).unwrap();
    let run = scene.run(None).unwrap();
    for fps in [30.0, 24.0] {
        let clip = export::from_scene_run(&scene, &run, fps).unwrap();
        assert_eq!(clip.frames, (2.0 * fps) as usize + 1);
        let Motion::Rigid {
            translation,
            rotation,
            ..
        } = &clip.objects[0].motion
        else {
            panic!("a rigid box is exported by its pose");
        };
        for k in 0..clip.frames {
            let t = k as f64 / fps;
            let want = V3::new(0.25, -0.5, 2.0) + V3::new(0.75, 0.5, -1.25) * t;
            assert!(
                (translation[k] - want).norm() < 1e-12,
                "{fps} fps frame {k}"
            );
            assert!(rotation[k].angle() < 1e-12);
        }
        // And the file keys hold it to f32 rounding, in glTF axes (x, z, −y).
        let (doc, bin) = split_glb(&gltf::glb_bytes(&clip).unwrap());
        let anim = &doc["animations"][0];
        let ch = anim["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["target"]["path"] == "translation")
            .unwrap();
        let s = &anim["samplers"][ch["sampler"].as_u64().unwrap() as usize];
        let out = floats(&doc, &bin, s["output"].as_u64().unwrap() as usize);
        for k in 0..clip.frames {
            let t = k as f64 / fps;
            let want = [0.25 + 0.75 * t, 2.0 - 1.25 * t, 0.5 - 0.5 * t];
            for d in 0..3 {
                // To f32 rounding (a 1e-15 residue of the f64 line is a
                // tiny non-zero f32 where the exact value is 0).
                let err = (out[3 * k + d] as f64 - want[d]).abs();
                assert!(
                    err <= 1e-7 * (1.0 + want[d].abs()),
                    "{fps} fps key {k}[{d}]: {err}"
                );
            }
        }
    }
}

fn le_i32(b: &[u8], o: usize) -> i32 {
    i32::from_le_bytes(b[o..o + 4].try_into().unwrap())
}

fn le_f32(b: &[u8], o: usize) -> f32 {
    f32::from_le_bytes(b[o..o + 4].try_into().unwrap())
}

#[test]
fn pc2_is_byte_for_byte_the_specified_layout() {
    // Two points, three samples, values chosen by hand; the expected file
    // is spelled out from the specification, not from the writer.
    let frames = vec![
        vec![V3::new(0.0, 1.0, 2.0), V3::new(-1.5, 0.25, 8.0)],
        vec![V3::new(0.5, 1.0, 2.0), V3::new(-1.5, 0.5, 7.0)],
        vec![V3::new(1.0, 1.0, 2.0), V3::new(-1.5, 0.75, 6.0)],
    ];
    let clip = Clip {
        name: "hand".into(),
        fps: 30.0,
        frames: 3,
        objects: vec![ClipObject {
            first_frame: 0,
            name: "pair".into(),
            kind: "rope".into(),
            label: String::new(),
            regime: String::new(),
            features: vec![],
            triangles: vec![],
            segments: vec![[0, 1]],
            body: None,
            render: None,
            motion: Motion::Deforming { frames },
        }],
        ground: None,
        wind: vec![],
        aero_law: String::new(),
        warnings: vec![],
    };
    let dir = scratch("pc2-hand");
    // In a 30 fps scene a 30 fps cache has a sample every frame.
    let written = pc2::write_pc2(&clip, &dir, 30.0).unwrap();
    assert_eq!(written.len(), 2);
    let got = std::fs::read(dir.join("pair.pc2")).unwrap();
    let mut want: Vec<u8> = Vec::new();
    want.extend_from_slice(b"POINTCACHE2\0"); // char[12] signature
    want.extend_from_slice(&[1, 0, 0, 0]); // int32 version = 1
    want.extend_from_slice(&[2, 0, 0, 0]); // int32 numPoints = 2
    want.extend_from_slice(&[0, 0, 0, 0]); // float32 startFrame = 0.0
    want.extend_from_slice(&[0, 0, 0x80, 0x3f]); // float32 sampleRate = 1.0
    want.extend_from_slice(&[3, 0, 0, 0]); // int32 numSamples = 3
    for v in [
        0.0f32, 1.0, 2.0, -1.5, 0.25, 8.0, //
        0.5, 1.0, 2.0, -1.5, 0.5, 7.0, //
        1.0, 1.0, 2.0, -1.5, 0.75, 6.0,
    ] {
        want.extend_from_slice(&v.to_le_bytes());
    }
    assert_eq!(got, want);
    assert_eq!(got.len(), 32 + 3 * 2 * 12);
    // For a 24 fps scene the cache holds the host's frames: t = 0 and
    // 1/24 s (the clip's frame 1.25: a quarter of the way from sample 1 to
    // 2), one sample a frame.
    pc2::write_pc2(&clip, &dir, 24.0).unwrap();
    let got = std::fs::read(dir.join("pair.pc2")).unwrap();
    assert_eq!(le_f32(&got, 24), 1.0);
    assert_eq!(got[28..32], [2, 0, 0, 0], "numSamples = 2");
    assert_eq!(got[32..56], want[32..56], "t = 0 unchanged");
    let at_1_24: Vec<f32> = (0..6).map(|i| le_f32(&got, 56 + 4 * i)).collect();
    for (got, want) in at_1_24.iter().zip([0.625f32, 1.0, 2.0, -1.5, 0.5625, 6.75]) {
        assert!((got - want).abs() < 1e-6, "{at_1_24:?}");
    }
    let obj = std::fs::read_to_string(dir.join("pair.obj")).unwrap();
    let body: Vec<&str> = obj.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(body, ["o pair", "v 0 1 2", "v -1.5 0.25 8", "l 1 2"]);
}

/// The `v` lines of an OBJ as f32.
fn obj_vertices(text: &str) -> Vec<[f32; 3]> {
    text.lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f32> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

#[test]
fn scene_export_to_pc2_keeps_the_obj_vertex_order_of_the_cache() {
    let dir = scratch("pc2-scene");
    let scene_file = dir.join("mixed.toml");
    std::fs::write(&scene_file, MIXED).unwrap();
    let out = dir.join("out");
    let o = leafmagic()
        .arg("scene")
        .arg(&scene_file)
        .args(["--export", "pc2", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The cache holds the host's frames (24 fps), resampled from the
    // export's 30.
    let clip = mixed_clip(DEFAULT_FPS).resampled(pc2::DEFAULT_HOST_FPS);
    assert_eq!(clip.frames, 25, "1 s on a 24 fps host");
    for obj in &clip.objects {
        let cache = std::fs::read(out.join(format!("{}.pc2", obj.name))).unwrap();
        assert_eq!(&cache[..12], pc2::SIGNATURE);
        assert_eq!(le_i32(&cache, 12), 1);
        let points = le_i32(&cache, 16) as usize;
        let samples = le_i32(&cache, 28) as usize;
        assert_eq!(points, obj.vertex_count());
        assert_eq!(samples, clip.frames);
        assert_eq!(cache.len(), 32 + samples * points * 12);
        let mesh = std::fs::read_to_string(out.join(format!("{}.obj", obj.name))).unwrap();
        let v = obj_vertices(&mesh);
        assert_eq!(v.len(), points, "{}: OBJ vertices = cache points", obj.name);
        for (i, p) in v.iter().enumerate() {
            for (d, x) in p.iter().enumerate() {
                // Bit for bit: OBJ vertex i is cache point i of sample 0.
                assert_eq!(x.to_bits(), le_f32(&cache, 32 + 12 * i + 4 * d).to_bits());
            }
        }
        // And the cache's last sample is the exported last frame.
        let last = obj.positions(clip.frames - 1);
        for (i, p) in last.iter().enumerate() {
            let at = 32 + ((samples - 1) * points + i) * 12;
            assert_eq!(le_f32(&cache, at), p.x as f32);
            assert_eq!(le_f32(&cache, at + 8), p.z as f32);
        }
    }
}

/// A directory with `gltf-validator` installed (once per target directory),
/// or None with the reason.
fn validator() -> Result<PathBuf, String> {
    if Command::new("node").arg("--version").output().is_err() {
        return Err("node is not installed".into());
    }
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("gltf-validator");
    let module = dir.join("node_modules/gltf-validator");
    if module.join("package.json").exists() {
        return Ok(dir);
    }
    if Command::new("npm").arg("--version").output().is_err() {
        return Err("npm is not installed".into());
    }
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let o = Command::new("npm")
        .args(["install", "--no-audit", "--no-fund", "--silent", "--prefix"])
        .arg(&dir)
        .arg("gltf-validator@2.0.0-dev.3.10")
        .output()
        .map_err(|e| e.to_string())?;
    if !o.status.success() || !module.exists() {
        return Err(format!(
            "npm install gltf-validator failed: {}",
            String::from_utf8_lossy(&o.stderr).trim()
        ));
    }
    Ok(dir)
}

const VALIDATE_JS: &str = r#"
const fs = require('fs');
const v = require('gltf-validator');
(async () => {
  const out = [];
  for (const f of process.argv.slice(2)) {
    const r = await v.validateBytes(new Uint8Array(fs.readFileSync(f)), { maxIssues: 100 });
    out.push({ file: f, errors: r.issues.numErrors, warnings: r.issues.numWarnings,
      messages: r.issues.messages.map(m => m.severity + ' ' + m.code + ' ' + (m.pointer || '') + ' ' + m.message) });
  }
  console.log(JSON.stringify(out));
})();
"#;

#[test]
fn exported_glb_files_pass_the_khronos_validator() {
    let dir = scratch("validator");
    let mixed = dir.join("mixed.glb");
    gltf::write_glb(&mixed_clip(30.0), &mixed).unwrap();
    // A bred-leaf style export: one leaf dropped for 10 s at 30 fps.
    let model = LeafSpec::load("b").unwrap().model().unwrap();
    let leaf = export::drop_clip("leaf-b", "spinner", &model, 10.0, 30.0).unwrap();
    let single = export::side_by_side("leaf-b", vec![leaf], 30.0, 0.0).unwrap();
    assert_eq!(single.frames, 301);
    let drop_glb = dir.join("leaf-b.glb");
    gltf::write_glb(&single, &drop_glb).unwrap();
    let dressed_glb = dir.join("leaf-b-dressed.glb");
    gltf::write_glb(&super::usd::leaf_clip(10.0, true), &dressed_glb).unwrap();
    let tool = match validator() {
        Ok(t) => t,
        Err(why) => {
            crate::common::missing_tool("exported_glb_files_pass_the_khronos_validator", &why);
            return;
        }
    };
    let script = tool.join("validate.js");
    std::fs::write(&script, VALIDATE_JS).unwrap();
    let o = Command::new("node")
        .arg(&script)
        .arg(&mixed)
        .arg(&drop_glb)
        .arg(&dressed_glb)
        .current_dir(&tool)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: Value = serde_json::from_slice(&o.stdout).unwrap();
    let report = report.as_array().unwrap();
    assert_eq!(report.len(), 3);
    for r in report {
        assert_eq!(r["errors"], 0, "{}: {:#}", r["file"], r["messages"]);
        assert_eq!(r["warnings"], 0, "{}: {:#}", r["file"], r["messages"]);
        eprintln!(
            "gltf-validator: {} — {} errors, {} warnings",
            r["file"], r["errors"], r["warnings"]
        );
    }
}

/// Bytes of the BIN chunk an accessor's data takes: its buffer view's, or
/// for a sparse accessor those of its indices' and values' views.
fn accessor_bytes(doc: &Value, accessor: usize) -> usize {
    let a = &doc["accessors"][accessor];
    let len = |v: &Value| {
        v.as_u64().map_or(0, |i| {
            doc["bufferViews"][i as usize]["byteLength"]
                .as_u64()
                .unwrap() as usize
        })
    };
    len(&a["bufferView"])
        + len(&a["sparse"]["indices"]["bufferView"])
        + len(&a["sparse"]["values"]["bufferView"])
}

#[test]
fn a_deforming_object_grows_linearly_with_its_frame_count() {
    // The same fall of leaf b exported at 15 and 30 fps (151 and 301
    // frames): the morph targets are the same (3 per particle), and what
    // grows is per frame only: a time, a translation, a rotation and one
    // weight per target, 4 + 12 + 16 + 4K bytes of the buffer.
    let model = LeafSpec::load("b").unwrap().model().unwrap();
    let mut sizes = Vec::new();
    for fps in [15.0, 30.0] {
        let leaf = export::drop_clip("leaf-b", "spinner", &model, 10.0, fps).unwrap();
        let clip = export::side_by_side("leaf-b", vec![leaf], fps, 0.0).unwrap();
        let n = clip.frames;
        let bytes = gltf::glb_bytes(&clip).unwrap();
        let (doc, bin) = split_glb(&bytes);
        let k = doc["meshes"][0]["primitives"][0]["targets"]
            .as_array()
            .unwrap()
            .len();
        assert_eq!(
            k,
            3 * model.len() + 1,
            "3 per particle + offset at {n} frames"
        );
        let anim = &doc["animations"][0];
        let ch = anim["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["target"]["path"] == "weights")
            .unwrap();
        let out = anim["samplers"][ch["sampler"].as_u64().unwrap() as usize]["output"]
            .as_u64()
            .unwrap() as usize;
        assert_eq!(doc["accessors"][out]["count"], n * k);
        assert_eq!(accessor_bytes(&doc, out), 4 * n * k);
        assert_eq!(bin.len() % 4, 0);
        sizes.push((n, k, bytes.len()));
    }
    let [(n1, k, f1), (n2, _, f2)] = sizes[..] else {
        unreachable!()
    };
    let per_frame = 4 + 12 + 16 + 4 * k;
    let growth = f2 - f1;
    let msg = format!(
        "{n1} → {n2} frames: file {f1} → {f2} bytes (+{growth}); {per_frame} bytes per frame × {} = {}",
        n2 - n1,
        per_frame * (n2 - n1)
    );
    eprintln!("{msg}");
    // The JSON's numbers (counts, offsets) take a few more digits.
    assert!(
        growth >= per_frame * (n2 - n1) && growth <= per_frame * (n2 - n1) + 64,
        "{msg}"
    );
}

#[test]
fn the_export_command_re_drops_bred_leaves_into_glb_and_pc2() {
    let dir = scratch("breed");
    let run = dir.join("run");
    let o = leafmagic()
        .args([
            "breed",
            "--population",
            "6",
            "--generations",
            "1",
            "--seconds",
            "3",
        ])
        .args(["--threads", "1", "--out"])
        .arg(&run)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for format in ["glb", "pc2"] {
        let out = dir.join(format);
        let o = leafmagic()
            .arg("export")
            .arg(&run)
            .args(["--top", "2", "--format", format, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let index = std::fs::read_to_string(out.join("index.csv")).unwrap();
        let ids: Vec<String> = index
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(1).unwrap().to_string())
            .collect();
        assert_eq!(ids.len(), 2);
        for id in &ids {
            let stem = out.join(format!("leaf-{id}"));
            assert!(stem.with_extension("toml").is_file());
            if format == "glb" {
                let clip = gltf::from_glb(&stem.with_extension("glb"), None, None).unwrap();
                // 3 s at 30 fps; the leaf falls (it was re-dropped, not posed).
                assert_eq!(clip.frames, 91);
                let o = &clip.objects[0];
                assert!(o.centre(90).z < o.centre(0).z - 0.5, "the leaf falls");
                let class = index
                    .lines()
                    .find(|l| l.split(',').nth(1) == Some(id))
                    .unwrap();
                assert!(
                    class.contains(&format!(",{},", o.label)),
                    "label = recorded class"
                );
            } else {
                let cache = std::fs::read(stem.with_extension("pc2")).unwrap();
                // 3 s on the frames of a 24 fps host.
                assert_eq!(le_i32(&cache, 28), 73);
                assert!(stem.with_extension("obj").is_file());
            }
        }
    }
    // The re-drop is the fall that earned the recorded class.
    let opened = leafmagic::breed::Run::open(&run).unwrap();
    let cp = opened.checkpoint.as_ref().unwrap();
    let best = leafmagic::breed::selection::rank(&cp.population)[0];
    let model = best.genome.model(&opened.proto).unwrap();
    let params = leafmagic::sim::drop::DropParams {
        seconds: 3.0,
        tilt_deg: best.eval.release_deg,
        ..Default::default()
    };
    let fall = leafmagic::sim::drop::drop_leaf(&model, &params).unwrap();
    let c = leafmagic::motion::classify::classify(&fall.trajectory, model.chord());
    assert_eq!(c.class.as_str(), best.eval.class_name());
    // …released as that drop was (its release attitude, drawn per
    // individual), not at the drop's default 10°, 2°.
    let exported = export::drop_individuals(&opened, &[best], 30.0).unwrap();
    let frames = |o: &ClipObject| match &o.motion {
        Motion::Deforming { frames } => frames.clone(),
        _ => panic!("a leaf deforms"),
    };
    let released =
        export::drop_clip_released("b", "", &model, 3.0, 30.0, best.eval.release_deg).unwrap();
    assert_eq!(frames(&exported[0]), frames(&released));
    assert_ne!(best.eval.release_deg, [10.0, 2.0]);
    let default = export::drop_clip("b", "", &model, 3.0, 30.0).unwrap();
    assert_ne!(frames(&exported[0]), frames(&default));
}

#[test]
fn bad_input_is_refused_with_the_file_and_the_reason() {
    let dir = scratch("bad");
    let run = |args: &[&str]| {
        let o = leafmagic().args(args).output().unwrap();
        assert!(!o.status.success(), "{args:?} should fail");
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let e = run(&["scene", "scenes/hover.toml", "--export", "fbx"]);
    assert!(e.contains("fbx") && e.contains("glb, pc2, usd"), "{e}");
    let missing = dir.join("nothing-here");
    let e = run(&["preview", missing.to_str().unwrap()]);
    assert!(
        e.contains("nothing-here") && e.contains("no such file"),
        "{e}"
    );
    let e = run(&["preview", dir.to_str().unwrap()]);
    assert!(
        e.contains("neither a breeding run") && e.contains("summary.toml"),
        "{e}"
    );
    let text = dir.join("notes.txt");
    std::fs::write(&text, "hello").unwrap();
    let e = run(&["preview", text.to_str().unwrap()]);
    assert!(
        e.contains("notes.txt") && e.contains("not an animation file") && e.contains(".abc"),
        "{e}"
    );
    let fake = dir.join("fake.glb");
    std::fs::write(&fake, b"glTF but not really").unwrap();
    let e = run(&["preview", fake.to_str().unwrap()]);
    assert!(
        e.contains("fake.glb") && e.contains("not a valid glTF"),
        "{e}"
    );
    // A scene directory whose scene file is gone.
    let scene_dir = dir.join("scene-out");
    std::fs::create_dir_all(&scene_dir).unwrap();
    std::fs::write(
        scene_dir.join("summary.toml"),
        "scene = \"gone\"\nsource = \"no/such/scene.toml\"\n",
    )
    .unwrap();
    let e = run(&["preview", scene_dir.to_str().unwrap()]);
    assert!(
        e.contains("summary.toml") && e.contains("no/such/scene.toml"),
        "{e}"
    );
    assert!("obj".parse::<Format>().is_err());
    let empty = Clip {
        name: "empty".into(),
        fps: 30.0,
        frames: 1,
        objects: vec![],
        ground: None,
        wind: vec![],
        aero_law: String::new(),
        warnings: vec![],
    };
    assert!(
        matches!(gltf::glb_bytes(&empty), Err(ExportError::Data(m)) if m.contains("no objects"))
    );
}

/// 100 leaves × 10 s × 30 fps (the issue's size target), each a real fall.
fn hundred_leaves() -> Clip {
    let model = LeafSpec::load("a").unwrap().model().unwrap();
    let one = export::drop_clip("leaf", "floater", &model, 10.0, 30.0).unwrap();
    let objects = (0..100)
        .map(|k| {
            let mut o = one.clone();
            o.name = format!("leaf-{k:03}");
            o
        })
        .collect();
    export::side_by_side("hundred", objects, 30.0, 0.2).unwrap()
}

#[test]
fn the_page_for_a_hundred_leaves_for_ten_seconds_stays_under_20_mb() {
    let clip = hundred_leaves();
    assert_eq!(clip.frames, 301);
    let page = leafmagic::output::preview::html(&clip, true).unwrap();
    // 100 × 301 × 7 vertices × 12 bytes of float32, base64: ≈ 3.4 MB.
    assert!(page.len() < 20_000_000, "page is {} bytes", page.len());
    assert!(
        page.len() > 3_000_000,
        "page is {} bytes: data missing?",
        page.len()
    );
    eprintln!(
        "preview page for 100 leaves × 10 s × 30 fps: {} bytes",
        page.len()
    );
}

// ----- the page in headless Chromium -----

fn chromium() -> Option<String> {
    ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|c| {
            Command::new(c)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .map(str::to_string)
}

const WIDTH: u32 = 800;
const HEIGHT: u32 = 600;
/// Height of the page's control bar, CSS px (page.html #bar).
const BAR: u32 = 44;

/// RGB pixels of a screenshot of `page#hash`.
fn screenshot(browser: &str, page: &Path, hash: &str, png: &Path) -> Vec<[u8; 3]> {
    let profile = png.with_extension("profile");
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--force-device-scale-factor=1",
            "--virtual-time-budget=3000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--window-size={WIDTH},{HEIGHT}"))
        .arg(format!("--screenshot={}", png.display()))
        .arg(format!("file://{}#{hash}", page.display()))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(90) {
            let _ = child.kill();
            panic!("chromium took over 90 s for {hash}");
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let mut decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(png).unwrap()));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (WIDTH, HEIGHT));
    let channels = info.line_size / info.width as usize;
    buf[..info.buffer_size()]
        .chunks(channels)
        .map(|p| [p[0], p[1], p[2]])
        .collect()
}

/// Leaf green as the page shades it (any light): green well above red and
/// blue. The background, ground grid (grey), wind glyphs (cyan) and labels
/// (white) are not.
fn leafy(p: [u8; 3]) -> bool {
    let [r, g, b] = p.map(i32::from);
    g > 40 && g > r + 20 && g > b + 20
}

#[test]
fn the_preview_page_draws_the_leaves_at_two_times_in_headless_chromium() {
    let Some(browser) = chromium() else {
        crate::common::missing_tool(
            "the_preview_page_draws_the_leaves...",
            "no chromium (apt-get install chromium)",
        );
        return;
    };
    let dir = scratch("chromium");
    let scene_file = dir.join("fall.toml");
    // Four leaves released tilted into a vortex over the ground.
    std::fs::write(
        &scene_file,
        r#"
name = "fall"
duration = 3.0
frame_rate = 60
seed = 3
[ground]
height = 0.0
static_friction = 0.5
kinetic_friction = 0.4
[[wind]]
kind = "line_vortex"
point = [0.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
circulation = 1.0
core_radius = 0.3
[[leaf]]
name = "leaf"
leaf = "b"
count = 4
position = [0.3, 0.0, 2.5]
spread = [0.2, 0.2, 0.1]
tilt_deg = 40.0
random_yaw = true
"#,
    )
    .unwrap();
    let out = dir.join("out");
    let o = leafmagic()
        .arg("scene")
        .arg(&scene_file)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let page = dir.join("page.html");
    let o = leafmagic()
        .arg("preview")
        .arg(&out)
        .arg("--out")
        .arg(&page)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The camera centres the followed leaf: it is drawn in the middle of
    // the view (the canvas above the control bar).
    let (cx, cy) = (WIDTH as usize / 2, (HEIGHT - BAR) as usize / 2);
    let mut masks = Vec::new();
    for (k, hash) in [
        "t=0.5&follow=leaf-001",
        "t=2.0&follow=leaf-001",
        "t=2.0&follow=leaf-001&renderer=2d",
    ]
    .iter()
    .enumerate()
    {
        let px = screenshot(&browser, &page, hash, &dir.join(format!("shot-{k}.png")));
        let mask: Vec<bool> = px.iter().map(|&p| leafy(p)).collect();
        let total = mask.iter().filter(|&&m| m).count();
        let near_centre = (cy - 60..cy + 60)
            .flat_map(|y| (cx - 60..cx + 60).map(move |x| (x, y)))
            .filter(|&(x, y)| mask[y * WIDTH as usize + x])
            .count();
        eprintln!("{hash}: {total} leaf pixels, {near_centre} within 60 px of the centre");
        assert!(
            near_centre >= 20,
            "{hash}: the followed leaf is not drawn at the centre"
        );
        masks.push(mask);
    }
    let changed = masks[0]
        .iter()
        .zip(&masks[1])
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        changed >= 50,
        "the leaves look the same at t = 0.5 s and 2 s ({changed} px differ)"
    );
    // With the camera on all objects, shortly after release, the four
    // leaves are drawn apart.
    let px = screenshot(&browser, &page, "t=0.5", &dir.join("shot-all.png"));
    let mask: Vec<bool> = px.iter().map(|&p| leafy(p)).collect();
    let n = blobs(&mask, WIDTH as usize, 10);
    eprintln!("t=0.5, all objects: {n} separate leaves drawn");
    assert!(n >= 3, "only {n} leaves drawn");
}

/// A PointInstancer's leaves live a part of the shot
/// (`tests/data/usd/instanced/leaves.usda`: `leaves[42]` is born at 2.5 s,
/// `leaves[99]` dies at 4.96 s): the page draws each only over its life,
/// and a camera on one waits where it will appear, or stays where it went.
#[test]
fn the_preview_page_shows_particles_only_while_they_live_in_headless_chromium() {
    let Some(browser) = chromium() else {
        crate::common::missing_tool(
            "the_preview_page_shows_particles...",
            "no chromium (apt-get install chromium)",
        );
        return;
    };
    let dir = scratch("chromium-lives");
    // The page `preview` makes of tests/data/`file`, at `dir`/`name`.
    let preview = |file: &str, name: &str| {
        let page = dir.join(name);
        let o = leafmagic()
            .arg("preview")
            .arg(
                Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("tests/data")
                    .join(file),
            )
            .arg("--out")
            .arg(&page)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        page
    };
    let page = preview("usd/instanced/leaves.usda", "leaves.html");
    // Anything but the page's background (#1d2430): leaf, label or glyph.
    let drawn = |p: [u8; 3]| {
        let bg = [29, 36, 48];
        (0..3).any(|c| (i32::from(p[c]) - bg[c]).abs() > 30)
    };
    let (cx, cy) = (WIDTH as usize / 2, (HEIGHT - BAR) as usize / 2);
    for (hash, alive) in [
        ("t=1.0&follow=leaves%5B42%5D", false),
        ("t=3.0&follow=leaves%5B42%5D", true),
        ("t=2.0&follow=leaves%5B99%5D", true),
        ("t=8.0&follow=leaves%5B99%5D", false),
    ] {
        let png = dir.join(format!("{}.png", hash.replace(['=', '&', '%', '.'], "_")));
        let px = screenshot(&browser, &page, hash, &png);
        let near_centre = (cy - 60..cy + 60)
            .flat_map(|y| (cx - 60..cx + 60).map(move |x| (x, y)))
            .filter(|&(x, y)| drawn(px[y * WIDTH as usize + x]))
            .count();
        eprintln!("{hash}: {near_centre} px drawn within 60 px of the centre");
        if alive {
            assert!(
                near_centre >= 20,
                "{hash}: the followed leaf is not drawn at the centre"
            );
        } else {
            assert_eq!(near_centre, 0, "{hash}: a leaf is drawn outside its life");
        }
    }
    // A particle of Blender's cache comes as its centre and size, and the
    // viewer draws its three crossed lines about it: followed, they reach
    // out on all four sides of the centre of the view (its vertical line
    // above and below, the other two left and right), where a marker
    // drawn from its centre alone would be a point or one ray.
    let cache = preview("particles/leaves.abc", "particles.html");
    let hash = "t=1.0&follow=tree%2Fleaves%2F2";
    let px = screenshot(&browser, &cache, hash, &dir.join("particle.png"));
    let count = |xs: std::ops::Range<usize>, ys: std::ops::Range<usize>| {
        ys.flat_map(|y| xs.clone().map(move |x| (x, y)))
            .filter(|&(x, y)| drawn(px[y * WIDTH as usize + x]))
            .count()
    };
    let sides = [
        count(cx - 3..cx + 3, cy - 70..cy - 30),
        count(cx - 3..cx + 3, cy + 30..cy + 70),
        count(cx - 70..cx - 30, cy - 60..cy + 60),
        count(cx + 30..cx + 70, cy - 60..cy + 60),
    ];
    assert!(
        sides.iter().all(|&n| n > 0),
        "{hash}: the marker's lines reach {sides:?} px above, below, left and right"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Connected groups (4-neighbour) of at least `min` true pixels.
fn blobs(mask: &[bool], width: usize, min: usize) -> usize {
    let mut seen = vec![false; mask.len()];
    let mut count = 0;
    for start in 0..mask.len() {
        if !mask[start] || seen[start] {
            continue;
        }
        let (mut size, mut stack) = (0, vec![start]);
        seen[start] = true;
        while let Some(i) = stack.pop() {
            size += 1;
            let (x, y) = (i % width, i / width);
            let mut visit = |j: usize| {
                if mask[j] && !seen[j] {
                    seen[j] = true;
                    stack.push(j);
                }
            };
            if x > 0 {
                visit(i - 1);
            }
            if x + 1 < width {
                visit(i + 1);
            }
            if y > 0 {
                visit(i - width);
            }
            if i + width < mask.len() {
                visit(i + width);
            }
        }
        if size >= min {
            count += 1;
        }
    }
    count
}

/// A breeding run of prototype A (6 leaves, 1 generation, 3 s falls).
fn small_run(dir: &Path) -> PathBuf {
    let run = dir.join("run");
    let o = leafmagic()
        .args(["breed", "--population", "6", "--generations", "1"])
        .args(["--seconds", "3", "--threads", "1", "--out"])
        .arg(&run)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    run
}

#[test]
fn export_dresses_bred_leaves_with_a_render_mesh_at_a_start_height() {
    let dir = scratch("dress");
    let run = small_run(&dir);
    // A render mesh in the prototype's own coordinates: its rest triangles
    // split in four, lifted off the surface, with UVs.
    let proto = LeafSpec::load("a").unwrap().model().unwrap();
    let tris: Vec<[u32; 3]> = proto
        .triangles
        .iter()
        .map(|t| t.corners.map(|i| i as u32))
        .collect();
    let mesh = super::usd::fine_mesh(&proto.rest_position, &tris);
    let mut obj = String::new();
    for p in &mesh.positions {
        obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for t in &mesh.uvs {
        obj += &format!("vt {} {}\n", t[0], t[1]);
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        obj += &format!("f {a}/{a} {b}/{b} {c}/{c}\n");
    }
    let obj_path = dir.join("fine.obj");
    std::fs::write(&obj_path, obj).unwrap();
    for format in ["glb", "usd"] {
        let out = dir.join(format);
        let o = leafmagic()
            .arg("export")
            .arg(&run)
            .args(["--top", "1", "--format", format, "--start-height", "5"])
            .arg("--render-mesh")
            .arg(&obj_path)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let index = std::fs::read_to_string(out.join("index.csv")).unwrap();
        let id = index.lines().nth(1).unwrap().split(',').nth(1).unwrap();
        if format == "glb" {
            let bytes = std::fs::read(out.join(format!("leaf-{id}.glb"))).unwrap();
            let (doc, bin) = split_glb(&bytes);
            let shown = client_positions(&doc, &bin, 0);
            assert_eq!(
                shown[0].1.len(),
                mesh.positions.len(),
                "the render mesh is shown"
            );
            let z: f64 = shown[0].1.iter().map(|p| p.z).sum::<f64>() / shown[0].1.len() as f64;
            assert!((z - 5.0).abs() < 0.02, "released at 5 m, not {z}");
            let last = client_positions(&doc, &bin, 90);
            let z_end = last[0].1.iter().map(|p| p.z).sum::<f64>() / last[0].1.len() as f64;
            assert!(z_end < 4.0, "and falls from there ({z_end})");
        } else {
            let text = std::fs::read_to_string(out.join(format!("leaf-{id}.usda"))).unwrap();
            assert!(text.contains("texCoord2f[] primvars:st"));
            assert!(text.contains(&format!("custom string leafmagic:name = \"leaf-{id}\"")));
        }
    }
    // A failed export leaves the directory as it was and names the file.
    let out = dir.join("glb");
    let before: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nvt 0 0\nf 1/1 2/1 1/1\n").unwrap();
    let o = leafmagic()
        .arg("export")
        .arg(&run)
        .args(["--top", "2", "--format", "glb", "--render-mesh"])
        .arg(dir.join("bad.obj"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("bad.obj") && e.contains("line 3") && e.contains("out of range"),
        "{e}"
    );
    let after: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(before, after, "the directory is as it was");
    let strays: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("partial"))
        .collect();
    assert!(strays.is_empty(), "no temporary left: {strays:?}");
}

/// A leaf that is one rigid body (a plate from `leafmagic plate`) is
/// exported from its drop as a rigid object, a pose per frame, not as every
/// vertex per frame: the vertices it places are where the particles fell
/// (to 1e-9 m on a 5 cm plate released at a tilt, at output frames that fall
/// on recorded ones), and its .glb carries no morph targets and is a
/// fraction of the size. A mass-spring leaf stays deforming.
#[test]
fn a_rigid_plate_is_exported_as_a_rigid_object() {
    use leafmagic::leaf::AeroSpec;
    use leafmagic::leaf::plates::{PlateShape, plate};
    use leafmagic::sim::drop::{DropParams, drop_leaf};
    let model = plate(PlateShape::Square, 0.05, 1.0, 0.07, AeroSpec::unsteady())
        .unwrap()
        .model()
        .unwrap();
    let tilt = [20.0, 5.0];
    let fps = 30.0;
    let object = export::drop_clip_released("plate", "", &model, 2.0, fps, tilt).unwrap();
    let Motion::Rigid { translation, .. } = &object.motion else {
        panic!("a rigid plate was exported as deforming");
    };
    let frames = translation.len();
    let fall = drop_leaf(
        &model,
        &DropParams {
            seconds: 2.0,
            record_particles: true,
            tilt_deg: tilt,
            ..DropParams::default()
        },
    )
    .unwrap();
    let particles = clip::resample_positions(
        &fall.trajectory.time,
        fall.particles.as_ref().unwrap(),
        fps,
        frames,
    );
    let mut worst: f64 = 0.0;
    for (k, expected) in particles.iter().enumerate() {
        for (a, b) in object.positions(k).iter().zip(expected) {
            worst = worst.max((a - b).norm());
        }
    }
    assert!(worst < 1e-9, "rigid placement off by {worst:.3e} m");
    let deforming = ClipObject {
        first_frame: 0,
        motion: Motion::Deforming { frames: particles },
        ..object.clone()
    };
    let bytes = |o: ClipObject| {
        gltf::glb_bytes(&Clip {
            name: "plate".into(),
            fps,
            frames,
            objects: vec![o],
            ground: None,
            wind: Vec::new(),
            aero_law: String::new(),
            warnings: vec![],
        })
        .unwrap()
    };
    let (rigid, morphed) = (bytes(object), bytes(deforming));
    let json = String::from_utf8_lossy(&rigid);
    assert!(!json.contains("\"targets\""));
    assert!(String::from_utf8_lossy(&morphed).contains("\"targets\""));
    println!(
        "glb: {} bytes rigid, {} deforming",
        rigid.len(),
        morphed.len()
    );
    assert!(rigid.len() * 5 < morphed.len());
    // Prototype A bends: it stays deforming.
    let a = LeafSpec::from_toml(leafmagic::leaf::PROTOTYPE_A, "a")
        .unwrap()
        .model()
        .unwrap();
    let leaf = export::drop_clip("a", "", &a, 1.0, fps).unwrap();
    assert!(matches!(leaf.motion, Motion::Deforming { .. }));
}

/// The particles of each leaf of a scene's output directory at each
/// output frame (`<leaf>-particles.csv`), keyed by the name Alembic gives
/// the leaf (`leaf_000`) and the frame at `fps`.
fn scene_particles(dir: &Path, fps: f64) -> std::collections::HashMap<(String, usize), Vec<V3>> {
    let mut out = std::collections::HashMap::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let file = path.file_name().unwrap().to_string_lossy().into_owned();
        let Some(leaf) = file.strip_suffix("-particles.csv") else {
            continue;
        };
        let mut r = csv::Reader::from_path(&path).unwrap();
        for row in r.records() {
            let row = row.unwrap();
            let t: f64 = row[0].parse().unwrap();
            let k = (t * fps).round();
            if (k / fps - t).abs() > 1e-9 {
                continue;
            }
            let n: Vec<f64> = row.iter().skip(1).map(|x| x.parse().unwrap()).collect();
            let points = n.chunks(3).map(|c| V3::new(c[0], c[1], c[2])).collect();
            out.insert((usd::identifier(leaf), k as usize), points);
        }
    }
    out
}

/// Alembic export: scenes written as Alembic archives read back, every
/// vertex at every frame, where the simulation put it (to f32), by
/// leafmagic's own reader; and the layout is one Blender reads: the files
/// in `tests/data/abc/`, written by this exporter from the same scenes
/// (16 deforming leaves; a rigid bin, its points once under a matrix per
/// frame), read in leafmagic exactly as Blender 5.0.1's importer evaluates
/// them (`*.blender.csv`, its `make.py`), and the leaves as the
/// simulation's particles.
#[test]
fn alembic_export_reads_back_as_the_simulation_and_as_blender_reads_it() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let read = |path: &Path| alembic::read_abc(&std::fs::read(path).unwrap(), "scene").unwrap();
    for (scene, seconds, frames, objects) in
        [("ground-blow", "0.5", 16, 16), ("rocking-bin", "1", 31, 1)]
    {
        // The scene's run exported as `format` into a scratch directory.
        let export = |format: &str| {
            let dir = scratch(&format!("abc-{scene}-{format}"));
            let o = leafmagic()
                .arg("scene")
                .arg(format!("scenes/{scene}.toml"))
                .args(["--seconds", seconds, "--export", format, "--out"])
                .arg(&dir)
                .current_dir(repo)
                .output()
                .unwrap();
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            dir
        };
        let dir = export("abc");
        // The exporter writes the committed archive byte for byte (the
        // simulation is reproducible), so what Blender read of it below,
        // points and UVs, is what this exporter writes. A deliberate change
        // of layout writes the archives and Blender's readings again
        // (`tests/data/abc/make.py`).
        assert!(
            std::fs::read(dir.join(format!("{scene}.abc"))).unwrap()
                == std::fs::read(repo.join(format!("tests/data/abc/{scene}.abc"))).unwrap(),
            "{scene}.abc is not the committed archive: write it and Blender's readings again (tests/data/abc/make.py)"
        );
        let fresh = read(&dir.join(format!("{scene}.abc")));
        assert_eq!(
            (fresh.frames, fresh.fps, fresh.objects.len()),
            (frames, 30.0, objects)
        );
        let committed = read(&repo.join(format!("tests/data/abc/{scene}.abc")));
        let mut blender: std::collections::HashMap<(String, usize), Vec<V3>> = Default::default();
        let mut r =
            csv::Reader::from_path(repo.join(format!("tests/data/abc/{scene}.blender.csv")))
                .unwrap();
        for row in r.records() {
            let row = row.unwrap();
            let p = V3::new(
                row[3].parse().unwrap(),
                row[4].parse().unwrap(),
                row[5].parse().unwrap(),
            );
            blender
                .entry((row[0].to_string(), row[1].parse().unwrap()))
                .or_default()
                .push(p);
        }
        // The fresh file as the committed one (the same simulation), the
        // committed one as Blender reads it, and leaves as their particles.
        let committed_points: std::collections::HashMap<(String, usize), Vec<V3>> = committed
            .objects
            .iter()
            .flat_map(|o| {
                let leaf = o.name.split_once('/').unwrap().0.to_string();
                (0..committed.frames).map(move |k| ((leaf.clone(), k), o.positions(k)))
            })
            .collect();
        let particles = scene_particles(&dir, 30.0);
        let mut checks = vec![(&fresh, &committed_points), (&committed, &blender)];
        if !particles.is_empty() {
            checks.push((&fresh, &particles));
        }
        for (clip, against) in checks {
            for obj in &clip.objects {
                // `leaf_000/leaf_000_mesh`: the Xform, then its mesh.
                let (leaf, mesh) = obj.name.split_once('/').unwrap();
                assert_eq!(mesh, format!("{leaf}_mesh"));
                for k in 0..clip.frames {
                    let want = &against[&(leaf.to_string(), k)];
                    let got = obj.positions(k);
                    assert_eq!(got.len(), want.len(), "{scene} {leaf} frame {k}");
                    for (i, (g, w)) in got.iter().zip(want).enumerate() {
                        // f32 points in the moving frame, f64 matrices.
                        assert!(
                            (g - w).norm() < 1e-6,
                            "{scene} {leaf} frame {k} vertex {i}: {g} against {w}"
                        );
                    }
                }
            }
        }
        // The texture coordinates: Blender's UV map of each archive, per
        // face corner, is the UV the OBJ of a PC2 export gives that
        // corner's vertex (the same UVs the USD and glTF exports carry).
        let pc2 = export("pc2");
        let mut corners = 0;
        let mut r =
            csv::Reader::from_path(repo.join(format!("tests/data/abc/{scene}.blender.uv.csv")))
                .unwrap();
        let mut uvs: std::collections::HashMap<String, Vec<[f64; 2]>> = Default::default();
        for row in r.records() {
            let row = row.unwrap();
            // `leaf_000` is the identifier of `leaf-000`.
            let uv = uvs.entry(row[0].to_string()).or_insert_with(|| {
                obj_vertex_uvs(&pc2.join(format!("{}.obj", row[0].replace('_', "-"))))
            });
            let vertex: usize = row[2].parse().unwrap();
            let (u, v): (f64, f64) = (row[3].parse().unwrap(), row[4].parse().unwrap());
            let want = uv[vertex];
            assert!(
                (u - want[0]).abs() < 1e-6 && (v - want[1]).abs() < 1e-6,
                "{scene} {} corner {} (vertex {vertex}): Blender's UV ({u}, {v}) against {want:?}",
                &row[0],
                &row[1]
            );
            corners += 1;
        }
        // Three corners to a triangle, every triangle of every object.
        let triangles: usize = committed.objects.iter().map(|o| o.triangles.len()).sum();
        assert_eq!(corners, 3 * triangles, "{scene}: a corner without a UV");
        let _ = std::fs::remove_dir_all(&pc2);
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// The UV of each vertex of an OBJ (`f v/vt` corners: the `vt` its
/// corners name, which the PC2 export makes one per vertex).
fn obj_vertex_uvs(path: &Path) -> Vec<[f64; 2]> {
    let text = std::fs::read_to_string(path).unwrap();
    let vt: Vec<[f64; 2]> = text
        .lines()
        .filter_map(|l| l.strip_prefix("vt "))
        .map(|l| {
            let mut it = l.split_whitespace().map(|x| x.parse::<f64>().unwrap());
            [it.next().unwrap(), it.next().unwrap()]
        })
        .collect();
    let vertices = text.lines().filter(|l| l.starts_with("v ")).count();
    let mut uv = vec![[f64::NAN; 2]; vertices];
    for corner in text
        .lines()
        .filter_map(|l| l.strip_prefix("f "))
        .flat_map(str::split_whitespace)
    {
        let (v, t) = corner.split_once('/').unwrap();
        let (v, t): (usize, usize) = (v.parse().unwrap(), t.parse().unwrap());
        uv[v - 1] = vt[t - 1];
    }
    uv
}

/// Alembic export of a rigid body and a deforming leaf (the mixed scene
/// less its rope): each reads back vertex for vertex (to f32), the rigid
/// body's points written once under a matrix per frame, under unique
/// names where two objects' names make the same identifier. A rope has no
/// faces: the export is refused by the rope's name, and nothing is left
/// behind.
#[test]
fn alembic_export_writes_rigid_and_deforming_objects_and_refuses_a_rope() {
    let dir = scratch("abc-mixed");
    let mut clip = mixed_clip(DEFAULT_FPS);
    let path = dir.join("mixed.abc");
    let err = alembic::write_abc(&clip, &path).unwrap_err().to_string();
    assert!(
        err.contains("object rope has no faces") && err.contains("glb or usd"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "nothing written"
    );
    clip.objects.retain(|o| o.name != "rope");
    // Two names whose identifiers are the same: the second gets `_2`, so
    // the archive's children stay unique.
    assert_eq!(clip.objects.len(), 2);
    clip.objects[0].name = "card-1".into();
    clip.objects[1].name = "card_1".into();
    alembic::write_abc(&clip, &path).unwrap();
    let back = alembic::read_abc(&std::fs::read(&path).unwrap(), "mixed").unwrap();
    assert_eq!((back.frames, back.fps), (clip.frames, clip.fps));
    assert_eq!(back.objects.len(), clip.objects.len());
    let mut rigid = 0;
    for ((o, b), id) in clip
        .objects
        .iter()
        .zip(&back.objects)
        .zip(["card_1", "card_1_2"])
    {
        assert_eq!(b.name, format!("{id}/{id}_mesh"));
        rigid += usize::from(matches!(o.motion, Motion::Rigid { .. }));
        for k in 0..clip.frames {
            for (g, w) in b.positions(k).iter().zip(o.positions(k)) {
                assert!(
                    (g - w).norm() < 1e-6 * (1.0 + w.norm()),
                    "{} frame {k}: {g} against {w}",
                    o.name
                );
            }
        }
    }
    assert!(rigid > 0, "the mixed scene has a rigid body");
    let _ = std::fs::remove_dir_all(&dir);
}

// ----- a directed scene's goals on the page -----

/// A small directed scene: two leaves released over a square on the
/// ground and two 2 m away (which cannot land on it), a mark the near ones
/// pass at 0.3 s and a box the far ones stay in; one free number, so that
/// the direct layer reads it as a problem.
const DIRECTED: &str = r#"
name = "goals"
duration = 1.5
frame_rate = 30
seed = 2
[ground]
height = 0.0
static_friction = 0.8
kinetic_friction = 0.6
[[leaf]]
name = "near"
leaf = "a"
count = 2
position = [0.0, 0.0, 0.4]
spread = [0.05, 0.05, 0.02]
[[leaf]]
name = "far"
leaf = "a"
count = 2
position = [2.0, 0.0, 0.4]
spread = [0.05, 0.05, 0.02]
[[goal]]
name = "on the square"
leaves = ["near", "far"]
kind = "land"
polygon = [[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]]
[[goal]]
name = "by the mark"
leaves = "near"
kind = "pass"
point = [0.0, 0.0, 0.3]
tolerance = 0.2
at = 0.3
[[goal]]
name = "in the box"
leaves = "far"
kind = "stay"
min = [1.5, -0.5, 0.0]
max = [2.5, 0.5, 1.0]
until = 1.0
[[free]]
parameter = "leaf[near].position[2]"
min = 0.3
max = 0.6
"#;

/// The data of a preview page.
fn page_data(page: &Path) -> Value {
    let page = std::fs::read_to_string(page).unwrap();
    let start = page.find("id=\"leafmagic-data\"").unwrap();
    let start = start + page[start..].find('>').unwrap() + 1;
    let end = start + page[start..].find("</script>").unwrap();
    serde_json::from_str(&page[start..end]).unwrap()
}

/// The goal outline's amber as the page draws it ([1, 0.72, 0.2]).
fn amber(p: [u8; 3]) -> bool {
    let [r, g, b] = p.map(i32::from);
    r > 200 && (140..=220).contains(&g) && b < 110
}

/// A missed leaf's red, shaded.
fn reddish(p: [u8; 3]) -> bool {
    let [r, g, b] = p.map(i32::from);
    r > 60 && r > g + 40 && r > b + 40
}

#[test]
fn the_preview_of_a_directed_scene_draws_its_goals_and_the_direct_judges_verdicts() {
    let dir = scratch("directed");
    let file = dir.join("goals.toml");
    std::fs::write(&file, DIRECTED).unwrap();
    let out = dir.join("out");
    let o = leafmagic()
        .arg("scene")
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let recorded: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("goals.json")).unwrap()).unwrap();
    // The oracle: the direct layer's own evaluation of the file's values.
    let problem =
        leafmagic::direct::Problem::from_toml(DIRECTED, "goals.toml", &dir).expect("a problem");
    let written: Vec<f64> = problem.free.iter().map(|f| f.written).collect();
    let judged = problem.evaluate(&written);
    assert!(judged.failed.is_none());
    let goals = recorded["goals"].as_array().unwrap();
    assert_eq!(goals.len(), 3);
    let (mut met, mut missed) = (0, 0);
    for ((g, r), want) in goals.iter().zip(&judged.goals).zip(&problem.goals) {
        assert_eq!(g["name"], want.name.as_str());
        assert_eq!(g["met_fraction"].as_f64().unwrap(), r.met_fraction);
        let leaves = g["leaves"].as_array().unwrap();
        assert_eq!(leaves.len(), r.leaves.len());
        for (l, v) in leaves.iter().zip(&r.leaves) {
            assert_eq!(l["met"].as_bool().unwrap(), v.met, "{g}");
            assert_eq!(l["distance"].as_f64().unwrap(), v.distance, "{g}");
            if v.met {
                met += 1;
            } else {
                missed += 1;
            }
        }
    }
    // Neither all met nor all missed: the far leaves cannot land on the
    // square 2 m away.
    assert!(met > 0 && missed >= 2, "{met} met, {missed} missed");
    assert_eq!(goals[0]["kind"], "land");
    assert_eq!(goals[0]["polygon"][2], serde_json::json!([0.5, 0.5]));
    assert_eq!(goals[1]["point"], serde_json::json!([0.0, 0.0, 0.3]));
    assert_eq!(goals[1]["tolerance"], 0.2);
    assert_eq!(goals[2]["max"], serde_json::json!([2.5, 0.5, 1.0]));

    // The page holds the goals and verdicts, on leaves it draws.
    let page = dir.join("page.html");
    let preview = |page: &Path| {
        let o = leafmagic()
            .arg("preview")
            .arg(&out)
            .arg("--out")
            .arg(page)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    preview(&page);
    let data = page_data(&page);
    assert_eq!(&data["goals"], &recorded["goals"]);
    let names: Vec<&str> = data["objects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| o["name"].as_str().unwrap())
        .collect();
    for g in goals {
        for l in g["leaves"].as_array().unwrap() {
            assert!(names.contains(&l["name"].as_str().unwrap()), "{l}");
        }
    }

    // Drawn: the goals' amber outlines and the missed leaves' red, which a
    // page of the same run without its goals has none of.
    let Some(browser) = chromium() else {
        crate::common::missing_tool(
            "the_preview_of_a_directed_scene_draws...",
            "no chromium (apt-get install chromium)",
        );
        return;
    };
    let bare = dir.join("bare.html");
    std::fs::remove_file(out.join("goals.json")).unwrap();
    preview(&bare);
    assert_eq!(page_data(&bare)["goals"], serde_json::json!([]));
    let count = |page: &Path, name: &str| {
        let px = screenshot(&browser, page, "t=0.2", &dir.join(name));
        (
            px.iter().filter(|&&p| amber(p)).count(),
            px.iter().filter(|&&p| reddish(p)).count(),
        )
    };
    let (goal_px, red_px) = count(&page, "goals.png");
    let (bare_goal_px, bare_red_px) = count(&bare, "bare.png");
    eprintln!(
        "goals drawn: {goal_px} amber, {red_px} red px; without: {bare_goal_px}, {bare_red_px}"
    );
    assert!(
        goal_px >= 200 && bare_goal_px < 20,
        "{goal_px} vs {bare_goal_px}"
    );
    assert!(red_px >= 20 && bare_red_px < 5, "{red_px} vs {bare_red_px}");
    let _ = std::fs::remove_dir_all(&dir);
}
