//! Line vortices: the paper's "vortex" (figure 2, φ = Γθ/(2π)), with the core
//! regularised per [`VortexCore`]: Lamb–Oseen (a line vortex diffused by
//! viscosity; Oseen 1912, Lamb's *Hydrodynamics* 1932) or Rankine (a
//! solid-body core).

use std::f64::consts::PI;
use std::fmt;

use nalgebra::Vector3;

use super::super::error::{FieldError, direction, finite, finite_vector, positive};
use super::super::spec::required;
use super::kind::{Evaluate, FlowKeys, FlowKind, array};
use super::vortex_core::VortexCore;

/// Peak of the Lamb–Oseen profile (1 − e^{−s²})/s, reached at s = ρ/r_c ≈ 1.12091,
/// rounded up so the speed bound stays an upper bound.
const LAMB_OSEEN_PEAK: f64 = 0.638_172_7;

/// Line vortex (the paper's "vortex"): φ = Γθ/(2π), v_θ = Γ/(2πρ),
/// rotating by the right-hand rule about the axis (v = Γ ê × d⊥/(2πρ²)).
/// `circulation` Γ in m²/s; the core is regularised per [`VortexCore`].
/// TOML kind `line_vortex`.
///
/// Notation: d = x − point, ê the unit axis, d⊥ = d − (d·ê)ê, ρ = |d⊥|.
#[derive(Clone, Debug, PartialEq)]
pub struct LineVortex {
    /// A point on the axis, m.
    pub point: Vector3<f64>,
    /// Axis direction (any length; normalised when built).
    pub axis: Vector3<f64>,
    /// Circulation Γ, m²/s.
    pub circulation: f64,
    /// Core radius r_c (Lamb–Oseen) or R (Rankine) > 0, m.
    pub core_radius: f64,
    /// Core model.
    pub core: VortexCore,
}

impl FlowKind for LineVortex {
    const KEYS: &'static [&'static str] = &["point", "axis", "circulation", "core_radius", "core"];

    type Eval = LineVortexEval;

    fn compile(&self) -> LineVortexEval {
        let (point, axis) = (self.point, self.axis.normalize());
        let r2 = self.core_radius * self.core_radius;
        match self.core {
            VortexCore::LambOseen => LineVortexEval::LambOseen {
                point,
                axis,
                coef: self.circulation / (2.0 * PI * r2),
                inv_rc2: 1.0 / r2,
            },
            VortexCore::Rankine => LineVortexEval::Rankine {
                point,
                axis,
                coef: self.circulation / (2.0 * PI),
                r2,
            },
        }
    }

    /// Γ/(2π r_c) times the core's peak: exact for Rankine (at ρ = R), the
    /// rounded-up `LAMB_OSEEN_PEAK` for Lamb–Oseen.
    fn speed_bound(&self) -> f64 {
        let free = self.circulation.abs() / (2.0 * PI * self.core_radius);
        match self.core {
            VortexCore::LambOseen => LAMB_OSEEN_PEAK * free,
            VortexCore::Rankine => free,
        }
    }

    fn validate(&self) -> Result<(), FieldError> {
        finite_vector(&self.point, "point")?;
        direction(&self.axis, "axis")?;
        finite(self.circulation, "circulation")?;
        positive(self.core_radius, "core_radius")
    }

    fn from_keys(keys: &FlowKeys, owner: &dyn fmt::Display) -> Result<Self, String> {
        Ok(Self {
            point: Vector3::from(required(keys.point, "point", owner)?),
            axis: Vector3::from(required(keys.axis, "axis", owner)?),
            circulation: required(keys.circulation, "circulation", owner)?,
            core_radius: required(keys.core_radius, "core_radius", owner)?,
            core: keys.core.unwrap_or_default(),
        })
    }

    fn to_keys(&self, keys: &mut FlowKeys) {
        keys.point = array(&self.point);
        keys.axis = array(&self.axis);
        keys.circulation = Some(self.circulation);
        keys.core_radius = Some(self.core_radius);
        keys.core = Some(self.core);
    }
}

/// A [`LineVortex`] ready to evaluate, one form per core model.
#[derive(Clone, Debug, PartialEq)]
pub(in crate::physics::field) enum LineVortexEval {
    /// v = coef·f(ρ²/r_c²)·(ê × d), coef = Γ/(2π r_c²), f(q) = (1 − e^{−q})/q.
    LambOseen {
        point: Vector3<f64>,
        axis: Vector3<f64>,
        coef: f64,
        inv_rc2: f64,
    },
    /// v = coef·(ê × d)/max(ρ², R²), coef = Γ/(2π).
    Rankine {
        point: Vector3<f64>,
        axis: Vector3<f64>,
        coef: f64,
        r2: f64,
    },
}

impl Evaluate for LineVortexEval {
    #[inline]
    fn velocity(&self, x: &Vector3<f64>) -> Vector3<f64> {
        match self {
            Self::LambOseen {
                point,
                axis,
                coef,
                inv_rc2,
            } => {
                let d = x - point;
                // ê × d = ê × d⊥, so the axial part needs no removal.
                let tangent = axis.cross(&d);
                let q = tangent.norm_squared() * inv_rc2;
                tangent * (coef * one_minus_exp_over(q))
            }
            Self::Rankine {
                point,
                axis,
                coef,
                r2,
            } => {
                let d = x - point;
                let tangent = axis.cross(&d);
                // Inside the core the divisor is R² (solid-body rotation), so it is never 0.
                tangent * (coef / tangent.norm_squared().max(*r2))
            }
        }
    }
}

/// (1 − e^{−q})/q for q ≥ 0, with its limit 1 at q = 0 (the vortex axis).
#[inline]
pub(in crate::physics::field) fn one_minus_exp_over(q: f64) -> f64 {
    if q < 1e-6 {
        // Taylor series; truncation error q³/24 < 1e-19.
        1.0 - q * (0.5 - q / 6.0)
    } else {
        -(-q).exp_m1() / q
    }
}
