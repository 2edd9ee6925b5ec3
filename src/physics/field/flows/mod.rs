//! The registry of flow kinds: each file of this folder defines one kind (or
//! a source and its sink) once, and `flows!` below lists them once.
//!
//! From that list come the public [`Flow`] enum (the parameters), its
//! compiled mirror `FlowEval` (evaluated on the hot path by a `match`, so
//! dispatch is static and nothing is boxed), the TOML `Kind` tag, and every
//! per-kind dispatch (compile, velocity, speed bound, validation, TOML keys).

use std::fmt;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::error::FieldError;
use super::spec::reject_extra;

mod kind;
mod line_source;
mod line_vortex;
mod point_source;
mod uniform;
mod vortex_core;

pub(super) use kind::FlowKeys;
use kind::{Evaluate, FlowKind};
pub use line_source::{LineSink, LineSource};
pub use line_vortex::LineVortex;
#[cfg(test)]
pub(super) use line_vortex::one_minus_exp_over;
pub use point_source::{PointSink, PointSource};
pub use uniform::Uniform;
pub use vortex_core::VortexCore;

/// Generates [`Flow`], `FlowEval`, `Kind` and their dispatch from one line
/// per kind: `Variant(Type) = "toml_kind"`, where `Type: FlowKind`.
macro_rules! flows {
    ($($variant:ident($ty:ident) = $kind:literal,)+) => {
        /// The potential flow a primitive describes (the paper's figure 2):
        /// one variant per kind, holding that kind's parameters.
        #[derive(Clone, Debug, PartialEq)]
        pub enum Flow {
            $(
                #[doc = concat!("TOML kind `", $kind, "`: see [`", stringify!($ty), "`].")]
                $variant($ty),
            )+
        }

        /// Each flow in its compiled form (unit axes, constant factors).
        /// `repr(u8)` gives it a tag of its own: without it rustc folds the
        /// tag into the vortex's inner one, which costs arithmetic on the
        /// tag before every dispatch of the hot path.
        #[derive(Clone, Debug, PartialEq)]
        #[repr(u8)]
        pub(in crate::physics::field) enum FlowEval {
            $($variant(<$ty as FlowKind>::Eval),)+
        }

        /// The `kind` of a `[[wind]]` table.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
        pub(in crate::physics::field) enum Kind {
            $(#[serde(rename = $kind)] $variant,)+
        }

        impl Kind {
            /// Every kind's name, as files write it.
            pub(in crate::physics::field) const NAMES: &'static [&'static str] = &[$($kind,)+];
        }

        impl fmt::Display for Kind {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(match self {
                    $(Kind::$variant => $kind,)+
                })
            }
        }

        $(
            impl From<$ty> for Flow {
                fn from(flow: $ty) -> Self {
                    Flow::$variant(flow)
                }
            }
        )+

        impl Flow {
            /// The compiled form evaluated by [`FlowEval::velocity`].
            pub(in crate::physics::field) fn compile(&self) -> FlowEval {
                match self {
                    $(Flow::$variant(f) => FlowEval::$variant(f.compile()),)+
                }
            }

            /// Peak |v| over all space, m/s.
            pub(in crate::physics::field) fn speed_bound(&self) -> f64 {
                match self {
                    $(Flow::$variant(f) => f.speed_bound(),)+
                }
            }

            /// Checks every number; items are named relative to the primitive.
            pub(in crate::physics::field) fn validate(&self) -> Result<(), FieldError> {
                match self {
                    $(Flow::$variant(f) => f.validate(),)+
                }
            }

            /// The flow's TOML `kind` and keys.
            pub(in crate::physics::field) fn to_keys(&self) -> (Kind, FlowKeys) {
                let mut keys = FlowKeys::default();
                let kind = match self {
                    $(Flow::$variant(f) => {
                        f.to_keys(&mut keys);
                        Kind::$variant
                    })+
                };
                (kind, keys)
            }

            /// The flow of a `[[wind]]` table of this `kind`: keys of other
            /// kinds are rejected first, then missing ones.
            pub(in crate::physics::field) fn from_keys(kind: Kind, keys: &FlowKeys) -> Result<Flow, String> {
                let owner = format!("kind \"{kind}\"");
                match kind {
                    $(Kind::$variant => parse::<$ty>(keys, &owner).map(Flow::$variant),)+
                }
            }
        }

        impl FlowEval {
            /// The flow's velocity at `x` (m), m/s.
            #[inline]
            pub(in crate::physics::field) fn velocity(&self, x: &Vector3<f64>) -> Vector3<f64> {
                match self {
                    $(FlowEval::$variant(e) => e.velocity(x),)+
                }
            }
        }
    };
}

flows! {
    Uniform(Uniform) = "uniform",
    PointSource(PointSource) = "point_source",
    PointSink(PointSink) = "point_sink",
    LineSource(LineSource) = "line_source",
    LineSink(LineSink) = "line_sink",
    LineVortex(LineVortex) = "line_vortex",
}

fn parse<F: FlowKind>(keys: &FlowKeys, owner: &dyn fmt::Display) -> Result<F, String> {
    reject_extra(&keys.present(), F::KEYS, owner)?;
    F::from_keys(keys, owner)
}
