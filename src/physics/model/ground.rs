//! The ground plane of a scene: its height, Coulomb friction and
//! restitution. How contact with it is resolved is
//! [`crate::physics::contact`].

use super::error::ModelError;
use serde::{Deserialize, Serialize};

/// The ground plane z = `height` with Coulomb friction and restitution.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ground {
    /// Height h of the plane, m.
    #[serde(default)]
    pub height: f64,
    /// Static friction coefficient μ_s (≥ μ_k).
    pub static_friction: f64,
    /// Kinetic friction coefficient μ_k.
    pub kinetic_friction: f64,
    /// Coefficient of restitution e ∈ [0, 1]: the ratio of rebound to impact
    /// normal speed.
    #[serde(default)]
    pub restitution: f64,
}

impl Ground {
    /// Checks every number, naming the field as `ground.<field>`.
    pub fn validate(&self) -> Result<(), ModelError> {
        let fail = |f: &str, reason: String| ModelError {
            item: format!("ground.{f}"),
            reason,
        };
        for (name, value) in [
            ("height", self.height),
            ("static_friction", self.static_friction),
            ("kinetic_friction", self.kinetic_friction),
            ("restitution", self.restitution),
        ] {
            if !value.is_finite() {
                return Err(fail(name, format!("must be a finite number, got {value}")));
            }
        }
        if self.kinetic_friction < 0.0 {
            return Err(fail(
                "kinetic_friction",
                format!("must be ≥ 0, got {}", self.kinetic_friction),
            ));
        }
        if self.static_friction < self.kinetic_friction {
            return Err(fail(
                "static_friction",
                format!(
                    "must be ≥ kinetic_friction ({}), got {}",
                    self.kinetic_friction, self.static_friction
                ),
            ));
        }
        if !(0.0..=1.0).contains(&self.restitution) {
            return Err(fail(
                "restitution",
                format!("must be in [0, 1], got {}", self.restitution),
            ));
        }
        Ok(())
    }
}
