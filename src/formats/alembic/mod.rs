//! Alembic (Ogawa): the archive leafmagic writes ([`write_abc`]: an
//! `AbcGeom_Xform` and `AbcGeom_PolyMesh` per object) and the reader of any
//! Ogawa archive as Blender, Houdini and Maya write them ([`read_abc`]:
//! transforms, meshes and point clouds, at the archive's own samples).
//!
//! Both are our own code against the layout the Alembic 1.8 library writes
//! (no maintained Rust reader exists; see `read`'s module doc).

mod read;
mod write;

pub use read::{DEFAULT_POINT_WIDTH_M, MAX_DEATHS_PER_SAMPLE, read_abc};
pub use write::write_abc;
