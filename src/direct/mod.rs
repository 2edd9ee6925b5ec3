//! Directing leaves (issue 62; the paper's section 5: forces generated
//! "from higher levels of abstraction"): a scene file states goals for its
//! leaves (`[[goal]]`: land in a region, pass a point at a time, stay in a
//! volume, enter the bin by a time) and which of its numbers are free
//! (`[[free]]`, with bounds), and a search finds values that meet the goals,
//! judged on runs of the scene: CMA-ES against random search with the same
//! budget.
//!
//! It runs scenes, so it sits above `sim` (whose scene files carry the two
//! tables and ignore them) and beside `breed`, whose CMA-ES it uses.
//!
//! Its files, one job each: `error` (where a table's error is reported),
//! `geometry` (regions and distances to them),
//! `goals` (goals checked and judged on a run's tracks), `free` (free
//! parameters: paths into the file, bounds, substitution), `problem` (a
//! scene file with both, and one evaluation), `search` (CMA-ES and the
//! random baseline over threads), `files` (the solved scene, the
//! history and the checkpoint a search resumes from written and read),
//! `record` (a plain scene run's goals judged, for `goals.json`).

pub mod error;
pub mod files;
pub mod free;
pub mod geometry;
pub mod goals;
pub mod problem;
pub mod record;
pub mod search;

#[cfg(test)]
mod tests;

pub use problem::{Evaluation, Problem};
pub use search::{Method, Outcome, Record, Settings, State, search};
