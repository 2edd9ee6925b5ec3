//! glTF 2.0: the binary glTF leafmagic writes ([`write_glb`]) and the
//! reader of any glTF 2.0 file, `.glb` or `.gltf` ([`from_glb`] for what a
//! player shows, [`read_gltf_keys`] at the file's own keys for a fall): its
//! node tree composed, skinned meshes posed by their joints
//! (`formats::skin`), morph targets blended.
//!
//! The `gltf` crate parses and validates the document; what is written by
//! hand here is what it leaves to its user: the layout of our own file, the
//! sampling of animation channels, and the checks of accessors and buffers
//! against hostile files.

mod data;
mod read;
mod write;

pub use read::{from_glb, from_glb_bytes, read_gltf_keys};
pub use write::{glb_bytes, write_glb};
