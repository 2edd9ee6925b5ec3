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
use super::usd_layer::{Prim, sample, world_transform};
use super::usd_skel::{Paths, targets};
use nalgebra::{Matrix4, Quaternion, UnitQuaternion, Vector3};
use std::collections::HashMap;

type V3 = Vector3<f64>;
type M4 = Matrix4<f64>;

/// One prototype: the meshes under its root prim, each with the prims from
/// the root down to it (the root first) and its triangles.
struct Prototype<'a> {
    meshes: Vec<(Vec<&'a Prim>, Vec<[u32; 3]>)>,
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
    let check = |name: &str, v: &Option<Vec<f64>>, width: usize| -> Result<(), String> {
        match v {
            Some(v) if v.len() != width * n => Err(at(format!(
                "{} numbers in `{name}` for {n} instances (protoIndices), not {width} each",
                v.len()
            ))),
            _ => Ok(()),
        }
    };
    let (orientations, scales, ids) = (read("orientations")?, read("scales")?, read("ids")?);
    check("positions", &Some(positions.clone()), 3)?;
    check("orientations", &orientations, 4)?;
    check("scales", &scales, 3)?;
    check("ids", &ids, 1)?;
    let transform = (0..n)
        .map(|i| {
            let mut m = match &orientations {
                Some(q) => UnitQuaternion::from_quaternion(Quaternion::new(
                    q[4 * i],
                    q[4 * i + 1],
                    q[4 * i + 2],
                    q[4 * i + 3],
                ))
                .to_homogeneous(),
                None => M4::identity(),
            };
            if let Some(s) = &scales {
                for c in 0..3 {
                    for r in 0..3 {
                        m[(r, c)] *= s[3 * i + c];
                    }
                }
            }
            for r in 0..3 {
                m[(r, 3)] = positions[3 * i + r];
            }
            m
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
        let mut found = Vec::new();
        prototype_meshes(root, &mut Vec::new(), &mut found);
        let meshes = found
            .into_iter()
            .map(|c| {
                let tris = c.last().expect("a chain ends at its mesh").triangles()?;
                Ok((c, tris))
            })
            .collect::<Result<Vec<_>, String>>()?;
        prototypes.push(Prototype { meshes });
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
    let vertices: Vec<usize> = prototypes
        .iter()
        .map(|p| {
            p.meshes
                .iter()
                .map(|(c, _)| {
                    c.last()
                        .expect("a mesh")
                        .attribute("points")
                        .map_or(0, |a| a.vector_count())
                })
                .sum()
        })
        .collect();
    let total: usize = objects.iter().map(|(_, p, _)| vertices[*p]).sum();
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
        for proto in &prototypes {
            let mut points = Vec::new();
            for (mesh_chain, _) in &proto.meshes {
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
            if placed[*proto].len() != vertices[*proto] {
                return Err(at(format!(
                    "prototype {proto}: its point count changes over time"
                )));
            }
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
            let mut triangles = Vec::new();
            let mut offset = 0u32;
            for (mesh_chain, tris) in &prototypes[proto].meshes {
                triangles.extend(tris.iter().map(|t| t.map(|v| v + offset)));
                offset += mesh_chain
                    .last()
                    .expect("a mesh")
                    .attribute("points")
                    .map_or(0, |a| a.vector_count()) as u32;
            }
            ClipObject::read_mesh(format!("{}[{id}]", prim.name), triangles, frames)
        })
        .collect())
}
