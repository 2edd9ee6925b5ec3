//! Clips of what leafmagic itself ran, for the writers of
//! [`crate::formats`] and the preview: drops of bred individuals, side by
//! side ([`drop_clip`], [`drop_individuals`], [`side_by_side`]), and scene
//! runs, in memory ([`from_scene_run`]) or read back from a scene's output
//! directory ([`from_scene_dir`]). These need the simulator and the breeding
//! run, which the formats layer knows nothing of.

mod drops;
mod scene;
mod scene_dir;

pub use drops::{drop_clip, drop_clip_released, drop_individuals, side_by_side};
pub use scene::from_scene_run;
pub use scene_dir::from_scene_dir;
