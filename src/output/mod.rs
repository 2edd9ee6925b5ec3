//! What leaves leafmagic for other tools: falls and scene runs resampled
//! into clips and written as binary glTF or PC2 + OBJ ([`export`]), and one
//! offline HTML page that plays them ([`preview`]).
//!
//! May use: every layer below ([`crate::breed`], [`crate::sim`],
//! [`crate::leaf`], [`crate::motion`], [`crate::physics`], [`crate::util`]).

pub mod export;
pub mod preview;
