//! The files of other tools, read and written: the format-free [`clip`]
//! every reader and writer shares, binary glTF ([`gltf`]), USD ([`usd`]),
//! Alembic ([`alembic`]), PC2 point caches with rest-pose OBJ meshes
//! ([`pc2`]), and the one entry point that turns any supported file into a
//! fall ([`fall`]).
//!
//! What leafmagic builds clips from, its own drops and scene runs, is in
//! [`crate::output::export`]; the HTML preview in [`crate::output::preview`].
//!
//! May use: [`crate::motion`], [`crate::physics`], [`crate::util`].

pub mod alembic;
pub mod clip;
mod error;
pub mod fall;
mod format;
pub mod gltf;
pub mod pc2;
mod sampling;
mod skin;
pub mod usd;

pub use error::ExportError;
pub use format::{Format, UnknownFormat};
