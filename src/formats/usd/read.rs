//! Animated meshes read from USD (a text layer, `.usda`, or through
//! [`super::stage`] a crate file, a package or a composed stage): what leafmagic's
//! own USD export writes ([`super::write`]) and what Blender's USD exporter
//! writes for an animated object, as a [`Clip`] whose objects deform (every
//! vertex in world metres, z up, per key), for [`crate::formats::fall`].
//!
//! Each `Mesh`'s `points`, `faceVertexCounts` and `faceVertexIndices` are
//! read, placed by the transforms of the prims above it, or, if the mesh
//! is skinned, by its UsdSkel skeleton ([`super::skel`]). The layer's
//! grammar, and what it refuses, are [`super::layer`]'s.

use super::instancer::instanced;
use super::layer::{
    Layer, MAX_NESTING, Prim, Value, check_text_nesting, composes, parse, sample, stored_binary,
    world_transform,
};
use super::skel::{BlendShapes, Paths, Skinning};
use super::stage::flatten;
use crate::formats::clip::{Clip, ClipObject};
use crate::formats::error::ExportError;
use crate::formats::sampling::{check_points, key_rate, sampled_frames};
use crate::util::confined::ReadScope;
use nalgebra::Vector3;
use std::path::Path;

type V3 = Vector3<f64>;

/// Every time code at which something of `prim` or below it is sampled.
fn sample_times(prim: &Prim, out: &mut Vec<f64>) {
    for (_, a) in &prim.attributes {
        out.extend(a.samples.iter().map(|(t, _)| *t));
    }
    for c in &prim.children {
        sample_times(c, out);
    }
}

/// Meshes under `prim` with the chain of prims above each (outermost first),
/// and likewise the PointInstancers; a PointInstancer's own prototypes are
/// drawn only through it (UsdGeom), so nothing below one is a mesh of its
/// own.
fn meshes<'a>(
    prim: &'a Prim,
    chain: &mut Vec<&'a Prim>,
    out: &mut Vec<Vec<&'a Prim>>,
    instancers: &mut Vec<Vec<&'a Prim>>,
) {
    chain.push(prim);
    if prim.type_name == "PointInstancer" {
        instancers.push(chain.clone());
        chain.pop();
        return;
    }
    if prim.type_name == "Mesh" && prim.attribute("points").is_some() {
        out.push(chain.clone());
    }
    for c in &prim.children {
        meshes(c, chain, out, instancers);
    }
    chain.pop();
}

/// The clip of a USD text layer's meshes (see the module doc), sampled at
/// its keys: from the first time sample to the last, one frame per
/// shortest interval between samples.
pub fn read_usda_keys(text: &str, name: &str) -> Result<Clip, ExportError> {
    read(text, name).map_err(ExportError::Data)
}

/// The clip of the USD file at `path` (its bytes `bytes`), as
/// [`read_usda_keys`] reads a text layer: one the text reader reads alone
/// is read so; a binary crate file, a USDZ package or a layer that needs
/// composing is composed and flattened first ([`super::stage`]).
pub fn read_usd_file(
    path: &Path,
    bytes: &[u8],
    name: &str,
    scope: &ReadScope,
) -> Result<Clip, ExportError> {
    let alone = if stored_binary(bytes).is_some() {
        None
    } else {
        let text = String::from_utf8_lossy(bytes);
        match parse(&text) {
            Ok(layer) => Some(layer),
            // The composing reader's parser recurses as ours does: deep
            // nesting is refused here, where the line can be named.
            Err(_) if composes(&text) => {
                check_text_nesting(&text).map_err(ExportError::Data)?;
                None
            }
            Err(e) => return Err(ExportError::Data(e)),
        }
    };
    let layer = match alone {
        Some(layer) => layer,
        None => flatten(path, scope).map_err(ExportError::Data)?,
    };
    read_layer(&layer, name).map_err(ExportError::Data)
}

fn read(text: &str, name: &str) -> Result<Clip, String> {
    read_layer(&parse(text)?, name)
}

/// `Err` if the prims of `layer` nest deeper than [`MAX_NESTING`], found
/// without recursing: the walks below recurse a level a prim, and a
/// layer from the composing child is bounded only by its JSON.
fn check_depth(layer: &Layer) -> Result<(), String> {
    let mut stack: Vec<(&Prim, usize)> = layer.roots.iter().map(|p| (p, 1)).collect();
    while let Some((prim, depth)) = stack.pop() {
        if depth > MAX_NESTING {
            return Err(format!(
                "prim `{}`: prims nest deeper than {MAX_NESTING} levels",
                prim.name
            ));
        }
        stack.extend(prim.children.iter().map(|c| (c, depth + 1)));
    }
    Ok(())
}

fn read_layer(layer: &Layer, name: &str) -> Result<Clip, String> {
    check_depth(layer)?;
    let mut codes = Vec::new();
    for r in &layer.roots {
        sample_times(r, &mut codes);
    }
    codes.sort_by(f64::total_cmp);
    codes.dedup();
    // The glTF reader's key grid (one frame per shortest interval, capped),
    // in time codes.
    let tcps = layer.time_codes_per_second;
    let shortest = codes
        .windows(2)
        .map(|w| (w[1] - w[0]) / tcps)
        .fold(f64::INFINITY, f64::min);
    let rate = key_rate(shortest).unwrap_or(tcps);
    let (start, step) = (codes.first().copied().unwrap_or(0.0), tcps / rate);
    let end = codes.last().copied().unwrap_or(start);
    let frames = sampled_frames(0.0, (end - start) / tcps, rate)?;
    let to_z_up = |p: V3| -> V3 {
        let p = p * layer.meters_per_unit;
        if layer.up_y {
            V3::new(p.x, -p.z, p.y)
        } else {
            p
        }
    };
    let (mut found, mut instancers) = (Vec::new(), Vec::new());
    for r in &layer.roots {
        meshes(r, &mut Vec::new(), &mut found, &mut instancers);
    }
    let paths = Paths::new(&layer.roots);
    if found.is_empty() && instancers.is_empty() {
        return Err("no Mesh prim with points in it".to_string());
    }
    let times: Vec<f64> = (0..frames).map(|k| start + k as f64 * step).collect();
    let mut objects = Vec::new();
    for chain in &instancers {
        objects.extend(instanced(&paths, chain, &times, &to_z_up)?);
    }
    for chain in found {
        let mesh = *chain.last().expect("a chain ends at its mesh");
        let triangles = mesh.triangles()?;
        let points = mesh.attribute("points").expect("found by its points");
        let skinning = Skinning::of(&paths, &chain)?;
        let shapes = BlendShapes::of(&paths, &chain)?;
        check_points(&mesh.name, frames, points.vector_count())?;
        let mut frame_list = Vec::with_capacity(frames);
        for k in 0..frames {
            let t = start + k as f64 * step;
            let p = sample(points, t)
                .ok_or_else(|| format!("mesh `{}`: points are not numbers", mesh.name))?;
            if p.len() % 3 != 0 || p.is_empty() {
                return Err(format!("mesh `{}`: points are not 3-vectors", mesh.name));
            }
            let mut p: Vec<V3> = p.chunks(3).map(|c| V3::new(c[0], c[1], c[2])).collect();
            if let Some(shapes) = &shapes {
                shapes.apply(&mut p, t)?;
            }
            let placed = match &skinning {
                // A skinned mesh is placed by its skeleton, not by the
                // prims above it (UsdSkel).
                Some(s) => {
                    if p.len() != s.vertices() {
                        return Err(format!(
                            "mesh `{}`: its point count changes over time",
                            mesh.name
                        ));
                    }
                    s.pose(&p, t)?
                }
                None => {
                    let world = world_transform(&chain, t)?;
                    p.iter()
                        .map(|c| world.transform_point(&(*c).into()).coords)
                        .collect()
                }
            };
            frame_list.push(placed.into_iter().map(to_z_up).collect::<Vec<V3>>());
        }
        let n = frame_list[0].len();
        if frame_list.iter().any(|f| f.len() != n) {
            return Err(format!(
                "mesh `{}`: its point count changes over time",
                mesh.name
            ));
        }
        if let Some(i) = triangles.iter().flatten().find(|&&i| i as usize >= n) {
            return Err(format!(
                "mesh `{}`: `faceVertexIndices` holds {i}, past its {n} points",
                mesh.name
            ));
        }
        // The object is named by the prim whose transform moves it (the
        // Xform above a mesh, as exporters write them), else the mesh; by
        // the name leafmagic kept in `leafmagic:name` where it wrote one.
        let named = chain
            .iter()
            .rev()
            .nth(1)
            .filter(|p| p.type_name == "Xform" && p.children.len() == 1)
            .unwrap_or(&mesh);
        let name = match named
            .attribute("leafmagic:name")
            .and_then(|a| a.default.as_ref())
        {
            Some(Value::Str(s)) => s.clone(),
            _ => named.name.clone(),
        };
        objects.push(ClipObject::read_mesh(name, triangles, frame_list));
    }
    Clip::read(name, rate, frames, objects)
}

#[cfg(test)]
mod tests {
    use super::*;

    const CARD: &str = r#"#usda 1.0
(
    metersPerUnit = 0.01
    timeCodesPerSecond = 10
    upAxis = "Y"
)

def Xform "root"
{
    double3 xformOp:translate = (0, 100, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]

    def Xform "card" (
        doc = """a card"""
    )
    {
        # moves 1 m along x over 1 s, turning 90° about y
        double3 xformOp:translate.timeSamples = {
            0: (0, 0, 0),
            10: (100, 0, 0),
        }
        float xformOp:rotateY.timeSamples = { 0: 0, 10: 90 }
        uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateY"]

        def Mesh "card"
        {
            int[] faceVertexCounts = [4]
            int[] faceVertexIndices = [0, 1, 2, 3]
            point3f[] points = [(-2, 0, -1), (2, 0, -1), (2, 0, 1), (-2, 0, 1)]
            rel material:binding = </root/Looks/paper>
        }
    }
}
"#;

    #[test]
    fn units_axes_hierarchy_and_samples_are_honoured() {
        let clip = read(CARD, "card").unwrap();
        // Keys at time codes 0 and 10, 10 codes a second: 1 Hz, 2 frames.
        assert_eq!(clip.fps, 1.0);
        assert_eq!(clip.frames, 2);
        let o = &clip.objects[0];
        assert_eq!(o.name, "card");
        assert_eq!(o.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        // Frame 0: root lifts 1 m along USD's y, which is up: z = 1 m.
        let p0 = o.positions(0);
        assert!(
            (p0[0] - V3::new(-0.02, 0.01, 1.0)).norm() < 1e-12,
            "{}",
            p0[0]
        );
        // Frame 1: 1 m along x, the card turned 90° about the (up) y:
        // USD (-2, 0, -1) cm → (-1, 0, 2) cm → z-up (x, -z, y).
        let p1 = o.positions(1);
        let want = V3::new(1.0 - 0.01, -0.02, 1.0);
        assert!((p1[0] - want).norm() < 1e-12, "{} against {want}", p1[0]);
        // Between samples: linear, held outside them.
        let layer = parse(CARD).unwrap();
        let card = &layer.roots[0].children[0];
        let turn = card.attribute("xformOp:rotateY").unwrap();
        assert_eq!(sample(turn, 5.0), Some(vec![45.0]));
        assert_eq!(sample(turn, -3.0), Some(vec![0.0]));
        assert_eq!(sample(turn, 12.0), Some(vec![90.0]));
        let shift = card.attribute("xformOp:translate").unwrap();
        assert_eq!(sample(shift, 2.5), Some(vec![25.0, 0.0, 0.0]));
    }

    #[test]
    fn keys_closer_than_the_cap_do_not_multiply_frames() {
        // Two samples a thousandth of a time code apart, then one 10 codes
        // on: sampled at glTF's cap of 1000 Hz, not at 24,000 Hz.
        let text = CARD
            .replace("timeCodesPerSecond = 10", "timeCodesPerSecond = 24")
            .replace(
                "0: (0, 0, 0),",
                "0: (0, 0, 0),\n            0.001: (0, 0, 0),",
            );
        let clip = read(&text, "card").unwrap();
        assert_eq!(clip.fps, crate::formats::sampling::MAX_KEY_RATE_HZ);
        assert_eq!(clip.frames, (10.0 / 24.0 * 1000.0f64).floor() as usize + 1);
    }
}
