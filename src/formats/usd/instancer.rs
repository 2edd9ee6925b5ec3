//! Leaves scattered by a UsdGeom PointInstancer: what a particle or
//! crowd simulation (Houdini's, a geometry-nodes scatter) writes for many
//! falling leaves, one prototype mesh placed per instance and per time
//! sample. For [`super::read`], which finds the instancers.
//!
//! Instance i of prototype `protoIndices[i]` is placed, per UsdGeom
//! ("PointInstancer"; Pixar's `ComputeInstanceTransformsAtTime` with the
//! prototype's own transform included), as
//!
//! ```text
//! p_world = W(t) · T(positions_i) · R(orientations_i) · S(scales_i) · P · p
//! ```
//!
//! (column vectors): W the instancer's world transform, P the transforms
//! from the prototype's root prim down to the mesh (the root's own
//! included), p the mesh's points. `orientations` and `scales` are
//! optional (identity). Each instance becomes an object named
//! `INSTANCER[ID]`, its id from `ids` where the instancer has them, else
//! its index; instances are matched across time samples by those ids.
//! Each is read over its own life, as a particle simulation emits and
//! kills its leaves: from the first sampled time it is shown to the last
//! before it is gone, hidden or given another prototype
//! ([`ClipObject::first_frame`] says where it starts). Shown is what
//! Pixar's `ComputeMaskAtTime` shows: not deactivated (`inactiveIds`,
//! list-edited prim metadata) nor hidden at that time (`invisibleIds`).
//! An id that comes back after its life ended is not read again (a
//! particle's id is not reused). Velocities, which only motion-blur
//! between samples, are not read.

use super::layer::{Attribute, Prim, held, sample, world_transform};
use super::skel::{Paths, targets};
use crate::formats::clip::ClipObject;
use crate::formats::sampling::check_points;
use crate::formats::skin::trs_matrix;
use nalgebra::{Matrix4, Vector3};
use std::collections::HashMap;

type V3 = Vector3<f64>;
type M4 = Matrix4<f64>;

/// One prototype: the meshes under its root prim, as one object.
struct Prototype<'a> {
    /// Each mesh with the prims from the root down to it (the root first).
    meshes: Vec<Vec<&'a Prim>>,
    /// Their triangles, the meshes' vertices numbered one after another.
    triangles: Vec<[u32; 3]>,
    /// Their vertices, all meshes'.
    vertices: usize,
}

/// Every Mesh with points at or under `prim`, with the prims from `prim`
/// down to it.
fn prototype_meshes<'a>(prim: &'a Prim, chain: &mut Vec<&'a Prim>, out: &mut Vec<Vec<&'a Prim>>) {
    chain.push(prim);
    if prim.type_name == "Mesh" && prim.attribute("points").is_some() {
        out.push(chain.clone());
    }
    for c in &prim.children {
        prototype_meshes(c, chain, out);
    }
    chain.pop();
}

/// The instancer's per-instance arrays at time code `t`.
struct Instances {
    ids: Vec<i64>,
    proto: Vec<usize>,
    transform: Vec<M4>,
    /// Whether each is shown: neither deactivated (`inactiveIds`) nor
    /// hidden at `t` (`invisibleIds`), Pixar's `ComputeMaskAtTime`.
    shown: Vec<bool>,
}

/// The instancer `prim`'s instances at time code `t`.
fn instances_at(prim: &Prim, t: f64) -> Result<Instances, String> {
    let at = |e: String| format!("PointInstancer `{}`: {e}", prim.name);
    let read = |name: &str,
                how: fn(&Attribute, f64) -> Option<Vec<f64>>|
     -> Result<Option<Vec<f64>>, String> {
        match prim.attribute(name) {
            None => Ok(None),
            Some(a) => how(a, t)
                .map(Some)
                .ok_or_else(|| at(format!("`{name}` is not numbers"))),
        }
    };
    let positions = read("positions", sample)?.ok_or_else(|| at("no `positions`".to_string()))?;
    // Integers are held, not interpolated, between samples (USD).
    let proto = read("protoIndices", held)?.ok_or_else(|| at("no `protoIndices`".to_string()))?;
    let n = proto.len();
    let check = |name: &str, v: Option<&Vec<f64>>, width: usize| -> Result<(), String> {
        match v {
            Some(v) if v.len() != width * n => Err(at(format!(
                "{} numbers in `{name}` for {n} instances (protoIndices), not {width} each",
                v.len()
            ))),
            _ => Ok(()),
        }
    };
    let (orientations, scales, ids) = (
        read("orientations", sample)?,
        read("scales", sample)?,
        read("ids", held)?,
    );
    check("positions", Some(&positions), 3)?;
    check("orientations", orientations.as_ref(), 4)?;
    check("scales", scales.as_ref(), 3)?;
    check("ids", ids.as_ref(), 1)?;
    let transform = (0..n)
        .map(|i| {
            let q = orientations.as_ref().map_or([1.0, 0.0, 0.0, 0.0], |q| {
                [q[4 * i], q[4 * i + 1], q[4 * i + 2], q[4 * i + 3]]
            });
            let s = scales
                .as_ref()
                .map_or(&[1.0; 3][..], |s| &s[3 * i..3 * i + 3]);
            trs_matrix(&positions[3 * i..3 * i + 3], q, s)
        })
        .collect();
    let ids: Vec<i64> = ids.map_or_else(
        || (0..n as i64).collect(),
        |v| v.iter().map(|&x| x as i64).collect(),
    );
    // Sorted, as `inactive_ids` is: a particle cache hides thousands.
    let mut hidden: Vec<i64> = read("invisibleIds", held)?
        .unwrap_or_default()
        .iter()
        .map(|&x| x as i64)
        .collect();
    hidden.sort_unstable();
    let shown = ids
        .iter()
        .map(|id| prim.inactive_ids.binary_search(id).is_err() && hidden.binary_search(id).is_err())
        .collect();
    Ok(Instances {
        ids,
        proto: proto.iter().map(|&x| x as usize).collect(),
        transform,
        shown,
    })
}

/// One instance's life over the sampled time codes: its id and
/// prototype, the index of the time code it first appears at, its
/// vertices at each time code from there on while it lasts, and whether
/// it has ended (gone, hidden, or placed with another prototype).
struct Life {
    id: i64,
    proto: usize,
    first: usize,
    frames: Vec<Vec<V3>>,
    ended: bool,
}

/// The objects the PointInstancer at the end of `chain` places, one per
/// instance over its life among the time codes `times` ([`Life`]; its
/// first one is the object's [`ClipObject::first_frame`]), each vertex in
/// world metres z up (`to_z_up` of the layer's units and axes).
pub(super) fn instanced(
    paths: &Paths<'_>,
    chain: &[&Prim],
    times: &[f64],
    to_z_up: &dyn Fn(V3) -> V3,
) -> Result<Vec<ClipObject>, String> {
    let prim = *chain.last().expect("a chain ends at its instancer");
    let at = |e: String| format!("PointInstancer `{}`: {e}", prim.name);
    let mut prototypes = Vec::new();
    for path in targets(prim, "prototypes")? {
        let root = paths
            .chain(&path)
            .and_then(|c| c.last().copied())
            .ok_or_else(|| at(format!("its prototype `{path}` is not in the layer")))?;
        let mut meshes = Vec::new();
        prototype_meshes(root, &mut Vec::new(), &mut meshes);
        let (mut triangles, mut vertices) = (Vec::new(), 0);
        for chain in &meshes {
            let mesh = *chain.last().expect("a chain ends at its mesh");
            let offset = vertices as u32;
            triangles.extend(mesh.triangles()?.iter().map(|t| t.map(|v| v + offset)));
            vertices += mesh.attribute("points").map_or(0, |a| a.vector_count());
        }
        prototypes.push(Prototype {
            meshes,
            triangles,
            vertices,
        });
    }
    let mut lives: Vec<Life> = Vec::new();
    let mut by_id: HashMap<i64, usize> = HashMap::new();
    let mut held_vertices = 0usize;
    for (k, &t) in times.iter().enumerate() {
        let now = instances_at(prim, t)?;
        let world = world_transform(chain, t)?;
        // Each prototype mesh placed in its prototype's frame, once per
        // time code: (prototype, its vertices there).
        let mut placed: Vec<Vec<V3>> = Vec::with_capacity(prototypes.len());
        for (p, proto) in prototypes.iter().enumerate() {
            let mut points = Vec::with_capacity(proto.vertices);
            for mesh_chain in &proto.meshes {
                let mesh = *mesh_chain.last().expect("a mesh");
                let v = sample(mesh.attribute("points").expect("found by its points"), t)
                    .filter(|v| v.len() % 3 == 0)
                    .ok_or_else(|| {
                        at(format!(
                            "prototype mesh `{}`: points are not 3-vectors",
                            mesh.name
                        ))
                    })?;
                let local = world_transform(mesh_chain, t)?;
                points.extend(v.chunks(3).map(|c| {
                    local
                        .transform_point(&V3::new(c[0], c[1], c[2]).into())
                        .coords
                }));
            }
            if points.len() != proto.vertices {
                return Err(at(format!(
                    "prototype {p}: its point count changes over time"
                )));
            }
            placed.push(points);
        }
        let mut seen = vec![false; lives.len()];
        for i in 0..now.ids.len() {
            let (id, p) = (now.ids[i], now.proto[i]);
            if p >= prototypes.len() {
                return Err(at(format!(
                    "instance {id} uses prototype {p}, of {}",
                    prototypes.len()
                )));
            }
            if !now.shown[i] {
                continue;
            }
            let l = match by_id.get(&id) {
                Some(&l) => {
                    if seen[l] {
                        return Err(at(format!(
                            "id {id} is given to two instances at time code {t}"
                        )));
                    }
                    seen[l] = true;
                    if lives[l].proto != p {
                        lives[l].ended = true;
                    }
                    l
                }
                None => {
                    held_vertices += prototypes[p].vertices;
                    check_points(&prim.name, times.len(), held_vertices)?;
                    by_id.insert(id, lives.len());
                    seen.push(true);
                    lives.push(Life {
                        id,
                        proto: p,
                        first: k,
                        frames: Vec::new(),
                        ended: false,
                    });
                    lives.len() - 1
                }
            };
            let life = &mut lives[l];
            if life.ended {
                continue;
            }
            let m = world * now.transform[i];
            life.frames.push(
                placed[p]
                    .iter()
                    .map(|v| to_z_up(m.transform_point(&(*v).into()).coords))
                    .collect(),
            );
        }
        // Gone (or hidden) at this time code: its life is over.
        for (life, seen) in lives.iter_mut().zip(seen) {
            life.ended |= !seen;
        }
    }
    Ok(lives
        .into_iter()
        .map(|life| {
            let triangles = prototypes[life.proto].triangles.clone();
            let mut o = ClipObject::read_mesh(
                format!("{}[{}]", prim.name, life.id),
                triangles,
                life.frames,
            );
            o.first_frame = life.first;
            o
        })
        .collect())
}
