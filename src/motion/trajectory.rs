//! The pose record of a fall: time, centre position and orientation of a leaf,
//! and its CSV form.
//!
//! File format (one header line, then one line per sample):
//!
//! ```text
//! t,x,y,z,qw,qx,qy,qz
//! 0,0,0,0,1,0,0,0
//! ```
//!
//! `t` in seconds, `x,y,z` in metres in the world frame with z up (gravity
//! along −z), `qw,qx,qy,qz` the orientation quaternion taking body vectors to
//! the world frame, scalar first. Body axes: z is the plate normal, x the long
//! axis.
//!
//! Numbers are written with Rust's `Display` for `f64`, which prints the
//! shortest decimal string that parses back to the same bits (never an
//! exponent). Output is therefore deterministic byte for byte, and
//! write → read is exact.

use std::fmt::Write as _;
use std::path::Path;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// The header line every trajectory CSV starts with.
pub const CSV_HEADER: &str = "t,x,y,z,qw,qx,qy,qz";

/// Column names, in file order (used in error messages).
const COLUMNS: [&str; 8] = ["t", "x", "y", "z", "qw", "qx", "qy", "qz"];

/// Largest accepted |‖q‖ − 1| when reading. A quaternion printed with 7
/// significant digits (the MuJoCo files) is off by at most ~1e-7; 1e-5 accepts
/// anything with 6 or more digits and still rejects a quaternion that is not a
/// rotation (e.g. a column mix-up).
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-5;

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
        /// Underlying I/O error.
        #[source]
        error: std::io::Error,
    },
    /// The source holds no bytes (or only white space).
    #[error("{file}: empty file, expected header `{CSV_HEADER}`")]
    Empty {
        /// Name of the source.
        file: String,
    },
    /// The first line is data, not the header.
    #[error("{file}: line 1: missing header `{CSV_HEADER}` (first line is `{found}`)")]
    MissingHeader {
        /// Name of the source.
        file: String,
        /// The first line as read.
        found: String,
    },
    /// The first line is a header, but not ours.
    #[error("{file}: line 1: wrong header `{found}`, expected `{CSV_HEADER}`")]
    WrongHeader {
        /// Name of the source.
        file: String,
        /// The header as read.
        found: String,
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
    /// A row with the wrong number of fields (truncated or extra columns).
    #[error(
        "{file}: line {line} (data row {row}): {found} fields where the header `{CSV_HEADER}` has 8: {}",
        if *.found < 8 {
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
        column: &'static str,
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
        column: &'static str,
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
        column: &'static str,
        /// The value.
        value: f64,
    },
    /// The three columns of a [`Trajectory`] have different lengths.
    #[error(
        "inconsistent trajectory: {time} times, {position} positions, {orientation} orientations"
    )]
    LengthMismatch {
        /// Length of `time`.
        time: usize,
        /// Length of `position`.
        position: usize,
        /// Length of `orientation`.
        orientation: usize,
    },
}

/// Poses of a falling leaf over time (one entry per sample, all three vectors
/// the same length).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// Sample times, seconds, strictly increasing.
    pub time: Vec<f64>,
    /// Centre position, metres, world frame, z up.
    pub position: Vec<Vector3<f64>>,
    /// Orientation, body to world. Body z is the plate normal, body x the long axis.
    pub orientation: Vec<UnitQuaternion<f64>>,
}

impl Trajectory {
    /// An empty trajectory with room for `n` samples.
    pub fn with_capacity(n: usize) -> Self {
        Self {
            time: Vec::with_capacity(n),
            position: Vec::with_capacity(n),
            orientation: Vec::with_capacity(n),
        }
    }

    /// Appends one sample.
    pub fn push(&mut self, t: f64, position: Vector3<f64>, orientation: UnitQuaternion<f64>) {
        self.time.push(t);
        self.position.push(position);
        self.orientation.push(orientation);
    }

    /// Number of samples (length of `time`).
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// Reads and validates a trajectory CSV file; errors name the file.
    pub fn read_csv(path: &Path) -> Result<Self, TrajectoryError> {
        let name = path.display().to_string();
        let file = std::fs::File::open(path).map_err(|error| TrajectoryError::Io {
            file: name.clone(),
            error,
        })?;
        Self::from_csv_reader(std::io::BufReader::new(file), &name)
    }

    /// Reads and validates a trajectory CSV from any reader. `source` is the
    /// name used in error messages. Checks, in order: non-empty, header,
    /// 8 fields per row, numbers, finite, time strictly increasing, unit
    /// quaternion (then normalised).
    pub fn from_csv_reader<R: std::io::Read>(
        reader: R,
        source: &str,
    ) -> Result<Self, TrajectoryError> {
        let file = || source.to_string();
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .trim(csv::Trim::All)
            .from_reader(reader);
        let mut records = rdr.records();
        let csv_err = |e: csv::Error| -> TrajectoryError {
            let line = e.position().map(|p| p.line()).unwrap_or(0);
            match e.into_kind() {
                csv::ErrorKind::Io(error) => TrajectoryError::Io {
                    file: file(),
                    error,
                },
                // Said as a sentence, not the CSV reader's debug form.
                csv::ErrorKind::Utf8 { pos, err } => TrajectoryError::Csv {
                    file: file(),
                    line: pos.map_or(line, |p| p.line()),
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
        };

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
        if header.iter().ne(COLUMNS.iter().copied()) {
            let found = header.iter().collect::<Vec<_>>().join(",");
            let looks_numeric = header.get(0).is_some_and(|f| f.parse::<f64>().is_ok());
            return Err(if looks_numeric {
                TrajectoryError::MissingHeader {
                    file: file(),
                    found,
                }
            } else {
                TrajectoryError::WrongHeader {
                    file: file(),
                    found,
                }
            });
        }

        let mut traj = Trajectory::default();
        let mut row = 0usize;
        for rec in records {
            let rec = rec.map_err(csv_err)?;
            let line = rec.position().map(|p| p.line()).unwrap_or(0);
            if rec.iter().all(|f| f.is_empty()) {
                continue; // blank line (e.g. trailing): not a data row
            }
            row += 1;
            if rec.len() != COLUMNS.len() {
                return Err(TrajectoryError::FieldCount {
                    file: file(),
                    line,
                    row,
                    found: rec.len(),
                });
            }
            let mut v = [0.0f64; 8];
            for (k, field) in rec.iter().enumerate() {
                let x: f64 = field.parse().map_err(|_| TrajectoryError::Number {
                    file: file(),
                    line,
                    row,
                    column: COLUMNS[k],
                    text: field.to_string(),
                })?;
                if !x.is_finite() {
                    return Err(TrajectoryError::NonFinite {
                        file: file(),
                        line,
                        row,
                        column: COLUMNS[k],
                        value: x,
                    });
                }
                v[k] = x;
            }
            if let Some(&previous) = traj.time.last()
                && v[0] <= previous
            {
                return Err(TrajectoryError::TimeOrder {
                    file: file(),
                    line,
                    row,
                    t: v[0],
                    previous,
                });
            }
            let q = Quaternion::new(v[4], v[5], v[6], v[7]);
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
            traj.push(v[0], Vector3::new(v[1], v[2], v[3]), q);
        }
        if traj.is_empty() {
            return Err(TrajectoryError::NoData { file: file() });
        }
        Ok(traj)
    }

    /// The CSV text, or an error if any value is NaN/infinite or the columns
    /// have different lengths. Deterministic: same data, same bytes.
    pub fn try_to_csv_bytes(&self) -> Result<Vec<u8>, TrajectoryError> {
        self.check_lengths()?;
        for (i, (t, (p, q))) in self
            .time
            .iter()
            .zip(self.position.iter().zip(&self.orientation))
            .enumerate()
        {
            let v = row_values(*t, p, q);
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                return Err(TrajectoryError::WriteNonFinite {
                    row: i + 1,
                    column: COLUMNS[k],
                    value: v[k],
                });
            }
        }
        Ok(self.to_csv_bytes())
    }

    /// The CSV text, formatted as is (deterministic, shortest round-trip
    /// decimals). This never fails: a non-finite value is printed as `NaN` or
    /// `inf`, which [`Trajectory::from_csv_reader`] then rejects. Use
    /// [`Trajectory::try_to_csv_bytes`] or [`Trajectory::write_csv`], which
    /// refuse such data, to produce files. Rows beyond the shortest column are
    /// dropped.
    pub fn to_csv_bytes(&self) -> Vec<u8> {
        // ~15 characters per number is typical for simulator output.
        let mut s = String::with_capacity(CSV_HEADER.len() + 1 + self.len() * 8 * 16);
        s.push_str(CSV_HEADER);
        s.push('\n');
        for (t, (p, q)) in self
            .time
            .iter()
            .zip(self.position.iter().zip(&self.orientation))
        {
            let v = row_values(*t, p, q);
            for (k, x) in v.iter().enumerate() {
                if k > 0 {
                    s.push(',');
                }
                // Writing to a String cannot fail.
                let _ = write!(s, "{x}");
            }
            s.push('\n');
        }
        s.into_bytes()
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
    /// positions interpolated linearly, orientations by slerp along the
    /// shorter arc (q and −q are the same rotation). Used to check that the
    /// classifier does not depend on the sampling rate. Returns an empty
    /// trajectory if `rate_hz` is not positive and finite.
    pub fn resampled(&self, rate_hz: f64) -> Trajectory {
        let n = self
            .time
            .len()
            .min(self.position.len())
            .min(self.orientation.len());
        if n == 0 || !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Trajectory::default();
        }
        let (t0, t1) = (self.time[0], self.time[n - 1]);
        let m = ((t1 - t0) * rate_hz + 1e-9).floor() as usize + 1;
        let mut out = Trajectory::with_capacity(m);
        let mut j = 0usize;
        for k in 0..m {
            let t = t0 + k as f64 / rate_hz;
            while j + 2 < n && self.time[j + 1] <= t {
                j += 1;
            }
            if n == 1 {
                out.push(t, self.position[0], self.orientation[0]);
                continue;
            }
            let (ta, tb) = (self.time[j], self.time[j + 1]);
            let s = ((t - ta) / (tb - ta)).clamp(0.0, 1.0);
            let p = self.position[j].lerp(&self.position[j + 1], s);
            let q = slerp_short(&self.orientation[j], &self.orientation[j + 1], s);
            out.push(t, p, q);
        }
        out
    }

    fn check_lengths(&self) -> Result<(), TrajectoryError> {
        let (a, b, c) = (self.time.len(), self.position.len(), self.orientation.len());
        if a == b && b == c {
            Ok(())
        } else {
            Err(TrajectoryError::LengthMismatch {
                time: a,
                position: b,
                orientation: c,
            })
        }
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

/// The eight numbers of one CSV row, in column order.
fn row_values(t: f64, p: &Vector3<f64>, q: &UnitQuaternion<f64>) -> [f64; 8] {
    [t, p.x, p.y, p.z, q.w, q.i, q.j, q.k]
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
            &["line 1", "wrong header"],
        );
        let ok = "0,0,0,0,1,0,0,0\n";
        assert_err(
            &format!("{H}{ok}0.1,0,0,-1,1,0\n"),
            &["line 3", "data row 2", "6 fields"],
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
            &format!("{H}{ok}0.1,0,0,-1,1,0.1,0,0\n"),
            &["line 3", "data row 2", "quaternion norm"],
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
}
