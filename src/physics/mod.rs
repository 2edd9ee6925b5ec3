//! The simulator of the paper's section 2: point masses joined by springs,
//! moved by Newton's law under gravity, wind and ground contact.
//!
//! Data: [`params`] (integrator, time-step policy) and [`model`] (the
//! immutable model and its parts) import nothing of forces or integrators;
//! [`state`] is what changes. [`field`] is the wind G(x, t). [`aero`] is the
//! aerodynamic law, one module per law (linear, quadratic, unsteady), each
//! owning its coefficients and leaf-file keys (the model's data), its one
//! validation, its forces, its rate bounds for the auto step and its cost.
//! The engine: [`forces`] (each term fills the accumulator), [`terms`]
//! (which terms a model needs), [`rigid`], [`contact`], [`pose`],
//! [`stability`], [`integrate`] (the step), [`batch`] (leaves in lockstep)
//! and [`run`] (the frame loops).
//!
//! May use: [`crate::util`]. Nothing above it.
//!
//! # The paper's equations and where they are
//!
//! | eq. | what | implemented by |
//! |---|---|---|
//! | 1 | a = F/m | [`forces::Forces::acceleration`] |
//! | 2–3 | forward Euler: v(t+h) = v + a h, r(t+h) = r + v h | [`integrate::Simulator`] (`Integrator::Euler`; four more schemes beside it) |
//! | 4–5 | wind as a superposition of potential flows, G = Σ Gᵢ | [`field::WindField::velocity`], [`field::Primitive::velocity`] |
//! | 6 | relative velocity v_r = G(x) − v | [`aero::triangle_aero`], [`forces::particle_drag`] |
//! | 7 | drag on a particle, F = α v_r | [`forces::particle_drag`] |
//! | 8 | normal and tangential parts of v_r | [`aero::linear::kernel::LinearTriangle`] |
//! | 9–10 | Fⁿ = αⁿ A vⁿ, Fᵗ = αᵗ A vᵗ per triangle | [`aero::linear`], one kernel over lanes ([`aero::linear::kernel`]; the laws that replace it: [`aero::quadratic`], [`aero::unsteady`]) |
//!
//! Springs and dashpots (section 2.1): [`forces::springs`]; bending:
//! [`forces::hinges`]; breaking: [`integrate::break_springs`]; rigid bodies
//! (after Hahn 1988): [`rigid`]; ground contact: [`contact`].

pub mod aero;
pub mod batch;
pub mod contact;
pub mod field;
pub mod forces;
pub mod integrate;
pub mod model;
pub mod params;
pub mod pose;
pub mod rigid;
pub mod run;
pub mod skip;
pub mod stability;
pub mod state;
pub mod terms;
