//! Utilities beneath every layer: atomic writes and plot helpers. Imports
//! nothing of leafmagic.

pub mod io;
pub mod svg;
