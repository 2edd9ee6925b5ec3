//! USD (`.usda`, text) of a [`Clip`], UsdGeom and UsdShade schemas:
//!
//! ```text
//! /<clip>_scene            Xform, kind = "assembly", the default prim
//!   Looks/                 Scope
//!     <kind>_<class>       Material → PreviewSurface (UsdPreviewSurface, diffuseColor)
//!   <object>               Xform: xformOp:translate (double3) and xformOp:orient (quatf),
//!                          time-sampled: the rigid part of the motion (origin at the
//!                          object's centre, turned with it); leafmagic:* custom attributes
//!     <object>_mesh        Mesh: points and normals time-sampled in the Xform's frame,
//!                          primvars:st (vertex UVs), extent; bound to its class's material
//!                          (a rope is a linear BasisCurves)
//! ```
//!
//! Stage metadata: `upAxis = "Z"`, `metersPerUnit = 1` (the simulator's axes
//! and units), `timeCodesPerSecond` = `framesPerSecond` = the host's frame
//! rate (24 by default, [`crate::formats::pc2::DEFAULT_HOST_FPS`]), `startTimeCode =
//! 0`, `endTimeCode` = the last sample's: sample k of a clip at `fps` sits at
//! time code k · host / fps, t = k / fps. Time codes count the host's frames
//! because Blender 4.5's importer plays time code n at scene frame n and
//! keeps its scene's rate (24 unless changed): a stage whose time codes
//! counted 30 fps samples played 25 % slow there (measured with Blender's
//! Python module). USD players interpolate between samples, and Houdini
//! converts by `timeCodesPerSecond`, so any clip rate plays right.
//!
//! USD names are identifiers (`[A-Za-z_][A-Za-z0-9_]*`): an object's name
//! has every other character replaced by `_` (`leaf-003` → `leaf_003`), and
//! its own name is kept in the custom attribute `leafmagic:name`.
//!
//! The text is written here, not by a crate: the pure-Rust `openusd` crate
//! 0.6.0 (0.7 and later need Rust 1.96) writes both encodings, but Pixar's
//! library (usd-core 26.11) refuses what it writes: its text writer prints a
//! one-item list op without brackets (`prepend apiSchemas =
//! "MaterialBindingAPI"`: "Expected None or ["), and its crate files fail
//! to open ("Invalid children found in primChildren field"). Numbers are
//! printed in their shortest round-trip form (f32 for points, f64 for
//! translations), so the text holds exactly the values a binary file would.
//! For `.usdc`, Pixar's library converts the text losslessly (see
//! [`USDC_HINT`]).

use crate::formats::clip::dress::vertex_normals;
use crate::formats::clip::look::{colour, material_name, shown};
use crate::formats::clip::{Clip, ClipObject};
use crate::formats::error::ExportError;
use nalgebra::Vector3;
use std::collections::BTreeSet;
use std::path::Path;

type V3 = Vector3<f64>;

/// How to get a `.usdc` from a `.usda`, with Pixar's library.
pub const USDC_HINT: &str = "leafmagic writes USD as text (the `usd` or `usda` format); convert it to \
    .usdc with Pixar's library: pip install usd-core, then python3 -c \"from pxr import Sdf; \
    Sdf.Layer.FindOrOpen('X.usda').Export('X.usdc')\"";

/// `name` as a USD identifier: characters outside `[A-Za-z0-9_]` become
/// `_`, and a leading digit (or an empty name) gets a `_` in front.
pub fn identifier(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    s
}

/// Unique identifiers for `names`, in order: a name whose identifier is
/// already taken gets `_2`, `_3`, … appended.
pub(crate) fn unique_identifiers<'a>(
    names: impl Iterator<Item = &'a str>,
    taken: &mut BTreeSet<String>,
) -> Vec<String> {
    names
        .map(|n| {
            let base = identifier(n);
            let mut id = base.clone();
            let mut k = 2;
            while taken.contains(&id) {
                id = format!("{base}_{k}");
                k += 1;
            }
            taken.insert(id.clone());
            id
        })
        .collect()
}

/// Text of an f32 (shortest form that reads back to the same f32).
fn f(x: f64) -> String {
    let v = x as f32;
    if v == 0.0 {
        "0".to_string()
    } else {
        format!("{v}")
    }
}

/// Text of an f64 (shortest form that reads back to the same f64).
fn d(x: f64) -> String {
    if x == 0.0 {
        "0".to_string()
    } else {
        format!("{x}")
    }
}

fn vec3f(v: &V3) -> String {
    format!("({}, {}, {})", f(v.x), f(v.y), f(v.z))
}

fn array<T>(items: &[T], each: impl Fn(&T) -> String) -> String {
    let parts: Vec<String> = items.iter().map(each).collect();
    format!("[{}]", parts.join(", "))
}

/// A USD string literal.
fn quoted(s: &str) -> String {
    let mut q = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => q.push_str("\\\""),
            '\\' => q.push_str("\\\\"),
            '\n' => q.push_str("\\n"),
            c => q.push(c),
        }
    }
    q.push('"');
    q
}

/// The extent (bounding box corners) of points.
fn extent(points: &[V3]) -> String {
    let mut lo = V3::repeat(f64::INFINITY);
    let mut hi = V3::repeat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    format!("[{}, {}]", vec3f(&lo), vec3f(&hi))
}

/// The text under construction, with its indentation.
struct Text {
    s: String,
    depth: usize,
    /// Host frames per sample: sample k is written at time code k × this.
    /// Kept as the ratio's two rates so that time codes are computed as
    /// (k · host) / fps, exact whenever they are whole numbers.
    host_fps: f64,
    fps: f64,
}

impl Text {
    fn line(&mut self, l: &str) {
        for _ in 0..self.depth {
            self.s.push_str("    ");
        }
        self.s.push_str(l);
        self.s.push('\n');
    }

    /// `def TYPE "name" (meta) {`, then `body`, then `}`.
    fn prim(
        &mut self,
        type_name: &str,
        name: &str,
        meta: &[String],
        body: impl FnOnce(&mut Text) -> Result<(), ExportError>,
    ) -> Result<(), ExportError> {
        if meta.is_empty() {
            self.line(&format!("def {type_name} \"{name}\""));
        } else {
            self.line(&format!("def {type_name} \"{name}\" ("));
            self.depth += 1;
            for m in meta {
                self.line(m);
            }
            self.depth -= 1;
            self.line(")");
        }
        self.line("{");
        self.depth += 1;
        body(self)?;
        self.depth -= 1;
        self.line("}");
        Ok(())
    }

    /// Sample `k`'s time code, as text.
    fn time_code(&self, k: usize) -> String {
        if self.host_fps == self.fps {
            k.to_string()
        } else {
            d(k as f64 * self.host_fps / self.fps)
        }
    }

    /// `DECL.timeSamples = { code: value, ... }`, one line per sample.
    fn samples(&mut self, decl: &str, values: impl Iterator<Item = String>) {
        self.line(&format!("{decl}.timeSamples = {{"));
        self.depth += 1;
        for (k, v) in values.enumerate() {
            let code = self.time_code(k);
            self.line(&format!("{code}: {v},"));
        }
        self.depth -= 1;
        self.line("}");
    }
}

/// The `.usda` text of `clip` (see the module doc).
fn usda(clip: &Clip, host_fps: f64) -> Result<String, ExportError> {
    clip.validate()?;
    if !(host_fps > 0.0 && host_fps.is_finite()) {
        return Err(ExportError::Data(format!(
            "the host frame rate must be positive, got {host_fps}"
        )));
    }
    let mut taken = BTreeSet::new();
    let root_id = identifier(&format!("{}_scene", clip.name));
    taken.insert(root_id.clone());
    taken.insert("Looks".to_string());
    let ids = unique_identifiers(clip.objects.iter().map(|o| o.name.as_str()), &mut taken);
    let mut t = Text {
        s: String::with_capacity(1 << 16),
        depth: 0,
        host_fps,
        fps: clip.fps,
    };
    t.line("#usda 1.0");
    t.line("(");
    t.depth += 1;
    t.line(&format!(
        "doc = {}",
        quoted(&format!(
            "leafmagic {}: {} ({} objects, {} samples at {} fps on time codes of a {} fps host: sample k at time code k * {} / {}, t = k / {})",
            env!("CARGO_PKG_VERSION"),
            clip.name,
            clip.objects.len(),
            clip.frames,
            clip.fps,
            d(host_fps),
            d(host_fps),
            d(clip.fps),
            d(clip.fps)
        ))
    ));
    if !clip.aero_law.is_empty() {
        // The law the falls were simulated under, where a pipeline reads a
        // layer's own data.
        t.line("customLayerData = {");
        t.depth += 1;
        t.line(&format!(
            "string leafmagic_aero_law = {}",
            quoted(&clip.aero_law)
        ));
        t.depth -= 1;
        t.line("}");
    }
    t.line(&format!("defaultPrim = \"{root_id}\""));
    t.line(&format!(
        "endTimeCode = {}",
        t.time_code(clip.frames.saturating_sub(1))
    ));
    t.line(&format!("framesPerSecond = {}", d(host_fps)));
    t.line("metersPerUnit = 1");
    t.line("startTimeCode = 0");
    t.line(&format!("timeCodesPerSecond = {}", d(host_fps)));
    t.line("upAxis = \"Z\"");
    t.depth -= 1;
    t.line(")");
    t.line("");
    // Materials: one per class (or kind), in name order.
    let mut looks: Vec<(String, [f32; 3])> = Vec::new();
    for o in &clip.objects {
        let m = identifier(&material_name(o));
        if !looks.iter().any(|(n, _)| *n == m) {
            looks.push((m, colour(o)));
        }
    }
    looks.sort_by(|a, b| a.0.cmp(&b.0));
    t.prim("Xform", &root_id, &["kind = \"assembly\"".to_string()], |t| {
        if let Some(g) = clip.ground {
            t.line(&format!("custom double leafmagic:ground_height = {}", d(g)));
        }
        t.prim("Scope", "Looks", &[], |t| {
            for (name, rgb) in &looks {
                t.prim("Material", name, &[], |t| {
                    t.line(&format!(
                        "token outputs:surface.connect = </{root_id}/Looks/{name}/PreviewSurface.outputs:surface>"
                    ));
                    t.prim("Shader", "PreviewSurface", &[], |t| {
                        t.line("uniform token info:id = \"UsdPreviewSurface\"");
                        t.line(&format!(
                            "color3f inputs:diffuseColor = ({}, {}, {})",
                            rgb[0], rgb[1], rgb[2]
                        ));
                        t.line("float inputs:metallic = 0");
                        t.line("float inputs:roughness = 0.8");
                        t.line("token outputs:surface");
                        Ok(())
                    })
                })?;
            }
            Ok(())
        })?;
        // Objects in parallel (formatting numbers is most of the work),
        // joined in order: the same bytes with any number of threads.
        use rayon::prelude::*;
        let depth = t.depth;
        let parts: Vec<String> = clip
            .objects
            .par_iter()
            .zip(&ids)
            .map(|(o, id)| {
                let mut part = Text {
                    s: String::new(),
                    depth,
                    host_fps,
                    fps: clip.fps,
                };
                object(&mut part, clip, o, &root_id, id).map(|()| part.s)
            })
            .collect::<Result<_, ExportError>>()?;
        parts.iter().for_each(|p| t.s.push_str(p));
        Ok(())
    })?;
    Ok(t.s)
}

fn object(
    t: &mut Text,
    clip: &Clip,
    o: &ClipObject,
    root_id: &str,
    id: &str,
) -> Result<(), ExportError> {
    let framed = o.framed();
    let surface = shown(o, &framed);
    let material = identifier(&material_name(o));
    t.prim("Xform", id, &[], |t| {
        t.samples(
            "double3 xformOp:translate",
            framed
                .origin
                .iter()
                .map(|c| format!("({}, {}, {})", d(c.x), d(c.y), d(c.z))),
        );
        // USD quaternions are written real part first.
        t.samples(
            "quatf xformOp:orient",
            framed
                .rotation
                .iter()
                .map(|q| format!("({}, {}, {}, {})", f(q.w), f(q.i), f(q.j), f(q.k))),
        );
        t.line("uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:orient\"]");
        t.line(&format!("custom string leafmagic:name = {}", quoted(&o.name)));
        t.line(&format!("custom string leafmagic:kind = {}", quoted(&o.kind)));
        if !o.label.is_empty() {
            t.line(&format!("custom string leafmagic:class = {}", quoted(&o.label)));
        }
        if !o.regime.is_empty() {
            t.line(&format!("custom string leafmagic:regime = {}", quoted(&o.regime)));
        }
        for (k, v) in &o.features {
            t.line(&format!(
                "custom double leafmagic:features:{} = {}",
                identifier(k),
                d(*v)
            ));
        }
        // The shown points in the Xform's frame, per frame (once if rigid).
        let local = |k: usize| -> Vec<V3> {
            let l = framed.local_at(k);
            match &o.render {
                Some(r) => r.place(l, &o.triangles),
                None => l.to_vec(),
            }
        };
        let frames: Vec<Vec<V3>> = if framed.deforms() {
            (0..clip.frames).map(local).collect()
        } else {
            vec![local(0)]
        };
        let attr = |t: &mut Text, decl: &str, of: &dyn Fn(&[V3]) -> String| {
            if frames.len() > 1 {
                t.samples(decl, frames.iter().map(|f| of(f)));
            } else {
                t.line(&format!("{decl} = {}", of(&frames[0])));
            }
        };
        let rgb = colour(o);
        let is_curve = surface.triangles.is_empty();
        let mesh_id = format!("{id}_mesh");
        t.prim(
            if is_curve { "BasisCurves" } else { "Mesh" },
            &mesh_id,
            &["prepend apiSchemas = [\"MaterialBindingAPI\"]".to_string()],
            |t| {
                t.line(&format!(
                    "rel material:binding = </{root_id}/Looks/{material}>"
                ));
                attr(t, "point3f[] points", &|p| array(p, vec3f));
                attr(t, "float3[] extent", &|p| extent(p));
                t.line(&format!(
                    "color3f[] primvars:displayColor = [({}, {}, {})] (interpolation = \"constant\")",
                    rgb[0], rgb[1], rgb[2]
                ));
                if is_curve {
                    // A rope: one linear curve through its vertices in order.
                    t.line("uniform token type = \"linear\"");
                    t.line(&format!("int[] curveVertexCounts = [{}]", surface.rest.len()));
                    t.line("float[] widths = [0.005] (interpolation = \"constant\")");
                    return Ok(());
                }
                t.line(&format!(
                    "int[] faceVertexCounts = {}",
                    array(&surface.triangles, |_| "3".to_string())
                ));
                t.line(&format!(
                    "int[] faceVertexIndices = {}",
                    array(&surface.triangles, |tri| format!("{}, {}, {}", tri[0], tri[1], tri[2]))
                ));
                attr(t, "normal3f[] normals", &|p| {
                    array(&vertex_normals(p, &surface.triangles), vec3f)
                });
                t.line("uniform token normals:interpolation = \"vertex\"");
                t.line(&format!(
                    "texCoord2f[] primvars:st = {} (interpolation = \"vertex\")",
                    array(&surface.uvs, |u| format!("({}, {})", f(u[0]), f(u[1])))
                ));
                t.line("uniform token subdivisionScheme = \"none\"");
                t.line("uniform bool doubleSided = 1");
                Ok(())
            },
        )
    })
}

/// The `.usda` bytes of `clip`, on the time codes of a host scene at
/// `host_fps` frames per second (see the module doc).
///
/// # Errors
/// [`ExportError::Data`] if the clip is inconsistent ([`Clip::validate`])
/// or `host_fps` is not a positive number.
pub fn usd_bytes(clip: &Clip, host_fps: f64) -> Result<Vec<u8>, ExportError> {
    Ok(usda(clip, host_fps)?.into_bytes())
}

/// Writes `clip` to `path` as `.usda` for a host at `host_fps`,
/// atomically; returns the byte count.
pub fn write_usd(clip: &Clip, path: &Path, host_fps: f64) -> Result<usize, ExportError> {
    let bytes = usd_bytes(clip, host_fps)?;
    crate::util::io::write_atomic(path, &bytes).map_err(|e| ExportError::io(path, e))?;
    Ok(bytes.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_become_unique_identifiers() {
        assert_eq!(identifier("leaf-003"), "leaf_003");
        assert_eq!(identifier("3d"), "_3d");
        assert_eq!(identifier(""), "_");
        let mut taken = BTreeSet::from(["Looks".to_string()]);
        let ids = unique_identifiers(["a-b", "a_b", "Looks", "é"].into_iter(), &mut taken);
        assert_eq!(ids, ["a_b", "a_b_2", "Looks_2", "_"]);
    }
}
