//! What the commands print for a person to read: the tables and lines made
//! from the library's results, returned as text for the command to print.
//! A file per group of commands, as the commands are. `--json` output is not
//! here: it is the results themselves, serialized by the command.

pub mod accuracy;
pub mod breed;
pub mod drop;
pub mod motion;
pub mod output;
pub mod scene;

use std::fmt;

/// The text `write` writes. Reports are written with `writeln!` and `?`;
/// formatting into a `String` does not fail.
fn text(write: impl FnOnce(&mut String) -> fmt::Result) -> String {
    let mut out = String::new();
    write(&mut out).expect("formatting into a String does not fail");
    out
}
