//! Uniform flow (the paper's figure 2, first row).

use std::fmt;

use nalgebra::Vector3;

use super::super::error::{FieldError, finite_vector};
use super::super::spec::required;
use super::kind::{Evaluate, FlowKeys, FlowKind, array};

/// Uniform flow, φ = ax + by + cz, v = (a, b, c). TOML kind `uniform`.
#[derive(Clone, Debug, PartialEq)]
pub struct Uniform {
    /// Wind velocity, m/s.
    pub velocity: Vector3<f64>,
}

impl FlowKind for Uniform {
    const KEYS: &'static [&'static str] = &["velocity"];

    /// Nothing to precompute: the flow evaluates as itself.
    type Eval = Uniform;

    fn compile(&self) -> Uniform {
        self.clone()
    }

    fn speed_bound(&self) -> f64 {
        self.velocity.norm()
    }

    fn validate(&self) -> Result<(), FieldError> {
        finite_vector(&self.velocity, "velocity")
    }

    fn from_keys(keys: &FlowKeys, owner: &dyn fmt::Display) -> Result<Self, String> {
        Ok(Self {
            velocity: Vector3::from(required(keys.velocity, "velocity", owner)?),
        })
    }

    fn to_keys(&self, keys: &mut FlowKeys) {
        keys.velocity = array(&self.velocity);
    }
}

impl Evaluate for Uniform {
    #[inline]
    fn velocity(&self, _x: &Vector3<f64>) -> Vector3<f64> {
        self.velocity
    }
}
