//! Reading what commands are pointed at (a leaf file or an embedded
//! prototype, a recorded fall), with the checks and error contexts that
//! several commands share.

use super::args::{LawArg, law_word};
use anyhow::{Result, bail};
use leafmagic::formats::fall::{self, AnimationFall, AnimationFormat, RecordedFall};
use leafmagic::leaf::LeafSpec;
use leafmagic::motion::classify::{self, Classification};
use leafmagic::motion::describe::Descriptors;
use leafmagic::motion::trajectory::{ReadNotes, Trajectory, UpAxis};
use leafmagic::physics::model::Model;
use leafmagic::physics::state::State;
use leafmagic::sim::accuracy;
use std::path::Path;

/// A leaf file, or `a` / `b` for the embedded prototypes, under `--law`
/// if given ([`LeafSpec::under_law`]), and its model; a scene file given
/// instead is named as one, with the command it wants.
pub fn leaf(arg: &str, law: Option<LawArg>) -> Result<(LeafSpec, Model)> {
    let (spec, model) = leaf_as_written(arg)?;
    match law {
        Some(law) if law.law() != spec.aero.law => {
            let spec = spec.under_law(law.law());
            let model = spec
                .model()
                .map_err(|e| anyhow::anyhow!("{arg} under --law {}: {e}", law_word(law.law())))?;
            Ok((spec, model))
        }
        _ => Ok((spec, model)),
    }
}

/// [`leaf`] under its own file's law.
fn leaf_as_written(arg: &str) -> Result<(LeafSpec, Model)> {
    LeafSpec::load_with_model(arg).map_err(|e| {
        let hint = (toml_kind(Path::new(arg)) == Some(TomlKind::Scene)).then(|| {
            format!(
                "\nhint: {arg} is a scene file ([[leaf]], [[rigid]], [[wind]] ... tables), not a leaf: run it with `leafmagic scene {arg}`"
            )
        });
        anyhow::anyhow!("{e}{}", hint.unwrap_or_default())
    })
}

/// Which of leafmagic's TOML files a file looks like, by its top-level
/// tables: what a wrong-file error can name.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TomlKind {
    /// A leaf file (`[[particle]]`, `[[triangle]]`, `[[spring]]`).
    Leaf,
    /// A scene file (`[[leaf]]`, `[[rigid]]`, `[[sheet]]`, `[[rope]]`, `duration`).
    Scene,
}

/// The kind of TOML file at `path`, if it parses and says; files over
/// 64 MiB are not looked at.
pub fn toml_kind(path: &Path) -> Option<TomlKind> {
    if std::fs::metadata(path).ok()?.len() > 64 << 20 {
        return None;
    }
    let table: toml::Table = std::fs::read_to_string(path).ok()?.parse().ok()?;
    let has = |keys: &[&str]| keys.iter().any(|k| table.contains_key(*k));
    if has(&["leaf", "rigid", "sheet", "rope", "duration", "frame_rate"]) {
        Some(TomlKind::Scene)
    } else if has(&["particle", "triangle", "spring"]) {
        Some(TomlKind::Leaf)
    } else {
        None
    }
}

/// What `accuracy` and `check --stress` run: a named model and its initial
/// state. A leaf is dropped as `drop` drops it; a scene file, once scenes
/// exist, brings its own model and state through this same function.
/// The name says the law: `leaf-a (paper law)`.
pub fn problem(arg: &str, law: Option<LawArg>) -> Result<(String, Model, State)> {
    let (spec, model) = leaf(arg, law)?;
    let initial = accuracy::default_release(&model);
    let name = format!("{} ({} law)", spec.name, law_word(spec.aero.law));
    Ok((name, model, initial))
}

/// The chord `classify` assumes for a CSV record when no `--size` is
/// given, m (an animation file gives its mesh's own).
pub const DEFAULT_SIZE_M: f64 = leafmagic::motion::classify::DEFAULT_CHORD_M;

/// A recorded fall as read: the record, what reading it noted, and what
/// an animation file told of it.
pub struct Record {
    /// The record.
    pub trajectory: Trajectory,
    /// What the CSV reader noted (empty for an animation file).
    pub notes: ReadNotes,
    /// For an animation file: the object read from it.
    pub object: Option<String>,
    /// For an animation file: the object's chord (longest extent), m.
    pub chord: Option<f64>,
    /// For an animation file: what its reader left out without refusing
    /// it, printed as `warning: FILE: …` and listed by `--json`.
    pub warnings: Vec<String>,
}

impl Record {
    /// The chord to classify the record with: `size` if given, else the
    /// animation's own, else [`DEFAULT_SIZE_M`] for a CSV record, which
    /// does not say.
    pub fn size_or(&self, size: Option<f64>) -> f64 {
        size.or(self.chord).unwrap_or(DEFAULT_SIZE_M)
    }
}

/// A recorded fall, read and classified.
pub struct Fall {
    /// The record.
    pub record: Record,
    /// Its classification.
    pub classification: Classification,
    /// The chord it was classified with, m.
    pub size: f64,
}

/// Checks a `--size` given on the command line.
pub fn check_size(size: Option<f64>) -> Result<()> {
    match size {
        Some(s) if !(s > 0.0 && s.is_finite()) => {
            bail!("--size must be a positive number of metres, got {s}")
        }
        _ => Ok(()),
    }
}

/// How a CSV record's numbers are read (`--up`, `--scale`, `--frame-rate`):
/// the library's [`fall::RecordUnits`].
pub use leafmagic::formats::fall::RecordUnits as CsvUnits;

/// Checks the flags: a finite, positive scale and frame rate.
fn check_units(units: &CsvUnits) -> Result<()> {
    if !(units.scale > 0.0 && units.scale.is_finite()) {
        bail!(
            "--scale must be a positive number of metres per unit of the file's lengths, got {}",
            units.scale
        );
    }
    if let Some(r) = units.frame_rate
        && !(r > 0.0 && r.is_finite())
    {
        bail!("--frame-rate must be a positive number of frames per second, got {r}");
    }
    Ok(())
}

/// Which fall of an animation file to read: the object where several move
/// (`--object`), and the glTF animation where several move it
/// (`--animation`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Pick<'a> {
    /// The object's name.
    pub object: Option<&'a str>,
    /// The animation's name (or index).
    pub animation: Option<&'a str>,
    /// What the file's references may reach and its read may take
    /// [default: its own folder, the default budget].
    pub policy: Option<&'a leafmagic::util::confined::ReadPolicy>,
}

/// Reads a recorded fall: a CSV record read in `units`, or an animation
/// file (glTF, y up by its specification; USD, as its stage says), of
/// which `pick` names the fall to read where it holds several
/// ([`fall::read_any_fall`] decides which). What the reading noticed goes
/// to stderr.
pub fn read_record(path: &Path, units: CsvUnits, pick: Pick<'_>) -> Result<Record> {
    check_units(&units)?;
    let default = leafmagic::util::confined::ReadPolicy::default();
    let policy = pick.policy.unwrap_or(&default);
    let read = fall::read_any_fall(path, units, pick.object, pick.animation, policy)?;
    let record = match read {
        RecordedFall::Record { trajectory, notes } => {
            note_csv(path, &notes);
            Record {
                trajectory,
                notes,
                object: None,
                chord: None,
                warnings: Vec::new(),
            }
        }
        RecordedFall::Animation { format, fall } => note_animation(path, units, format, fall),
    };
    for note in implausible_units(&record.trajectory) {
        eprintln!("note: {}: {note}", path.display());
    }
    Ok(record)
}

/// Reads and classifies a recorded fall ([`read_record`]) with chord `size`
/// (default: an animation's own, [`DEFAULT_SIZE_M`] for a CSV record).
pub fn read_fall(path: &Path, size: Option<f64>, units: CsvUnits, pick: Pick<'_>) -> Result<Fall> {
    check_size(size)?;
    let record = read_record(path, units, pick)?;
    let size = record.size_or(size);
    let classification = classify::classify(&record.trajectory, size);
    Ok(Fall {
        record,
        classification,
        size,
    })
}

/// What reading a CSV record noticed, to stderr.
fn note_csv(path: &Path, notes: &ReadNotes) {
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
    if let Some(depth) = &notes.depth_missing {
        eprintln!(
            "note: {}: no column `{depth}`: read as a fall in a vertical plane (one camera's view), its `{depth}` 0; the drift is the plane's, and a helix about the vertical reads as a swing in it",
            path.display()
        );
    }
    if let Some(lost) = &notes.lost_rows {
        eprintln!(
            "note: {}: left out {} row{} without a position (every position field empty or NaN: frames where the tracker lost the leaf), lines {}–{}",
            path.display(),
            lost.count,
            if lost.count > 1 { "s" } else { "" },
            lost.first_line,
            lost.last_line
        );
    }
}

/// [`read_record`] of an animation file: what reading it noticed, to
/// stderr, and its fall as a record.
fn note_animation(
    path: &Path,
    units: CsvUnits,
    format: AnimationFormat,
    fall: AnimationFall,
) -> Record {
    for warning in &fall.warnings {
        eprintln!("warning: {}: {warning}", path.display());
    }
    if units.up != UpAxis::Z {
        eprintln!(
            "note: {}: --up does not apply to an animation file, which says its own up axis (glTF: y; USD: its upAxis; Alembic: y): read as such",
            path.display()
        );
    }
    // Alembic carries no unit: --scale says what one is (the library
    // applied it).
    let alembic = format == AnimationFormat::Alembic;
    if (units.scale != 1.0 && !alembic) || units.frame_rate.is_some() {
        eprintln!(
            "note: {}: {} not apply to an animation file, which says its own units (glTF: metres and seconds; USD: metersPerUnit and timeCodesPerSecond; Alembic: seconds, and metres unless --scale says otherwise): read as such",
            path.display(),
            if alembic {
                "--frame-rate does"
            } else {
                "--scale and --frame-rate do"
            }
        );
    }
    let appears = if fall.appears_s > 0.0 {
        format!(
            " (it appears {:.2} s after the file's first key; its times start there)",
            fall.appears_s
        )
    } else {
        String::new()
    };
    eprintln!(
        "note: {}: object `{}`, {} keys at {} Hz, chord {:.4} m{appears}",
        path.display(),
        fall.object,
        fall.trajectory.len(),
        fall.rate_hz,
        fall.chord,
    );
    if !fall.still.is_empty() {
        eprintln!(
            "note: {}: left out what does not move: {}",
            path.display(),
            fall.still.join(", ")
        );
    }
    if let Some(why) = &fall.no_orientation {
        eprintln!("note: {}: {why}", path.display());
    }
    Record {
        trajectory: fall.trajectory,
        notes: ReadNotes::default(),
        object: Some(fall.object),
        chord: Some(fall.chord),
        warnings: fall.warnings,
    }
}

/// Fastest mean descent through air a leaf-like fall is taken to have,
/// m/s: a paper card diving edge-on falls at a few metres per second,
/// leafmagic's fastest divers at 8 (docs/reference.md, the archive), raindrops at 9.
/// A record faster than this on average is more likely written in
/// millimetres, centimetres or pixels than in metres (our choice, with
/// room).
const MAX_PLAUSIBLE_DESCENT_M_S: f64 = 25.0;

/// Longest median interval between samples of a record whose time is in
/// seconds, s: no camera or simulator records a fall at under 2 frames per
/// second, while a time column in frames steps by 1 and one in
/// milliseconds by 10 or more (our choice).
const MAX_PLAUSIBLE_INTERVAL_S: f64 = 0.5;

/// Why a record's units look wrong, if they do: lengths in millimetres read
/// a thousand times too fast and are still classified (the classes are
/// scale-free) with nonsense speeds; a time in frames or milliseconds reads
/// as a record sampled at 1 Hz or less, refused for its rate without saying
/// why it is so slow.
fn implausible_units(traj: &Trajectory) -> Vec<String> {
    let mut notes = Vec::new();
    let (Some(&t0), Some(&t1), Some(p0), Some(p1)) = (
        traj.time.first(),
        traj.time.last(),
        traj.position.first(),
        traj.position.last(),
    ) else {
        return notes;
    };
    let n = traj.len();
    if n < 2 {
        return notes;
    }
    let mut steps: Vec<f64> = traj.time.windows(2).map(|w| w[1] - w[0]).collect();
    let mid = steps.len() / 2;
    let median = *steps.select_nth_unstable_by(mid, f64::total_cmp).1;
    if median > MAX_PLAUSIBLE_INTERVAL_S {
        notes.push(format!(
            "its samples are {median:.3} s apart (median), slower than any camera or simulator records a fall: t must be in seconds; is it in frames or milliseconds? (--frame-rate FPS reads a t that counts frames)"
        ));
    }
    let fall = p0.z - p1.z;
    let speed = fall / (t1 - t0);
    if speed > MAX_PLAUSIBLE_DESCENT_M_S {
        notes.push(format!(
            "it falls {fall:.3} m in {:.3} s ({speed:.0} m/s on average), faster than leaves fall through air (under {MAX_PLAUSIBLE_DESCENT_M_S} m/s): x, y, z must be in metres; is the file in millimetres, centimetres or image pixels? (--scale METRES_PER_UNIT reads them, --up=-y a y that counts image rows down)",
            t1 - t0
        ));
    }
    notes
}

/// Reads and describes a fall (see [`read_fall`]), or says why it cannot
/// be described.
pub fn describe_fall(
    path: &Path,
    size: Option<f64>,
    units: CsvUnits,
    pick: Pick<'_>,
) -> Result<(Fall, Descriptors)> {
    let fall = read_fall(path, size, units, pick)?;
    let d = describe(path, &fall.classification)?;
    Ok((fall, d))
}

/// The descriptors of a classified fall read from `path`, or why it has
/// none.
pub fn describe(path: &Path, c: &Classification) -> Result<Descriptors> {
    Descriptors::of(c).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}
