//! Motion: what a fall looks like, read from its trajectory alone.
//!
//! [`trajectory`] reads and writes pose CSVs (from leafmagic or any other
//! source), [`classify`] names the motion (the paper's floaters, spinners
//! and lilters, with a sub-regime) of the part [`at_rest`] finds in the
//! air, and [`describe`] turns a fall into
//! descriptors and measures the distance between two falls.
//!
//! May use: [`crate::util`]. Knows nothing of physics: a pose is all it needs.

pub mod at_rest;
pub mod class;
pub mod classify;
pub mod describe;
pub mod path;
mod rules;
pub mod trajectory;
