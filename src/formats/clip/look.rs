//! What a client is shown of an object, whatever the format: its mesh at
//! rest in its body frame (the simulated triangles or the render mesh placed
//! on them), and its colour and material name by motion class or kind.
//! Shared by the glTF and USD writers so that both dress an object alike.

use super::ClipObject;
use super::dress::outline_uvs;
use super::frame::Framed;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

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

/// The mesh a client sees of an object, in its body frame at rest: the
/// simulated vertices, or the render mesh placed on them.
pub struct Shown {
    /// Rest positions, body frame (simulator axes), m.
    pub rest: Vec<V3>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// UVs (v up, as in OBJ and USD).
    pub uvs: Vec<[f64; 2]>,
}

/// What is shown of `o` at rest (see [`Shown`]).
pub fn shown(o: &ClipObject, framed: &Framed) -> Shown {
    match &o.render {
        Some(r) => Shown {
            rest: r.place(&framed.rest, &o.triangles),
            triangles: r.triangles.clone(),
            uvs: r.uvs.clone(),
        },
        None => Shown {
            rest: framed.rest.clone(),
            triangles: o.triangles.clone(),
            uvs: outline_uvs(&framed.rest),
        },
    }
}

/// The material name of an object's class (or kind): `<kind>-<label>`.
pub fn material_name(o: &ClipObject) -> String {
    if o.label.is_empty() {
        o.kind.clone()
    } else {
        format!("{}-{}", o.kind, o.label)
    }
}
