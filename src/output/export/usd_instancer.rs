//! Leaves scattered by a UsdGeom PointInstancer: what a particle or
//! crowd simulation (Houdini's, a geometry-nodes scatter) writes for many
//! falling leaves, one prototype mesh placed per instance and per time
//! sample. For [`super::usda_read`], which finds the instancers.
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
//! its index; instances are matched across time samples by those ids, and
//! an instance missing at any sampled time (born or dead during the clip)
//! is left out. Velocities, which only motion-blur between samples, are
//! not read; `inactiveIds` and `invisibleIds` are not either.

use super::clip::ClipObject;
use super::read::check_points;
use super::skin::trs_matrix;
use super::usd_layer::{Prim, sample, world_transform};
use super::usd_skel::{Paths, targets};
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
}

/// The instancer `prim`'s instances at time code `t`.
fn instances_at(prim: &Prim, t: f64) -> Result<Instances, String> {
    let at = |e: String| format!("PointInstancer `{}`: {e}", prim.name);
    let read = |name: &str| -> Result<Option<Vec<f64>>, String> {
        match prim.attribute(name) {
            None => Ok(None),
            Some(a) => sample(a, t)
                .map(Some)
                .ok_or_else(|| at(format!("`{name}` is not numbers"))),
        }
    };
    let positions = read("positions")?.ok_or_else(|| at("no `positions`".to_string()))?;
    let proto = read("protoIndices")?.ok_or_else(|| at("no `protoIndices`".to_string()))?;
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
    let (orientations, scales, ids) = (read("orientations")?, read("scales")?, read("ids")?);
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
    Ok(Instances {
        ids: ids.map_or_else(
            || (0..n as i64).collect(),
            |v| v.iter().map(|&x| x as i64).collect(),
        ),
        proto: proto.iter().map(|&x| x as usize).collect(),
        transform,
    })
}

/// The objects the PointInstancer at the end of `chain` places, one per
/// instance present at every time code of `times`, each vertex in world
/// metres z up (`to_z_up` of the layer's units and axes).
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
    let Some(&first) = times.first() else {
        return Ok(Vec::new());
    };
    let start = instances_at(prim, first)?;
    // Each instance of the first time code, by id: its prototype and, per
    // frame, its vertices (the prototype's meshes one after another).
    let mut objects: Vec<(i64, usize, Vec<Vec<V3>>)> = Vec::new();
    for (&id, &p) in start.ids.iter().zip(&start.proto) {
        if p >= prototypes.len() {
            return Err(at(format!(
                "instance {id} uses prototype {p}, of {}",
                prototypes.len()
            )));
        }
        objects.push((id, p, Vec::with_capacity(times.len())));
    }
    let total: usize = objects
        .iter()
        .map(|(_, p, _)| prototypes[*p].vertices)
        .sum();
    check_points(&prim.name, times.len(), total)?;
    let mut present = vec![true; objects.len()];
    for &t in times {
        let now = if t == first {
            None
        } else {
            Some(instances_at(prim, t)?)
        };
        let now = now.as_ref().unwrap_or(&start);
        let index: HashMap<i64, usize> =
            now.ids.iter().enumerate().map(|(k, &id)| (id, k)).collect();
        let world = world_transform(chain, t)?;
        // Each prototype mesh placed in its prototype's frame, once per
        // time code: (prototype, its vertices there).
        let mut placed: Vec<Vec<V3>> = Vec::with_capacity(prototypes.len());
        for (k, proto) in prototypes.iter().enumerate() {
            let mut points = Vec::with_capacity(proto.vertices);
            for mesh_chain in &proto.meshes {
                let mesh = *mesh_chain.last().expect("a mesh");
                let p = sample(mesh.attribute("points").expect("found by its points"), t)
                    .filter(|p| p.len() % 3 == 0)
                    .ok_or_else(|| {
                        at(format!(
                            "prototype mesh `{}`: points are not 3-vectors",
                            mesh.name
                        ))
                    })?;
                let local = world_transform(mesh_chain, t)?;
                points.extend(p.chunks(3).map(|c| {
                    local
                        .transform_point(&V3::new(c[0], c[1], c[2]).into())
                        .coords
                }));
            }
            if points.len() != proto.vertices {
                return Err(at(format!(
                    "prototype {k}: its point count changes over time"
                )));
            }
            placed.push(points);
        }
        for (k, (id, proto, frames)) in objects.iter_mut().enumerate() {
            let Some(&i) = index.get(id).filter(|&&i| now.proto[i] == *proto) else {
                present[k] = false;
                continue;
            };
            if !present[k] {
                continue;
            }
            let m = world * now.transform[i];
            frames.push(
                placed[*proto]
                    .iter()
                    .map(|p| to_z_up(m.transform_point(&(*p).into()).coords))
                    .collect(),
            );
        }
    }
    Ok(objects
        .into_iter()
        .zip(present)
        .filter(|(_, kept)| *kept)
        .map(|((id, proto, frames), _)| {
            let triangles = prototypes[proto].triangles.clone();
            ClipObject::read_mesh(format!("{}[{id}]", prim.name), triangles, frames)
        })
        .collect())
}
