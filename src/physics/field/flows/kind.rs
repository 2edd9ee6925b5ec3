//! What a flow kind provides: the contract every file of `flows/` implements
//! once, and the TOML keys a flow may read.

use std::fmt;

use nalgebra::Vector3;

use super::super::error::FieldError;
use super::vortex_core::VortexCore;

/// One kind of potential-flow primitive: a `kind = "..."` of `[[wind]]`.
///
/// The registry in `flows/mod.rs` dispatches each method through the
/// [`Flow`](super::Flow) enum, so every call is static.
pub(in crate::physics::field) trait FlowKind: Sized {
    /// Keys of the `[[wind]]` table this kind takes, besides the ones every
    /// primitive takes (`keys`, `interpolation`, `bounds`, `front`).
    const KEYS: &'static [&'static str];

    /// The form evaluated on the hot path: unit axes and constant factors
    /// computed once, so [`Evaluate::velocity`] neither allocates nor divides
    /// by what it could have precomputed.
    type Eval: Evaluate;

    /// Precomputes the evaluation form.
    fn compile(&self) -> Self::Eval;

    /// Upper bound of |v| over all space, m/s (used by the stability
    /// estimate); finite because cores are regularised.
    fn speed_bound(&self) -> f64;

    /// Checks every number; items are named relative to the primitive
    /// (`core_radius`).
    fn validate(&self) -> Result<(), FieldError>;

    /// Builds the flow from its table's keys. Keys outside [`FlowKind::KEYS`]
    /// have already been rejected; a missing one is reported as
    /// "`{owner}` requires ..." (see `spec::required`).
    fn from_keys(keys: &FlowKeys, owner: &dyn fmt::Display) -> Result<Self, String>;

    /// Writes the flow's keys, for serialisation.
    fn to_keys(&self, keys: &mut FlowKeys);
}

/// A compiled flow: its velocity v(x), m/s, before bounds, front and keys.
pub(in crate::physics::field) trait Evaluate {
    /// Velocity at `x` (m).
    fn velocity(&self, x: &Vector3<f64>) -> Vector3<f64>;
}

/// The keys of a `[[wind]]` table that belong to its flow: the union over
/// all kinds, each optional; a kind takes those of its [`FlowKind::KEYS`].
///
/// Mirrors the flow part of the primitive's flat serde table (`primitive.rs`),
/// field for field and in its order.
#[derive(Default)]
pub(in crate::physics::field) struct FlowKeys {
    pub velocity: Option<[f64; 3]>,
    pub point: Option<[f64; 3]>,
    pub axis: Option<[f64; 3]>,
    pub flux: Option<f64>,
    pub circulation: Option<f64>,
    pub core_radius: Option<f64>,
    pub core: Option<VortexCore>,
}

impl FlowKeys {
    /// Which keys the table has, in table order (the first one a kind does
    /// not take is the one reported).
    pub(in crate::physics::field) fn present(&self) -> [(&'static str, bool); 7] {
        [
            ("velocity", self.velocity.is_some()),
            ("point", self.point.is_some()),
            ("axis", self.axis.is_some()),
            ("flux", self.flux.is_some()),
            ("circulation", self.circulation.is_some()),
            ("core_radius", self.core_radius.is_some()),
            ("core", self.core.is_some()),
        ]
    }
}

/// `[x, y, z]` of a TOML array, for [`FlowKind::to_keys`].
pub(in crate::physics::field) fn array(v: &Vector3<f64>) -> Option<[f64; 3]> {
    Some([v.x, v.y, v.z])
}
