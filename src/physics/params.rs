//! The choices that govern how a model is stepped: the integrator and the
//! time-step policy. Their limits (the auto step's safety factor, the step
//! and frame budget) sit with the code that applies them:
//! [`crate::physics::stability::AUTO_SAFETY`], [`crate::physics::run::MAX_STEPS`].

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// A time-stepping scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Integrator {
    /// Forward Euler exactly as the paper's eq. 1–3: the position update uses
    /// the old velocity v(t). First order; unstable for undamped springs.
    Euler,
    /// Semi-implicit (symplectic) Euler: velocity first, then position with
    /// the new velocity. First order, stable for ωh < 2.
    Symplectic,
    /// Velocity Verlet; velocity-dependent forces are evaluated at the
    /// predicted velocity v + h a, which keeps second order with dashpots and
    /// drag. One force evaluation per step.
    Verlet,
    /// Classical fourth-order Runge–Kutta. Four force evaluations per step.
    Rk4,
    /// Linearised backward Euler (Baraff & Witkin 1998): one Newton step per
    /// time step, solved by preconditioned conjugate gradients. First order,
    /// stable at any step, numerically damped.
    Implicit,
}

impl Integrator {
    /// All integrators, in the order they are reported.
    pub const ALL: [Integrator; 5] = [
        Integrator::Euler,
        Integrator::Symplectic,
        Integrator::Verlet,
        Integrator::Rk4,
        Integrator::Implicit,
    ];

    /// The explicit integrators, whose steps a stability limit bounds.
    pub const EXPLICIT: [Integrator; 4] = [
        Integrator::Euler,
        Integrator::Symplectic,
        Integrator::Verlet,
        Integrator::Rk4,
    ];

    /// The command-line and file name.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Euler => "euler",
            Integrator::Symplectic => "symplectic",
            Integrator::Verlet => "verlet",
            Integrator::Rk4 => "rk4",
            Integrator::Implicit => "implicit",
        }
    }

    /// How far, in units of dt, the new position moves per unit of velocity
    /// gained from a force constant over the step: x_{n+1} gains c h Δv with
    /// Δv = a h. Forward Euler 0 (its position uses the old velocity),
    /// symplectic and backward Euler 1, Verlet and RK4 ½ (h²/2 a). An
    /// impulse applied after the step (ground contact) moves positions by the
    /// same amount, as if it had acted within the step.
    pub fn impulse_position_factor(self) -> f64 {
        match self {
            Integrator::Euler => 0.0,
            Integrator::Symplectic | Integrator::Implicit => 1.0,
            Integrator::Verlet | Integrator::Rk4 => 0.5,
        }
    }

    /// Order of convergence of the global error.
    pub fn order(self) -> u32 {
        match self {
            Integrator::Euler | Integrator::Symplectic | Integrator::Implicit => 1,
            Integrator::Verlet => 2,
            Integrator::Rk4 => 4,
        }
    }
}

impl fmt::Display for Integrator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is no integrator's.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown integrator '{0}' (expected euler, symplectic, verlet, rk4 or implicit)")]
pub struct UnknownIntegrator(pub String);

impl FromStr for Integrator {
    type Err = UnknownIntegrator;
    fn from_str(s: &str) -> Result<Self, UnknownIntegrator> {
        Integrator::ALL
            .into_iter()
            .find(|i| i.name() == s)
            .ok_or_else(|| UnknownIntegrator(s.to_string()))
    }
}

/// How the time step is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimeStep {
    /// A fixed step, s (snapped down to divide the frame interval where a
    /// run needs steps to land on frames, [`crate::physics::run::resolve_dt`]; used as given by
    /// drops, [`crate::physics::run::resolve_step`]).
    Fixed(f64),
    /// From the model's stability estimate (see [`crate::physics::stability::StabilityEstimate::auto_dt`]).
    Auto,
}
