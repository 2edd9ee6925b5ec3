//! Wind velocity fields: superposed potential-flow primitives (the paper's
//! section 2.2, eq. 4–5 and figure 2).
//!
//! A [`WindField`] maps a position and a time to the wind velocity G(x, t)
//! (m/s). Each [`Primitive`] is an analytic solution of Laplace's equation
//! ∇²φ = 0 with v = ∇φ, so any sum of them is still inviscid, incompressible
//! and irrotational, except where we deliberately depart from the paper:
//!
//! - **Regularised cores.** Sources, sinks and vortices are singular on their
//!   point or axis; each carries a `core_radius` that smooths the core so G is
//!   finite everywhere (a vortex core has vorticity, a smoothed source has a
//!   distributed divergence that integrates to the same total flux).
//! - **Bounds and moving fronts** multiply a primitive by a smooth weight in
//!   [0, 1]; inside the falloff band the field is no longer divergence-free.
//!   They realise the paper's "bounded" fields and the shockwave of its
//!   section 4.2 directly instead of with rows of sinks.
//! - **Keyframed strength** makes any primitive time-varying.
//!
//! The paper's "source" formula v_r = a/(2πr), φ = a ln(r)/2π, is the 2-D
//! *line* source (r is the distance to an axis); here it is
//! [`LineSource`]. A true 3-D point source is [`PointSource`].
//!
//! Units: SI, f64, z up. Velocities m/s, lengths m, time s.
//!
//! The evaluation path ([`WindField::velocity`]) does not allocate: unit axes,
//! normals and constant factors are computed once when a primitive is built
//! or deserialised. Call [`WindField::validate`] after loading; fields that
//! fail validation may evaluate to NaN.
//!
//! # Layout
//!
//! A flow kind is defined once, in a file of `flows/`: its parameters (the
//! public struct its [`Flow`] variant holds), its compiled form and velocity,
//! its speed bound, validation and TOML keys, as the implementation of one
//! crate-private trait, `FlowKind`. The registry, `flows/mod.rs`, lists the
//! kinds one `flows!` line each and generates from that list the [`Flow`]
//! enum, its compiled mirror, the TOML `kind` tag and every per-kind `match`.
//! Dispatch is an enum `match` rather than a trait object because
//! [`WindField::velocity`] is sampled at every particle every step: it stays
//! static, inlinable and allocation-free, as it was. What all primitives share
//! has a file of its own: [`Primitive`] and its `[[wind]]` table
//! (`primitive.rs`), [`Bounds`] (`bounds.rs`), [`Front`] (`front.rs`),
//! [`Keyframes`] (`keys.rs`), the falloff weight (`weight.rs`), [`FieldError`]
//! and the number checks (`error.rs`), the key checks of every table
//! (`spec.rs`), and which primitives can act together, for the field's speed
//! bound (`reach.rs`). No file imports from the `mod.rs` above it (the tests aside)
//! or from a file that imports it back; that is why [`VortexCore`], named by
//! the vortex and by the TOML keys alike, has a file of its own
//! (`flows/vortex_core.rs`).
//!
//! Adding a kind: its file in `flows/` (parameters, `FlowKind` and its
//! `Eval`), then in `flows/mod.rs` a `mod` line, a `pub use` line and its line
//! in `flows!`, and its name in the `pub use flows::{...}` below. Only a TOML
//! key that no kind has used before also needs a field in `FlowKeys`
//! (`flows/kind.rs`) and in the primitive's table (`primitive.rs`).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

mod bounds;
mod error;
mod flows;
mod front;
mod keys;
mod primitive;
mod reach;
mod spec;
mod weight;

#[cfg(test)]
mod tests;

pub use bounds::{Bounds, Region};
pub use error::FieldError;
pub use flows::{
    Flow, LineSink, LineSource, LineVortex, PointSink, PointSource, Uniform, VortexCore,
};
pub use front::Front;
pub use keys::{Interpolation, Keyframes};
pub use primitive::Primitive;

/// Superposition of wind primitives (the paper's eq. 4–5 and figure 2):
/// G(x, t) = Σ_i G_i(x, t).
///
/// In TOML it is an array of tables `[[wind]]`, one per [`Primitive`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct WindField {
    primitives: Vec<Primitive>,
}

impl WindField {
    /// Still air: no primitives, G ≡ 0.
    pub fn still() -> Self {
        Self::default()
    }

    /// A field made of the given primitives, summed.
    pub fn new(primitives: Vec<Primitive>) -> Self {
        Self { primitives }
    }

    /// The primitives, in the order they are summed.
    pub fn primitives(&self) -> &[Primitive] {
        &self.primitives
    }

    /// True when there are no primitives, so callers may skip wind evaluation.
    pub fn is_still(&self) -> bool {
        self.primitives.is_empty()
    }

    /// Wind velocity G(x, t) in m/s at position `x` (m) and time `t` (s).
    #[inline]
    pub fn velocity(&self, x: &Vector3<f64>, t: f64) -> Vector3<f64> {
        let mut g = Vector3::zeros();
        for p in &self.primitives {
            g += p.velocity(x, t);
        }
        g
    }

    /// [`WindField::velocity`] summing only the primitives with
    /// `active[i]` true. Bit for bit the full sum when every left-out
    /// primitive would give exact zeros: the sum starts at +0 and an IEEE
    /// sum is −0 only if both terms are, so it is never −0, and g + 0 = g.
    #[inline]
    pub fn velocity_of(&self, x: &Vector3<f64>, t: f64, active: &[bool]) -> Vector3<f64> {
        let mut g = Vector3::zeros();
        for (p, &on) in self.primitives.iter().zip(active) {
            if on {
                g += p.velocity(x, t);
            }
        }
        g
    }

    /// Checks every number of every primitive.
    ///
    /// # Errors
    /// The first bad item, named as `wind[i].name` (e.g. `wind[2].core_radius`,
    /// `wind[0].bounds.falloff`, `wind[1].keys[3]`).
    pub fn validate(&self) -> Result<(), FieldError> {
        for (i, p) in self.primitives.iter().enumerate() {
            p.validate().map_err(|e| e.within(&format!("wind[{i}]")))?;
        }
        Ok(())
    }

    /// Upper bound of |G| over all space and time (m/s): the largest speed
    /// of a group of primitives whose regions (with their falloff bands)
    /// can meet, uniform primitives without keys added as vectors and the
    /// others by peak speed times largest |keyframe multiplier| (`reach.rs`);
    /// never more than the sum of every primitive's peak speed. Exact for a
    /// single primitive without bounds; finite because cores are
    /// regularised.
    pub fn speed_bound(&self) -> f64 {
        reach::speed_bound(&self.primitives)
    }
}
