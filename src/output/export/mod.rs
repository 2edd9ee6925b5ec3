//! Export of recorded motion for other tools: binary glTF ([`glb`]), USD
//! text ([`usd`]) and PC2 point caches with rest-pose OBJ meshes ([`pc2`]),
//! plus the common, format-free form all three (and the HTML previewer,
//! [`crate::output::preview`]) start from: a [`Clip`].
//!
//! A clip is a set of objects sampled on one uniform time grid at the output
//! frame rate ([`DEFAULT_FPS`] unless asked otherwise). Recorded frames
//! (240 Hz for drops, the scene's rate for scenes) are resampled onto it by
//! linear interpolation of positions and spherical interpolation of
//! rotations, so a glTF player's LINEAR interpolation between the exported
//! keys stays close to the simulated motion.
//!
//! Objects that move rigidly (rigid bodies, rigid leaves) keep their shape in
//! a body frame and carry a pose per frame; deforming objects (mass-spring
//! leaves, sheets, ropes) carry every vertex's position per frame.

pub mod abc;
mod abc_read;
mod clip;
mod dress;
mod drops;
mod error;
pub mod fall;
mod format;
pub mod frame;
pub mod glb;
mod gltf_data;
mod look;
pub mod pc2;
mod read;
pub mod render_mesh;
mod scene;
mod skin;
pub mod usd;
mod usd_instancer;
mod usd_layer;
mod usd_skel;
mod usd_stage;
mod usda_read;
mod wind;

pub use abc_read::{DEFAULT_POINT_WIDTH_M, MAX_DEATHS_PER_SAMPLE, read_abc};
pub use clip::{
    Clip, ClipObject, DEFAULT_FPS, MARKER_KIND, Motion, POINT_KIND, frame_count, resample_positions,
};
pub use drops::{drop_clip, drop_clip_released, drop_individuals, side_by_side};
pub use error::ExportError;
pub use format::{Format, UnknownFormat};
pub use frame::{Body, Framed};
pub use read::{from_glb, from_glb_bytes, from_scene_dir, read_gltf_keys};
pub use render_mesh::RenderMesh;
pub use scene::from_scene_run;
pub use usd_stage::{ComposeRequest, compose_usd_stage, watch_parent};
pub use usda_read::read_usda_keys;
pub use wind::WindGlyph;
