//! The record of a fall: time, centre position and, when the source has
//! them, the orientation of the leaf and the projected areas a camera saw;
//! and its CSV form.
//!
//! File format: one header line naming the columns, then one line per
//! sample; fields separated by commas, or by tabs or semicolons when the
//! header has no comma (with semicolons, a comma is the decimal mark).
//! Columns are found by name, in any order:
//!
//! | column | | meaning |
//! |---|---|---|
//! | `t` | required | time, s, strictly increasing |
//! | `x`, `y`, `z` | required: the vertical and at least one other | centre position, m, world frame, z up (gravity along −z; `y` up with [`UpAxis::Y`]); without one horizontal column, a fall seen by one camera in a vertical plane, its depth read as 0 ([`ReadNotes::depth_missing`]) |
//! | `qw`, `qx`, `qy`, `qz` | optional, all four or none | orientation quaternion taking body vectors to the world frame, scalar first; body z is the plate normal, body x the long axis |
//! | `area`, `area1`, `area2`, `area_…` | optional, any number | projected area of the leaf seen by a camera, any unit (video tracking) |
//!
//! Other columns are ignored and listed in [`ReadNotes::ignored_columns`].
//! What `drop` and scenes write is the pose form:
//!
//! ```text
//! t,x,y,z,qw,qx,qy,qz
//! 0,0,0,0,1,0,0,0
//! ```
//!
//! and a record of video tracking may look like `t,x,y,z,area1,area2`.
//!
//! Numbers are written with Rust's `Display` for `f64`, which prints the
//! shortest decimal string that parses back to the same bits (never an
//! exponent). Output is therefore deterministic byte for byte, and
//! write → read is exact.

use crate::util::setting::Setting;
use std::fmt::Write as _;
use std::path::Path;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// The header line of a pose trajectory (what `drop` and scenes write).
pub const CSV_HEADER: &str = "t,x,y,z,qw,qx,qy,qz";

/// The columns every record must have.
pub const REQUIRED_COLUMNS: [&str; 4] = ["t", "x", "y", "z"];

/// The orientation columns: all four or none.
pub const QUATERNION_COLUMNS: [&str; 4] = ["qw", "qx", "qy", "qz"];

/// Largest accepted |‖q‖ − 1| when reading; what is accepted is normalised.
/// A quaternion printed with 7 significant digits (the MuJoCo files) is off
/// by ~1e-7, one printed with 3 decimals (a spreadsheet, a quick export
/// script) by up to ~2e-3 (0.9996–1.0004 on the MuJoCo falls so rounded);
/// 1e-2 reads those and still refuses columns that do not hold a rotation's
/// quaternion (Euler angles, another quantity), whose norm is not within 1 %
/// of 1 row after row.
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-2;

/// Quaternions already unit to within this are kept bit for bit instead of
/// being renormalised, so that write → read round-trips exactly (renormalising
/// an already normalised quaternion can change the last bit).
const UNIT_EXACT_TOLERANCE: f64 = 4.0 * f64::EPSILON;

/// Why a trajectory could not be read or written. Read errors name the
/// source (`file`) and, where a row is at fault, both the 1-based line of the
/// file (`line`, the header is line 1) and the 1-based data row (`row`).
#[derive(Debug, thiserror::Error)]
pub enum TrajectoryError {
    /// The source could not be opened or read.
    #[error("{file}: cannot read: {error}")]
    Io {
        /// Name of the source.
        file: String,
        /// Underlying I/O error (in the message, so not also a `source`:
        /// an error chain would print it twice).
        error: std::io::Error,
    },
    /// The source holds no bytes (or only white space).
    #[error("{file}: empty file, expected a header naming the columns (at least t,x,y,z)")]
    Empty {
        /// Name of the source.
        file: String,
    },
    /// The first line is data, not a header.
    #[error(
        "{file}: line 1: missing header (first line is `{found}`); the first line must name the columns, at least t,x,y,z, e.g. `{CSV_HEADER}`"
    )]
    MissingHeader {
        /// Name of the source.
        file: String,
        /// The first line as read.
        found: String,
    },
    /// The header lacks a required column, has some but not all quaternion
    /// columns, or names a column twice.
    #[error("{file}: line 1: header `{found}`: {problem}")]
    WrongHeader {
        /// Name of the source.
        file: String,
        /// The header as read.
        found: String,
        /// What is wrong with it.
        problem: String,
    },
    /// A header and no data.
    #[error("{file}: no data rows after the header")]
    NoData {
        /// Name of the source.
        file: String,
    },
    /// The CSV layer could not split a line (e.g. invalid UTF-8).
    #[error("{file}: line {line}: malformed CSV: {message}")]
    Csv {
        /// Name of the source.
        file: String,
        /// 1-based line of the file.
        line: u64,
        /// What the CSV reader said.
        message: String,
    },
    /// A row with another number of fields than the header has columns.
    #[error(
        "{file}: line {line} (data row {row}): {found} fields where the header names {expected}: {}",
        if *.found < *.expected {
            "the row is cut short (a truncated file?); complete or delete it"
        } else {
            "remove the extra fields (a trailing comma counts as one)"
        }
    )]
    FieldCount {
        /// Name of the source.
        file: String,
        /// 1-based line of the file.
        line: u64,
        /// 1-based data row.
        row: usize,
        /// Number of fields found.
        found: usize,
        /// Number of columns the header names.
        expected: usize,
    },
    /// A field that is not a number.
    #[error(
        "{file}: line {line} (data row {row}): column `{column}`: cannot parse `{text}` as a number"
    )]
    Number {
        /// Name of the source.
        file: String,
        /// 1-based line of the file.
        line: u64,
        /// 1-based data row.
        row: usize,
        /// Column name.
        column: String,
        /// The offending text.
        text: String,
    },
    /// A NaN or infinite value.
    #[error("{file}: line {line} (data row {row}): column `{column}` is {value} (not finite)")]
    NonFinite {
        /// Name of the source.
        file: String,
        /// 1-based line of the file.
        line: u64,
        /// 1-based data row.
        row: usize,
        /// Column name.
        column: String,
        /// The value read.
        value: f64,
    },
    /// Time does not increase strictly from the previous row.
    #[error(
        "{file}: line {line} (data row {row}): time {t} is not after the previous row's {previous}"
    )]
    TimeOrder {
        /// Name of the source.
        file: String,
        /// 1-based line of the file.
        line: u64,
        /// 1-based data row.
        row: usize,
        /// Time on this row.
        t: f64,
        /// Time on the previous row.
        previous: f64,
    },
    /// The quaternion's norm is not 1 within [`QUATERNION_NORM_TOLERANCE`].
    #[error(
        "{file}: line {line} (data row {row}): quaternion norm {norm} is not 1 (tolerance {QUATERNION_NORM_TOLERANCE})"
    )]
    NonUnitQuaternion {
        /// Name of the source.
        file: String,
        /// 1-based line of the file.
        line: u64,
        /// 1-based data row.
        row: usize,
        /// The norm found.
        norm: f64,
    },
    /// Refused to write a NaN or infinite value.
    #[error("cannot write data row {row}: column `{column}` is {value} (not finite)")]
    WriteNonFinite {
        /// 1-based data row.
        row: usize,
        /// Column name.
        column: String,
        /// The value.
        value: f64,
    },
    /// The columns of a [`Trajectory`] have different lengths.
    #[error("inconsistent trajectory: {time} times, but {what} has {found} values")]
    LengthMismatch {
        /// Length of `time`.
        time: usize,
        /// Which column: `position`, `orientation` or an area signal's name.
        what: String,
        /// Its length.
        found: usize,
    },
}

/// Which world axis points up in a file. leafmagic works with z up; a file
/// with y up (as many animation tools and trackers write) is turned about x
/// by +90° on reading, so that its y becomes z: (x, y, z) → (x, −z, y), and
/// the orientation q → r q with r that rotation. A file whose y points
/// down (image rows, as a tracker's pixel coordinates count them) is
/// turned about x by −90°: (x, y, z) → (x, z, −y), a rotation too, so an
/// orientation stays one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UpAxis {
    /// z up, gravity along −z (leafmagic's convention).
    #[default]
    Z,
    /// y up, gravity along −y.
    Y,
    /// y down, gravity along +y (image coordinates).
    YDown,
}

impl std::str::FromStr for UpAxis {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim() {
            "z" | "Z" => Ok(UpAxis::Z),
            "y" | "Y" => Ok(UpAxis::Y),
            "-y" | "-Y" | "y-down" => Ok(UpAxis::YDown),
            other => Err(format!(
                "`{other}` is not an up axis (expected z, y, or -y for a y that points down as image rows do)"
            )),
        }
    }
}

/// The projected area of the leaf seen from one camera, one value per
/// sample (any unit: only its variation is used).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AreaSignal {
    /// The column name (`area`, `area1`, `area_cam2`, …).
    pub name: String,
    /// One value per sample.
    pub values: Vec<f64>,
}

/// What reading a file noticed without refusing it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ReadNotes {
    /// Columns the header names that are neither time, position,
    /// orientation nor an area: ignored.
    pub ignored_columns: Vec<String>,
    /// The horizontal position column the header lacks, read as 0: a fall
    /// tracked by one camera (`t,x,y` from a tracker with y up), whose
    /// path lies in a vertical plane.
    pub depth_missing: Option<String>,
    /// Data rows left out because every position field in them is empty
    /// or NaN (frames where a tracker lost the leaf), and the file lines
    /// of the first and the last of them: what remains has gaps there,
    /// which the classifier bridges or refuses by their length.
    pub lost_rows: Option<LostRows>,
}

/// Rows of a record without a position (see [`ReadNotes::lost_rows`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LostRows {
    /// How many.
    pub count: usize,
    /// File line of the first.
    pub first_line: u64,
    /// File line of the last.
    pub last_line: u64,
}

/// The record of a falling leaf over time: one entry per sample in `time`
/// and `position`; `orientation` the same length or empty (a record without
/// orientation, e.g. from video), and each area signal the same length.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// Sample times, seconds, strictly increasing.
    pub time: Vec<f64>,
    /// Centre position, metres, world frame, z up.
    pub position: Vec<Vector3<f64>>,
    /// Orientation, body to world (body z the plate normal, body x the long
    /// axis); empty when the record has none.
    pub orientation: Vec<UnitQuaternion<f64>>,
    /// Projected-area signals, if the record has any.
    pub areas: Vec<AreaSignal>,
}

/// What a header column holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Column {
    Time,
    Position(usize),
    Quaternion(usize),
    Area(usize),
    Ignored,
}

/// True for the names of projected-area columns: `area`, `area` followed by
/// digits (`area1`), or `area_`/`area-` and letters, digits, `_` or `-`.
fn is_area_name(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    let Some(rest) = lower.strip_prefix("area") else {
        return false;
    };
    let tail_ok = |s: &str| {
        s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    };
    rest.is_empty()
        || rest.chars().all(|c| c.is_ascii_digit())
        || (rest.starts_with(['_', '-']) && rest.len() > 1 && tail_ok(rest))
}

/// What a header says: what each column holds, the area columns' names and
/// the ignored columns' names.
struct Layout {
    columns: Vec<Column>,
    areas: Vec<String>,
    ignored: Vec<String>,
    /// The one position column the header lacks, if it lacks one (its
    /// index among x, y, z).
    missing_position: Option<usize>,
}

/// The field separator of a record: a comma, or a tab or a semicolon when
/// the header line has no comma but one of those (video-analysis tools
/// export delimited text, tabs among the choices; European spreadsheets
/// write semicolons).
fn field_separator(text: &[u8]) -> u8 {
    let header = text
        .split(|&b| b == b'\n' || b == b'\r')
        .find(|line| line.iter().any(|b| !b.is_ascii_whitespace()))
        .unwrap_or_default();
    if header.contains(&b',') {
        b','
    } else if header.contains(&b'\t') {
        b'\t'
    } else if header.contains(&b';') {
        b';'
    } else {
        b','
    }
}

/// Line numbers (from 1) of the records of a text, from their byte
/// offsets. `\r\n`, `\n` and a lone `\r` each end a line, as the csv
/// reader takes them. Records are asked for in order, so the count goes on
/// from the last one asked (a whole read counts each line end once).
struct LineCounter<'a> {
    text: &'a [u8],
    /// The byte offset last asked for and its line.
    cursor: std::cell::Cell<(usize, u64)>,
}

impl<'a> LineCounter<'a> {
    fn new(text: &'a [u8]) -> Self {
        LineCounter {
            text,
            cursor: std::cell::Cell::new((0, 1)),
        }
    }

    /// The line of the record the csv reader says starts at `byte`. After
    /// a CRLF it points at the `\n` it has not consumed yet (rust-csv issue
    /// 395): the record starts past the line end.
    fn line_at(&self, byte: u64) -> u64 {
        let text = self.text;
        let mut k = usize::try_from(byte).unwrap_or(usize::MAX).min(text.len());
        while k < text.len() && matches!(text[k], b'\r' | b'\n') {
            k += 1;
        }
        let (mut at, mut line) = self.cursor.get();
        if k < at {
            (at, line) = (0, 1);
        }
        for i in at..k {
            let crlf = text[i] == b'\r' && text.get(i + 1) == Some(&b'\n');
            if text[i] == b'\n' || (text[i] == b'\r' && !crlf) {
                line += 1;
            }
        }
        self.cursor.set((k, line));
        line
    }
}

/// The layout of a header, or what is wrong with it.
fn layout(header: &[&str]) -> Result<Layout, String> {
    let mut columns = Vec::with_capacity(header.len());
    let mut areas = Vec::new();
    let mut ignored = Vec::new();
    let mut seen: Vec<String> = Vec::with_capacity(header.len());
    for name in header {
        let lower = name.to_ascii_lowercase();
        if seen.contains(&lower) {
            return Err(format!("column `{name}` appears twice"));
        }
        seen.push(lower.clone());
        let col = if lower == "t" {
            Column::Time
        } else if let Some(k) = REQUIRED_COLUMNS[1..].iter().position(|c| *c == lower) {
            Column::Position(k)
        } else if let Some(k) = QUATERNION_COLUMNS.iter().position(|c| *c == lower) {
            Column::Quaternion(k)
        } else if is_area_name(name) {
            areas.push(name.to_string());
            Column::Area(areas.len() - 1)
        } else {
            ignored.push(name.to_string());
            Column::Ignored
        };
        columns.push(col);
    }
    let missing: Vec<&str> = REQUIRED_COLUMNS
        .iter()
        .copied()
        .filter(|c| !seen.iter().any(|s| s == c))
        .collect();
    // One position column may be missing (a fall in a vertical plane; the
    // reader checks that it is not the vertical).
    let missing_position = match missing.as_slice() {
        [one] if *one != "t" => REQUIRED_COLUMNS[1..].iter().position(|c| c == one),
        _ => None,
    };
    if !missing.is_empty() && missing_position.is_none() {
        let list = missing
            .iter()
            .map(|c| format!("`{c}`"))
            .collect::<Vec<_>>()
            .join(", ");
        return Err(format!(
            "no column {list} (required: t,x,y,z, or t, the vertical and one other for a fall in a vertical plane; optional: qw,qx,qy,qz and area columns)"
        ));
    }
    let quats = columns
        .iter()
        .filter(|c| matches!(c, Column::Quaternion(_)))
        .count();
    if quats != 0 && quats != 4 {
        let (has, lacks): (Vec<&str>, Vec<&str>) = QUATERNION_COLUMNS
            .iter()
            .partition(|c| seen.iter().any(|s| s == *c));
        return Err(format!(
            "quaternion columns incomplete: has {} but not {} (all four of qw,qx,qy,qz, or none)",
            has.join(","),
            lacks.join(",")
        ));
    }
    Ok(Layout {
        columns,
        areas,
        ignored,
        missing_position,
    })
}

impl Trajectory {
    /// An empty trajectory with room for `n` poses.
    pub fn with_capacity(n: usize) -> Self {
        Self {
            time: Vec::with_capacity(n),
            position: Vec::with_capacity(n),
            orientation: Vec::with_capacity(n),
            areas: Vec::new(),
        }
    }

    /// Appends one pose (a sample with orientation).
    pub fn push(&mut self, t: f64, position: Vector3<f64>, orientation: UnitQuaternion<f64>) {
        self.time.push(t);
        self.position.push(position);
        self.orientation.push(orientation);
    }

    /// Appends one sample of position only (a record without orientation).
    pub fn push_position(&mut self, t: f64, position: Vector3<f64>) {
        self.time.push(t);
        self.position.push(position);
    }

    /// Number of samples (length of `time`).
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// True when every sample has an orientation (a pose record).
    pub fn has_orientation(&self) -> bool {
        !self.time.is_empty() && self.orientation.len() == self.time.len()
    }

    /// Samples `first..=last` of the record, every column.
    pub fn slice(&self, first: usize, last: usize) -> Trajectory {
        self.samples((first..=last).collect::<Vec<_>>())
    }

    /// Every `step`-th sample from the first, every column: what a camera
    /// running `step` times slower would have recorded.
    pub fn every(&self, step: usize) -> Trajectory {
        self.samples((0..self.len()).step_by(step.max(1)).collect::<Vec<_>>())
    }

    /// The samples at `keep` (indices in order), every column.
    fn samples(&self, keep: Vec<usize>) -> Trajectory {
        let pick = |v: &[f64]| keep.iter().map(|&k| v[k]).collect::<Vec<f64>>();
        Trajectory {
            time: pick(&self.time),
            position: keep.iter().map(|&k| self.position[k]).collect(),
            orientation: if self.orientation.is_empty() {
                Vec::new()
            } else {
                keep.iter().map(|&k| self.orientation[k]).collect()
            },
            areas: self
                .areas
                .iter()
                .map(|a| AreaSignal {
                    name: a.name.clone(),
                    values: pick(&a.values),
                })
                .collect(),
        }
    }

    /// The same record without its orientation (what video tracking of
    /// this fall would give, areas apart).
    pub fn without_orientation(&self) -> Trajectory {
        Trajectory {
            orientation: Vec::new(),
            ..self.clone()
        }
    }

    /// Reads and validates a trajectory CSV file (z up); errors name the
    /// file. See [`Trajectory::read_csv_with`] for the y-up convention and
    /// the notes.
    pub fn read_csv(path: &Path) -> Result<Self, TrajectoryError> {
        Self::read_csv_with(path, UpAxis::Z).map(|(t, _)| t)
    }

    /// Reads and validates a trajectory CSV file written with `up` as the
    /// vertical axis, turned to leafmagic's z up; also returns what was
    /// noticed (ignored columns). Errors name the file.
    pub fn read_csv_with(path: &Path, up: UpAxis) -> Result<(Self, ReadNotes), TrajectoryError> {
        let name = path.display().to_string();
        let file = std::fs::File::open(path).map_err(|error| TrajectoryError::Io {
            file: name.clone(),
            error,
        })?;
        Self::from_csv_reader_with(std::io::BufReader::new(file), &name, up)
    }

    /// Reads and validates a trajectory CSV from any reader (z up). `source`
    /// is the name used in error messages.
    pub fn from_csv_reader<R: std::io::Read>(
        reader: R,
        source: &str,
    ) -> Result<Self, TrajectoryError> {
        Self::from_csv_reader_with(reader, source, UpAxis::Z).map(|(t, _)| t)
    }

    /// Reads and validates a trajectory CSV from any reader, `up` being the
    /// file's vertical axis. Checks, in order: non-empty, a header naming
    /// `t,x,y,z` (and all four quaternion columns or none, no name twice),
    /// as many fields per row as the header names, numbers, finite, time
    /// strictly increasing, unit quaternion (then normalised).
    pub fn from_csv_reader_with<R: std::io::Read>(
        reader: R,
        source: &str,
        up: UpAxis,
    ) -> Result<(Self, ReadNotes), TrajectoryError> {
        let file = || source.to_string();
        // The whole text is kept so that a line number is counted from a
        // record's byte offset: the csv crate's own line count lags by one
        // in files with CRLF line ends (rust-csv issue 395), which every
        // file saved on Windows has, the real squares' included.
        let mut text = Vec::new();
        let mut reader = reader;
        reader
            .read_to_end(&mut text)
            .map_err(|error| TrajectoryError::Io {
                file: file(),
                error,
            })?;
        let lines = LineCounter::new(&text);
        let separator = field_separator(&text);
        // Semicolons separate fields where the comma is the decimal mark
        // (spreadsheets and trackers in most of Europe write `0,01;0,52`).
        let decimal_comma = separator == b';';
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .trim(csv::Trim::All)
            .delimiter(separator)
            .from_reader(text.as_slice());
        let mut records = rdr.records();
        let csv_err = |e: csv::Error| csv_error(e, &lines, source);

        // Header.
        let header = loop {
            match records.next() {
                None => return Err(TrajectoryError::Empty { file: file() }),
                Some(Err(e)) => return Err(csv_err(e)),
                // A line of blanks only: keep looking (an all-blank file is "empty").
                Some(Ok(r)) if r.iter().all(|f| f.is_empty()) => continue,
                Some(Ok(r)) => break r,
            }
        };
        let names: Vec<&str> = header.iter().collect();
        let found = names.join(",");
        if names.first().is_some_and(|f| f.parse::<f64>().is_ok()) {
            return Err(TrajectoryError::MissingHeader {
                file: file(),
                found,
            });
        }
        let Layout {
            columns,
            areas: area_names,
            ignored,
            missing_position,
        } = layout(&names).map_err(|problem| TrajectoryError::WrongHeader {
            file: file(),
            found: found.clone(),
            problem,
        })?;
        check_vertical(missing_position, up, source, &found)?;
        let quaternion = columns.iter().any(|c| matches!(c, Column::Quaternion(_)));

        let mut traj = Trajectory {
            areas: area_names
                .into_iter()
                .map(|name| AreaSignal {
                    name,
                    values: Vec::new(),
                })
                .collect(),
            ..Trajectory::default()
        };
        let mut row = 0usize;
        let mut lost_rows: Option<LostRows> = None;
        for rec in records {
            let rec = rec.map_err(csv_err)?;
            let line = rec.position().map_or(0, |p| lines.line_at(p.byte()));
            if rec.iter().all(|f| f.is_empty()) {
                continue; // blank line (e.g. trailing): not a data row
            }
            row += 1;
            if rec.len() != columns.len() {
                return Err(TrajectoryError::FieldCount {
                    file: file(),
                    line,
                    row,
                    found: rec.len(),
                    expected: columns.len(),
                });
            }
            // A frame where a tracker lost the leaf: no position at all
            // (empty or NaN in every position field). Left out, noted; a
            // NaN beside numbers is still an error below.
            let lost = columns
                .iter()
                .zip(rec.iter())
                .filter(|(c, _)| matches!(c, Column::Position(_)))
                .all(|(_, f)| f.is_empty() || f.eq_ignore_ascii_case("nan"));
            if lost {
                let l = lost_rows.get_or_insert(LostRows {
                    count: 0,
                    first_line: line,
                    last_line: line,
                });
                l.count += 1;
                l.last_line = line;
                continue;
            }
            let at = Where {
                file: source,
                line,
                row,
            };
            let (t, p, q) = parse_row(&rec, &columns, &names, decimal_comma, at, &mut traj.areas)?;
            if let Some(&previous) = traj.time.last()
                && t <= previous
            {
                return Err(TrajectoryError::TimeOrder {
                    file: file(),
                    line,
                    row,
                    t,
                    previous,
                });
            }
            let position = Vector3::new(p[0], p[1], p[2]);
            if quaternion {
                let q = unit_quaternion(q, at)?;
                traj.push(t, position, q);
            } else {
                traj.push_position(t, position);
            }
        }
        if traj.is_empty() {
            return Err(TrajectoryError::NoData { file: file() });
        }
        traj.turn_to_z_up(up);
        Ok((
            traj,
            ReadNotes {
                ignored_columns: ignored,
                depth_missing: missing_position.map(|k| REQUIRED_COLUMNS[1 + k].to_string()),
                lost_rows,
            },
        ))
    }

    /// Turns a record written with `up` as its vertical into z up (see
    /// [`UpAxis`]): a quarter turn about x, its positions by swapping
    /// components (exact, where the rotation matrix's cos(π/2) is not 0).
    fn turn_to_z_up(&mut self, up: UpAxis) {
        let sign = match up {
            UpAxis::Z => return,
            UpAxis::Y => 1.0,
            UpAxis::YDown => -1.0,
        };
        let r =
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), sign * std::f64::consts::FRAC_PI_2);
        for p in &mut self.position {
            *p = Vector3::new(p.x, -sign * p.z, sign * p.y);
        }
        for q in &mut self.orientation {
            *q = r * *q;
        }
    }

    /// Multiplies every position by `metres_per_unit` and divides every
    /// time by `frames_per_second` where given (a tracker's record in
    /// pixels, its `t` a frame number); orientations and areas unchanged.
    pub fn rescale(&mut self, metres_per_unit: f64, frames_per_second: Option<f64>) {
        for p in &mut self.position {
            *p *= metres_per_unit;
        }
        if let Some(fps) = frames_per_second {
            for t in &mut self.time {
                *t /= fps;
            }
        }
    }

    /// The header line this record is written with: `t,x,y,z`, the
    /// quaternion columns if it has an orientation, then its area columns.
    pub fn csv_header(&self) -> String {
        let mut h = REQUIRED_COLUMNS.join(",");
        if !self.orientation.is_empty() {
            for c in QUATERNION_COLUMNS {
                h.push(',');
                h.push_str(c);
            }
        }
        for a in &self.areas {
            h.push(',');
            h.push_str(&a.name);
        }
        h
    }

    /// The column names of [`Trajectory::csv_header`], in order.
    fn column_names(&self) -> Vec<String> {
        self.csv_header().split(',').map(str::to_string).collect()
    }

    /// The numbers of data row `k` (0-based), in column order.
    fn row_values(&self, k: usize, out: &mut Vec<f64>) {
        out.clear();
        let p = &self.position[k];
        out.extend_from_slice(&[self.time[k], p.x, p.y, p.z]);
        if let Some(q) = self.orientation.get(k) {
            out.extend_from_slice(&[q.w, q.i, q.j, q.k]);
        }
        out.extend(self.areas.iter().map(|a| a.values[k]));
    }

    /// The CSV text, or an error if any value is NaN/infinite or the columns
    /// have different lengths. Deterministic: same data, same bytes.
    pub fn try_to_csv_bytes(&self) -> Result<Vec<u8>, TrajectoryError> {
        self.check_lengths()?;
        let names = self.column_names();
        let mut v = Vec::with_capacity(names.len());
        for k in 0..self.len() {
            self.row_values(k, &mut v);
            if let Some(c) = v.iter().position(|x| !x.is_finite()) {
                return Err(TrajectoryError::WriteNonFinite {
                    row: k + 1,
                    column: names[c].clone(),
                    value: v[c],
                });
            }
        }
        Ok(self.to_csv_bytes())
    }

    /// The CSV text, formatted as is (deterministic, shortest round-trip
    /// decimals). This never fails: a non-finite value is printed as `NaN` or
    /// `inf`, which [`Trajectory::from_csv_reader`] then rejects. Use
    /// [`Trajectory::try_to_csv_bytes`] or [`Trajectory::write_csv`], which
    /// refuse such data, to produce files. Rows beyond the shortest column
    /// are dropped.
    pub fn to_csv_bytes(&self) -> Vec<u8> {
        let header = self.csv_header();
        let n = self.rows_written();
        let columns = header.split(',').count();
        // ~15 characters per number is typical for simulator output.
        let mut s = String::with_capacity(header.len() + 1 + n * columns * 16);
        s.push_str(&header);
        s.push('\n');
        let mut v = Vec::with_capacity(columns);
        for k in 0..n {
            self.row_values(k, &mut v);
            for (c, x) in v.iter().enumerate() {
                if c > 0 {
                    s.push(',');
                }
                // Writing to a String cannot fail.
                let _ = write!(s, "{x}");
            }
            s.push('\n');
        }
        s.into_bytes()
    }

    /// Rows every written column has.
    fn rows_written(&self) -> usize {
        let mut n = self.time.len().min(self.position.len());
        if !self.orientation.is_empty() {
            n = n.min(self.orientation.len());
        }
        self.areas.iter().fold(n, |n, a| n.min(a.values.len()))
    }

    /// Writes the CSV atomically (temporary file + rename). Refuses NaN or
    /// infinite values and inconsistent column lengths with an
    /// [`std::io::ErrorKind::InvalidData`] error, writing nothing.
    pub fn write_csv(&self, path: &Path) -> std::io::Result<()> {
        let bytes = self
            .try_to_csv_bytes()
            .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))?;
        crate::util::io::write_atomic(path, &bytes)
    }

    /// The same fall sampled at `rate_hz` from the first sample time onwards:
    /// positions and areas interpolated linearly, orientations by slerp
    /// along the shorter arc (q and −q are the same rotation). Returns an
    /// empty trajectory if `rate_hz` is not positive and finite.
    pub fn resampled(&self, rate_hz: f64) -> Trajectory {
        let n = self.rows_written();
        if n == 0 || !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Trajectory::default();
        }
        let (t0, t1) = (self.time[0], self.time[n - 1]);
        let m = ((t1 - t0) * rate_hz + 1e-9).floor() as usize + 1;
        let times: Vec<f64> = (0..m).map(|k| t0 + k as f64 / rate_hz).collect();
        self.sampled_at(&times)
    }

    /// The record interpolated at the given times (increasing; clamped to
    /// the record's span), as [`Trajectory::resampled`] interpolates.
    pub fn sampled_at(&self, times: &[f64]) -> Trajectory {
        let n = self.rows_written();
        let has_q = !self.orientation.is_empty();
        let mut out = Trajectory {
            time: Vec::with_capacity(times.len()),
            position: Vec::with_capacity(times.len()),
            orientation: Vec::with_capacity(if has_q { times.len() } else { 0 }),
            areas: self
                .areas
                .iter()
                .map(|a| AreaSignal {
                    name: a.name.clone(),
                    values: Vec::with_capacity(times.len()),
                })
                .collect(),
        };
        if n == 0 {
            return out;
        }
        let mut j = 0usize;
        for &t in times {
            while j + 2 < n && self.time[j + 1] <= t {
                j += 1;
            }
            out.time.push(t);
            if n == 1 {
                out.position.push(self.position[0]);
                if has_q {
                    out.orientation.push(self.orientation[0]);
                }
                for (o, a) in out.areas.iter_mut().zip(&self.areas) {
                    o.values.push(a.values[0]);
                }
                continue;
            }
            let (ta, tb) = (self.time[j], self.time[j + 1]);
            let s = ((t - ta) / (tb - ta)).clamp(0.0, 1.0);
            out.position
                .push(self.position[j].lerp(&self.position[j + 1], s));
            if has_q {
                out.orientation.push(slerp_short(
                    &self.orientation[j],
                    &self.orientation[j + 1],
                    s,
                ));
            }
            for (o, a) in out.areas.iter_mut().zip(&self.areas) {
                o.values
                    .push(a.values[j] + s * (a.values[j + 1] - a.values[j]));
            }
        }
        out
    }

    fn check_lengths(&self) -> Result<(), TrajectoryError> {
        let n = self.time.len();
        let mismatch = |what: &str, found: usize| TrajectoryError::LengthMismatch {
            time: n,
            what: what.to_string(),
            found,
        };
        if self.position.len() != n {
            return Err(mismatch("position", self.position.len()));
        }
        if !self.orientation.is_empty() && self.orientation.len() != n {
            return Err(mismatch("orientation", self.orientation.len()));
        }
        for a in &self.areas {
            if a.values.len() != n {
                return Err(mismatch(&a.name, a.values.len()));
            }
        }
        Ok(())
    }
}

/// Spherical interpolation from `a` (s = 0) to `b` (s = 1) along the shorter
/// arc. Falls back to normalised linear interpolation when the two are nearly
/// equal, where slerp's 1/sin(angle) is ill-conditioned.
fn slerp_short(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>, s: f64) -> UnitQuaternion<f64> {
    let qa = a.coords;
    let mut qb = b.coords;
    let mut c = qa.dot(&qb);
    if c < 0.0 {
        qb = -qb;
        c = -c;
    }
    let v = if c > 0.9999 {
        qa * (1.0 - s) + qb * s
    } else {
        let angle = c.min(1.0).acos();
        let sin = angle.sin();
        qa * (((1.0 - s) * angle).sin() / sin) + qb * ((s * angle).sin() / sin)
    };
    UnitQuaternion::new_normalize(Quaternion::from(v))
}

/// A CSV reader's error, said with the line it is on (`lines` counts them
/// in the text of `source`).
fn csv_error(e: csv::Error, lines: &LineCounter, source: &str) -> TrajectoryError {
    let file = || source.to_string();
    let line = e.position().map_or(0, |p| lines.line_at(p.byte()));
    match e.into_kind() {
        csv::ErrorKind::Io(error) => TrajectoryError::Io {
            file: file(),
            error,
        },
        // Said as a sentence, not the CSV reader's debug form.
        csv::ErrorKind::Utf8 { pos, err } => TrajectoryError::Csv {
            file: file(),
            line: pos.map_or(line, |p| lines.line_at(p.byte())),
            message: format!(
                "field {} is not UTF-8 text (bad byte after {} valid bytes of the field); \
                 a trajectory CSV is plain text: save it as UTF-8 or ASCII",
                err.field() + 1,
                err.valid_up_to()
            ),
        },
        kind => TrajectoryError::Csv {
            file: file(),
            line,
            message: format!("{kind:?}"),
        },
    }
}

/// Refuses a header of `source` (`found`) without the vertical column
/// `up` names: a fall needs its height.
fn check_vertical(
    missing_position: Option<usize>,
    up: UpAxis,
    source: &str,
    found: &str,
) -> Result<(), TrajectoryError> {
    let file = || source.to_string();
    let found = found.to_string();
    let vertical = match up {
        UpAxis::Z => 2,
        UpAxis::Y | UpAxis::YDown => 1,
    };
    if missing_position == Some(vertical) {
        let name = REQUIRED_COLUMNS[1 + vertical];
        return Err(TrajectoryError::WrongHeader {
            file: file(),
            found,
            problem: format!(
                "no column `{name}`, the vertical ({}): a fall needs its height; a record in a vertical plane has t, the vertical and one horizontal column{}",
                Setting::Up.set(name),
                if up == UpAxis::Z {
                    format!(
                        " (with {}, or {} where it points down, `y` is the vertical)",
                        Setting::Up.set("y"),
                        Setting::Up.set("-y")
                    )
                } else {
                    String::new()
                }
            ),
        });
    }
    Ok(())
}

/// Where a row of a trajectory CSV is, for its errors.
#[derive(Clone, Copy)]
struct Where<'a> {
    file: &'a str,
    /// The line, 1-based.
    line: u64,
    /// The data row, 1-based.
    row: usize,
}

/// The time, position and quaternion of data row `rec` (its columns
/// `columns`, named `names`), its areas pushed onto `areas`; every field a
/// finite number.
fn parse_row(
    rec: &csv::StringRecord,
    columns: &[Column],
    names: &[&str],
    decimal_comma: bool,
    at: Where<'_>,
    areas: &mut [AreaSignal],
) -> Result<(f64, [f64; 3], [f64; 4]), TrajectoryError> {
    let Where { line, row, .. } = at;
    let file = || at.file.to_string();
    let (mut t, mut p, mut q) = (0.0f64, [0.0f64; 3], [0.0f64; 4]);
    for (k, field) in rec.iter().enumerate() {
        let col = columns[k];
        if col == Column::Ignored {
            continue;
        }
        let decimal = if decimal_comma {
            std::borrow::Cow::Owned(field.replace(',', "."))
        } else {
            std::borrow::Cow::Borrowed(field)
        };
        let x: f64 = decimal.parse().map_err(|_| TrajectoryError::Number {
            file: file(),
            line,
            row,
            column: names[k].to_string(),
            text: field.to_string(),
        })?;
        if !x.is_finite() {
            return Err(TrajectoryError::NonFinite {
                file: file(),
                line,
                row,
                column: names[k].to_string(),
                value: x,
            });
        }
        match col {
            Column::Time => t = x,
            Column::Position(i) => p[i] = x,
            Column::Quaternion(i) => q[i] = x,
            Column::Area(i) => areas[i].values.push(x),
            Column::Ignored => {}
        }
    }
    Ok((t, p, q))
}

/// The orientation a row's quaternion `q` (w, x, y, z) gives: within
/// [`QUATERNION_NORM_TOLERANCE`] of unit length, normalised unless within
/// [`UNIT_EXACT_TOLERANCE`] of it.
fn unit_quaternion(q: [f64; 4], at: Where<'_>) -> Result<UnitQuaternion<f64>, TrajectoryError> {
    let Where { line, row, .. } = at;
    let file = || at.file.to_string();
    let q = Quaternion::new(q[0], q[1], q[2], q[3]);
    let norm = q.norm();
    if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
        return Err(TrajectoryError::NonUnitQuaternion {
            file: file(),
            line,
            row,
            norm,
        });
    }
    let q = if (norm - 1.0).abs() <= UNIT_EXACT_TOLERANCE {
        UnitQuaternion::new_unchecked(q)
    } else {
        UnitQuaternion::new_normalize(q)
    };
    Ok(q)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Trajectory {
        let mut tr = Trajectory::with_capacity(50);
        for k in 0..50 {
            let t = k as f64 / 240.0;
            let q = UnitQuaternion::from_euler_angles(0.3 * t, -0.1 + t, 2.0 * t);
            tr.push(
                t,
                Vector3::new(0.1 * t, -1e-9 * t, -0.7 * t * t - 1.0 / 3.0),
                q,
            );
        }
        tr
    }

    fn read_str(s: &str) -> Result<Trajectory, TrajectoryError> {
        Trajectory::from_csv_reader(s.as_bytes(), "mem.csv")
    }

    fn tmp_path(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("leafmagic-traj-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    #[test]
    fn round_trip_is_exact_through_a_file() {
        let tr = sample();
        let path = tmp_path("rt.csv");
        tr.write_csv(&path).unwrap();
        let back = Trajectory::read_csv(&path).unwrap();
        assert_eq!(back.len(), tr.len());
        for k in 0..tr.len() {
            assert_eq!(back.time[k].to_bits(), tr.time[k].to_bits());
            for d in 0..3 {
                assert_eq!(back.position[k][d].to_bits(), tr.position[k][d].to_bits());
            }
            for d in 0..4 {
                assert_eq!(
                    back.orientation[k].coords[d].to_bits(),
                    tr.orientation[k].coords[d].to_bits(),
                    "row {k} quaternion component {d}"
                );
            }
        }
        // And the re-written bytes are the same as the first ones.
        assert_eq!(back.to_csv_bytes(), std::fs::read(&path).unwrap());
    }

    #[test]
    fn identical_data_gives_identical_bytes() {
        let a = sample().try_to_csv_bytes().unwrap();
        let b = sample().clone().try_to_csv_bytes().unwrap();
        assert_eq!(a, b);
        let text = String::from_utf8(a).unwrap();
        assert!(text.starts_with("t,x,y,z,qw,qx,qy,qz\n0,0,-0,"));
        assert!(!text.contains('e'), "no exponent notation expected");
    }

    fn assert_err(s: &str, want: &[&str]) {
        let err = read_str(s).expect_err("expected an error").to_string();
        assert!(err.contains("mem.csv"), "no source in `{err}`");
        for w in want {
            assert!(err.contains(w), "`{err}` lacks `{w}`");
        }
    }

    const H: &str = "t,x,y,z,qw,qx,qy,qz\n";

    #[test]
    fn read_errors_name_source_row_and_reason() {
        assert_err("", &["empty"]);
        assert_err("  \n\n", &["empty"]);
        assert_err(H, &["no data"]);
        assert_err("0,0,0,0,1,0,0,0\n", &["line 1", "missing header"]);
        assert_err(
            "time,x,y,z,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n",
            &["line 1", "no column `t`", "required: t,x,y,z"],
        );
        assert_err(
            "t,x,y,area1\n0,0,0,1\n",
            &["line 1", "no column `z`, the vertical", "with up = y"],
        );
        assert_err("t,z\n0,1\n", &["line 1", "no column `x`, `y`"]);
        assert_err(
            "t,x,y,z,qw,qx\n0,0,0,0,1,0\n",
            &["line 1", "quaternion columns incomplete", "not qy,qz"],
        );
        assert_err("t,x,y,z,X\n0,0,0,0,0\n", &["line 1", "`X` appears twice"]);
        let ok = "0,0,0,0,1,0,0,0\n";
        assert_err(
            &format!("{H}{ok}0.1,0,0,-1,1,0\n"),
            &[
                "line 3",
                "data row 2",
                "6 fields where the header names 8",
                "cut short",
            ],
        );
        assert_err(
            &format!("{H}{ok}0.1,0,zero,-1,1,0,0,0\n"),
            &["line 3", "data row 2", "`y`", "zero"],
        );
        assert_err(
            &format!("{H}{ok}{ok}"),
            &["line 3", "data row 2", "not after"],
        );
        assert_err(
            &format!("{H}{ok}0.1,0,0,0,1,0,0,0\n0.05,0,0,0,1,0,0,0\n"),
            &["line 4", "data row 3", "not after"],
        );
        assert_err(
            &format!("{H}{ok}0.1,NaN,0,-1,1,0,0,0\n"),
            &["line 3", "data row 2", "`x`", "not finite"],
        );
        assert_err(
            &format!("{H}0,0,0,0,1,0,0,inf\n"),
            &["line 2", "data row 1", "`qz`", "not finite"],
        );
        assert_err(
            &format!("{H}{ok}0.1,0,0,-1,1,0.2,0,0\n"),
            &["line 3", "data row 2", "quaternion norm"],
        );
    }

    /// Errors name the file's own line whatever ends its lines: LF, CRLF
    /// (where the csv crate's count lags by one), a lone CR; blank lines
    /// count.
    #[test]
    fn errors_name_the_line_with_any_line_ends() {
        for end in ["\n", "\r\n", "\r"] {
            let text = ["t,x,y,z", "0,0,0,1", "", "0.1,0,0,0.9", "0.2,abc,0,0.8", ""].join(end);
            let err = read_str(&text).unwrap_err().to_string();
            assert!(err.contains("line 5 (data row 3)"), "{end:?}: {err}");
        }
    }

    /// A row whose every position field is empty or NaN (the tracker lost
    /// the leaf) is left out and counted with its lines; NaN beside numbers
    /// is still refused.
    #[test]
    fn rows_without_a_position_are_left_out_and_noted() {
        let text =
            "t,x,y,z,area1\r\n0,0,0,1,5\r\n0.01,,,,6\r\n0.02,NaN,nan,NaN,7\r\n0.03,0,0,0.97,8\r\n";
        let (tr, notes) = read_with_notes(text, UpAxis::Z);
        assert_eq!(tr.time, vec![0.0, 0.03]);
        assert_eq!(tr.areas[0].values, vec![5.0, 8.0]);
        assert_eq!(
            notes.lost_rows,
            Some(LostRows {
                count: 2,
                first_line: 3,
                last_line: 4
            })
        );
        assert_eq!(
            read_with_notes("t,x,y,z\n0,0,0,1\n", UpAxis::Z).1.lost_rows,
            None
        );
        let err = read_str("t,x,y,z\n0,0,0,1\n0.01,NaN,0,1\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("line 3 (data row 2)") && err.contains("NaN"),
            "{err}"
        );
    }

    /// Tab- and semicolon-separated records are read as comma-separated
    /// ones are; with semicolons, a comma is the decimal mark.
    #[test]
    fn tabs_and_semicolons_with_decimal_commas_are_read() {
        let comma = read_str("t,x,y,z\n0,0.5,0,1.25\n0.01,0.5,0,1.2\n").unwrap();
        let tab = read_str("t\tx\ty\tz\n0\t0.5\t0\t1.25\n0.01\t0.5\t0\t1.2\n").unwrap();
        let semi = read_str("t;x;y;z\n0;0,5;0;1,25\n0,01;0,5;0;1,2\n").unwrap();
        assert_eq!(tab, comma);
        assert_eq!(semi, comma);
        let err = read_str("t;x;y;z\n0;0,5;0;abc\n").unwrap_err().to_string();
        assert!(err.contains("line 2") && err.contains("`z`"), "{err}");
    }

    /// A fall seen by one camera: t, the vertical and one horizontal
    /// column, the depth read as 0 and named in the notes; z up or y up.
    #[test]
    fn a_record_in_a_vertical_plane_is_read_with_its_depth_zero() {
        let (tr, notes) = read_with_notes("t,x,z,area1\n0,0.1,1,5\n0.01,0.2,0.99,6\n", UpAxis::Z);
        assert_eq!(notes.depth_missing.as_deref(), Some("y"));
        assert_eq!(tr.position[1], Vector3::new(0.2, 0.0, 0.99));
        assert_eq!(tr.areas[0].values, vec![5.0, 6.0]);
        // A tracker's export, y up: x across the image, y up it.
        let (tr, notes) = read_with_notes("t,x,y\n0,0.1,1\n0.01,0.2,0.99\n", UpAxis::Y);
        assert_eq!(notes.depth_missing.as_deref(), Some("z"));
        assert_eq!(tr.position[1], Vector3::new(0.2, 0.0, 0.99));
        let (_, notes) = read_with_notes("t,x,y,z\n0,0,0,1\n", UpAxis::Z);
        assert_eq!(notes.depth_missing, None);
    }

    fn read_with_notes(s: &str, up: UpAxis) -> (Trajectory, ReadNotes) {
        Trajectory::from_csv_reader_with(s.as_bytes(), "mem.csv", up).unwrap()
    }

    /// Quaternions printed with three decimals are read, normalised; a
    /// quaternion 2 % off unit is refused.
    #[test]
    fn rounded_quaternions_are_read_and_normalised() {
        let half = std::f64::consts::FRAC_1_SQRT_2;
        let text = format!("t,x,y,z,qw,qx,qy,qz\n0,0,0,0,{half:.3},{half:.3},0,0\n");
        let tr = read_str(&text).unwrap();
        let q = tr.orientation[0];
        assert!((q.coords.norm() - 1.0).abs() < 1e-15);
        assert!((q.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let off = "t,x,y,z,qw,qx,qy,qz\n0,0,0,0,1.02,0,0,0\n";
        let err = read_str(off).unwrap_err().to_string();
        assert!(
            err.contains("quaternion norm 1.02 is not 1 (tolerance 0.01)"),
            "{err}"
        );
    }

    #[test]
    fn accepts_seven_digit_quaternions_and_normalises_them() {
        let tr = read_str(&format!(
            "{H}0.000000,0,0,0,0.9846578,0.1736217,0.01718727,0.003030579\n"
        ))
        .unwrap();
        assert!((tr.orientation[0].coords.norm() - 1.0).abs() < 1e-15);
        // Sign-flipped quaternion reads as the same rotation.
        let tr2 = read_str(&format!(
            "{H}0,0,0,0,-0.9846578,-0.1736217,-0.01718727,-0.003030579\n"
        ))
        .unwrap();
        assert!(tr.orientation[0].angle_to(&tr2.orientation[0]) < 1e-12);
    }

    #[test]
    fn refuses_to_write_non_finite_values() {
        let mut tr = sample();
        tr.position[7].y = f64::NAN;
        let err = tr.try_to_csv_bytes().unwrap_err().to_string();
        assert!(err.contains("row 8") && err.contains("`y`"), "{err}");
        let path = tmp_path("nan.csv");
        let _ = std::fs::remove_file(&path);
        let io = tr.write_csv(&path).unwrap_err();
        assert_eq!(io.kind(), std::io::ErrorKind::InvalidData);
        assert!(!path.exists(), "nothing must be written");
        let mut tr = sample();
        tr.time[3] = f64::INFINITY;
        assert!(tr.try_to_csv_bytes().is_err());
        let mut tr = sample();
        tr.time.pop();
        assert!(matches!(
            tr.try_to_csv_bytes(),
            Err(TrajectoryError::LengthMismatch { .. })
        ));
    }

    #[test]
    fn resampling_hits_the_requested_rate_and_interpolates() {
        let tr = sample(); // 240 Hz, 50 samples
        let r = tr.resampled(60.0);
        assert_eq!(r.len(), 13); // 0 .. 49/240 s at 1/60 s
        for k in 0..r.len() {
            // Every 4th original sample coincides with a 60 Hz one.
            let j = 4 * k;
            assert!((r.time[k] - tr.time[j]).abs() < 1e-12);
            assert!((r.position[k] - tr.position[j]).norm() < 1e-12);
            assert!(r.orientation[k].angle_to(&tr.orientation[j]) < 1e-9);
        }
    }

    #[test]
    fn columns_are_found_by_name_in_any_order_and_extras_are_noted() {
        let text = "z,frame,t,area2,x,y,area1\n1.0,0,0,10,0.1,0.2,20\n0.9,1,0.01,11,0.1,0.21,19\n";
        let (tr, notes) =
            Trajectory::from_csv_reader_with(text.as_bytes(), "v.csv", UpAxis::Z).unwrap();
        assert_eq!(notes.ignored_columns, vec!["frame".to_string()]);
        assert!(!tr.has_orientation() && tr.orientation.is_empty());
        assert_eq!(tr.time, vec![0.0, 0.01]);
        assert_eq!(tr.position[1], Vector3::new(0.1, 0.21, 0.9));
        let names: Vec<&str> = tr.areas.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, ["area2", "area1"]);
        assert_eq!(tr.areas[1].values, vec![20.0, 19.0]);
        // Written back in leafmagic's order, and read back the same.
        let bytes = tr.try_to_csv_bytes().unwrap();
        let text = String::from_utf8(bytes.clone()).unwrap();
        assert!(
            text.starts_with("t,x,y,z,area2,area1\n0,0.1,0.2,1,10,20\n"),
            "{text}"
        );
        let back = Trajectory::from_csv_reader(&bytes[..], "back.csv").unwrap();
        assert_eq!(back, tr);
        // A pose file with columns shuffled reads as the pose file.
        let shuffled = "qz,t,qy,x,qx,y,qw,z\n0,0,0,1,0,2,1,3\n";
        let tr = read_str(shuffled).unwrap();
        assert!(tr.has_orientation());
        assert_eq!(tr.position[0], Vector3::new(1.0, 2.0, 3.0));
        assert_eq!(tr.orientation[0], UnitQuaternion::identity());
        assert_eq!(tr.csv_header(), CSV_HEADER);
    }

    #[test]
    fn area_column_names() {
        for yes in ["area", "area1", "AREA2", "area_cam1", "area-left"] {
            assert!(is_area_name(yes), "{yes}");
        }
        for no in ["areal", "areas", "area_", "volume", "xarea", "area1b"] {
            assert!(!is_area_name(no), "{no}");
        }
    }

    #[test]
    fn y_up_files_are_turned_to_z_up() {
        // Falling along -y, drifting along +x; a plate whose normal is the
        // file's up axis (y).
        let s = 0.5f64.sqrt();
        let text =
            format!("t,x,y,z,qw,qx,qy,qz\n0,0,1,0,1,0,0,0\n0.1,0.05,0.9,-0.02,{s},-{s},0,0\n");
        let (tr, _) =
            Trajectory::from_csv_reader_with(text.as_bytes(), "y.csv", UpAxis::Y).unwrap();
        assert_eq!(tr.position[0], Vector3::new(0.0, 0.0, 1.0));
        assert!((tr.position[1] - Vector3::new(0.05, 0.02, 0.9)).norm() < 1e-15);
        // Body z (the normal): at row 1 the file's rotation of -90° about x
        // takes it to the file's +y, i.e. up.
        let n = tr.orientation[1] * Vector3::z();
        assert!((n - Vector3::z()).norm() < 1e-12, "{n}");
        assert!("y".parse::<UpAxis>().unwrap() == UpAxis::Y);
        assert!("w".parse::<UpAxis>().is_err());
    }

    #[test]
    fn y_down_files_are_turned_to_z_up_by_a_rotation() {
        // Image rows: falling along +y; a plate whose normal is the file's
        // up (−y) at row 1 (turned 90° about x from its rest normal z).
        let s = 0.5f64.sqrt();
        let text =
            format!("t,x,y,z,qw,qx,qy,qz\n0,0,-1,0,1,0,0,0\n0.1,0.05,-0.9,0.02,{s},{s},0,0\n");
        let (tr, _) =
            Trajectory::from_csv_reader_with(text.as_bytes(), "down.csv", UpAxis::YDown).unwrap();
        // (x, y, z) → (x, z, −y): 1 m up, then 0.9 m and 2 cm along +y.
        assert_eq!(tr.position[0], Vector3::new(0.0, 0.0, 1.0));
        assert!((tr.position[1] - Vector3::new(0.05, 0.02, 0.9)).norm() < 1e-15);
        let n = tr.orientation[1] * Vector3::z();
        assert!((n - Vector3::z()).norm() < 1e-12, "{n}");
        // A rotation, not a mirror: right-handed axes stay right-handed.
        let q = tr.orientation[0];
        let (x, y, z) = (q * Vector3::x(), q * Vector3::y(), q * Vector3::z());
        assert!((x.cross(&y) - z).norm() < 1e-12);
        for spelled in ["-y", "y-down"] {
            assert!(spelled.parse::<UpAxis>().unwrap() == UpAxis::YDown);
        }
        // Pixels and frame numbers to metres and seconds.
        let mut tr = tr;
        tr.rescale(0.001, Some(10.0));
        assert!((tr.position[0].z - 0.001).abs() < 1e-18);
        assert!((tr.time[1] - 0.01).abs() < 1e-18);
    }

    #[test]
    fn position_only_records_round_trip_and_resample() {
        let mut tr = Trajectory::default();
        tr.areas.push(AreaSignal {
            name: "area".to_string(),
            values: Vec::new(),
        });
        for k in 0..11 {
            let t = k as f64 * 0.1;
            tr.push_position(t, Vector3::new(t, 0.0, -t));
            tr.areas[0].values.push(2.0 * t);
        }
        let r = tr.resampled(20.0);
        assert_eq!(r.len(), 21);
        assert!(r.orientation.is_empty());
        assert!((r.position[3].x - 0.15).abs() < 1e-12);
        assert!((r.areas[0].values[3] - 0.3).abs() < 1e-12);
        let path = tmp_path("pos.csv");
        tr.write_csv(&path).unwrap();
        assert_eq!(Trajectory::read_csv(&path).unwrap(), tr);
        tr.areas[0].values.pop();
        let err = tr.try_to_csv_bytes().unwrap_err().to_string();
        assert!(err.contains("area") && err.contains("10 values"), "{err}");
    }
}
