//! leafmagic: design the motion of falling leaves by breeding them in a
//! physically based simulator (after Haumann et al., "An Application of
//! Motion Design and Control for Physically-Based Animation").
//!
//! Data flow: a leaf file ([`leaf`]) becomes an immutable [`model::Model`];
//! [`integrate::Simulator`] advances a mutable [`state::State`] under the
//! forces of [`force`] (gravity, springs, the paper's per-triangle
//! aerodynamics in the wind of [`field`]); [`sim`] runs frames and records
//! poses ([`pose`]) into a trajectory.
#![warn(missing_docs)]

pub mod accuracy;
pub mod aero;
pub mod breed;
pub mod classify;
pub mod contact;
pub mod describe;
pub mod executor;
pub mod export;
pub mod field;
pub mod force;
pub mod genome;
pub mod integrate;
pub mod io;
pub mod leaf;
pub mod model;
pub mod plates;
pub mod plot;
pub mod pose;
pub mod preview;
pub mod recipes;
pub mod rigid;
pub mod scene;
pub mod shard;
pub mod sim;
pub mod stability;
pub mod state;
pub mod stress;
pub mod terms;
pub mod trajectory;
