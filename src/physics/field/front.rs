//! Moving fronts: the paper's section 4.2 shockwave ("the boundaries of
//! uniform fields moved up through the leaves"), as a moving half-space
//! instead of rows of sinks.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::error::{FieldError, direction, finite, non_negative};
use super::weight::falloff_weight;

/// A moving half-space boundary (the paper's section 4.2 shockwave: the
/// boundaries of uniform fields moved up through the leaves).
///
/// The front is the plane n̂·x = offset + speed·t. The primitive acts fully
/// behind it (n̂·x ≤ offset(t)) and fades to zero over `falloff` m ahead of
/// it with the same quintic smoothstep as [`Bounds`](super::Bounds). A
/// positive speed sweeps the active side forward along n̂.
#[derive(Clone, Debug, PartialEq)]
pub struct Front {
    /// Direction the front faces and moves along (any length; normalised when built).
    pub normal: Vector3<f64>,
    /// Plane offset along the unit normal at t = 0, m.
    pub offset: f64,
    /// Speed of the plane along the unit normal, m/s (TOML default 0).
    pub speed: f64,
    /// Width of the smooth falloff band ahead of the plane, m (≥ 0).
    pub falloff: f64,
}

impl Front {
    /// Plane offset at time `t`: offset + speed·t, m.
    pub fn offset_at(&self, t: f64) -> f64 {
        self.offset + self.speed * t
    }

    /// Checks the front; items are named relative to it (`normal`).
    pub(super) fn validate(&self) -> Result<(), FieldError> {
        direction(&self.normal, "normal")?;
        finite(self.offset, "offset")?;
        finite(self.speed, "speed")?;
        non_negative(self.falloff, "falloff")
    }
}

/// A [`Front`] ready to evaluate: its normal normalised.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct FrontEval {
    normal: Vector3<f64>,
    offset: f64,
    speed: f64,
    falloff: f64,
}

impl FrontEval {
    pub(super) fn new(f: &Front) -> Self {
        Self {
            normal: f.normal.normalize(),
            offset: f.offset,
            speed: f.speed,
            falloff: f.falloff,
        }
    }

    /// The front's weight w(x, t) in [0, 1].
    #[inline]
    pub(super) fn weight(&self, x: &Vector3<f64>, t: f64) -> f64 {
        let ahead = self.normal.dot(x) - (self.offset + self.speed * t);
        falloff_weight(ahead, self.falloff)
    }

    /// True when the weight is exactly 0 at time `t` at every point of the
    /// box [lo, hi]: the least n̂·x over the box (each term at the corner
    /// that minimises it) less the offset is ≥ the falloff, by a margin
    /// 1e-9 × the scale that exceeds the rounding error of `weight`.
    pub(super) fn zero_on_box(&self, lo: &Vector3<f64>, hi: &Vector3<f64>, t: f64) -> bool {
        let (mut least, mut scale) = (0.0, 1.0);
        for i in 0..3 {
            let n = self.normal[i];
            least += n * if n >= 0.0 { lo[i] } else { hi[i] };
            scale += n.abs() * lo[i].abs().max(hi[i].abs());
        }
        let offset = self.offset + self.speed * t;
        scale += offset.abs();
        least - offset - 1e-9 * scale >= self.falloff
    }
}

/// The `front` table of a `[[wind]]` primitive.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FrontSpec {
    normal: [f64; 3],
    offset: f64,
    #[serde(default)]
    speed: f64,
    falloff: f64,
}

impl FrontSpec {
    pub(super) fn into_front(self) -> Front {
        Front {
            normal: Vector3::from(self.normal),
            offset: self.offset,
            speed: self.speed,
            falloff: self.falloff,
        }
    }

    pub(super) fn from_front(f: &Front) -> Self {
        FrontSpec {
            normal: [f.normal.x, f.normal.y, f.normal.z],
            offset: f.offset,
            speed: f.speed,
            falloff: f.falloff,
        }
    }
}
