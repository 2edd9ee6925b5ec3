//! Leaves: what is dropped. Leaf files ([`spec`], with the paper's two
//! prototypes of figure 4 embedded), the genome that varies a prototype
//! ([`genome`], the paper's folds, mass distribution and stiffness), the
//! paper's recipes for each motion class ([`recipes`]) and flat plates of
//! the falling-plate literature ([`plates`]).
//!
//! May use: [`crate::physics`] (a leaf becomes a [`crate::physics::model::Model`]), [`crate::util`].

pub mod genome;
pub mod plates;
pub mod recipes;
pub mod spec;

pub use spec::{
    AeroLawName, AeroSpec, BendingSpec, Bounds, FoldSpec, LeafError, LeafSpec, PAPER_ALPHA,
    PROTOTYPE_A, PROTOTYPE_B, ParticleSpec, SpringSpec, TriangleSpec,
};
