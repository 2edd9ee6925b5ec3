//! Bounded fields: a primitive limited to a region (the paper's "bounded"
//! fields of section 2.2; Blender's and Maya's "max distance" with a falloff).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::error::{FieldError, direction, finite_vector, non_negative};
use super::spec::{reject_extra, required};
use super::weight::falloff_weight;

/// Region in which a bounded primitive acts at full strength.
#[derive(Clone, Debug, PartialEq)]
pub enum Region {
    /// Ball of `radius` m around `center`. TOML `shape = "sphere"`.
    Sphere {
        /// Centre, m.
        center: Vector3<f64>,
        /// Radius ≥ 0, m.
        radius: f64,
    },
    /// Axis-aligned box. TOML `shape = "box"`.
    Box {
        /// Lower corner, m.
        min: Vector3<f64>,
        /// Upper corner, m (each component ≥ `min`'s).
        max: Vector3<f64>,
    },
    /// Infinite tube of `radius` m around an axis. TOML `shape = "cylinder"`.
    Cylinder {
        /// A point on the axis, m.
        point: Vector3<f64>,
        /// Axis direction (any length; normalised when built).
        axis: Vector3<f64>,
        /// Radius ≥ 0, m.
        radius: f64,
    },
}

/// Limits a primitive to a region (the paper's "bounded" fields; Blender/Maya
/// "max distance" with a falloff).
///
/// With d the distance from x to the region (0 inside) and s = d/`falloff`,
/// the primitive is multiplied by w = 1 − (6s⁵ − 15s⁴ + 10s³) for 0 < s < 1
/// (a quintic smoothstep: w and its first two derivatives are continuous),
/// w = 1 inside, w = 0 beyond; so the "max distance" is the region's size plus
/// `falloff`. `falloff = 0` gives a hard (discontinuous) edge.
#[derive(Clone, Debug, PartialEq)]
pub struct Bounds {
    /// Full-strength region.
    pub region: Region,
    /// Width of the smooth falloff band outside the region, m (≥ 0).
    pub falloff: f64,
}

impl Bounds {
    /// Checks the region and falloff; items are named relative to the bounds (`radius`).
    pub(super) fn validate(&self) -> Result<(), FieldError> {
        match &self.region {
            Region::Sphere { center, radius } => {
                finite_vector(center, "center")?;
                non_negative(*radius, "radius")?;
            }
            Region::Box { min, max } => {
                finite_vector(min, "min")?;
                finite_vector(max, "max")?;
                for (i, c) in ["x", "y", "z"].iter().enumerate() {
                    if min[i] > max[i] {
                        return Err(FieldError::new(
                            "min",
                            format!("min.{c} = {} exceeds max.{c} = {}", min[i], max[i]),
                        ));
                    }
                }
            }
            Region::Cylinder {
                point,
                axis,
                radius,
            } => {
                finite_vector(point, "point")?;
                direction(axis, "axis")?;
                non_negative(*radius, "radius")?;
            }
        }
        non_negative(self.falloff, "falloff")
    }
}

// ---------------------------------------------------------------------------
// Evaluation: the region with its axis normalised, built once.

/// A [`Bounds`] ready to evaluate: its region with a unit cylinder axis.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct RegionEval {
    region: Region,
    falloff: f64,
}

impl RegionEval {
    pub(super) fn new(b: &Bounds) -> Self {
        let region = match b.region {
            Region::Cylinder {
                point,
                axis,
                radius,
            } => Region::Cylinder {
                point,
                axis: axis.normalize(),
                radius,
            },
            ref other => other.clone(),
        };
        Self {
            region,
            falloff: b.falloff,
        }
    }

    /// Distance from x to the region, ≤ 0 inside.
    #[inline]
    fn distance(&self, x: &Vector3<f64>) -> f64 {
        match &self.region {
            Region::Sphere { center, radius } => (x - center).norm() - radius,
            Region::Box { min, max } => {
                let outside = (min - x).sup(&(x - max)).sup(&Vector3::zeros());
                outside.norm()
            }
            Region::Cylinder {
                point,
                axis,
                radius,
            } => axis.cross(&(x - point)).norm() - radius,
        }
    }

    /// The bound's weight w(x) in [0, 1].
    #[inline]
    pub(super) fn weight(&self, x: &Vector3<f64>) -> f64 {
        falloff_weight(self.distance(x), self.falloff)
    }

    /// True when the weight is exactly 0 at every point of the box
    /// [lo, hi]: a lower bound of `distance` over the box is ≥ `falloff`.
    /// For spheres and boxes the bound is the distance of the box's nearest
    /// point, computed with the same operations as `distance`: rounding is
    /// monotone, so no particle in the box computes a smaller distance. For
    /// cylinders (a cross product, not monotone) it is the distance of the
    /// box's centre less its half-diagonal, less a margin 1e-9 × the scale
    /// that exceeds the rounding error by many orders.
    pub(super) fn zero_on_box(&self, lo: &Vector3<f64>, hi: &Vector3<f64>) -> bool {
        let zero = Vector3::zeros();
        let lower = match &self.region {
            Region::Sphere { center, radius } => {
                (lo - center).sup(&(center - hi)).sup(&zero).norm() - radius
            }
            Region::Box { min, max } => (min - hi).sup(&(lo - max)).sup(&zero).norm(),
            Region::Cylinder {
                point,
                axis,
                radius,
            } => {
                let mid = (lo + hi) * 0.5;
                let half = ((hi - lo) * 0.5).norm();
                let scale = (mid - point).norm() + half + radius + 1.0;
                axis.cross(&(mid - point)).norm() - radius - half - 1e-9 * scale
            }
        };
        lower >= self.falloff
    }
}

// ---------------------------------------------------------------------------
// TOML: `bounds = { shape = "...", <that shape's keys>, falloff = ... }`.

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Shape {
    Sphere,
    Box,
    Cylinder,
}

fn shape_name<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Shape, D::Error> {
    crate::util::named::by_name(d, &["sphere", "box", "cylinder"])
}

/// The `bounds` table of a `[[wind]]` primitive.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BoundsSpec {
    #[serde(deserialize_with = "shape_name")]
    shape: Shape,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    center: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    radius: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    min: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    max: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    point: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    axis: Option<[f64; 3]>,
    falloff: f64,
}

impl BoundsSpec {
    pub(super) fn into_bounds(self) -> Result<Bounds, String> {
        let shape = self.shape;
        let owner = format!(
            "bounds shape \"{}\"",
            match shape {
                Shape::Sphere => "sphere",
                Shape::Box => "box",
                Shape::Cylinder => "cylinder",
            }
        );
        let present = [
            ("center", self.center.is_some()),
            ("radius", self.radius.is_some()),
            ("min", self.min.is_some()),
            ("max", self.max.is_some()),
            ("point", self.point.is_some()),
            ("axis", self.axis.is_some()),
        ];
        let allowed: &[&str] = match shape {
            Shape::Sphere => &["center", "radius"],
            Shape::Box => &["min", "max"],
            Shape::Cylinder => &["point", "axis", "radius"],
        };
        reject_extra(&present, allowed, &owner)?;
        let region = match shape {
            Shape::Sphere => Region::Sphere {
                center: Vector3::from(required(self.center, "center", &owner)?),
                radius: required(self.radius, "radius", &owner)?,
            },
            Shape::Box => Region::Box {
                min: Vector3::from(required(self.min, "min", &owner)?),
                max: Vector3::from(required(self.max, "max", &owner)?),
            },
            Shape::Cylinder => Region::Cylinder {
                point: Vector3::from(required(self.point, "point", &owner)?),
                axis: Vector3::from(required(self.axis, "axis", &owner)?),
                radius: required(self.radius, "radius", &owner)?,
            },
        };
        Ok(Bounds {
            region,
            falloff: self.falloff,
        })
    }

    pub(super) fn from_bounds(b: &Bounds) -> Self {
        let a = |v: &Vector3<f64>| Some([v.x, v.y, v.z]);
        let mut s = BoundsSpec {
            shape: Shape::Sphere,
            center: None,
            radius: None,
            min: None,
            max: None,
            point: None,
            axis: None,
            falloff: b.falloff,
        };
        match &b.region {
            Region::Sphere { center, radius } => {
                s.center = a(center);
                s.radius = Some(*radius);
            }
            Region::Box { min, max } => {
                s.shape = Shape::Box;
                s.min = a(min);
                s.max = a(max);
            }
            Region::Cylinder {
                point,
                axis,
                radius,
            } => {
                s.shape = Shape::Cylinder;
                s.point = a(point);
                s.axis = a(axis);
                s.radius = Some(*radius);
            }
        }
        s
    }
}
