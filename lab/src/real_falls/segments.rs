//! The films' segments: reading them from their files (the squares in
//! `tests/data/real-falls/squares/`, or another shape's films in the same
//! format), their size bins, and the authors' labelling rule (two cluster
//! centres) fitted on them.

use super::films::{Features, Film, Label};
use leafmagic::leaf::plates::PlateShape;
use nalgebra::Vector3;
use std::path::Path;

type V3 = Vector3<f64>;

/// The experiment's size bins, on the half-side r (m): [lo, hi).
pub const SQUARE_BINS: [(f64, f64); 5] = [
    (0.015, 0.019),
    (0.019, 0.0225),
    (0.0225, 0.030),
    (0.030, 0.040),
    (0.040, 0.0505),
];

/// One real segment of `tests/data/real-falls/squares/` (or of another
/// shape's films, [`read_films`]).
#[derive(Clone, Debug, PartialEq)]
pub struct RealSegment {
    /// File name without extension.
    pub name: String,
    /// The paper's shape.
    pub shape: PlateShape,
    /// Half the plate's size as `leafmagic plate --size` takes it (twice
    /// the inradius): a square's half-side, a circle's radius, a hexagon's
    /// inradius, m.
    pub radius: f64,
    /// Released on edge (else flat).
    pub on_edge: bool,
    /// People's label.
    pub human: Label,
    /// The authors' k-means label.
    pub auto: Label,
    /// The segment as filmed.
    pub film: Film,
}

/// Why the real data cannot be read.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {reason}")]
pub struct RealFallsError {
    /// The file.
    pub file: String,
    /// What is wrong.
    pub reason: String,
}

/// Reads `labels.csv` and every segment it lists from `dir`, all squares
/// (`tests/data/real-falls/squares/`): a segment of another shape is an
/// error naming its line.
pub fn read_squares(dir: &Path) -> Result<Vec<RealSegment>, RealFallsError> {
    read_films(dir, Some(PlateShape::Square))
}

/// Reads `labels.csv` (`name,shape,radius_m,width_px,release_vertical,
/// human,auto[,rows]`; labels 1 tumbling, 2 chaotic, 3 steady) and every
/// segment it lists from `dir` (`NAME.csv`: `t,x,y,z,area1,area2`), the
/// squares' format: the study's held-out shapes, once given in it, are
/// read and compared as the squares are. `shape` is `square`, `circle` or
/// `hexagon`, every row the same one, and `radius_m` half the size that
/// `leafmagic plate --size` takes (so a hexagon's inradius, not its
/// circumradius). With `only`, a segment of another shape is an error.
pub fn read_films(
    dir: &Path,
    only: Option<PlateShape>,
) -> Result<Vec<RealSegment>, RealFallsError> {
    let fail = |file: &Path, reason: String| RealFallsError {
        file: file.display().to_string(),
        reason,
    };
    let labels = dir.join("labels.csv");
    let text =
        std::fs::read_to_string(&labels).map_err(|e| fail(&labels, format!("cannot read: {e}")))?;
    let mut out = Vec::new();
    for (line, row) in text.lines().enumerate().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        let bad = |what: &str| fail(&labels, format!("line {}: {what}", line + 1));
        if f.len() < 7 {
            return Err(bad(
                "expected name,shape,radius_m,width_px,release_vertical,human,auto,rows",
            ));
        }
        let num = |k: usize| {
            f[k].trim()
                .parse::<f64>()
                .map_err(|_| bad(&format!("column {} is not a number", k + 1)))
        };
        let label = |k: usize| {
            f[k].trim()
                .parse::<u32>()
                .ok()
                .and_then(Label::from_code)
                .ok_or_else(|| bad(&format!("column {} is not a label 1, 2 or 3", k + 1)))
        };
        let shape = match f[1].trim().parse::<PlateShape>() {
            Ok(shape) if shape != PlateShape::Rectangle => shape,
            _ => {
                return Err(bad(&format!(
                    "column 2 (shape) is {:?}: expected square, circle, hexagon or cross",
                    f[1].trim()
                )));
            }
        };
        let first = out.first().map(|s: &RealSegment| s.shape);
        if let Some(want) = only.or(first).filter(|&want| want != shape) {
            return Err(bad(&format!(
                "column 2 (shape) is {}, where {} {}",
                shape.as_str(),
                if only.is_some() {
                    "the reader wants"
                } else {
                    "the rows above are"
                },
                want.as_str()
            )));
        }
        let name = f[0].trim().to_string();
        let path = dir.join(format!("{name}.csv"));
        let data =
            std::fs::read_to_string(&path).map_err(|e| fail(&path, format!("cannot read: {e}")))?;
        let mut film = Film::default();
        for (k, r) in data.lines().enumerate().skip(1) {
            let v: Vec<f64> = r
                .split(',')
                .map(|s| s.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| fail(&path, format!("line {}: not numbers", k + 1)))?;
            if v.len() != 6 {
                return Err(fail(
                    &path,
                    format!("line {}: expected t,x,y,z,area1,area2", k + 1),
                ));
            }
            if let Some(c) = v.iter().position(|x| !x.is_finite()) {
                let column = ["t", "x", "y", "z", "area1", "area2"][c];
                return Err(fail(
                    &path,
                    format!(
                        "line {}: {column} is {} (a film's values are finite)",
                        k + 1,
                        v[c]
                    ),
                ));
            }
            film.position.push(V3::new(v[1], v[2], v[3]));
            film.area[0].push(v[4]);
            film.area[1].push(v[5]);
        }
        let radius = num(2)?;
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(bad(&format!(
                "column 3 (radius_m) is {radius}: expected a size > 0 m"
            )));
        }
        out.push(RealSegment {
            name,
            shape,
            radius,
            on_edge: num(4)? != 0.0,
            human: label(5)?,
            auto: label(6)?,
            film,
        });
    }
    Ok(out)
}

/// The two cluster centres (Osc, SpeedZ) of tumbling and chaotic segments:
/// the means of the real segments of each automatic label.
pub fn centres(real: &[RealSegment]) -> [[f64; 2]; 2] {
    let mean = |label: Label| {
        let f: Vec<Features> = real
            .iter()
            .filter(|s| s.auto == label)
            .filter_map(|s| s.film.features())
            .collect();
        let n = f.len().max(1) as f64;
        [
            f.iter().map(|f| f.osc).sum::<f64>() / n,
            f.iter().map(|f| f.speed_z).sum::<f64>() / n,
        ]
    };
    [mean(Label::Tumbling), mean(Label::Chaotic)]
}

/// The experiment's rule: the label of the nearer centre.
pub fn label_of(f: &Features, centres: &[[f64; 2]; 2]) -> Label {
    let d = |c: [f64; 2]| (f.osc - c[0]).powi(2) + (f.speed_z - c[1]).powi(2);
    if d(centres[0]) <= d(centres[1]) {
        Label::Tumbling
    } else {
        Label::Chaotic
    }
}

/// The bin of [`SQUARE_BINS`] a square of half-side `radius` falls in.
pub fn bin_of(radius: f64) -> Option<usize> {
    SQUARE_BINS
        .iter()
        .position(|&(lo, hi)| (lo..hi).contains(&radius))
}
