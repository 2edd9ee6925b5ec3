//! What leaves leafmagic: clips of its own drops and scene runs ([`export`]),
//! which the writers of [`crate::formats`] turn into glTF, USD, Alembic or
//! PC2 + OBJ, one offline HTML page that plays them ([`preview`]), and
//! verdicts as a CI pipeline's JUnit XML report ([`junit`]).
//!
//! May use: every layer below ([`crate::breed`], [`crate::sim`],
//! [`crate::leaf`], [`crate::formats`], [`crate::motion`],
//! [`crate::physics`], [`crate::util`]).

pub mod export;
pub mod junit;
pub mod preview;
