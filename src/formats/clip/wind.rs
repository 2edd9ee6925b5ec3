//! The wind as the previewer and the glTF extras draw it: each primitive of
//! a wind field reduced to a glyph (kind, point, direction, strength), kept
//! apart from the field so that a clip carries plain data.

use crate::physics::field::{
    Flow, LineSink, LineSource, LineVortex, PointSink, PointSource, Region, Uniform,
};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

type V3 = Vector3<f64>;

/// A wind primitive reduced to what a glyph needs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WindGlyph {
    /// `uniform`, `point_source`, `point_sink`, `line_source`, `line_sink`, `line_vortex`.
    pub kind: String,
    /// Where to draw it: the primitive's point, or the centre of a uniform
    /// flow's bounds (the origin when unbounded), m.
    pub point: [f64; 3],
    /// Unit flow direction (uniform) or axis (line primitives); zero for point primitives.
    pub direction: [f64; 3],
    /// Speed (uniform, m/s), flux (sources, sinks) or circulation (vortex).
    pub strength: f64,
}

impl WindGlyph {
    /// The glyph of one primitive of a wind field.
    pub fn of(p: &crate::physics::field::Primitive) -> WindGlyph {
        let unit = |v: &V3| -> [f64; 3] {
            let n = v.norm();
            if n > 0.0 { (v / n).into() } else { [0.0; 3] }
        };
        let (kind, point, direction, strength) = match p.flow() {
            Flow::Uniform(Uniform { velocity }) => {
                let centre = match p.bounds().map(|b| &b.region) {
                    Some(Region::Sphere { center, .. }) => *center,
                    Some(Region::Box { min, max }) => (min + max) / 2.0,
                    Some(Region::Cylinder { point, .. }) => *point,
                    None => V3::zeros(),
                };
                ("uniform", centre, unit(velocity), velocity.norm())
            }
            Flow::PointSource(PointSource { point, flux, .. }) => {
                ("point_source", *point, [0.0; 3], *flux)
            }
            Flow::PointSink(PointSink { point, flux, .. }) => {
                ("point_sink", *point, [0.0; 3], *flux)
            }
            Flow::LineSource(LineSource {
                point, axis, flux, ..
            }) => ("line_source", *point, unit(axis), *flux),
            Flow::LineSink(LineSink {
                point, axis, flux, ..
            }) => ("line_sink", *point, unit(axis), *flux),
            Flow::LineVortex(LineVortex {
                point,
                axis,
                circulation,
                ..
            }) => ("line_vortex", *point, unit(axis), *circulation),
        };
        WindGlyph {
            kind: kind.to_string(),
            point: point.into(),
            direction,
            strength,
        }
    }
}
