//! USD: the text layer (`.usda`) leafmagic writes ([`write_usd`]) and the
//! reader of USD stages: a text layer read by hand ([`read_usda_keys`]:
//! meshes, transforms, UsdSkel skinning and blend shapes, PointInstancers),
//! and a crate file, a package or a composed stage flattened first by the
//! `openusd` crate, in a child process ([`compose_usd_stage`]).
//!
//! - `write`'s text layer: one mesh per object, time-sampled points or
//!   transforms;
//! - `layer`: the grammar of a text layer, parsed into prims and
//!   attributes, and what it refuses;
//! - `read`: a flattened layer's meshes sampled into a clip;
//! - `skel`, `instancer`: UsdSkel skinning and blend shapes, PointInstancers;
//! - `stage`: composition (sublayers, references, payloads, variants,
//!   crate files and packages) into one flat layer.
//!
//! The text grammar (`layer`) is our own and runs in this process; the
//! `openusd` crate, pinned at 0.6 (`Cargo.toml`), runs only in the child,
//! because 0.6 trusts the counts a damaged crate file gives and can abort
//! the process that reads it. openusd 0.8 bounds those counts, but 0.7 and
//! later need Rust 1.96; once the toolchain allows it, openusd could read
//! text layers in this process too and take over `layer`'s hand-written
//! grammar, leaving ours only what `read`, `skel` and `instancer` take
//! from a flat stage.

mod instancer;
mod layer;
mod read;
mod skel;
mod stage;
mod write;

pub(crate) use read::read_usd_file;
pub use read::read_usda_keys;
pub use stage::{ComposeRequest, compose_usd_stage, watch_parent};
pub(crate) use write::unique_identifiers;
pub use write::{USDC_HINT, identifier, usd_bytes, write_usd};
