//! Utilities beneath every layer: atomic writes, numbers in messages, plot
//! helpers and a quiet exit when stdout's reader goes away. Imports nothing of leafmagic.

pub mod confined;
pub mod io;
pub mod number;
pub mod pipe;
pub mod svg;
