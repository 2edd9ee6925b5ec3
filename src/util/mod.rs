//! Utilities beneath every layer: one shape for a bad input's error and the TOML line lookup it uses, atomic writes and folder swaps, the content hash, enum names in files, numbers in messages, the
//! settings a message names ([`setting::Setting`]), plot helpers and a quiet exit when stdout's reader goes away. Imports nothing of leafmagic.

pub mod bad_input;
pub mod confined;
pub mod hash;
pub mod io;
pub mod named;
pub mod number;
pub mod pipe;
pub mod setting;
pub mod svg;
pub mod toml_lines;
