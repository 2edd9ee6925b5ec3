//! Utilities beneath every layer: atomic writes and folder swaps, the content hash, enum names in files, numbers in messages, plot
//! helpers and a quiet exit when stdout's reader goes away. Imports nothing of leafmagic.

pub mod confined;
pub mod hash;
pub mod io;
pub mod named;
pub mod number;
pub mod pipe;
pub mod svg;
