//! Binary glTF 2.0 (`.glb`) of a [`Clip`], built with the `gltf-json` typed
//! document (no hand-written JSON) and written with `gltf`'s GLB container.
//!
//! Layout: one node and one mesh per object, one animation (`motion`) with
//! every channel, all samplers sharing one input accessor of frame times.
//!
//! - Rigid objects: the mesh holds the body-frame vertices; the node's
//!   `translation` and `rotation` channels (LINEAR: lerp and slerp) carry the
//!   pose per frame.
//! - Deforming objects: the mesh holds the frame-0 positions; morph target k
//!   is the displacement of frame k from frame 0 (one target per frame), and
//!   the `weights` channel keys a one-hot weight vector per frame (a sparse
//!   accessor: only the ones are stored, so the size is linear in the frame
//!   count, see `one_hot_weights`). With LINEAR
//!   interpolation, between keys k and k+1 the weights are (1 − s, s), which
//!   gives exactly the linear interpolation of the two frames' positions,
//!   because every target is a displacement from the same base.
//!
//! Axes: glTF is y-up, the simulator z-up; a point (x, y, z) is written as
//! (x, z, −y), a rotation by the same change of basis, so Blender's importer
//! (which turns y-up back into z-up) shows the scene as simulated.
//!
//! Scene-level `extras.leafmagic` carries what glTF has no place for (the
//! ground height, the wind glyphs, the frame rate), node `extras` the
//! object's kind and label; the previewer reads them back.

use crate::formats::clip::dress::{triangle_normals, vertex_normals};
use crate::formats::clip::frame::Framed;
use crate::formats::clip::look::{colour, material_name, shown};
use crate::formats::clip::{Clip, ClipObject};
use crate::formats::error::ExportError;
use crate::util::setting::Setting;
use gltf::json;
use json::accessor::{ComponentType, GenericComponentType, Type};
use json::validation::{Checked::Valid, USize64};
use json::{Accessor, Index, Root};
use nalgebra::{UnitQuaternion, Vector3};
use serde_json::json as js;
use std::borrow::Cow;
use std::path::Path;

type V3 = Vector3<f64>;

/// Simulator (z-up) to glTF (y-up) coordinates, f32.
pub fn to_gltf(v: &V3) -> [f32; 3] {
    [v.x as f32, v.z as f32, -v.y as f32]
}

/// glTF (y-up) to simulator (z-up) coordinates.
pub fn from_gltf(v: [f32; 3]) -> V3 {
    V3::new(v[0] as f64, -(v[2] as f64), v[1] as f64)
}

/// A simulator rotation as a glTF quaternion `[x, y, z, w]`: the vector part
/// changes basis like a point; renormalised after rounding to f32 so it is
/// unit to f32 precision.
pub fn quat_to_gltf(q: &UnitQuaternion<f64>) -> [f32; 4] {
    let c = [q.i, q.k, -q.j, q.w];
    let n = c.iter().map(|x| x * x).sum::<f64>().sqrt();
    c.map(|x| (x / n) as f32)
}

/// The binary chunk under construction: every view starts on a 4-byte
/// boundary, as accessors of 4-byte components require.
struct Bin {
    bytes: Vec<u8>,
}

impl Bin {
    fn view(
        &mut self,
        root: &mut Root,
        data: &[u8],
        target: Option<json::buffer::Target>,
    ) -> Index<json::buffer::View> {
        while self.bytes.len() % 4 != 0 {
            self.bytes.push(0);
        }
        let offset = self.bytes.len();
        self.bytes.extend_from_slice(data);
        root.push(json::buffer::View {
            buffer: Index::new(0),
            byte_length: USize64::from(data.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            extensions: None,
            extras: None,
            name: None,
            target: target.map(Valid),
        })
    }
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn accessor(
    root: &mut Root,
    view: Index<json::buffer::View>,
    count: usize,
    component: ComponentType,
    type_: Type,
    min_max: Option<(Vec<f32>, Vec<f32>)>,
) -> Index<Accessor> {
    let (min, max) = match min_max {
        Some((a, b)) => (Some(js!(a)), Some(js!(b))),
        None => (None, None),
    };
    root.push(Accessor {
        buffer_view: Some(view),
        byte_offset: None,
        count: USize64::from(count),
        component_type: Valid(GenericComponentType(component)),
        extensions: None,
        extras: None,
        type_: Valid(type_),
        min,
        max,
        name: None,
        normalized: false,
        sparse: None,
    })
}

/// Per-component minimum and maximum of vec3s (glTF requires them on every
/// POSITION accessor, morph targets included, and on animation inputs).
fn bounds3(v: &[[f32; 3]]) -> (Vec<f32>, Vec<f32>) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in v {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (lo.to_vec(), hi.to_vec())
}

fn vec3_accessor(root: &mut Root, bin: &mut Bin, v: &[[f32; 3]], target: bool) -> Index<Accessor> {
    let flat: Vec<f32> = v.iter().flatten().copied().collect();
    let view = bin.view(
        root,
        &f32_bytes(&flat),
        target.then_some(json::buffer::Target::ArrayBuffer),
    );
    accessor(
        root,
        view,
        v.len(),
        ComponentType::F32,
        Type::Vec3,
        Some(bounds3(v)),
    )
}

/// A LINEAR sampler of `output` over the shared frame times, and the
/// channel that drives `path` of `node` with it.
fn sampler_channel(
    samplers: &mut Vec<json::animation::Sampler>,
    channels: &mut Vec<json::animation::Channel>,
    input: Index<Accessor>,
    output: Index<Accessor>,
    node: Index<json::Node>,
    path: json::animation::Property,
) {
    samplers.push(json::animation::Sampler {
        extensions: None,
        extras: None,
        input,
        interpolation: Valid(json::animation::Interpolation::Linear),
        output,
    });
    channels.push(json::animation::Channel {
        sampler: Index::new(samplers.len() as u32 - 1),
        target: json::animation::Target {
            extensions: None,
            extras: None,
            node,
            path: Valid(path),
        },
        extensions: None,
        extras: None,
    });
}

/// The scene's `extras.leafmagic`: the clip's rate and span, ground and
/// wind, and the law its falls were simulated under when known.
fn scene_extras(clip: &Clip) -> serde_json::Value {
    let mut leafmagic = js!({
        "fps": clip.fps,
        "frames": clip.frames,
        "start_s": 0.0,
        "end_s": clip.duration(),
        "ground": clip.ground,
        "wind": clip.wind,
    });
    if !clip.aero_law.is_empty() {
        leafmagic["aero_law"] = js!(clip.aero_law);
    }
    js!({ "leafmagic": leafmagic })
}

fn raw_extras(value: serde_json::Value) -> Option<Box<json::extras::RawValue>> {
    serde_json::value::to_raw_value(&value).ok()
}

/// A morph target that moves few vertices: a sparse accessor (glTF 2.0
/// §3.6.2.3) over `count` vertices, zero but for `values` at `indices`
/// (strictly increasing), with the `min`/`max` of the whole, zeros
/// included, as POSITION accessors require.
fn sparse_vec3(
    root: &mut Root,
    bin: &mut Bin,
    count: usize,
    indices: &[u32],
    values: &[[f32; 3]],
) -> Index<Accessor> {
    let (mut lo, mut hi) = bounds3(values);
    if indices.len() < count {
        for d in 0..3 {
            lo[d] = lo[d].min(0.0);
            hi[d] = hi[d].max(0.0);
        }
    }
    let index_bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
    let index_view = bin.view(root, &index_bytes, None);
    let flat: Vec<f32> = values.iter().flatten().copied().collect();
    let value_view = bin.view(root, &f32_bytes(&flat), None);
    root.push(Accessor {
        buffer_view: None,
        byte_offset: None,
        count: USize64::from(count),
        component_type: Valid(GenericComponentType(ComponentType::F32)),
        extensions: None,
        extras: None,
        type_: Valid(Type::Vec3),
        min: Some(js!(lo)),
        max: Some(js!(hi)),
        name: None,
        normalized: false,
        sparse: Some(json::accessor::sparse::Sparse {
            count: USize64::from(indices.len()),
            indices: json::accessor::sparse::Indices {
                buffer_view: index_view,
                byte_offset: USize64(0),
                component_type: Valid(json::accessor::IndexComponentType(ComponentType::U32)),
                extensions: None,
                extras: None,
            },
            values: json::accessor::sparse::Values {
                buffer_view: value_view,
                byte_offset: USize64(0),
                extensions: None,
                extras: None,
            },
            extensions: None,
            extras: None,
        }),
    })
}

/// The deformation of an object in its moving frame as a fixed set of
/// morph targets, one per degree of freedom of the simulated mesh, whatever
/// the number of frames.
///
/// Without a render mesh, degree of freedom (i, a) is the displacement Δ of
/// particle i from its rest place along glTF axis a, and its target moves
/// vertex i along a: base + Σ Δ · targets is then the local shape exactly.
/// With a render mesh bound to the simulated triangles (Σ bᵢ pᵢ + h n, see
/// [`crate::formats::clip::render_mesh`]), target (i, a) moves each render vertex on a
/// triangle of particle i by bᵢ along a, and target (T, a) moves each render
/// vertex of triangle T by its offset h along a, driven by the change of T's
/// unit normal: exact again, because the binding is linear in the corners
/// and in the normal.
///
/// Every weight is kept in 0 … 1, because Blender clamps a shape key's
/// value to its slider range (0 … 1 unless set otherwise; a negative weight
/// became 0 there, 2.3 mm off, measured): over the frames, degree of freedom
/// j ranges over [lo, hi], its target is scaled by hi − lo and weighted
/// (Δ − lo) / (hi − lo), and one more target, `offset`, weighted 1 at every
/// frame, adds the Σ lo · targets this leaves out. Still linear in Δ, so
/// LINEAR interpolation between keys is the interpolation of the shapes.
struct Rig {
    /// Per target: (vertex indices, displacement per unit weight), glTF axes.
    targets: Vec<(Vec<u32>, Vec<[f32; 3]>)>,
    /// Target names (Blender's shape keys, three.js morph names).
    names: Vec<String>,
    /// Weights per frame, `targets.len()` each, all in 0 … 1.
    weights: Vec<Vec<f32>>,
    /// The weights that give the rest shape (the mesh's default).
    rest_weights: Vec<f32>,
}

fn axis(a: usize) -> [f32; 3] {
    let mut e = [0.0; 3];
    e[a] = 1.0;
    e
}

const AXES: [&str; 3] = ["x", "y", "z"];

fn rig(o: &ClipObject, framed: &Framed) -> Rig {
    let n = framed.rest.len();
    let rest: Vec<[f32; 3]> = framed.rest.iter().map(to_gltf).collect();
    // Which frames' displacements drive which target: particle moves, and
    // for a render mesh the triangle normals' changes.
    let mut targets = Vec::new();
    let mut names = Vec::new();
    let mut drivers: Vec<(usize, usize, bool)> = Vec::new(); // (particle or triangle, axis, is normal)
    match &o.render {
        None => {
            for i in 0..n {
                for (a, name) in AXES.iter().enumerate() {
                    targets.push((vec![i as u32], vec![axis(a)]));
                    names.push(format!("particle{i}.{name}"));
                    drivers.push((i, a, false));
                }
            }
        }
        Some(r) => {
            let mut by_particle: Vec<(Vec<u32>, Vec<f32>)> = vec![(Vec::new(), Vec::new()); n];
            let mut by_triangle: Vec<(Vec<u32>, Vec<f32>)> =
                vec![(Vec::new(), Vec::new()); o.triangles.len()];
            for (v, b) in r.bindings.iter().enumerate() {
                let t = o.triangles[b.triangle as usize];
                for (slot, &i) in t.iter().enumerate() {
                    let e = &mut by_particle[i as usize];
                    // A vertex on two corners of one triangle cannot be; but
                    // keep indices increasing and unique regardless.
                    if e.0.last() == Some(&(v as u32)) {
                        *e.1.last_mut().unwrap() += b.barycentric[slot] as f32;
                    } else {
                        e.0.push(v as u32);
                        e.1.push(b.barycentric[slot] as f32);
                    }
                }
                if b.offset != 0.0 {
                    let e = &mut by_triangle[b.triangle as usize];
                    e.0.push(v as u32);
                    e.1.push(b.offset as f32);
                }
            }
            for (i, (ix, w)) in by_particle.iter().enumerate() {
                if ix.is_empty() {
                    continue;
                }
                for (a, name) in AXES.iter().enumerate() {
                    let vals = w.iter().map(|&w| axis(a).map(|e| e * w)).collect();
                    targets.push((ix.clone(), vals));
                    names.push(format!("particle{i}.{name}"));
                    drivers.push((i, a, false));
                }
            }
            for (t, (ix, h)) in by_triangle.iter().enumerate() {
                if ix.is_empty() {
                    continue;
                }
                for (a, name) in AXES.iter().enumerate() {
                    let vals = h.iter().map(|&h| axis(a).map(|e| e * h)).collect();
                    targets.push((ix.clone(), vals));
                    names.push(format!("normal{t}.{name}"));
                    drivers.push((t, a, true));
                }
            }
        }
    }
    let rest_normals: Vec<[f32; 3]> = triangle_normals(&framed.rest, &o.triangles)
        .iter()
        .map(to_gltf)
        .collect();
    let raw: Vec<Vec<f32>> = (0..framed.origin.len())
        .map(|k| {
            let local = framed.local_at(k);
            let normals: Vec<[f32; 3]> = if o.render.is_some() {
                triangle_normals(local, &o.triangles)
                    .iter()
                    .map(to_gltf)
                    .collect()
            } else {
                Vec::new()
            };
            drivers
                .iter()
                .map(|&(j, a, normal)| {
                    if normal {
                        normals[j][a] - rest_normals[j][a]
                    } else {
                        to_gltf(&local[j])[a] - rest[j][a]
                    }
                })
                .collect()
        })
        .collect();
    // Each weight's range over the frames, and the offset that brings its
    // lower end to 0 (see the doc of `Rig`).
    let count = base_count(o, n);
    let mut offset = vec![[0.0f32; 3]; count];
    let mut weights = raw.clone();
    for (j, (ix, vals)) in targets.iter_mut().enumerate() {
        let lo = raw.iter().map(|w| w[j]).fold(f32::INFINITY, f32::min);
        let hi = raw.iter().map(|w| w[j]).fold(f32::NEG_INFINITY, f32::max);
        let scale = if hi > lo { hi - lo } else { 1.0 };
        for (v, d) in ix.iter().zip(vals.iter_mut()) {
            for c in 0..3 {
                offset[*v as usize][c] += lo * d[c];
                d[c] *= scale;
            }
        }
        for w in &mut weights {
            w[j] = ((w[j] - lo) / scale).clamp(0.0, 1.0);
        }
    }
    let moved: Vec<u32> = (0..count as u32)
        .filter(|&v| offset[v as usize] != [0.0; 3])
        .collect();
    if !moved.is_empty() {
        let vals = moved.iter().map(|&v| offset[v as usize]).collect();
        targets.push((moved, vals));
        names.push("offset".to_string());
        weights.iter_mut().for_each(|w| w.push(1.0));
    }
    // The weights of the rest shape (Δ = 0), for the mesh's default.
    let rest_weights = weights
        .first()
        .map(|_| {
            let mut w: Vec<f32> = (0..raw[0].len())
                .map(|j| {
                    let lo = raw.iter().map(|w| w[j]).fold(f32::INFINITY, f32::min);
                    let hi = raw.iter().map(|w| w[j]).fold(f32::NEG_INFINITY, f32::max);
                    let scale = if hi > lo { hi - lo } else { 1.0 };
                    ((0.0 - lo) / scale).clamp(0.0, 1.0)
                })
                .collect();
            if names.last().is_some_and(|n| n == "offset") {
                w.push(1.0);
            }
            w
        })
        .unwrap_or_default();
    Rig {
        targets,
        names,
        weights,
        rest_weights,
    }
}

/// The number of vertices a rig's targets move: the render mesh's, or the
/// simulated mesh's.
fn base_count(o: &ClipObject, n: usize) -> usize {
    o.render.as_ref().map_or(n, |r| r.vertex_count())
}

/// The `.glb` bytes of `clip`.
///
/// Layout: one node per object, named as the object, whose `translation`
/// and `rotation` carry the rigid part of its motion (the origin follows
/// the object: its centre, turned with it); its mesh (`<object>-mesh`)
/// holds the rest shape in that frame with smooth normals and UVs, and a
/// deforming object's mesh a fixed set of morph targets keyed once per
/// frame (see `Rig`), so the file grows linearly with the frames. The scene
/// is `<clip>-scene`, the animation `motion`.
///
/// # Errors
/// [`ExportError::Data`] if the clip is inconsistent ([`Clip::validate`]) or
/// the file would exceed the 4 GiB a GLB header can describe.
pub fn glb_bytes(clip: &Clip) -> Result<Vec<u8>, ExportError> {
    clip.validate()?;
    let mut glb = GlbBuilder::new(clip);
    for o in &clip.objects {
        glb.object(o);
    }
    glb.finish(clip)
}

/// A .glb being written: the document, its binary chunk, the key times
/// every channel shares, and the nodes, animation channels and materials
/// so far. Objects are added in order ([`GlbBuilder::object`]), each
/// pushing its material (first use), accessors, mesh, node and channels in
/// that order, so the bytes depend only on the clip.
struct GlbBuilder {
    root: Root,
    bin: Bin,
    time_accessor: Index<json::Accessor>,
    /// A single key cannot be interpolated; the animation is only written
    /// when there are two frames or more.
    animate: bool,
    nodes: Vec<Index<json::Node>>,
    channels: Vec<json::animation::Channel>,
    samplers: Vec<json::animation::Sampler>,
    materials: std::collections::BTreeMap<String, Index<json::Material>>,
}

impl GlbBuilder {
    fn new(clip: &Clip) -> Self {
        let mut root = Root {
            asset: json::Asset {
                generator: Some(format!("leafmagic {}", env!("CARGO_PKG_VERSION"))),
                ..Default::default()
            },
            ..Default::default()
        };
        let mut bin = Bin { bytes: Vec::new() };
        let times: Vec<f32> = clip.times().iter().map(|&t| t as f32).collect();
        let time_view = bin.view(&mut root, &f32_bytes(&times), None);
        let time_accessor = accessor(
            &mut root,
            time_view,
            times.len(),
            ComponentType::F32,
            Type::Scalar,
            Some((vec![times[0]], vec![*times.last().unwrap_or(&0.0)])),
        );
        GlbBuilder {
            root,
            bin,
            time_accessor,
            animate: clip.frames >= 2,
            nodes: Vec::new(),
            channels: Vec::new(),
            samplers: Vec::new(),
            materials: std::collections::BTreeMap::new(),
        }
    }

    /// One object: its material, mesh, node and (animated) channels.
    fn object(&mut self, o: &ClipObject) {
        let material = self.material(o);
        let framed = o.framed();
        let rig = (self.animate && framed.deforms()).then(|| rig(o, &framed));
        let mesh = self.mesh(o, &framed, material, rig.as_ref());
        let node = self.node(o, &framed, mesh);
        self.nodes.push(node);
        if self.animate {
            self.channels_of(node, &framed, rig);
        }
    }

    /// The material of `o`'s kind and class, made on its first use.
    fn material(&mut self, o: &ClipObject) -> Index<json::Material> {
        let rgb = colour(o);
        let key = material_name(o);
        let root = &mut self.root;
        *self.materials.entry(key.clone()).or_insert_with(|| {
            root.push(json::Material {
                name: Some(key),
                double_sided: true,
                pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                    base_color_factor: json::material::PbrBaseColorFactor([
                        rgb[0], rgb[1], rgb[2], 1.0,
                    ]),
                    metallic_factor: json::material::StrengthFactor(0.0),
                    roughness_factor: json::material::StrengthFactor(0.8),
                    ..Default::default()
                },
                ..Default::default()
            })
        })
    }

    /// `o`'s mesh at rest: positions, and for a surface normals, UVs and
    /// triangles (a rope's segments as lines, lone points as points), with
    /// the rig's morph targets when it deforms.
    fn mesh(
        &mut self,
        o: &ClipObject,
        framed: &Framed,
        material: Index<json::Material>,
        rig: Option<&Rig>,
    ) -> Index<json::Mesh> {
        let (root, bin) = (&mut self.root, &mut self.bin);
        let surface = shown(o, framed);
        let base: Vec<[f32; 3]> = surface.rest.iter().map(to_gltf).collect();
        let position = vec3_accessor(root, bin, &base, true);
        let mut attributes = vec![(Valid(json::mesh::Semantic::Positions), position)];
        let (indices, mode) = if surface.triangles.is_empty() {
            (
                o.segments.iter().flatten().copied().collect::<Vec<u32>>(),
                json::mesh::Mode::Lines,
            )
        } else {
            let normals: Vec<[f32; 3]> = vertex_normals(&surface.rest, &surface.triangles)
                .iter()
                .map(to_gltf)
                .collect();
            let normal = vec3_accessor(root, bin, &normals, true);
            attributes.push((Valid(json::mesh::Semantic::Normals), normal));
            // glTF's UV origin is the top left: v runs down.
            let uv: Vec<f32> = surface
                .uvs
                .iter()
                .flat_map(|t| [t[0] as f32, 1.0 - t[1] as f32])
                .collect();
            let view = bin.view(
                root,
                &f32_bytes(&uv),
                Some(json::buffer::Target::ArrayBuffer),
            );
            let texcoord = accessor(
                root,
                view,
                surface.uvs.len(),
                ComponentType::F32,
                Type::Vec2,
                None,
            );
            attributes.push((Valid(json::mesh::Semantic::TexCoords(0)), texcoord));
            (
                surface.triangles.iter().flatten().copied().collect(),
                json::mesh::Mode::Triangles,
            )
        };
        let index_accessor = (!indices.is_empty()).then(|| {
            let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
            let view = bin.view(root, &bytes, Some(json::buffer::Target::ElementArrayBuffer));
            accessor(
                root,
                view,
                indices.len(),
                ComponentType::U32,
                Type::Scalar,
                None,
            )
        });
        let mode = if index_accessor.is_none() {
            json::mesh::Mode::Points
        } else {
            mode
        };
        let mut targets = None;
        let mut weights = None;
        let mut mesh_extras = None;
        if let Some(rig) = rig {
            let list = rig
                .targets
                .iter()
                .map(|(ix, vals)| json::mesh::MorphTarget {
                    positions: Some(sparse_vec3(root, bin, base.len(), ix, vals)),
                    normals: None,
                    tangents: None,
                })
                .collect();
            targets = Some(list);
            weights = Some(rig.rest_weights.clone());
            // The names of the targets, where Blender and three.js look.
            mesh_extras = raw_extras(js!({ "targetNames": rig.names }));
        }
        root.push(json::Mesh {
            extensions: None,
            extras: mesh_extras,
            name: Some(format!("{}-mesh", o.name)),
            primitives: vec![json::mesh::Primitive {
                attributes: attributes.into_iter().collect(),
                extensions: None,
                extras: None,
                indices: index_accessor,
                material: Some(material),
                mode: Valid(mode),
                targets,
            }],
            weights,
        })
    }

    /// `o`'s node at its first pose, with its kind, class, regime and
    /// features in the extras.
    fn node(
        &mut self,
        o: &ClipObject,
        framed: &Framed,
        mesh: Index<json::Mesh>,
    ) -> Index<json::Node> {
        let mut extras = js!({"kind": o.kind, "label": o.label});
        if !o.regime.is_empty() {
            extras["regime"] = js!(o.regime);
        }
        if !o.features.is_empty() {
            extras["features"] = o
                .features
                .iter()
                .map(|(k, v)| (k.clone(), js!(v)))
                .collect::<serde_json::Map<_, _>>()
                .into();
        }
        self.root.push(json::Node {
            mesh: Some(mesh),
            name: Some(o.name.clone()),
            translation: Some(to_gltf(&framed.origin[0])),
            rotation: Some(json::scene::UnitQuaternion(quat_to_gltf(
                &framed.rotation[0],
            ))),
            extras: raw_extras(extras),
            ..Default::default()
        })
    }

    /// The node's translation and rotation channels, and its morph
    /// weights' when it deforms, all on the shared key times.
    fn channels_of(&mut self, node: Index<json::Node>, framed: &Framed, rig: Option<Rig>) {
        let t: Vec<f32> = framed.origin.iter().flat_map(to_gltf).collect();
        self.channel(
            node,
            t,
            Type::Vec3,
            framed.origin.len(),
            json::animation::Property::Translation,
        );
        let r: Vec<f32> = framed.rotation.iter().flat_map(quat_to_gltf).collect();
        self.channel(
            node,
            r,
            Type::Vec4,
            framed.rotation.len(),
            json::animation::Property::Rotation,
        );
        if let Some(rig) = rig {
            let w: Vec<f32> = rig.weights.into_iter().flatten().collect();
            let count = w.len();
            self.channel(
                node,
                w,
                Type::Scalar,
                count,
                json::animation::Property::MorphTargetWeights,
            );
        }
    }

    fn channel(
        &mut self,
        node: Index<json::Node>,
        output: Vec<f32>,
        type_: Type,
        count: usize,
        path: json::animation::Property,
    ) {
        let view = self.bin.view(&mut self.root, &f32_bytes(&output), None);
        let out = accessor(&mut self.root, view, count, ComponentType::F32, type_, None);
        sampler_channel(
            &mut self.samplers,
            &mut self.channels,
            self.time_accessor,
            out,
            node,
            path,
        );
    }

    /// The animation, the scene with the clip's timing in its extras, the
    /// buffer, and the GLB container around the JSON and binary chunks.
    fn finish(self, clip: &Clip) -> Result<Vec<u8>, ExportError> {
        let GlbBuilder {
            mut root,
            mut bin,
            animate,
            nodes,
            channels,
            samplers,
            ..
        } = self;
        if animate {
            root.push(json::Animation {
                extensions: None,
                extras: None,
                channels,
                name: Some("motion".to_string()),
                samplers,
            });
        }
        let scene = root.push(json::Scene {
            extensions: None,
            extras: raw_extras(scene_extras(clip)),
            name: Some(format!("{}-scene", clip.name)),
            nodes,
        });
        root.scene = Some(scene);
        while bin.bytes.len() % 4 != 0 {
            bin.bytes.push(0);
        }
        root.push(json::Buffer {
            byte_length: USize64::from(bin.bytes.len()),
            extensions: None,
            extras: None,
            name: None,
            uri: None,
        });
        let text = json::serialize::to_vec(&root)
            .map_err(|e| ExportError::Data(format!("cannot serialise the glTF document: {e}")))?;
        let total = 12 + 8 + text.len().next_multiple_of(4) + 8 + bin.bytes.len();
        let length = u32::try_from(total).map_err(|_| {
            ExportError::Data(format!(
                "{}: {total} bytes exceed the 4 GiB a .glb can hold; export fewer frames ({}) or objects",
                clip.name,
                Setting::Fps
            ))
        })?;
        let glb = gltf::binary::Glb {
            header: gltf::binary::Header {
                magic: *b"glTF",
                version: 2,
                length,
            },
            json: Cow::Owned(text),
            bin: Some(Cow::Owned(bin.bytes)),
        };
        glb.to_vec()
            .map_err(|e| ExportError::Data(format!("cannot write the GLB container: {e}")))
    }
}

/// Writes `clip` to `path` as `.glb`, atomically; returns the byte count.
pub fn write_glb(clip: &Clip, path: &Path) -> Result<usize, ExportError> {
    let bytes = glb_bytes(clip)?;
    crate::util::io::write_atomic(path, &bytes).map_err(|e| ExportError::io(path, e))?;
    Ok(bytes.len())
}
