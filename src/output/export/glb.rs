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

use super::{Clip, ClipObject, ExportError, Motion};
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

/// Colour of an object by its label (motion class) or kind, linear RGB.
pub fn colour(o: &ClipObject) -> [f32; 3] {
    match (o.label.as_str(), o.kind.as_str()) {
        ("floater", _) => [0.22, 0.62, 0.16],
        ("spinner", _) => [0.90, 0.50, 0.08],
        ("lilter", _) => [0.72, 0.74, 0.10],
        ("diverged", _) => [0.85, 0.12, 0.10],
        ("undetermined", _) => [0.62, 0.45, 0.25],
        (_, "leaf") => [0.30, 0.66, 0.18],
        (_, "rigid") => [0.52, 0.58, 0.68],
        (_, "sheet") => [0.86, 0.72, 0.46],
        (_, "rope") => [0.45, 0.30, 0.18],
        _ => [0.6, 0.6, 0.6],
    }
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

/// The output of a `weights` channel for `n` keys and `n` morph targets:
/// key k holds the one-hot vector e_k, so the accessor has n·n scalars, all
/// zero but the n at flat index k·n + k. It is written as a sparse accessor
/// (glTF 2.0 §3.6.2.3): no buffer view (all zeros), and the n indices
/// (unsigned int, strictly increasing) and n ones that replace them, so it
/// takes 8n bytes of the buffer instead of 4n².
fn one_hot_weights(
    root: &mut Root,
    bin: &mut Bin,
    n: usize,
    name: &str,
) -> Result<Index<Accessor>, ExportError> {
    let count = n * n;
    // The last index, n·n − 1, must fit in an unsigned int.
    if u32::try_from(count.saturating_sub(1)).is_err() {
        return Err(ExportError::Data(format!(
            "{name}: {n} frames are too many for the morph-target weights of a .glb \
             (at most 65536); export fewer frames (--fps)"
        )));
    }
    let indices: Vec<u8> = (0..n)
        .flat_map(|k| ((k * n + k) as u32).to_le_bytes())
        .collect();
    let index_view = bin.view(root, &indices, None);
    let value_view = bin.view(root, &f32_bytes(&vec![1.0; n]), None);
    Ok(root.push(Accessor {
        buffer_view: None,
        byte_offset: None,
        count: USize64::from(count),
        component_type: Valid(GenericComponentType(ComponentType::F32)),
        extensions: None,
        extras: None,
        type_: Valid(Type::Scalar),
        min: None,
        max: None,
        name: None,
        normalized: false,
        sparse: Some(json::accessor::sparse::Sparse {
            count: USize64::from(n),
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
    }))
}

fn raw_extras(value: serde_json::Value) -> Option<Box<json::extras::RawValue>> {
    serde_json::value::to_raw_value(&value).ok()
}

/// The `.glb` bytes of `clip`.
///
/// # Errors
/// [`ExportError::Data`] if the clip is inconsistent ([`Clip::validate`]) or
/// the file would exceed the 4 GiB a GLB header can describe.
pub fn glb_bytes(clip: &Clip) -> Result<Vec<u8>, ExportError> {
    clip.validate()?;
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
    // A single key cannot be interpolated; the animation is only written
    // when there are two frames or more.
    let animate = clip.frames >= 2;
    let mut nodes = Vec::new();
    let mut channels = Vec::new();
    let mut samplers = Vec::new();
    let mut materials = std::collections::BTreeMap::new();
    for o in &clip.objects {
        let rgb = colour(o);
        let key = format!("{}/{}", o.kind, o.label);
        let material = *materials.entry(key.clone()).or_insert_with(|| {
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
        });
        let frame0 = o.positions(0);
        let base: Vec<[f32; 3]> = match &o.motion {
            Motion::Rigid { local, .. } => local.iter().map(to_gltf).collect(),
            Motion::Deforming { .. } => frame0.iter().map(to_gltf).collect(),
        };
        let position = vec3_accessor(&mut root, &mut bin, &base, true);
        let (indices, mode) = if o.triangles.is_empty() {
            (
                o.segments.iter().flatten().copied().collect::<Vec<u32>>(),
                json::mesh::Mode::Lines,
            )
        } else {
            (
                o.triangles.iter().flatten().copied().collect(),
                json::mesh::Mode::Triangles,
            )
        };
        let index_accessor = (!indices.is_empty()).then(|| {
            let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
            let view = bin.view(
                &mut root,
                &bytes,
                Some(json::buffer::Target::ElementArrayBuffer),
            );
            accessor(
                &mut root,
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
        if let (Motion::Deforming { frames }, true) = (&o.motion, animate) {
            let mut list = Vec::with_capacity(frames.len());
            for f in frames {
                let d: Vec<[f32; 3]> = f
                    .iter()
                    .zip(&base)
                    .map(|(x, b)| {
                        let p = to_gltf(x);
                        [p[0] - b[0], p[1] - b[1], p[2] - b[2]]
                    })
                    .collect();
                list.push(json::mesh::MorphTarget {
                    positions: Some(vec3_accessor(&mut root, &mut bin, &d, true)),
                    normals: None,
                    tangents: None,
                });
            }
            weights = Some(vec![0.0; frames.len()]);
            targets = Some(list);
        }
        let mesh = root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: Some(o.name.clone()),
            primitives: vec![json::mesh::Primitive {
                attributes: [(Valid(json::mesh::Semantic::Positions), position)].into(),
                extensions: None,
                extras: None,
                indices: index_accessor,
                material: Some(material),
                mode: Valid(mode),
                targets,
            }],
            weights,
        });
        let (translation, rotation) = match &o.motion {
            Motion::Rigid {
                translation,
                rotation,
                ..
            } => (
                Some(to_gltf(&translation[0])),
                Some(json::scene::UnitQuaternion(quat_to_gltf(&rotation[0]))),
            ),
            Motion::Deforming { .. } => (None, None),
        };
        let node = root.push(json::Node {
            mesh: Some(mesh),
            name: Some(o.name.clone()),
            translation,
            rotation,
            extras: raw_extras(js!({"kind": o.kind, "label": o.label})),
            ..Default::default()
        });
        nodes.push(node);
        if !animate {
            continue;
        }
        let mut channel = |root: &mut Root,
                           bin: &mut Bin,
                           output: Vec<f32>,
                           type_: Type,
                           count: usize,
                           path: json::animation::Property| {
            let view = bin.view(root, &f32_bytes(&output), None);
            let out = accessor(root, view, count, ComponentType::F32, type_, None);
            sampler_channel(&mut samplers, &mut channels, time_accessor, out, node, path);
        };
        match &o.motion {
            Motion::Rigid {
                translation,
                rotation,
                ..
            } => {
                let t: Vec<f32> = translation.iter().flat_map(to_gltf).collect();
                channel(
                    &mut root,
                    &mut bin,
                    t,
                    Type::Vec3,
                    translation.len(),
                    json::animation::Property::Translation,
                );
                let r: Vec<f32> = rotation.iter().flat_map(quat_to_gltf).collect();
                channel(
                    &mut root,
                    &mut bin,
                    r,
                    Type::Vec4,
                    rotation.len(),
                    json::animation::Property::Rotation,
                );
            }
            Motion::Deforming { frames } => {
                let out = one_hot_weights(&mut root, &mut bin, frames.len(), &o.name)?;
                sampler_channel(
                    &mut samplers,
                    &mut channels,
                    time_accessor,
                    out,
                    node,
                    json::animation::Property::MorphTargetWeights,
                );
            }
        }
    }
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
        extras: raw_extras(js!({"leafmagic": {
            "fps": clip.fps,
            "ground": clip.ground,
            "wind": clip.wind,
        }})),
        name: Some(clip.name.clone()),
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
            "{}: {total} bytes exceed the 4 GiB a .glb can hold; export fewer frames (--fps) or objects",
            clip.name
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

/// Writes `clip` to `path` as `.glb`, atomically; returns the byte count.
pub fn write_glb(clip: &Clip, path: &Path) -> Result<usize, ExportError> {
    let bytes = glb_bytes(clip)?;
    crate::util::io::write_atomic(path, &bytes).map_err(|e| ExportError::io(path, e))?;
    Ok(bytes.len())
}
