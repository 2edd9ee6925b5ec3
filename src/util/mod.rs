//! Utilities beneath every layer: atomic writes, numbers in messages and
//! plot helpers. Imports nothing of leafmagic.

pub mod io;
pub mod number;
pub mod svg;
