//! 2-D line sources and sinks: the paper's "source" and "sink" (figure 2,
//! v_r = a/(2πr), φ = a ln(r)/2π, r the distance to an axis), with a smoothed
//! core so the field is finite on the axis.

use std::f64::consts::PI;
use std::fmt;

use nalgebra::Vector3;

use super::super::error::{FieldError, direction, finite, finite_vector, positive};
use super::super::spec::required;
use super::kind::{Evaluate, FlowKeys, FlowKind, array};

/// 2-D line source along an axis (the paper's "source": φ = a ln(ρ)/2π,
/// v_ρ = a/(2πρ), with ρ the distance to the axis); `flux` a is the outflow
/// per unit length of axis, m²/s. Core smoothing:
/// v = a d⊥/(2π(ρ² + ε²)), ε = `core_radius`; flux per unit length through
/// a coaxial cylinder of radius R is a R²/(R² + ε²). TOML kind `line_source`.
///
/// Notation: d = x − point, ê the unit axis, d⊥ = d − (d·ê)ê, ρ = |d⊥|.
#[derive(Clone, Debug, PartialEq)]
pub struct LineSource {
    /// A point on the axis, m.
    pub point: Vector3<f64>,
    /// Axis direction (any length; normalised when built).
    pub axis: Vector3<f64>,
    /// Outflow per unit length a, m²/s.
    pub flux: f64,
    /// Smoothing length ε > 0, m.
    pub core_radius: f64,
}

/// 2-D line sink (the paper's "sink"): a [`LineSource`] of flux −a,
/// so a positive `flux` (m²/s) means inflow. TOML kind `line_sink`.
#[derive(Clone, Debug, PartialEq)]
pub struct LineSink {
    /// A point on the axis, m.
    pub point: Vector3<f64>,
    /// Axis direction (any length; normalised when built).
    pub axis: Vector3<f64>,
    /// Inflow per unit length a, m²/s.
    pub flux: f64,
    /// Smoothing length ε > 0, m.
    pub core_radius: f64,
}

impl FlowKind for LineSource {
    const KEYS: &'static [&'static str] = &["point", "axis", "flux", "core_radius"];

    type Eval = LineSourceEval;

    fn compile(&self) -> LineSourceEval {
        LineSourceEval::new(self.point, self.axis, self.flux, self.core_radius)
    }

    /// The smoothed profile ρ/(ρ² + ε²) peaks at ρ = ε: a/(4πε).
    fn speed_bound(&self) -> f64 {
        self.flux.abs() / (4.0 * PI * self.core_radius)
    }

    fn validate(&self) -> Result<(), FieldError> {
        finite_vector(&self.point, "point")?;
        direction(&self.axis, "axis")?;
        finite(self.flux, "flux")?;
        positive(self.core_radius, "core_radius")
    }

    fn from_keys(keys: &FlowKeys, owner: &dyn fmt::Display) -> Result<Self, String> {
        let point = Vector3::from(required(keys.point, "point", owner)?);
        let axis = Vector3::from(required(keys.axis, "axis", owner)?);
        let flux = required(keys.flux, "flux", owner)?;
        let core_radius = required(keys.core_radius, "core_radius", owner)?;
        Ok(Self {
            point,
            axis,
            flux,
            core_radius,
        })
    }

    fn to_keys(&self, keys: &mut FlowKeys) {
        keys.point = array(&self.point);
        keys.axis = array(&self.axis);
        keys.flux = Some(self.flux);
        keys.core_radius = Some(self.core_radius);
    }
}

impl LineSink {
    /// The same numbers read as a source's (not negated): a sink is checked,
    /// bounded and written exactly as a source is.
    fn as_source(&self) -> LineSource {
        LineSource {
            point: self.point,
            axis: self.axis,
            flux: self.flux,
            core_radius: self.core_radius,
        }
    }
}

impl FlowKind for LineSink {
    const KEYS: &'static [&'static str] = LineSource::KEYS;

    type Eval = LineSourceEval;

    fn compile(&self) -> LineSourceEval {
        LineSourceEval::new(self.point, self.axis, -self.flux, self.core_radius)
    }

    fn speed_bound(&self) -> f64 {
        self.as_source().speed_bound()
    }

    fn validate(&self) -> Result<(), FieldError> {
        self.as_source().validate()
    }

    fn from_keys(keys: &FlowKeys, owner: &dyn fmt::Display) -> Result<Self, String> {
        let LineSource {
            point,
            axis,
            flux,
            core_radius,
        } = LineSource::from_keys(keys, owner)?;
        Ok(Self {
            point,
            axis,
            flux,
            core_radius,
        })
    }

    fn to_keys(&self, keys: &mut FlowKeys) {
        self.as_source().to_keys(keys);
    }
}

/// v = coef·d⊥/(ρ² + ε²), coef = ±a/(2π).
#[derive(Clone, Debug, PartialEq)]
pub(in crate::physics::field) struct LineSourceEval {
    point: Vector3<f64>,
    axis: Vector3<f64>,
    coef: f64,
    eps2: f64,
}

impl LineSourceEval {
    /// `flux` is the outflow: a sink passes its inflow negated.
    fn new(point: Vector3<f64>, axis: Vector3<f64>, flux: f64, core_radius: f64) -> Self {
        Self {
            point,
            axis: axis.normalize(),
            coef: flux / (2.0 * PI),
            eps2: core_radius * core_radius,
        }
    }
}

impl Evaluate for LineSourceEval {
    #[inline]
    fn velocity(&self, x: &Vector3<f64>) -> Vector3<f64> {
        let d = x - self.point;
        let perp = d - self.axis * self.axis.dot(&d);
        perp * (self.coef / (perp.norm_squared() + self.eps2))
    }
}
