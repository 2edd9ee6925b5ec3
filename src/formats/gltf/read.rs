//! glTF 2.0 files read as clips (ours, or any glTF 2.0 file: its node tree
//! composed, skinned meshes posed by their joints ([`crate::formats::skin`]),
//! morph targets blended, the document opened and read through
//! [`super::data`]).

use super::data::{Reading, buffer_data, check_accessor, check_sampler, open_gltf, vec3s};
use super::write::from_gltf;
use crate::formats::clip::{Clip, ClipObject, DEFAULT_FPS, Motion, WindGlyph};
use crate::formats::error::ExportError;
use crate::formats::sampling::{check_points, key_rate, sampled_frames};
use crate::formats::skin::{self, Influences};
use crate::util::confined::ReadScope;
use crate::util::setting::Setting;
use gltf::accessor::DataType::{F32, U8, U16, U32};
use gltf::accessor::Dimensions;
use gltf::animation::util::ReadOutputs;
use gltf::animation::{Interpolation, Property};
use nalgebra::{Matrix4, Quaternion, UnitQuaternion, Vector3};
use serde::Deserialize;
use std::collections::HashMap;
use std::path::Path;

type V3 = Vector3<f64>;
type M4 = Matrix4<f64>;

/// Reads a `.glb` file as a clip (see [`from_glb_bytes`]).
pub fn from_glb(
    path: &Path,
    fps: Option<f64>,
    animation: Option<&str>,
) -> Result<Clip, ExportError> {
    let bytes = std::fs::read(path).map_err(|e| ExportError::io(path, e))?;
    let name = path
        .file_stem()
        .map_or("glb".to_string(), |s| s.to_string_lossy().into_owned());
    from_glb_bytes(&bytes, &name, fps, animation).map_err(|e| match e {
        ExportError::Data(reason) => ExportError::input(path, reason),
        e => e,
    })
}

#[derive(Deserialize, Default)]
struct SceneExtras {
    #[serde(default)]
    leafmagic: Option<LeafmagicExtras>,
}

#[derive(Deserialize, Default)]
struct LeafmagicExtras {
    fps: Option<f64>,
    ground: Option<f64>,
    #[serde(default)]
    wind: Vec<WindGlyph>,
    /// Absent or null in a file written before the law was recorded, or
    /// of falls whose law is not known.
    #[serde(default)]
    aero_law: Option<String>,
}

#[derive(Deserialize, Default)]
struct NodeExtras {
    #[serde(default)]
    kind: String,
    #[serde(default)]
    label: String,
    #[serde(default)]
    regime: String,
    #[serde(default)]
    features: std::collections::BTreeMap<String, f64>,
}

/// Keyframes of one animated property: times and values (flattened, `width`
/// numbers per key).
struct Track {
    times: Vec<f32>,
    values: Vec<f32>,
    width: usize,
    step: bool,
}

impl Track {
    /// Values at `t`: linear between keys (quaternions renormalised by the
    /// caller), the key before for STEP, clamped outside the keys.
    fn at(&self, t: f64) -> Vec<f64> {
        let w = self.width;
        let n = self.times.len();
        let key = |k: usize| -> Vec<f64> {
            self.values[k * w..(k + 1) * w]
                .iter()
                .map(|&x| x as f64)
                .collect()
        };
        if n == 0 {
            return vec![0.0; w];
        }
        let j = self.times.partition_point(|&x| (x as f64) <= t);
        if j == 0 {
            return key(0);
        }
        if j >= n {
            return key(n - 1);
        }
        let (ta, tb) = (self.times[j - 1] as f64, self.times[j] as f64);
        let (a, b) = (key(j - 1), key(j));
        if self.step || tb <= ta {
            return a;
        }
        let s = (t - ta) / (tb - ta);
        a.iter().zip(&b).map(|(x, y)| x + (y - x) * s).collect()
    }
}

/// A clip from the bytes of a `.glb`: every node of the default scene's
/// tree that has a mesh becomes an object, sampled at `fps` (default: the
/// file's own rate if leafmagic wrote it, else [`DEFAULT_FPS`]) over the
/// span of its animation. A root node without morph targets moves rigidly
/// by its TRS channels; one with morph targets, a node below others and a
/// skinned one deform (every vertex placed per frame). Ground and wind
/// glyphs come from leafmagic's scene `extras`. Of several animations,
/// `animation` names the one to play, as [`read_gltf_keys`] reads them.
pub fn from_glb_bytes(
    bytes: &[u8],
    name: &str,
    fps: Option<f64>,
    animation: Option<&str>,
) -> Result<Clip, ExportError> {
    read_gltf(bytes, name, None, Grid::From0(fps), animation)
}

/// A clip from the bytes of a glTF file (`.glb`, or `.gltf` whose buffers
/// are data URIs or files in the folder `files` names, as far as its scope reaches), sampled at its own keys: from the
/// first key to the last, one frame per shortest key interval (see
/// `Grid::Keys`). What a fall is read from ([`crate::formats::fall`]).
/// Of a file with several animations, `animation` names the one to read
/// (by name, or by index where none has that name); without it, animations
/// that move different nodes are read together, and two that move the same
/// node's same property are refused, listed by name: an exporter writes
/// each action of an object as an animation of its own (Blender writes
/// the stashed actions beside the active one), and which is the fall only
/// its author knows.
pub fn read_gltf_keys(
    bytes: &[u8],
    name: &str,
    files: Option<(&Path, &ReadScope)>,
    animation: Option<&str>,
) -> Result<Clip, ExportError> {
    read_gltf(bytes, name, files, Grid::Keys, animation)
}

/// The index of the animation `want` names among `doc`'s (its name, else
/// its index), or why none does.
fn named_animation(doc: &gltf::Document, want: &str) -> Result<usize, String> {
    let count = doc.animations().len();
    doc.animations()
        .find(|a| a.name() == Some(want))
        .map(|a| a.index())
        .or_else(|| want.parse::<usize>().ok().filter(|&k| k < count))
        .ok_or_else(|| {
            if count == 0 {
                format!("{}: it holds no animation", Setting::Animation.set(want))
            } else {
                format!(
                    "{}: no animation of that name; it holds {}",
                    Setting::Animation.set(want),
                    animation_names(doc.animations())
                )
            }
        })
}

/// Animations listed for a message: `name`, or `#k` for an unnamed one.
fn animation_names<'a>(anims: impl Iterator<Item = gltf::Animation<'a>>) -> String {
    anims
        .map(|a| match a.name() {
            Some(n) => format!("`{n}`"),
            None => format!("#{}", a.index()),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Refuses `doc` when two of its animations move the same node's same
/// property ([`read_gltf_keys`] says why), naming them and the node.
fn check_one_take(doc: &gltf::Document) -> Result<(), String> {
    // The first animation to move each (node, property); gltf's Property
    // is not Hash, its discriminant is.
    let mut mover: HashMap<(usize, u8), usize> = HashMap::new();
    for anim in doc.animations() {
        for ch in anim.channels() {
            let node = ch.target().node();
            let key = (node.index(), ch.target().property() as u8);
            let Some(&first) = mover.get(&key) else {
                mover.insert(key, anim.index());
                continue;
            };
            if first == anim.index() {
                continue;
            }
            let moving: Vec<gltf::Animation<'_>> = doc
                .animations()
                .filter(|a| {
                    a.channels()
                        .any(|c| c.target().node().index() == node.index())
                })
                .collect();
            return Err(format!(
                "{} of its animations move node `{}` ({}): name the one to read with {}",
                moving.len(),
                node.name()
                    .map_or_else(|| format!("#{}", node.index()), str::to_string),
                animation_names(moving.into_iter()),
                Setting::Animation.set("NAME")
            ));
        }
    }
    Ok(())
}

/// Where a clip read from glTF is sampled.
#[derive(Clone, Copy, Debug)]
enum Grid {
    /// From t = 0 to the last key at this rate (default: the file's own if
    /// leafmagic wrote it, else [`DEFAULT_FPS`]): what players show.
    From0(Option<f64>),
    /// From the first key to the last at the keys' own rate (one frame per
    /// shortest key interval): what a fall's classification reads, with no
    /// made-up hold before the first key (Blender's keys start at frame 1,
    /// 1/24 s) and no interpolation between keys it does not need.
    Keys,
}

/// A clip from the bytes of a glTF file (binary, or JSON whose buffers are
/// data URIs or files in the folder `files` names, as far as its scope reaches), sampled on `grid`: of its animations, the
/// one `animation` names, else all of them, refusing two that move the
/// same node ([`read_gltf_keys`]).
fn read_gltf(
    bytes: &[u8],
    name: &str,
    files: Option<(&Path, &ReadScope)>,
    grid: Grid,
    animation: Option<&str>,
) -> Result<Clip, ExportError> {
    let gltf = open_gltf(bytes)?;
    // A read without files (the bytes of a .glb) is charged to a budget
    // of its own, as a file's read is to its scope's.
    let unanchored;
    let budget = match files {
        Some((_, scope)) => scope,
        None => {
            unanchored = ReadScope::unanchored();
            &unanchored
        }
    };
    let buffers = buffer_data(&gltf, files, budget)?;
    let data = Reading {
        buffers: &buffers,
        budget,
    };
    let doc = &gltf.document;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| ExportError::Data("the file has no scene".into()))?;
    let extras: LeafmagicExtras = scene
        .extras()
        .as_ref()
        .and_then(|r| serde_json::from_str::<SceneExtras>(r.get()).ok())
        .and_then(|e| e.leafmagic)
        .unwrap_or_default();
    let only = match animation {
        Some(want) => Some(named_animation(doc, want).map_err(ExportError::Data)?),
        None => {
            check_one_take(doc).map_err(ExportError::Data)?;
            None
        }
    };
    let tree = NodeTree::of(doc, &scene).map_err(ExportError::Data)?;
    let nodes: Vec<gltf::Node<'_>> = tree
        .scene_order
        .iter()
        .filter_map(|&i| doc.nodes().nth(i))
        .filter(|n| n.mesh().is_some())
        .collect();
    let moves_a_mesh = nodes_moving_meshes(&tree, &nodes);
    let mut warnings = Vec::new();
    let (tracks, t_start, t_end) = read_tracks(doc, only, &data, &moves_a_mesh, &mut warnings)?;
    let (start, fps) = match grid {
        Grid::From0(fps) => (0.0, fps.or(extras.fps).unwrap_or(DEFAULT_FPS)),
        Grid::Keys => match key_rate(
            tracks
                .iter()
                .flat_map(|(_, _, t)| t.times.windows(2).map(|w| w[1] as f64 - w[0] as f64))
                .filter(|d| *d > 0.0)
                .fold(f64::INFINITY, f64::min),
        ) {
            Some(rate) => (t_start, rate),
            // No animation, or one key: a single frame.
            None => (t_start.min(t_end).max(0.0), DEFAULT_FPS),
        },
    };
    let frames = sampled_frames(start, t_end, fps).map_err(ExportError::Data)?;
    let sampling = Sampling { start, fps, frames };
    let animated = Animated {
        doc,
        tree: &tree,
        tracks: &tracks,
        data: &data,
    };
    let mut objects = Vec::new();
    for node in nodes {
        if let Some(object) = read_object(&animated, node, sampling, &objects, &mut warnings)? {
            objects.push(object);
        }
    }
    if objects.is_empty() {
        return Err(ExportError::Data(
            "the default scene has no node with a mesh".into(),
        ));
    }
    let clip = Clip {
        name: name.to_string(),
        fps,
        frames,
        objects,
        ground: extras.ground,
        wind: extras.wind,
        aero_law: extras.aero_law.unwrap_or_default(),
        warnings,
    };
    clip.validate()?;
    Ok(clip)
}

/// Tracks per (node, property).
type Tracks = Vec<(usize, Property, Track)>;

/// The frames a clip is sampled at: `frames` of them from `start`, s, at
/// `fps`.
#[derive(Clone, Copy, Debug)]
struct Sampling {
    start: f64,
    fps: f64,
    frames: usize,
}

impl Sampling {
    /// The time of frame `k`, s.
    fn time(self, k: usize) -> f64 {
        self.start + k as f64 / self.fps
    }
}

/// A document's nodes with what animates them, as read.
struct Animated<'a> {
    doc: &'a gltf::Document,
    tree: &'a NodeTree,
    tracks: &'a [(usize, Property, Track)],
    data: &'a Reading<'a>,
}

/// The nodes whose motion moves a mesh read: the mesh nodes, their
/// skins' joints, and every node above them.
fn nodes_moving_meshes(tree: &NodeTree, nodes: &[gltf::Node<'_>]) -> Vec<bool> {
    let mut moves_a_mesh = vec![false; tree.parents.len()];
    for node in nodes {
        let skin = node.skin();
        let joints = skin.iter().flat_map(|s| s.joints().map(|j| j.index()));
        for start in std::iter::once(node.index()).chain(joints) {
            let mut up = Some(start);
            while let Some(i) = up.filter(|&i| !moves_a_mesh[i]) {
                moves_a_mesh[i] = true;
                up = tree.parents[i];
            }
        }
    }
    moves_a_mesh
}

/// The tracks of the animations read (the one `only` names, else all), and
/// the first and last key's times. A broken channel is refused if its
/// node moves a mesh, else said in `warnings` and left out.
fn read_tracks(
    doc: &gltf::Document,
    only: Option<usize>,
    data: &Reading<'_>,
    moves_a_mesh: &[bool],
    warnings: &mut Vec<String>,
) -> Result<(Tracks, f64, f64), ExportError> {
    let mut tracks: Tracks = Vec::new();
    let mut t_end = 0.0f64;
    let mut t_start = f64::INFINITY;
    for anim in doc
        .animations()
        .filter(|a| only.is_none_or(|k| a.index() == k))
    {
        for ch in anim.channels() {
            let node = ch.target().node();
            let track = match read_track(&ch, data) {
                Ok(track) => track,
                Err(why) => {
                    let label = format!(
                        "animation {}{}, channel {} (node {}{}, {}), sampler {}: {why}",
                        anim.index(),
                        anim.name().map_or(String::new(), |n| format!(" `{n}`")),
                        ch.index(),
                        node.index(),
                        node.name().map_or(String::new(), |n| format!(" `{n}`")),
                        property_name(ch.target().property()),
                        ch.sampler().index(),
                    );
                    // A broken channel of a node that moves no mesh read
                    // changes nothing read: said, and left out.
                    if moves_a_mesh[node.index()] {
                        return Err(ExportError::Data(label));
                    }
                    warnings.push(format!("{label}; left out, as the node moves no mesh"));
                    continue;
                }
            };
            if let (Some(&first), Some(&last)) = (track.times.first(), track.times.last()) {
                t_start = t_start.min(first as f64);
                t_end = t_end.max(last as f64);
            }
            tracks.push((node.index(), ch.target().property(), track));
        }
    }
    Ok((tracks, t_start, t_end))
}

/// The clip object of mesh node `node`, sampled at `sampling` (`None`,
/// said in `warnings`, for a mesh with no primitive); `objects` are those
/// read before it, whose names its own must differ from.
fn read_object(
    animated: &Animated<'_>,
    node: gltf::Node<'_>,
    sampling: Sampling,
    objects: &[ClipObject],
    warnings: &mut Vec<String>,
) -> Result<Option<ClipObject>, ExportError> {
    let Animated {
        doc,
        tree,
        tracks,
        data,
    } = *animated;
    let Some(mesh) = node.mesh() else {
        return Ok(None);
    };
    let frames = sampling.frames;
    let parents = &tree.parents;
    // World transforms of every node at frame k, for meshes below animated
    // parents and for skins' joints: computed frame by frame, not held for
    // all frames (a long bake of a deep rig would hold gigabytes).
    let worlds_at = |k: usize| world_matrices(doc, tree, tracks, sampling.time(k));
    let node_extras: NodeExtras = node
        .extras()
        .as_ref()
        .and_then(|r| serde_json::from_str(r.get()).ok())
        .unwrap_or_default();
    let Some(MeshData {
        base,
        triangles,
        segments,
        targets,
        influences,
        unread,
    }) = mesh_data(&node, &mesh, data)?
    else {
        warnings.push(format!(
            "node {} has mesh {}, which has no primitive: left out",
            node.index(),
            mesh.index()
        ));
        return Ok(None);
    };
    warnings.extend(unread);
    let track = |p: Property| track_of(tracks, node.index(), p);
    let default_weights: Vec<f64> = mesh
        .weights()
        .map(|w| w.iter().map(|&x| x as f64).collect())
        .unwrap_or_else(|| vec![0.0; targets.len()]);
    let weights_at =
        |t: f64| track(Property::MorphTargetWeights).map_or(default_weights.clone(), |x| x.at(t));
    let morphed = |i: usize, b: &[f32; 3], weights: &[f64]| morphed(&targets, i, b, weights);
    // Below other nodes or skinned: placed vertex by vertex.
    let composed = parents[node.index()].is_some() || node.skin().is_some();
    if composed || !targets.is_empty() {
        check_points(node.name().unwrap_or("a mesh"), frames, base.len())
            .map_err(ExportError::Data)?;
    }
    let motion = if composed {
        // The mesh's own vertices at frame k, morph targets applied.
        let points_at = |k: usize| -> Vec<V3> {
            let weights = weights_at(sampling.time(k));
            base.iter()
                .enumerate()
                .map(|(i, b)| V3::from(morphed(i, b, &weights)))
                .collect()
        };
        composed_motion(
            &node,
            frames,
            worlds_at,
            points_at,
            influences.as_ref(),
            data,
        )?
    } else {
        own_motion(&node, tracks, sampling, &base, &targets, weights_at)
    };
    Ok(Some(ClipObject {
        first_frame: 0,
        name: object_name(doc, parents, &node, objects),
        kind: if node_extras.kind.is_empty() {
            "mesh".to_string()
        } else {
            node_extras.kind
        },
        label: node_extras.label,
        regime: node_extras.regime,
        features: node_extras.features.into_iter().collect(),
        triangles,
        segments,
        body: None,
        render: None,
        motion,
    }))
}

/// Vertex `i` at rest `b`, its morph `targets` weighted by `weights`.
fn morphed(targets: &[Vec<[f32; 3]>], i: usize, b: &[f32; 3], weights: &[f64]) -> [f64; 3] {
    let mut p = b.map(f64::from);
    for (target, w) in targets.iter().zip(weights) {
        if *w != 0.0
            && let Some(d) = target.get(i)
        {
            for c in 0..3 {
                p[c] += w * d[c] as f64;
            }
        }
    }
    p
}

/// The motion of a mesh moved by its own node alone (a root, not
/// skinned): rigid, or deforming where morph targets move its vertices.
fn own_motion(
    node: &gltf::Node<'_>,
    tracks: &[(usize, Property, Track)],
    sampling: Sampling,
    base: &[[f32; 3]],
    targets: &[Vec<[f32; 3]>],
    weights_at: impl Fn(f64) -> Vec<f64>,
) -> Motion {
    let frames = sampling.frames;
    let mut translation = Vec::with_capacity(frames);
    let mut rotation = Vec::with_capacity(frames);
    let mut scale = Vec::with_capacity(frames);
    let mut weights = Vec::with_capacity(frames);
    for k in 0..frames {
        let t = sampling.time(k);
        let (tr, r, s) = trs(node, tracks, t);
        // glTF [x, y, z, w] → the simulator's axes: (w, X, −Z, Y).
        let q = UnitQuaternion::new_normalize(Quaternion::new(r[3], r[0], -r[2], r[1]));
        translation.push(from_gltf([tr[0] as f32, tr[1] as f32, tr[2] as f32]));
        rotation.push(q);
        scale.push([s[0], s[1], s[2]]);
        weights.push(weights_at(t));
    }
    let scaled = |p: [f64; 3], s: [f64; 3]| -> V3 {
        from_gltf([
            (p[0] * s[0]) as f32,
            (p[1] * s[1]) as f32,
            (p[2] * s[2]) as f32,
        ])
    };
    if targets.is_empty() {
        Motion::Rigid {
            local: base
                .iter()
                .map(|p| scaled(p.map(f64::from), scale.first().copied().unwrap_or([1.0; 3])))
                .collect(),
            translation,
            rotation,
        }
    } else {
        let frames_out = (0..frames)
            .map(|k| {
                base.iter()
                    .enumerate()
                    .map(|(i, b)| {
                        translation[k]
                            + rotation[k] * scaled(morphed(targets, i, b, &weights[k]), scale[k])
                    })
                    .collect()
            })
            .collect();
        Motion::Deforming { frames: frames_out }
    }
}

/// A glTF node tree, checked to be one: every node below at most one
/// parent, no node its own ancestor, none reached twice from the scene.
/// Walked without recursion, as every traversal of it here: a file
/// chooses its depth (a chain of 100,000 nodes is 2 MB of JSON).
struct NodeTree {
    /// Each node's parent (`None` for a root).
    parents: Vec<Option<usize>>,
    /// Every node, each after its parent.
    order: Vec<usize>,
    /// The nodes of the scene's trees, depth first in the scene's order.
    scene_order: Vec<usize>,
}

impl NodeTree {
    /// `doc`'s node tree and `scene`'s part of it, or why it is no tree:
    /// a node that is its own ancestor (named with its loop), a child of
    /// two parents, or reached twice from the scene. glTF forbids each;
    /// left in, a loop would be walked for ever and a node reached twice
    /// (a scene listing one node 400,000 times) read as that many objects.
    fn of(doc: &gltf::Document, scene: &gltf::Scene<'_>) -> Result<NodeTree, String> {
        let n = doc.nodes().len();
        let mut parents: Vec<Option<usize>> = vec![None; n];
        for node in doc.nodes() {
            for child in node.children() {
                let (c, p) = (child.index(), node.index());
                if c == p {
                    return Err(format!(
                        "node {p} is its own ancestor: {p} → {p} (it lists itself as a child)"
                    ));
                }
                if let Some(q) = parents[c] {
                    return Err(if q == p {
                        format!("node {p} lists node {c} twice as a child")
                    } else {
                        format!(
                            "node {c} is a child of both node {q} and node {p} (a glTF node has one parent)"
                        )
                    });
                }
                parents[c] = Some(p);
            }
        }
        // Each node's parent chain followed once: 1 while on the chain
        // being followed, 2 when known to end at a root.
        let mut state = vec![0u8; n];
        for start in 0..n {
            let mut chain = Vec::new();
            let mut at = Some(start);
            while let Some(i) = at {
                match state[i] {
                    2 => break,
                    1 => {
                        let from = chain.iter().position(|&c| c == i).unwrap_or(0);
                        // Parent first, each node a child of the one before.
                        let names: Vec<String> = std::iter::once(i)
                            .chain(chain[from..].iter().rev().copied())
                            .map(|k| k.to_string())
                            .collect();
                        return Err(format!(
                            "node {i} is its own ancestor: {}",
                            names.join(" → ")
                        ));
                    }
                    _ => {
                        state[i] = 1;
                        chain.push(i);
                        at = parents[i];
                    }
                }
            }
            for i in chain {
                state[i] = 2;
            }
        }
        let children: Vec<Vec<usize>> = doc
            .nodes()
            .map(|node| node.children().map(|c| c.index()).collect())
            .collect();
        // Depth first from `roots`, a node's children in their order.
        let walk = |roots: &mut dyn Iterator<Item = usize>| -> Vec<usize> {
            let mut out = Vec::new();
            for root in roots {
                let mut stack = vec![root];
                while let Some(i) = stack.pop() {
                    out.push(i);
                    stack.extend(children[i].iter().rev());
                }
            }
            out
        };
        let order = walk(&mut (0..n).filter(|&i| parents[i].is_none()));
        let scene_order = walk(&mut scene.nodes().map(|r| r.index()));
        let mut reached: Vec<Option<usize>> = vec![None; n];
        for (k, &i) in scene_order.iter().enumerate() {
            if reached[i].is_some() {
                let listed = scene.nodes().filter(|r| r.index() == i).count();
                return Err(match (listed, parents[i]) {
                    (2.., _) => format!(
                        "the scene lists node {i} {listed} times (glTF lists each root once)"
                    ),
                    (_, Some(p)) => format!(
                        "node {i} is reached twice from the scene: listed in it, and a child of node {p}"
                    ),
                    _ => format!("node {i} is reached twice from the scene"),
                });
            }
            reached[i] = Some(k);
        }
        Ok(NodeTree {
            parents,
            order,
            scene_order,
        })
    }
}

/// A glTF animation property in words.
fn property_name(property: Property) -> &'static str {
    match property {
        Property::Translation => "translation",
        Property::Rotation => "rotation",
        Property::Scale => "scale",
        Property::MorphTargetWeights => "weights",
    }
}

/// The keys of one animation channel, every accessor checked before it is
/// read ([`check_sampler`]), or why they cannot be read.
fn read_track(ch: &gltf::animation::Channel<'_>, data: &Reading<'_>) -> Result<Track, String> {
    let text = |e: ExportError| e.to_string();
    check_sampler(ch, data).map_err(text)?;
    let reader = ch.reader(data.get());
    let input = ch.sampler().input().index();
    let output = ch.sampler().output().index();
    let times: Vec<f32> = reader
        .read_inputs()
        .ok_or_else(|| format!("accessor {input} (key times) cannot be read"))?
        .collect();
    let (values, width): (Vec<f32>, usize) = match reader.read_outputs() {
        Some(ReadOutputs::Translations(it)) => (it.flatten().collect(), 3),
        Some(ReadOutputs::Rotations(r)) => (r.into_f32().flatten().collect(), 4),
        Some(ReadOutputs::Scales(it)) => (it.flatten().collect(), 3),
        Some(ReadOutputs::MorphTargetWeights(w)) => {
            // gltf's accessor iterator applies sparse substitution
            // (zeros, or the buffer view, with `sparse.values` at
            // `sparse.indices`), as leafmagic writes these weights.
            let v: Vec<f32> = w.into_f32().collect();
            let width = v.len() / times.len().max(1);
            (v, width)
        }
        None => return Err(format!("accessor {output} (key values) cannot be read")),
    };
    let cubic = ch.sampler().interpolation() == Interpolation::CubicSpline;
    let per_key = width * if cubic { 3 } else { 1 };
    if times.is_empty() || per_key == 0 || values.len() != times.len() * per_key {
        return Err(format!(
            "{} key times and {} values, not {} a key",
            times.len(),
            values.len(),
            per_key.max(1)
        ));
    }
    if times
        .windows(2)
        .any(|w| w[0].partial_cmp(&w[1]) != Some(std::cmp::Ordering::Less))
        || !(times[0].is_finite() && times[times.len() - 1].is_finite())
    {
        return Err("its key times are not finite and increasing".into());
    }
    // Cubic splines store (in-tangent, value, out-tangent) per key: keep
    // the values (the motion through the keys, not between them).
    let values = if cubic {
        values
            .chunks(3 * width)
            .flat_map(|c| c[width..2 * width].to_vec())
            .collect()
    } else {
        values
    };
    Ok(Track {
        times,
        values,
        width,
        step: ch.sampler().interpolation() == Interpolation::Step,
    })
}

/// The track animating `property` of node `node`, if any.
fn track_of(
    tracks: &[(usize, Property, Track)],
    node: usize,
    property: Property,
) -> Option<&Track> {
    tracks
        .iter()
        .find(|(n, p, _)| *n == node && *p == property)
        .map(|(_, _, t)| t)
}

/// A node's translation, rotation (glTF's `[x, y, z, w]`) and scale at
/// time `t`: its channels' values where it has them, else its own.
fn trs(
    node: &gltf::Node<'_>,
    tracks: &[(usize, Property, Track)],
    t: f64,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let track = |p| track_of(tracks, node.index(), p);
    let (t0, r0, s0) = node.transform().decomposed();
    (
        track(Property::Translation).map_or(t0.map(f64::from).to_vec(), |x| x.at(t)),
        track(Property::Rotation).map_or(r0.map(f64::from).to_vec(), |x| x.at(t)),
        track(Property::Scale).map_or(s0.map(f64::from).to_vec(), |x| x.at(t)),
    )
}

/// A node's local transform at time `t` (glTF axes, column vectors): its
/// animated or default translation, rotation and scale as T·R·S, or its
/// `matrix` where it has one and no channel moves it (glTF forbids
/// animating a node given by a matrix).
fn local_matrix(node: &gltf::Node<'_>, tracks: &[(usize, Property, Track)], t: f64) -> M4 {
    let track = |p| track_of(tracks, node.index(), p);
    let animated = [Property::Translation, Property::Rotation, Property::Scale]
        .into_iter()
        .any(|p| track(p).is_some());
    if !animated {
        let columns = node.transform().matrix();
        return M4::from_fn(|r, c| columns[c][r] as f64);
    }
    let (tr, r, s) = trs(node, tracks, t);
    skin::trs_matrix(&tr, [r[3], r[0], r[1], r[2]], &s)
}

/// Every node's world transform at time `t`: its parents' composed with
/// its own, each parent's before its children's ([`NodeTree::order`]).
fn world_matrices(
    doc: &gltf::Document,
    tree: &NodeTree,
    tracks: &[(usize, Property, Track)],
    t: f64,
) -> Vec<M4> {
    let local: Vec<M4> = doc.nodes().map(|n| local_matrix(&n, tracks, t)).collect();
    let mut world = local.clone();
    for &i in &tree.order {
        if let Some(p) = tree.parents[i] {
            world[i] = world[p] * local[i];
        }
    }
    world
}

/// A point in glTF's axes (y up) in the simulator's (z up), in f64.
fn z_up(p: V3) -> V3 {
    V3::new(p.x, -p.z, p.y)
}

/// A mesh's geometry: every primitive's vertices in one list (Blender
/// writes one primitive per material), with their triangles or segments,
/// morph target displacements and skin influences.
struct MeshData {
    base: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    segments: Vec<[u32; 2]>,
    targets: Vec<Vec<[f32; 3]>>,
    influences: Option<Influences>,
    /// What of it was not read, for a warning: primitives drawn as
    /// strips, fans or loops, whose vertices are read but not their
    /// triangles or segments.
    unread: Vec<String>,
}

/// How many JOINTS_n / WEIGHTS_n sets a primitive has, and each vertex's
/// joints and weights from them.
type SkinSets = (u32, Vec<Vec<usize>>, Vec<Vec<f64>>);

/// Every JOINTS_n / WEIGHTS_n set of primitive `prim` of skinned `node`,
/// four influences each: how many sets, and each of its `n` vertices'
/// joints and weights.
fn skin_sets(
    node: &gltf::Node<'_>,
    prim: &gltf::Primitive<'_>,
    n: usize,
    reading: &Reading<'_>,
) -> Result<SkinSets, ExportError> {
    let reader = prim.reader(reading.get());
    let mut set = 0;
    let (mut j, mut w) = (vec![Vec::new(); n], vec![Vec::new(); n]);
    while let (Some(ja), Some(wa)) = (
        prim.get(&gltf::Semantic::Joints(set)),
        prim.get(&gltf::Semantic::Weights(set)),
    ) {
        check_accessor(&ja, &[U8, U16], Dimensions::Vec4, "joints", reading)?;
        check_accessor(&wa, &[U8, U16, F32], Dimensions::Vec4, "weights", reading)?;
        let (Some(js), Some(ws)) = (reader.read_joints(set), reader.read_weights(set)) else {
            return Err(ExportError::Data(format!(
                "mesh of node {}: joints or weights {set} lie outside their buffer",
                node.index()
            )));
        };
        for (v, (js, ws)) in js.into_u16().zip(ws.into_f32()).enumerate().take(n) {
            j[v].extend(js.map(usize::from));
            w[v].extend(ws.map(f64::from));
        }
        set += 1;
    }
    Ok((set, j, w))
}

/// The geometry of `node`'s `mesh` (`None` if it has no primitive).
fn mesh_data<'a>(
    node: &gltf::Node<'a>,
    mesh: &gltf::Mesh<'a>,
    reading: &Reading<'_>,
) -> Result<Option<MeshData>, ExportError> {
    let get = reading.get();
    let mut data = MeshData {
        base: Vec::new(),
        triangles: Vec::new(),
        segments: Vec::new(),
        targets: Vec::new(),
        influences: None,
        unread: Vec::new(),
    };
    let mut joints: Vec<usize> = Vec::new();
    let mut weights: Vec<f64> = Vec::new();
    let mut sets = None;
    let mut any = false;
    for (k, prim) in mesh.primitives().enumerate() {
        any = true;
        let reader = prim.reader(get.clone());
        let at = u32::try_from(data.base.len()).map_err(|_| {
            ExportError::Data(format!(
                "mesh of node {} has more vertices than 32-bit indices reach",
                node.index()
            ))
        })?;
        let base = prim
            .get(&gltf::Semantic::Positions)
            .map(|a| vec3s(a, reading))
            .transpose()?
            .ok_or_else(|| {
                ExportError::Data(format!("mesh of node {} has no POSITION", node.index()))
            })?;
        let n = base.len();
        let Some(end) = u32::try_from(n).ok().and_then(|n| n.checked_add(at)) else {
            return Err(ExportError::Data(format!(
                "mesh of node {} has more vertices than 32-bit indices reach",
                node.index()
            )));
        };
        if let Some(a) = prim.indices() {
            check_accessor(&a, &[U8, U16, U32], Dimensions::Scalar, "indices", reading)?;
        }
        let indices: Vec<u32> = match (prim.indices(), reader.read_indices()) {
            // An index past the vertices is refused by the clip's check;
            // added without wrapping, it cannot pass for another vertex.
            (_, Some(i)) => i.into_u32().map(|i| i.saturating_add(at)).collect(),
            (Some(a), None) => {
                return Err(ExportError::Data(format!(
                    "mesh of node {}: accessor {} (indices) cannot be read",
                    node.index(),
                    a.index()
                )));
            }
            (None, None) => (at..end).collect(),
        };
        match prim.mode() {
            gltf::mesh::Mode::Triangles => data
                .triangles
                .extend(indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]])),
            gltf::mesh::Mode::Lines => data
                .segments
                .extend(indices.chunks_exact(2).map(|c| [c[0], c[1]])),
            gltf::mesh::Mode::LineStrip => data
                .segments
                .extend(indices.windows(2).map(|c| [c[0], c[1]])),
            // Points have no topology to read.
            gltf::mesh::Mode::Points => {}
            mode => data.unread.push(format!(
                "mesh {} of node {}: primitive {k} is drawn as {mode:?}, whose faces are not read (its vertices are)",
                mesh.index(),
                node.index()
            )),
        }
        let targets: Vec<Vec<[f32; 3]>> = prim
            .morph_targets()
            .map(|t| {
                t.positions()
                    .map(|a| vec3s(a, reading))
                    .transpose()
                    .map(Option::unwrap_or_default)
            })
            .collect::<Result<_, _>>()?;
        if k > 0 && targets.len() != data.targets.len() {
            return Err(ExportError::Data(format!(
                "mesh of node {}: its primitives have {} and {} morph targets (glTF asks for the same number)",
                node.index(),
                data.targets.len(),
                targets.len()
            )));
        }
        data.targets.resize(targets.len(), Vec::new());
        for (all, t) in data.targets.iter_mut().zip(targets) {
            // A target without positions moves nothing.
            all.resize(at as usize, [0.0; 3]);
            all.extend(t.iter().copied().chain(std::iter::repeat([0.0; 3])).take(n));
        }
        if node.skin().is_some() {
            let (set, j, w) = skin_sets(node, &prim, n, reading)?;
            if set == 0 || sets.is_some_and(|s| s != set) {
                return Err(ExportError::Data(format!(
                    "mesh of node {} has a skin but primitive {k} has {set} JOINTS/WEIGHTS sets",
                    node.index()
                )));
            }
            sets = Some(set);
            joints.extend(j.into_iter().flatten());
            weights.extend(w.into_iter().flatten());
        }
        data.base.extend(base);
    }
    if !any {
        return Ok(None);
    }
    if let (Some(sets), Some(skin)) = (sets, node.skin()) {
        data.influences = Some(
            Influences {
                per_vertex: 4 * sets as usize,
                joints,
                weights,
            }
            .normalised(data.base.len(), skin.joints().count())
            .map_err(|e| {
                ExportError::Data(format!("skin of the mesh of node {}: {e}", node.index()))
            })?,
        );
    }
    Ok(Some(data))
}

/// The motion of a mesh below other nodes, or skinned: every vertex in
/// world space per frame. A plain mesh takes its node's world transform;
/// a skinned one is moved by its joints, Σ w_j (world_j · inverseBind_j) p,
/// its own node's transform ignored as glTF says. `points_at(k)` gives the
/// mesh's own vertices at frame k (morph targets applied, in its space),
/// `worlds_at(k)` every node's world transform then.
fn composed_motion(
    node: &gltf::Node<'_>,
    frames: usize,
    worlds_at: impl Fn(usize) -> Vec<M4>,
    points_at: impl Fn(usize) -> Vec<V3>,
    influences: Option<&Influences>,
    reading: &Reading<'_>,
) -> Result<Motion, ExportError> {
    let skin = match (node.skin(), influences) {
        (Some(skin), Some(inf)) => {
            let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
            if let Some(a) = skin.inverse_bind_matrices() {
                check_accessor(
                    &a,
                    &[F32],
                    Dimensions::Mat4,
                    "inverse bind matrices",
                    reading,
                )?;
            }
            let inverse_bind: Vec<M4> =
                match skin.reader(reading.get()).read_inverse_bind_matrices() {
                    Some(m) => m
                        .map(|columns| M4::from_fn(|r, c| columns[c][r] as f64))
                        .collect(),
                    None => vec![M4::identity(); joints.len()],
                };
            if inverse_bind.len() < joints.len() {
                return Err(ExportError::Data(format!(
                    "skin {} has {} joints but {} inverse bind matrices",
                    skin.index(),
                    joints.len(),
                    inverse_bind.len()
                )));
            }
            Some((joints, inverse_bind, inf))
        }
        _ => None,
    };
    let frames = (0..frames)
        .map(|k| {
            let (world, points) = (worlds_at(k), points_at(k));
            let placed = match &skin {
                Some((joints, inverse_bind, inf)) => {
                    let matrices: Vec<M4> = joints
                        .iter()
                        .zip(inverse_bind)
                        .map(|(j, ib)| world[*j] * ib)
                        .collect();
                    skin::blend(&points, inf, &matrices)
                }
                None => points
                    .iter()
                    .map(|p| world[node.index()].transform_point(&(*p).into()).coords)
                    .collect(),
            };
            placed.into_iter().map(z_up).collect()
        })
        .collect();
    Ok(Motion::Deforming { frames })
}

/// The name of the object a mesh node makes: the node's, or where it has
/// none (gltfpack moves a mesh into an unnamed child that carries its
/// dequantisation) the nearest named node's above it, unless an object
/// already has that name; else `node-N`.
fn object_name(
    doc: &gltf::Document,
    parents: &[Option<usize>],
    node: &gltf::Node<'_>,
    objects: &[ClipObject],
) -> String {
    if let Some(name) = node.name() {
        return name.to_string();
    }
    let mut up = parents[node.index()];
    let mut hops = 0;
    while let Some(p) = up.filter(|_| hops < parents.len()) {
        if let Some(name) = doc
            .nodes()
            .nth(p)
            .and_then(|n| n.name().map(str::to_string))
        {
            if objects.iter().all(|o| o.name != name) {
                return name;
            }
            break;
        }
        up = parents[p];
        hops += 1;
    }
    format!("node-{}", node.index())
}
