//! Why a run stopped: divergence (with the diagnosis a user needs to fix
//! it) or a failed implicit solve; and the limits that count as a runaway.

use crate::physics::params::Integrator;
use crate::util::setting::Setting;
use std::fmt;

/// Why a run stopped before its end.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SimError {
    /// The state became non-finite or ran away.
    #[error("{0}")]
    Diverged(Box<Divergence>),
    /// The implicit solver's conjugate gradients did not converge.
    #[error("{}", solver_failed(*.step, *.time, *.iterations, *.residual))]
    SolverFailed {
        /// Step index (0-based) at which it failed.
        step: u64,
        /// Simulated time at the start of that step, s.
        time: f64,
        /// Iterations spent.
        iterations: usize,
        /// Relative residual reached.
        residual: f64,
    },
}

/// Where and how a run diverged, with what is needed to fix it.
#[derive(Clone, Debug, PartialEq)]
pub struct Divergence {
    /// Step index (0-based) whose result was bad.
    pub step: u64,
    /// Simulated time at the end of that step, s.
    pub time: f64,
    /// The particle with the bad value.
    pub particle: usize,
    /// "position" or "velocity".
    pub quantity: &'static str,
    /// Its magnitude (m or m/s; NaN or inf when non-finite).
    pub value: f64,
    /// The integrator.
    pub integrator: Integrator,
    /// The time step used, s.
    pub dt: f64,
    /// The estimated largest stable step for this integrator, s (None when
    /// unconditionally stable).
    pub dt_max: Option<f64>,
    /// The largest force term on that particle, with its magnitude in N.
    pub dominant_force: (&'static str, f64),
    /// The spring with the largest k (1/m_i + 1/m_j), if any.
    pub stiffest_spring: Option<usize>,
}

/// The message of a failed implicit solve.
fn solver_failed(step: u64, time: f64, iterations: usize, residual: f64) -> String {
    let why = if residual.is_finite() {
        format!("relative residual {residual:.2e}")
    } else {
        // pᵀAp ≤ 0 or overflowed: the linearised system is no longer
        // positive definite; there is no residual to show.
        "the system matrix lost positive definiteness".to_string()
    };
    format!(
        "implicit solver did not converge at step {step} (t = {time:.6} s): {why} \
         after {iterations} CG iterations; the system is ill-conditioned, try a smaller {}",
        Setting::Dt
    )
}

/// The dominant term of a [`Divergence`] whose wind is not finite at the
/// particle: the cause is the field, not the integration.
pub const WIND_NOT_FINITE: &str = "aero: the wind field is not finite at the particle";

impl fmt::Display for Divergence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let d = self;
        if d.quantity == "pose" {
            return write!(
                f,
                "the leaf's pose (centre of mass and best-fit rotation) became non-finite at step {} \
                 (t = {:.6} s) while every particle is finite: particle {} dominates the \
                 mass-weighted sums (m·|x − c| = {}); dominant force term on it: {} ({}); \
                 integrator {}, dt = {:.3e} s; likely cause: masses so large that the \
                 mass-weighted sums overflow f64 (total mass or m·x past 1e308): give the \
                 particles realistic masses (a leaf weighs grams)",
                d.step,
                d.time,
                d.particle,
                if d.value.is_finite() {
                    format!("{:.3e} kg·m", d.value)
                } else {
                    "not finite".to_string()
                },
                d.dominant_force.0,
                if d.dominant_force.1.is_finite() {
                    format!("{:.3e} N", d.dominant_force.1)
                } else {
                    "not finite".to_string()
                },
                d.integrator,
                d.dt
            );
        }
        if d.dominant_force.0 == WIND_NOT_FINITE {
            return write!(
                f,
                "simulation diverged at step {} (t = {:.6} s): particle {} {} became non-finite; \
                 dominant force term: aero (the wind field is not finite at the particle); \
                 integrator {}, dt = {:.3e} s; likely cause: a wind primitive too extreme for \
                 f64 (a core radius so small that its square is 0, or a strength past 1e308): \
                 give every core_radius a physical size (millimetres or more)",
                d.step, d.time, d.particle, d.quantity, d.integrator, d.dt
            );
        }
        let kind = if d.value.is_finite() {
            "ran away"
        } else {
            "became non-finite"
        };
        // Non-finite magnitudes are said in words: a diagnosis never
        // prints NaN.
        let magnitude = |v: f64, unit: &str| {
            if v.is_finite() {
                format!("{v:.3e}{unit}")
            } else {
                "non-finite".to_string()
            }
        };
        write!(
            f,
            "simulation diverged at step {} (t = {:.6} s): particle {} {} {}",
            d.step, d.time, d.particle, d.quantity, kind
        )?;
        if d.value.is_finite() {
            write!(f, " ({:.3e})", d.value)?;
        }
        write!(
            f,
            "; dominant force term: {} ({}); integrator {}, dt = {:.3e} s",
            d.dominant_force.0,
            magnitude(d.dominant_force.1, " N"),
            d.integrator,
            d.dt
        )?;
        match d.dt_max {
            Some(m) if d.dt > m => write!(
                f,
                ", above the estimated stable limit dt_max = {m:.3e} s: \
                 the time step is too large for the stiffness; use the automatic step (`{}`, or `dt = \"auto\"` in a scene file) or a step below dt_max",
                Setting::Dt.set("auto")
            )?,
            Some(m) => write!(
                f,
                ", below the estimated stable limit dt_max = {m:.3e} s; \
                 likely cause: forces growing without bound (extreme wind or parameters)"
            )?,
            None => write!(f, "; likely cause: extreme forces or parameters")?,
        }
        if let Some(s) = d.stiffest_spring {
            write!(f, "; stiffest spring: {s}")?;
        }
        Ok(())
    }
}

/// Speeds above this (m/s), or plus ten times the wind's bound, count as a
/// runaway: no falling leaf or scene object gets anywhere near it, while an
/// unstable integration passes it many steps before overflowing to inf.
pub const RUNAWAY_SPEED: f64 = 1e4;
/// Positions farther than this from the origin (m) count as a runaway.
pub const RUNAWAY_DISTANCE: f64 = 1e7;

/// The speed past which a particle of `model` counts as run away, m/s:
/// [`RUNAWAY_SPEED`] plus ten times its wind's bound.
pub fn runaway_speed(model: &crate::physics::model::Model) -> f64 {
    RUNAWAY_SPEED + 10.0 * model.wind.speed_bound()
}
