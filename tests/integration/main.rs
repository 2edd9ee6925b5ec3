//! Integration tests: one binary (one link on a 2-core machine), one module
//! per topic. Oracles are exact where the notes give one (numerics notes §3).

mod aero_law;
mod alloc;
mod classes;
mod common;
mod genome;
mod integrators;
mod invariants;
mod leaves;
mod stability;
mod validation;
