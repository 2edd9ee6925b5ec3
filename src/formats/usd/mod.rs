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
