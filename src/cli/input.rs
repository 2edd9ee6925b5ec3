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
    if let Some(note) = implausible_units(&traj) {
        eprintln!("note: {}: {note}", path.display());
    }
    let c = classify::classify(&traj, size);
    Ok((traj, notes, c))
}

/// Fastest mean descent through air a leaf-like fall is taken to have,
/// m/s: a paper card diving edge-on falls at a few metres per second,
/// leafmagic's fastest divers at 8 (README, the archive), raindrops at 9.
/// A record faster than this on average is more likely written in
/// millimetres or centimetres than in metres (our choice, with room).
const MAX_PLAUSIBLE_DESCENT_M_S: f64 = 25.0;

/// Why a record's lengths look like they are not in metres, if they do: a
/// fall in millimetres reads a thousand times too fast, and is still
/// classified (the classes are scale-free) with nonsense speeds.
fn implausible_units(traj: &Trajectory) -> Option<String> {
    let (n, (t0, t1)) = (traj.len(), (traj.time.first()?, traj.time.last()?));
    let fall = traj.position.first()?.z - traj.position.last()?.z;
    let speed = fall / (t1 - t0);
    (n > 1 && speed > MAX_PLAUSIBLE_DESCENT_M_S).then(|| {
        format!(
            "it falls {fall:.3} m in {:.3} s ({speed:.0} m/s on average), faster than leaves fall through air (under {MAX_PLAUSIBLE_DESCENT_M_S} m/s): x, y, z must be in metres; is the file in millimetres or centimetres?",
            t1 - t0
        )
    })
}

/// Reads and describes a fall, or says why it cannot be described.
pub fn describe_file(path: &Path, size: f64, up: UpAxis) -> Result<Descriptors> {
    let (_, _, c) = classify_file(path, size, up)?;
    Descriptors::of(&c).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}
