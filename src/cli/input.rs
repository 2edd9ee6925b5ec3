//! Reading what commands are pointed at (a leaf file or an embedded
//! prototype, a recorded fall), with the checks and error contexts that
//! several commands share.

use anyhow::{Result, bail};
use leafmagic::leaf::LeafSpec;
use leafmagic::motion::classify::{self, Classification};
use leafmagic::motion::describe::Descriptors;
use leafmagic::motion::trajectory::{ReadNotes, Trajectory, UpAxis};
use leafmagic::physics::model::Model;
use leafmagic::physics::state::State;
use leafmagic::sim::accuracy;
use std::path::Path;

/// A leaf file, or `a` / `b` for the embedded prototypes, and its model.
pub fn leaf(arg: &str) -> Result<(LeafSpec, Model)> {
    Ok(LeafSpec::load_with_model(arg)?)
}

/// What `accuracy` and `check --stress` run: a named model and its initial
/// state. A leaf is dropped as `drop` drops it; a scene file, once scenes
/// exist, brings its own model and state through this same function.
pub fn problem(arg: &str) -> Result<(String, Model, State)> {
    let (spec, model) = leaf(arg)?;
    let initial = accuracy::default_release(&model);
    Ok((spec.name, model, initial))
}

/// Reads and classifies a recorded fall of a leaf of chord `size`, whose
/// file has `up` as its vertical axis; columns the reader ignored are noted
/// on stderr.
pub fn classify_file(
    path: &Path,
    size: f64,
    up: UpAxis,
) -> Result<(Trajectory, ReadNotes, Classification)> {
    if !(size > 0.0 && size.is_finite()) {
        bail!("--size must be a positive number of metres, got {size}");
    }
    let (traj, notes) = Trajectory::read_csv_with(path, up)?;
    if !notes.ignored_columns.is_empty() {
        eprintln!(
            "note: {}: ignored column{} {}",
            path.display(),
            if notes.ignored_columns.len() > 1 {
                "s"
            } else {
                ""
            },
            notes.ignored_columns.join(", ")
        );
    }
    let c = classify::classify(&traj, size);
    Ok((traj, notes, c))
}

/// Reads and describes a fall, or says why it cannot be described.
pub fn describe_file(path: &Path, size: f64, up: UpAxis) -> Result<Descriptors> {
    let (_, _, c) = classify_file(path, size, up)?;
    Descriptors::of(&c).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}
