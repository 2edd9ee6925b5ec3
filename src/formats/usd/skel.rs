//! Meshes skinned to a UsdSkel skeleton, posed as UsdSkel defines it
//! (Pixar, "UsdSkel: Skinning" and "Joint Transforms"): what Blender's USD
//! exporter writes for a leaf bent by an armature. For
//! [`super::read`], which finds the meshes.
//!
//! A skinned point's world position at time t is
//!
//! ```text
//! p_world = S(t) · Σ_j w_j · J_j(t) · B_j⁻¹ · G · p
//! ```
//!
//! (column vectors; USD writes its matrices for row vectors, so each is
//! read transposed): G the mesh's `primvars:skel:geomBindTransform`, B_j
//! the Skeleton's `bindTransforms` (joint j in the bind pose, skeleton
//! space), J_j(t) joint j's skeleton-space transform, its parents' composed
//! with its local one, and S(t) the Skeleton prim's world transform. A
//! joint's local transform is T·R·S from the bound SkelAnimation's
//! `translations`, `rotations` and `scales` where it animates the joint,
//! else the Skeleton's `restTransforms`. The mesh's own transform and
//! those between it and the SkelRoot take no part, as UsdSkel says.
//!
//! Read: the binding (`skel:skeleton` on the mesh or the nearest prim
//! above it, `skel:animationSource` on the Skeleton or above it),
//! `skel:joints` on the mesh (its own joint order), `jointIndices` and
//! `jointWeights` with their `elementSize`, per vertex or `constant`.
//!
//! Blend shapes ([`BlendShapes`], "UsdSkel: Blend Shapes"), which is how
//! Blender writes a shape key (a leaf that curls): before skinning,
//!
//! ```text
//! p_i += Σ_s w_s(t) · offset_s,k    for each k with pointIndices_s[k] = i
//! ```
//!
//! (every point in order where a shape has no `pointIndices`), the
//! weights w_s the bound SkelAnimation's `blendShapeWeights`, matched to
//! the mesh's `skel:blendShapes` by name (a shape the animation does not
//! name weighs 0). Refused by name: inbetween shapes.

use super::layer::{Attribute, Prim, Value, sample, world_transform};
use crate::formats::skin::{Influences, blend, trs_matrix};
use nalgebra::{Matrix4, Vector3};
use std::collections::HashMap;

type V3 = Vector3<f64>;
type M4 = Matrix4<f64>;

/// Every prim of a layer by its absolute path (`/root/rig/rig`).
pub(super) struct Paths<'a> {
    by_path: HashMap<String, &'a Prim>,
}

impl<'a> Paths<'a> {
    /// The paths of `roots` and everything below them.
    pub(super) fn new(roots: &'a [Prim]) -> Self {
        fn walk<'a>(prim: &'a Prim, parent: &str, out: &mut HashMap<String, &'a Prim>) {
            let path = format!("{parent}/{}", prim.name);
            for c in &prim.children {
                walk(c, &path, out);
            }
            out.insert(path, prim);
        }
        let mut by_path = HashMap::new();
        for r in roots {
            walk(r, "", &mut by_path);
        }
        Paths { by_path }
    }

    /// The prims from the root down to the one at `path`.
    pub(super) fn chain(&self, path: &str) -> Option<Vec<&'a Prim>> {
        let mut out = Vec::new();
        let mut at = String::new();
        for part in path.trim_start_matches('/').split('/') {
            at.push('/');
            at.push_str(part);
            out.push(*self.by_path.get(&at)?);
        }
        Some(out)
    }
}

/// The single target of relationship `name` on `prim`, if it has one.
fn target(prim: &Prim, name: &str) -> Result<Option<String>, String> {
    let Some(rel) = prim.attribute(name).filter(|a| a.type_name == "rel") else {
        return Ok(None);
    };
    let path = match &rel.default {
        Some(Value::Path(p)) => p.clone(),
        Some(Value::List(items)) if items.len() == 1 => match &items[0] {
            Value::Path(p) => p.clone(),
            v => return Err(format!("prim `{}`: `{name}` targets {v:?}", prim.name)),
        },
        _ => return Ok(None),
    };
    if !path.starts_with('/') {
        return Err(format!(
            "prim `{}`: `{name}` targets `{path}`, a relative path this reader does not resolve",
            prim.name
        ));
    }
    Ok(Some(path))
}

/// The single target of relationship `name` on the last prim of `chain`
/// that has one (the prims above inherit a binding, UsdSkel).
fn nearest_target(chain: &[&Prim], name: &str) -> Result<Option<String>, String> {
    for p in chain.iter().rev() {
        if let Some(path) = target(p, name)? {
            return Ok(Some(path));
        }
    }
    Ok(None)
}

/// Every target of relationship `name` on `prim` (none if it has none).
pub(super) fn targets(prim: &Prim, name: &str) -> Result<Vec<String>, String> {
    let Some(rel) = prim.attribute(name).filter(|a| a.type_name == "rel") else {
        return Ok(Vec::new());
    };
    let items = match &rel.default {
        Some(Value::List(items)) => items.clone(),
        Some(v) => vec![v.clone()],
        None => Vec::new(),
    };
    items
        .into_iter()
        .map(|v| match v {
            Value::Path(p) if p.starts_with('/') => Ok(p),
            v => Err(format!(
                "prim `{}`: `{name}` targets {v:?}, not an absolute path",
                prim.name
            )),
        })
        .collect()
}

/// What the mesh at the end of `chain` is bound to: the prims from the
/// root to its Skeleton (`skel:skeleton` on the mesh or the nearest prim
/// above it) and the SkelAnimation that drives it (`skel:animationSource`
/// on the Skeleton or above it), or `None` if it is bound to none.
#[allow(clippy::type_complexity)]
fn binding<'a>(
    paths: &Paths<'a>,
    chain: &[&'a Prim],
) -> Result<Option<(Vec<&'a Prim>, Option<&'a Prim>)>, String> {
    let mesh = *chain.last().expect("a chain ends at its mesh");
    let Some(skeleton_path) = nearest_target(chain, "skel:skeleton")? else {
        return Ok(None);
    };
    let skeleton = paths.chain(&skeleton_path).ok_or_else(|| {
        format!(
            "mesh `{}` is bound to the skeleton `{skeleton_path}`, which is not in the layer",
            mesh.name
        )
    })?;
    let skel = *skeleton.last().expect("a path has a prim");
    let animation = match nearest_target(&skeleton, "skel:animationSource")? {
        None => None,
        Some(path) => Some(
            paths
                .chain(&path)
                .and_then(|c| c.last().copied())
                .ok_or_else(|| {
                    format!(
                        "skeleton `{}` is animated by `{path}`, which is not in the layer",
                        skel.name
                    )
                })?,
        ),
    };
    Ok(Some((skeleton, animation)))
}

/// A uniform attribute's value (its default).
fn uniform<'p>(prim: &'p Prim, name: &str) -> Option<&'p Value> {
    prim.attribute(name).and_then(|a| a.default.as_ref())
}

/// An array of USD matrices (`matrix4d[]`, rows for row vectors) as
/// column-vector matrices.
fn matrices(prim: &Prim, name: &str) -> Result<Option<Vec<M4>>, String> {
    let Some(v) = uniform(prim, name) else {
        return Ok(None);
    };
    let n = v.numbers().filter(|n| n.len() % 16 == 0).ok_or_else(|| {
        format!(
            "prim `{}`: `{name}` is not a list of 4×4 matrices",
            prim.name
        )
    })?;
    Ok(Some(
        n.chunks(16)
            .map(|m| M4::from_row_slice(m).transpose())
            .collect(),
    ))
}

/// Joint names as written (paths such as `root/tip`, parents first).
fn joint_names(prim: &Prim, name: &str) -> Result<Option<Vec<String>>, String> {
    match uniform(prim, name) {
        None => Ok(None),
        Some(v) => v.strings().map(Some).ok_or_else(|| {
            format!(
                "prim `{}`: `{name}` is not a list of joint names",
                prim.name
            )
        }),
    }
}

/// How a skinned mesh is posed: its skeleton, its animation and its
/// vertices' joints, resolved once.
pub(super) struct Skinning<'a> {
    /// The prims from the root to the Skeleton, whose transforms give S(t).
    skeleton: Vec<&'a Prim>,
    /// Each joint's parent joint.
    parent: Vec<Option<usize>>,
    /// B_j⁻¹ per joint.
    bind_inverse: Vec<M4>,
    /// Each joint's local transform where no animation moves it.
    rest: Vec<M4>,
    /// The SkelAnimation and, for each of its joints, the skeleton's.
    animation: Option<(&'a Prim, Vec<Option<usize>>)>,
    /// G.
    geom_bind: M4,
    /// The mesh's vertices' joints (the skeleton's order) and weights.
    influences: Influences,
}

impl<'a> Skinning<'a> {
    /// The skinning of the mesh at the end of `chain` (the prims above it
    /// first), or `None` if it is not bound to a skeleton.
    pub(super) fn of(paths: &Paths<'a>, chain: &[&'a Prim]) -> Result<Option<Self>, String> {
        let mesh = *chain.last().expect("a chain ends at its mesh");
        if mesh.attribute("primvars:skel:jointIndices").is_none() {
            return Ok(None);
        }
        let Some((skeleton, anim)) = binding(paths, chain)? else {
            // Joint influences without a skeleton deform nothing (UsdSkel).
            return Ok(None);
        };
        let skel = *skeleton.last().expect("a path has a prim");
        let joints = joint_names(skel, "joints")?
            .ok_or_else(|| format!("skeleton `{}` has no `joints`", skel.name))?;
        let n = joints.len();
        let index: HashMap<&str, usize> = joints
            .iter()
            .enumerate()
            .map(|(i, j)| (j.as_str(), i))
            .collect();
        let parent = (0..n).map(|j| parent_of(&joints, &index, j)).collect();
        let count = |what: &str, m: &Vec<M4>| {
            if m.len() == n {
                Ok(())
            } else {
                Err(format!(
                    "skeleton `{}` has {n} joints but {} {what}",
                    skel.name,
                    m.len()
                ))
            }
        };
        let bind = matrices(skel, "bindTransforms")?
            .ok_or_else(|| format!("skeleton `{}` has no `bindTransforms`", skel.name))?;
        count("bindTransforms", &bind)?;
        let bind_inverse = bind
            .iter()
            .enumerate()
            .map(|(j, b)| {
                b.try_inverse().ok_or_else(|| {
                    format!(
                        "skeleton `{}`: the bind transform of joint `{}` cannot be inverted",
                        skel.name, joints[j]
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        // Without rest transforms a joint no animation moves stays at its
        // bind pose: its local transform is its bind relative to its
        // parent's.
        let rest = match matrices(skel, "restTransforms")? {
            Some(rest) => {
                count("restTransforms", &rest)?;
                rest
            }
            None => (0..n)
                .map(|j| match parent_of(&joints, &index, j) {
                    Some(p) => bind_inverse[p] * bind[j],
                    None => bind[j],
                })
                .collect(),
        };
        // An animation that names no joints moves none (Blender writes
        // one for blend-shape weights alone).
        let animation = match anim {
            None => None,
            Some(anim) => {
                let map = joint_names(anim, "joints")?
                    .unwrap_or_default()
                    .iter()
                    .map(|j| index.get(j.as_str()).copied())
                    .collect();
                Some((anim, map))
            }
        };
        let geom_bind =
            matrices(mesh, "primvars:skel:geomBindTransform")?.map_or(Ok(M4::identity()), |m| {
                m.first().copied().filter(|_| m.len() == 1).ok_or_else(|| {
                    format!("mesh `{}`: geomBindTransform is not one matrix", mesh.name)
                })
            })?;
        let influences = influences(mesh, &joints, &index)?;
        Ok(Some(Skinning {
            skeleton,
            parent,
            bind_inverse,
            rest,
            animation,
            geom_bind,
            influences,
        }))
    }

    /// How many vertices the influences are for.
    pub(super) fn vertices(&self) -> usize {
        self.influences.joints.len() / self.influences.per_vertex
    }

    /// The mesh's `points` (its own space) skinned at time code `t`, in
    /// the layer's world space and units.
    pub(super) fn pose(&self, points: &[V3], t: f64) -> Result<Vec<V3>, String> {
        let mut local = self.rest.clone();
        if let Some((anim, map)) = self.animation.as_ref().filter(|(_, map)| !map.is_empty()) {
            // This reader poses a joint from all three channels, as
            // exporters write them; a missing one is named.
            let channel = |name: &str, width: usize| -> Result<Vec<f64>, String> {
                let a = anim
                    .attribute(name)
                    .ok_or_else(|| format!("animation `{}` has no `{name}`", anim.name))?;
                sample(a, t).filter(|v| v.len() == width * map.len()).ok_or_else(|| {
                    format!(
                        "animation `{}`: `{name}` does not hold {width} numbers for each of its {} joints",
                        anim.name,
                        map.len()
                    )
                })
            };
            let (tr, rot, sc) = (
                channel("translations", 3)?,
                channel("rotations", 4)?,
                channel("scales", 3)?,
            );
            for (k, j) in map.iter().enumerate() {
                let Some(j) = *j else { continue };
                let q = [rot[4 * k], rot[4 * k + 1], rot[4 * k + 2], rot[4 * k + 3]];
                local[j] = trs_matrix(&tr[3 * k..3 * k + 3], q, &sc[3 * k..3 * k + 3]);
            }
        }
        // Skeleton space, parents before children (UsdSkel orders joints
        // so; a parent written later is composed on its own first).
        let mut skel_space: Vec<Option<M4>> = vec![None; local.len()];
        for j in 0..local.len() {
            let mut m = local[j];
            let mut up = self.parent[j];
            while let Some(p) = up {
                if let Some(pm) = skel_space[p] {
                    m = pm * m;
                    break;
                }
                m = local[p] * m;
                up = self.parent[p];
            }
            skel_space[j] = Some(m);
        }
        let world = world_transform(&self.skeleton, t)?;
        let skinning: Vec<M4> = skel_space
            .iter()
            .zip(&self.bind_inverse)
            .map(|(j, b)| world * j.expect("every joint composed") * b * self.geom_bind)
            .collect();
        Ok(blend(points, &self.influences, &skinning))
    }
}

/// A mesh's UsdSkel blend shapes (module docs): each shape's offsets by
/// point, and the animation that weighs them.
pub(super) struct BlendShapes<'a> {
    /// The mesh's name, for errors.
    mesh: String,
    /// Each shape's (point index, offset).
    shapes: Vec<Vec<(usize, V3)>>,
    /// The SkelAnimation and, for each shape, its index among the
    /// animation's `blendShapes`; `None` without one (every weight 0).
    weights: Option<(&'a Prim, Vec<Option<usize>>)>,
}

impl<'a> BlendShapes<'a> {
    /// The blend shapes of the mesh at the end of `chain`, or `None` if it
    /// has none.
    pub(super) fn of(paths: &Paths<'a>, chain: &[&'a Prim]) -> Result<Option<Self>, String> {
        let mesh = *chain.last().expect("a chain ends at its mesh");
        let Some(names) = joint_names(mesh, "skel:blendShapes")? else {
            return Ok(None);
        };
        let at = |e: String| format!("mesh `{}`: {e}", mesh.name);
        let found = targets(mesh, "skel:blendShapeTargets")?;
        if found.len() != names.len() {
            return Err(at(format!(
                "{} skel:blendShapes but {} skel:blendShapeTargets",
                names.len(),
                found.len()
            )));
        }
        let points = mesh.attribute("points").map_or(0, Attribute::vector_count);
        let mut shapes = Vec::with_capacity(names.len());
        for (name, path) in names.iter().zip(&found) {
            let shape = paths
                .chain(path)
                .and_then(|c| c.last().copied())
                .ok_or_else(|| {
                    at(format!(
                        "blend shape `{name}` is `{path}`, which is not in the layer"
                    ))
                })?;
            if let Some((inbetween, _)) = shape
                .attributes
                .iter()
                .find(|(n, _)| n.starts_with("inbetweens:"))
            {
                return Err(at(format!(
                    "blend shape `{name}` has the inbetween shape `{inbetween}`, which this reader does not apply"
                )));
            }
            let offsets = uniform(shape, "offsets")
                .and_then(Value::numbers)
                .filter(|o| o.len() % 3 == 0)
                .ok_or_else(|| {
                    at(format!(
                        "blend shape `{name}` has no `offsets` of 3-vectors"
                    ))
                })?;
            let offsets: Vec<V3> = offsets
                .chunks(3)
                .map(|c| V3::new(c[0], c[1], c[2]))
                .collect();
            let indices: Vec<usize> = match uniform(shape, "pointIndices") {
                None => (0..offsets.len()).collect(),
                Some(v) => v
                    .numbers()
                    .ok_or_else(|| {
                        at(format!(
                            "blend shape `{name}`: `pointIndices` are not numbers"
                        ))
                    })?
                    .into_iter()
                    .map(|x| x as usize)
                    .collect(),
            };
            if indices.len() != offsets.len() || indices.iter().any(|&i| i >= points) {
                return Err(at(format!(
                    "blend shape `{name}`: {} offsets for {} point indices, of {points} points",
                    offsets.len(),
                    indices.len()
                )));
            }
            shapes.push(indices.into_iter().zip(offsets).collect());
        }
        let weights = match binding(paths, chain)? {
            Some((_, Some(anim))) => {
                let order = joint_names(anim, "blendShapes")?.unwrap_or_default();
                let map = names
                    .iter()
                    .map(|n| order.iter().position(|o| o == n))
                    .collect();
                Some((anim, map))
            }
            _ => None,
        };
        Ok(Some(BlendShapes {
            mesh: mesh.name.clone(),
            shapes,
            weights,
        }))
    }

    /// Adds each shape's offsets, times its weight at time code `t`, to
    /// `points` (the mesh's own, before skinning).
    pub(super) fn apply(&self, points: &mut [V3], t: f64) -> Result<(), String> {
        let Some((anim, map)) = &self.weights else {
            return Ok(());
        };
        let names = map.iter().flatten().count();
        if names == 0 {
            return Ok(());
        }
        let w = anim
            .attribute("blendShapeWeights")
            .and_then(|a| sample(a, t))
            .ok_or_else(|| {
                format!(
                    "animation `{}` weighs blend shapes but has no `blendShapeWeights`",
                    anim.name
                )
            })?;
        for (shape, k) in self.shapes.iter().zip(map) {
            let Some(&weight) = k.and_then(|k| w.get(k)) else {
                if k.is_some() {
                    return Err(format!(
                        "animation `{}`: `blendShapeWeights` holds {} weights, fewer than its `blendShapes`",
                        anim.name,
                        w.len()
                    ));
                }
                continue;
            };
            for &(i, offset) in shape {
                let p = points.get_mut(i).ok_or_else(|| {
                    format!(
                        "mesh `{}`: a blend shape moves point {i}, past its points",
                        self.mesh
                    )
                })?;
                *p += offset * weight;
            }
        }
        Ok(())
    }
}

/// Joint `j`'s parent, from its path.
fn parent_of(joints: &[String], index: &HashMap<&str, usize>, j: usize) -> Option<usize> {
    joints[j]
        .rsplit_once('/')
        .and_then(|(up, _)| index.get(up).copied())
}

/// A primvar's `elementSize` (1 when unset) and whether it is `constant`
/// (one set of values for every vertex).
fn layout(a: &Attribute) -> (usize, bool) {
    let size = match a.meta("elementSize") {
        Some(Value::Number(n)) if *n >= 1.0 => *n as usize,
        _ => 1,
    };
    let constant = matches!(a.meta("interpolation"), Some(Value::Str(s)) if s == "constant");
    (size, constant)
}

/// The mesh's joint influences, as indices into the skeleton's joints.
fn influences(
    mesh: &Prim,
    joints: &[String],
    index: &HashMap<&str, usize>,
) -> Result<Influences, String> {
    let read = |name: &str| -> Result<(Vec<f64>, usize, bool), String> {
        let a = mesh
            .attribute(name)
            .ok_or_else(|| format!("mesh `{}` has jointIndices but no `{name}`", mesh.name))?;
        let v =
            a.default.as_ref().and_then(Value::numbers).ok_or_else(|| {
                format!("mesh `{}`: `{name}` is not a list of numbers", mesh.name)
            })?;
        let (size, constant) = layout(a);
        Ok((v, size, constant))
    };
    let (ji, size, constant) = read("primvars:skel:jointIndices")?;
    let (jw, wsize, wconstant) = read("primvars:skel:jointWeights")?;
    if (size, constant) != (wsize, wconstant) || ji.len() != jw.len() {
        return Err(format!(
            "mesh `{}`: jointIndices and jointWeights differ in length or layout",
            mesh.name
        ));
    }
    // The mesh's own joint order, if it has one, maps to the skeleton's.
    let own = joint_names(mesh, "skel:joints")?
        .map(|names| {
            names
                .iter()
                .map(|n| {
                    index.get(n.as_str()).copied().ok_or_else(|| {
                        format!(
                            "mesh `{}` names joint `{n}`, which its skeleton lacks",
                            mesh.name
                        )
                    })
                })
                .collect::<Result<Vec<usize>, String>>()
        })
        .transpose()?;
    let joint = |x: f64| -> Result<usize, String> {
        let i = x as usize;
        match &own {
            Some(own) => own.get(i).copied().ok_or_else(|| {
                format!(
                    "mesh `{}`: joint index {i} is past its `skel:joints`",
                    mesh.name
                )
            }),
            None => Ok(i),
        }
    };
    let points = mesh.attribute("points").map_or(0, Attribute::vector_count);
    let repeat = if constant { points } else { 1 };
    let joints_of = ji
        .iter()
        .map(|x| joint(*x))
        .collect::<Result<Vec<usize>, String>>()?;
    Influences {
        per_vertex: size,
        joints: joints_of.repeat(repeat),
        weights: jw.repeat(repeat),
    }
    .normalised(points, joints.len())
    .map_err(|e| format!("mesh `{}`: {e}", mesh.name))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::usd::layer::parse;

    /// Two shapes of a four-point mesh weighed by an animation that names
    /// them in its own order (and one more), a third shape it does not name.
    const SHAPED: &str = r#"#usda 1.0
def SkelRoot "leaf"
{
    def Mesh "m"
    {
        point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
        uniform token[] skel:blendShapes = ["lift", "slide", "ghost"]
        rel skel:blendShapeTargets = [</leaf/m/lift>, </leaf/m/slide>, </leaf/m/ghost>]
        rel skel:skeleton = </leaf/skel>

        def BlendShape "lift"
        {
            uniform vector3f[] offsets = [(0, 0, 1), (0, 0, 2)]
            uniform int[] pointIndices = [1, 3]
        }
        def BlendShape "slide"
        {
            uniform vector3f[] offsets = [(1, 0, 0), (1, 0, 0), (1, 0, 0), (2, 0, 0)]
        }
        def BlendShape "ghost"
        {
            uniform vector3f[] offsets = [(100, 0, 0), (100, 0, 0), (100, 0, 0), (100, 0, 0)]
        }
    }
    def Skeleton "skel"
    {
        rel skel:animationSource = </leaf/skel/anim>
        def SkelAnimation "anim"
        {
            uniform token[] blendShapes = ["slide", "other", "lift"]
            float[] blendShapeWeights.timeSamples = {
                0: [0, 9, 0.5],
                10: [1, 9, 1],
            }
        }
    }
}
"#;

    #[test]
    fn blend_shapes_add_their_weighted_offsets_by_name() {
        let layer = parse(SHAPED).unwrap();
        let paths = Paths::new(&layer.roots);
        let (root, mesh) = (&layer.roots[0], &layer.roots[0].children[0]);
        let shapes = BlendShapes::of(&paths, &[root, mesh]).unwrap().unwrap();
        let rest = [
            V3::new(0.0, 0.0, 0.0),
            V3::new(1.0, 0.0, 0.0),
            V3::new(1.0, 1.0, 0.0),
            V3::new(0.0, 1.0, 0.0),
        ];
        // Time code 5: slide weighs 0.5, lift 0.75 (linear between
        // samples); ghost, which the animation does not name, 0.
        let mut p = rest;
        shapes.apply(&mut p, 5.0).unwrap();
        let (slide, lift) = (0.5, 0.75);
        let want = [
            rest[0] + V3::new(1.0, 0.0, 0.0) * slide,
            rest[1] + V3::new(1.0, 0.0, 0.0) * slide + V3::new(0.0, 0.0, 1.0) * lift,
            rest[2] + V3::new(1.0, 0.0, 0.0) * slide,
            rest[3] + V3::new(2.0, 0.0, 0.0) * slide + V3::new(0.0, 0.0, 2.0) * lift,
        ];
        for (g, w) in p.iter().zip(&want) {
            assert!((g - w).norm() < 1e-12, "{g} against {w}");
        }
        // A mesh with no animation bound weighs every shape 0.
        let unbound = SHAPED.replace("rel skel:skeleton = </leaf/skel>", "");
        let layer = parse(&unbound).unwrap();
        let paths = Paths::new(&layer.roots);
        let (root, mesh) = (&layer.roots[0], &layer.roots[0].children[0]);
        let shapes = BlendShapes::of(&paths, &[root, mesh]).unwrap().unwrap();
        let mut p = rest;
        shapes.apply(&mut p, 5.0).unwrap();
        assert_eq!(p, rest);
    }

    #[test]
    fn blend_shapes_that_do_not_fit_the_mesh_are_named() {
        for (from, to, want) in [
            (
                "uniform int[] pointIndices = [1, 3]",
                "uniform int[] pointIndices = [1, 4]",
                "blend shape `lift`: 2 offsets for 2 point indices, of 4 points",
            ),
            (
                "</leaf/m/slide>, ",
                "",
                "3 skel:blendShapes but 2 skel:blendShapeTargets",
            ),
            (
                "</leaf/m/ghost>]",
                "</leaf/m/gone>]",
                "blend shape `ghost` is `/leaf/m/gone`, which is not in the layer",
            ),
        ] {
            let text = SHAPED.replace(from, to);
            let layer = parse(&text).unwrap();
            let paths = Paths::new(&layer.roots);
            let (root, mesh) = (&layer.roots[0], &layer.roots[0].children[0]);
            let e = BlendShapes::of(&paths, &[root, mesh]).err().unwrap();
            assert!(e.contains(want), "{e}");
        }
    }
}
