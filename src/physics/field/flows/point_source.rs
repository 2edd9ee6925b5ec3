//! 3-D point sources and sinks. The paper's figure 2 "source" is the 2-D line
//! source (`line_source.rs`); this is the true 3-D one, φ = −a/(4πr), with a
//! Plummer-smoothed core (the softening of gravitational N-body codes).

use std::f64::consts::PI;
use std::fmt;

use nalgebra::Vector3;

use super::super::error::{FieldError, finite, finite_vector, positive};
use super::super::spec::required;
use super::kind::{Evaluate, FlowKeys, FlowKind, array};

/// Peak of the smoothed point-source profile s/(1 + s²)^{3/2} = 2/(3√3), at s = 1/√2.
const POINT_SOURCE_PEAK: f64 = 0.384_900_179_459_750_5;

/// 3-D point source, φ = −a/(4πr), v = a r̂/(4πr²); `flux` a is the volume
/// outflow in m³/s (negative a is a sink). Core smoothing (Plummer):
/// v = a d/(4π(r² + ε²)^{3/2}), ε = `core_radius`, the gradient of
/// φ = −a/(4π√(r²+ε²)); flux through a centred sphere of radius R is
/// a R³/(R² + ε²)^{3/2}. TOML kind `point_source`.
#[derive(Clone, Debug, PartialEq)]
pub struct PointSource {
    /// Location of the source, m.
    pub point: Vector3<f64>,
    /// Volume outflow a, m³/s.
    pub flux: f64,
    /// Smoothing length ε > 0, m.
    pub core_radius: f64,
}

/// 3-D point sink: a [`PointSource`] of flux −a, so a positive `flux`
/// (m³/s) means inflow. TOML kind `point_sink`.
#[derive(Clone, Debug, PartialEq)]
pub struct PointSink {
    /// Location of the sink, m.
    pub point: Vector3<f64>,
    /// Volume inflow a, m³/s.
    pub flux: f64,
    /// Smoothing length ε > 0, m.
    pub core_radius: f64,
}

impl FlowKind for PointSource {
    const KEYS: &'static [&'static str] = &["point", "flux", "core_radius"];

    type Eval = PointSourceEval;

    fn compile(&self) -> PointSourceEval {
        PointSourceEval::new(self.point, self.flux, self.core_radius)
    }

    fn speed_bound(&self) -> f64 {
        POINT_SOURCE_PEAK * self.flux.abs() / (4.0 * PI * self.core_radius * self.core_radius)
    }

    fn validate(&self) -> Result<(), FieldError> {
        finite_vector(&self.point, "point")?;
        finite(self.flux, "flux")?;
        positive(self.core_radius, "core_radius")
    }

    fn from_keys(keys: &FlowKeys, owner: &dyn fmt::Display) -> Result<Self, String> {
        let point = Vector3::from(required(keys.point, "point", owner)?);
        let flux = required(keys.flux, "flux", owner)?;
        let core_radius = required(keys.core_radius, "core_radius", owner)?;
        Ok(Self {
            point,
            flux,
            core_radius,
        })
    }

    fn to_keys(&self, keys: &mut FlowKeys) {
        keys.point = array(&self.point);
        keys.flux = Some(self.flux);
        keys.core_radius = Some(self.core_radius);
    }
}

impl PointSink {
    /// The same numbers read as a source's (not negated): a sink is checked,
    /// bounded and written exactly as a source is.
    fn as_source(&self) -> PointSource {
        PointSource {
            point: self.point,
            flux: self.flux,
            core_radius: self.core_radius,
        }
    }
}

impl FlowKind for PointSink {
    const KEYS: &'static [&'static str] = PointSource::KEYS;

    type Eval = PointSourceEval;

    fn compile(&self) -> PointSourceEval {
        PointSourceEval::new(self.point, -self.flux, self.core_radius)
    }

    fn speed_bound(&self) -> f64 {
        self.as_source().speed_bound()
    }

    fn validate(&self) -> Result<(), FieldError> {
        self.as_source().validate()
    }

    fn from_keys(keys: &FlowKeys, owner: &dyn fmt::Display) -> Result<Self, String> {
        let PointSource {
            point,
            flux,
            core_radius,
        } = PointSource::from_keys(keys, owner)?;
        Ok(Self {
            point,
            flux,
            core_radius,
        })
    }

    fn to_keys(&self, keys: &mut FlowKeys) {
        self.as_source().to_keys(keys);
    }
}

/// v = coef·d/(r² + ε²)^{3/2}, coef = ±a/(4π).
#[derive(Clone, Debug, PartialEq)]
pub(in crate::physics::field) struct PointSourceEval {
    point: Vector3<f64>,
    coef: f64,
    eps2: f64,
}

impl PointSourceEval {
    /// `flux` is the outflow: a sink passes its inflow negated.
    fn new(point: Vector3<f64>, flux: f64, core_radius: f64) -> Self {
        Self {
            point,
            coef: flux / (4.0 * PI),
            eps2: core_radius * core_radius,
        }
    }
}

impl Evaluate for PointSourceEval {
    #[inline]
    fn velocity(&self, x: &Vector3<f64>) -> Vector3<f64> {
        let d = x - self.point;
        let s = d.norm_squared() + self.eps2;
        d * (self.coef / (s * s.sqrt()))
    }
}
