//! The data of a breeding run: what one drop showed ([`Evaluation`]), the
//! members and children of a generation, a generation before evaluation
//! ([`Plan`]), the per-generation summary and the resumable checkpoint;
//! what an executor is handed ([`Job`]); the run's error and its progress
//! observer.

use super::cmaes::CmaState;
use super::settings::{BreedSettings, SettingsError};
use crate::leaf::LeafSpec;
use crate::leaf::genome::Genome;
use crate::motion::classify::{MotionClass, ParseNameError, Regime};
use crate::util::svg::PlotError;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// What one drop of one individual showed: its outcome and its score.
///
/// Written (to `gen-NNN.csv`, shard files and the checkpoint) as one flat
/// record, [`EvaluationRecord`], whose `class` column names the outcome
/// (`floater`, `spinner`, `lilter`, `undetermined` or `diverged`); reading
/// it back refuses a record that names no outcome or a regime the
/// classifier does not have.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(into = "EvaluationRecord", try_from = "EvaluationRecord")]
pub struct Evaluation {
    /// How the drop ended.
    pub outcome: Outcome,
    /// Selection score (see [`super::evaluate::score`]).
    pub score: f64,
    /// Distance to the run's motion target ([`crate::motion::describe`]),
    /// when it has one and the fall passes its class gate.
    pub distance: Option<f64>,
    /// Release attitudes the individual was dropped from
    /// ([`super::robust`]); the outcome, score and distance are those of
    /// the lower-median drop.
    pub releases: usize,
    /// How many of the [`Evaluation::releases`] drops kept the target class
    /// (for `--target-features` without a class: were described at all).
    pub kept: usize,
    /// The release attitude of the drop shown (tilt about the body x and y
    /// axes, degrees, as [`crate::sim::drop::DropParams::tilt_deg`]).
    pub release_deg: [f64; 2],
    /// The drop's scaled descriptor differences to the run's motion target
    /// ([`crate::motion::describe::MotionTarget::residuals`]), when it has
    /// a [`Evaluation::distance`]; empty otherwise. What the hybrid's
    /// Levenberg–Marquardt steps fit ([`super::least_squares`]).
    pub residuals: Vec<f64>,
    /// How far apart the drops that fell came out, release to release:
    /// max − min over them of descent speed (m/s), drift ratio and
    /// rotation rate (rad/s), in [`SPREAD_NAMES`] order ([`super::robust`]).
    /// Two leaves whose recorded values differ by more than the sum of
    /// their spreads in one of these fall apart from any release
    /// ([`super::novelty`]). Zeros in a run written before them.
    pub spread: [f64; 3],
}

/// The descriptors of [`Evaluation::spread`], in order.
pub const SPREAD_NAMES: [&str; 3] = ["descent_m_s", "drift_ratio", "spin_rad_s"];

/// How one individual's drop ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// It fell to the end and the classifier named its motion (possibly
    /// `undetermined`).
    Fell(Fall),
    /// Its model was invalid, or the simulation diverged or failed: the error.
    Diverged(String),
}

/// A completed fall, as the classifier saw it.
#[derive(Clone, Debug, PartialEq)]
pub struct Fall {
    /// The motion class.
    pub class: MotionClass,
    /// The sub-regime.
    pub regime: Regime,
    /// The classifier's distance from the nearest class boundary, 0–1.
    pub margin: f64,
    /// Mean descent speed, m/s.
    pub descent_m_s: f64,
    /// Horizontal drift over fall.
    pub drift_ratio: f64,
    /// Net turns about the dominant horizontal axis.
    pub net_turns: f64,
    /// Turns about the vertical.
    pub yaw_turns: f64,
    /// Rotation rate, rad/s: 2π (|net turns| + |yaw turns|) over the
    /// classifier's analysis window (an archive descriptor).
    pub spin_rad_s: f64,
    /// Pitch reversals in the analysis window.
    pub reversals: usize,
    /// Normal flips in the analysis window.
    pub flips: usize,
    /// Mean tilt of the leaf plane from horizontal, degrees.
    pub tilt_deg: f64,
    /// The time step used, s.
    pub dt: f64,
}

/// What one leaf's evaluation came to: one of the classifier's motion
/// classes, or a drop that diverged. The five a generation is counted by
/// (the breed table, generations.csv, the plot, the progress bar).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum OutcomeKind {
    /// Classified a floater.
    Floater,
    /// Classified a spinner.
    Spinner,
    /// Classified a lilter.
    Lilter,
    /// Classified undetermined.
    Undetermined,
    /// The drop diverged.
    Diverged,
}

impl OutcomeKind {
    /// All five, in the order the run's files list them.
    pub const ALL: [OutcomeKind; 5] = [
        OutcomeKind::Floater,
        OutcomeKind::Spinner,
        OutcomeKind::Lilter,
        OutcomeKind::Undetermined,
        OutcomeKind::Diverged,
    ];

    /// The name files and tables use (the class's own name, or `diverged`).
    pub const fn name(self) -> &'static str {
        match self {
            OutcomeKind::Floater => "floater",
            OutcomeKind::Spinner => "spinner",
            OutcomeKind::Lilter => "lilter",
            OutcomeKind::Undetermined => "undetermined",
            OutcomeKind::Diverged => "diverged",
        }
    }

    /// The outcome of a fall classified `class`.
    pub fn of_class(class: MotionClass) -> OutcomeKind {
        match class {
            MotionClass::Floater => OutcomeKind::Floater,
            MotionClass::Spinner => OutcomeKind::Spinner,
            MotionClass::Lilter => OutcomeKind::Lilter,
            MotionClass::Undetermined => OutcomeKind::Undetermined,
        }
    }
}

/// Leaves per [`OutcomeKind`] (written as the five numbers, in
/// [`OutcomeKind::ALL`]'s order).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct OutcomeCounts(pub [usize; 5]);

impl OutcomeCounts {
    /// The counts in [`OutcomeKind::ALL`]'s order, with their kinds.
    pub fn iter(&self) -> impl Iterator<Item = (OutcomeKind, usize)> + '_ {
        OutcomeKind::ALL.into_iter().zip(self.0)
    }

    /// The largest count.
    pub fn max(&self) -> usize {
        self.0.into_iter().max().unwrap_or(0)
    }
}

impl std::ops::Index<OutcomeKind> for OutcomeCounts {
    type Output = usize;
    fn index(&self, kind: OutcomeKind) -> &usize {
        &self.0[kind as usize]
    }
}

impl std::ops::IndexMut<OutcomeKind> for OutcomeCounts {
    fn index_mut(&mut self, kind: OutcomeKind) -> &mut usize {
        &mut self.0[kind as usize]
    }
}

/// The name of a diverged outcome where a class name would be.
pub const DIVERGED: &str = OutcomeKind::Diverged.name();

impl Evaluation {
    /// The fall, unless the drop diverged.
    pub fn fall(&self) -> Option<&Fall> {
        match &self.outcome {
            Outcome::Fell(f) => Some(f),
            Outcome::Diverged(_) => None,
        }
    }

    /// The class, or diverged.
    pub fn kind(&self) -> OutcomeKind {
        match &self.outcome {
            Outcome::Fell(f) => OutcomeKind::of_class(f.class),
            Outcome::Diverged(_) => OutcomeKind::Diverged,
        }
    }

    /// The class name, or `diverged`.
    pub fn class_name(&self) -> &'static str {
        self.kind().name()
    }

    /// The flat record the run's files hold.
    pub fn record(&self) -> EvaluationRecord {
        self.clone().into()
    }
}

/// An [`Evaluation`] as one flat row: what `gen-NNN.csv`, shard files and
/// the checkpoint hold. A diverged drop has an empty regime, zero numbers
/// and its error; a fall has an empty error.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvaluationRecord {
    /// `floater`, `spinner`, `lilter`, `undetermined`, or `diverged`.
    pub class: String,
    /// The sub-regime (empty when diverged).
    pub regime: String,
    /// See [`Evaluation::score`].
    pub score: f64,
    /// See [`Fall::margin`].
    pub margin: f64,
    /// See [`Fall::descent_m_s`].
    pub descent_m_s: f64,
    /// See [`Fall::drift_ratio`].
    pub drift_ratio: f64,
    /// See [`Fall::net_turns`].
    pub net_turns: f64,
    /// See [`Fall::yaw_turns`].
    pub yaw_turns: f64,
    /// See [`Fall::spin_rad_s`].
    #[serde(default)]
    pub spin_rad_s: f64,
    /// See [`Fall::reversals`].
    pub reversals: usize,
    /// See [`Fall::flips`].
    pub flips: usize,
    /// See [`Fall::tilt_deg`].
    pub tilt_deg: f64,
    /// See [`Fall::dt`].
    pub dt: f64,
    /// The error of a diverged drop.
    pub error: String,
    /// See [`Evaluation::distance`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distance: Option<f64>,
    /// See [`Evaluation::releases`] (1 in a run written before them).
    #[serde(default = "one")]
    pub releases: usize,
    /// See [`Evaluation::kept`].
    #[serde(default)]
    pub kept: usize,
    /// See [`Evaluation::release_deg`] (the drop's default, 10° and 2°, in
    /// a run written before them).
    #[serde(default = "default_release")]
    pub release_deg: [f64; 2],
    /// See [`Evaluation::residuals`] (empty in a run written before them).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub residuals: Vec<f64>,
    /// See [`Evaluation::spread`] (zeros in a run written before them).
    #[serde(default)]
    pub spread: [f64; 3],
}

fn one() -> usize {
    1
}

fn default_release() -> [f64; 2] {
    crate::sim::drop::DropParams::default().tilt_deg
}

impl From<Evaluation> for EvaluationRecord {
    fn from(mut e: Evaluation) -> EvaluationRecord {
        let residuals = std::mem::take(&mut e.residuals);
        let (class, regime, error) = match &e.outcome {
            Outcome::Fell(f) => (f.class.to_string(), f.regime.to_string(), String::new()),
            Outcome::Diverged(error) => (DIVERGED.to_string(), String::new(), error.clone()),
        };
        let zero = Fall {
            class: MotionClass::Undetermined,
            regime: Regime::Undetermined,
            margin: 0.0,
            descent_m_s: 0.0,
            drift_ratio: 0.0,
            net_turns: 0.0,
            yaw_turns: 0.0,
            spin_rad_s: 0.0,
            reversals: 0,
            flips: 0,
            tilt_deg: 0.0,
            dt: 0.0,
        };
        let f = e.fall().unwrap_or(&zero);
        EvaluationRecord {
            class,
            regime,
            score: e.score,
            margin: f.margin,
            descent_m_s: f.descent_m_s,
            drift_ratio: f.drift_ratio,
            net_turns: f.net_turns,
            yaw_turns: f.yaw_turns,
            spin_rad_s: f.spin_rad_s,
            reversals: f.reversals,
            flips: f.flips,
            tilt_deg: f.tilt_deg,
            dt: f.dt,
            error,
            distance: e.distance,
            releases: e.releases,
            kept: e.kept,
            release_deg: e.release_deg,
            residuals,
            spread: e.spread,
        }
    }
}

/// A record whose class or regime the classifier does not name.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(transparent)]
pub struct RecordError(#[from] ParseNameError);

impl TryFrom<EvaluationRecord> for Evaluation {
    type Error = RecordError;
    fn try_from(r: EvaluationRecord) -> Result<Evaluation, RecordError> {
        let outcome = if r.class == DIVERGED {
            Outcome::Diverged(r.error)
        } else {
            let class = r.class.parse::<MotionClass>()?;
            let regime = r.regime.parse::<Regime>()?;
            Outcome::Fell(Fall {
                class,
                regime,
                margin: r.margin,
                descent_m_s: r.descent_m_s,
                drift_ratio: r.drift_ratio,
                net_turns: r.net_turns,
                yaw_turns: r.yaw_turns,
                spin_rad_s: r.spin_rad_s,
                reversals: r.reversals,
                flips: r.flips,
                tilt_deg: r.tilt_deg,
                dt: r.dt,
            })
        };
        Ok(Evaluation {
            outcome,
            score: r.score,
            distance: r.distance,
            releases: r.releases,
            kept: r.kept,
            release_deg: r.release_deg,
            residuals: r.residuals,
            spread: r.spread,
        })
    }
}

/// One member of a generation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Individual {
    /// Unique within the run, assigned in order.
    pub id: u64,
    /// The individual it was bred from (none for the first generation's
    /// copies of the prototype... which name the prototype as `None`).
    pub parent: Option<u64>,
    /// Copied unchanged from the previous generation.
    pub elite: bool,
    /// Its genes.
    pub genome: Genome,
    /// Its fall.
    pub eval: Evaluation,
}

/// One child of a generation, bred (or copied from the prototype) but not
/// yet dropped.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Child {
    /// Its id (unique within the run).
    pub id: u64,
    /// The individual it was bred from (`None` in generation 0).
    pub parent: Option<u64>,
    /// Its genes.
    pub genome: Genome,
    /// The parent's score (NaN in generation 0), for the 1/5 success rule.
    pub parent_score: f64,
}

/// A generation before evaluation: what [`super::run::Run::plan`] derives from the
/// checkpoint.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The generation's index.
    pub generation: usize,
    /// The variation scale its children were bred with.
    pub scale: f64,
    /// The next id to assign after its children.
    pub next_id: u64,
    /// The children to evaluate, in id order.
    pub children: Vec<Child>,
    /// The previous generation's best, copied unchanged (already evaluated).
    pub elites: Vec<Individual>,
    /// How many of the children, the last ones, CMA-ES drew
    /// ([`super::strategy`]); the rest were bred by the GA and, just
    /// before CMA-ES's, by Levenberg–Marquardt steps.
    pub cma_children: usize,
    /// How many of the children, those just before CMA-ES's, are
    /// Levenberg–Marquardt steps ([`super::least_squares`]).
    pub model_children: usize,
}

/// Per-generation summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GenerationSummary {
    /// Generation index.
    pub generation: usize,
    /// Leaves per outcome.
    pub counts: OutcomeCounts,
    /// Best score.
    pub best_score: f64,
    /// Mean score.
    pub mean_score: f64,
    /// Id of the best individual.
    pub best_id: u64,
    /// Variation scale used to breed this generation.
    pub scale: f64,
    /// Fraction of children that scored at least as well as their parent.
    pub success_rate: f64,
    /// The best individual's distance to the motion target, if the run has
    /// one and the best passes its class gate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub best_distance: Option<f64>,
    /// How many of its releases kept the target class, for the best
    /// individual ([`Evaluation::kept`]; 0 in a run written before them).
    #[serde(default)]
    pub best_kept: usize,
    /// Releases per individual ([`Evaluation::releases`]).
    #[serde(default = "one")]
    pub releases: usize,
    /// How many leaves of the generation hold the target class robustly
    /// and fall pairwise apart ([`super::novelty::distinct`]): what a run
    /// toward a class improves once the class is held (issue 60); 0 in a
    /// run toward descriptors or written before it.
    #[serde(default)]
    pub distinct: usize,
}

/// The resumable state after a completed generation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The settings of the run.
    pub settings: BreedSettings,
    /// The last completed generation.
    pub generation: usize,
    /// Its population, in id order.
    pub population: Vec<Individual>,
    /// Variation scale for the next generation.
    pub scale: f64,
    /// Next id to assign.
    pub next_id: u64,
    /// Summaries of all completed generations.
    pub history: Vec<GenerationSummary>,
    /// The MAP-Elites archive (empty unless `settings.archive`).
    #[serde(default)]
    pub archive: Vec<ArchiveEntry>,
    /// The CMA-ES state ([`super::cmaes`]) for the next generation, once
    /// the strategy has started it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cmaes: Option<CmaState>,
    /// Content hashes (FNV-1a 64, 16 hex digits) of `run.toml` and of every
    /// `gen-NNN.csv` up to this generation, as written: what a resumed run
    /// checks the files against ([`super::verify`]). Empty in a checkpoint
    /// written before hashes were recorded.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub fnv1a64: std::collections::BTreeMap<String, String>,
}

/// One occupied cell of the archive.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArchiveEntry {
    /// Descent-speed bin (index into [`super::archive::ARCHIVE_DESCENT_EDGES`]).
    pub descent_bin: usize,
    /// Rotation-rate bin (index into [`super::archive::ARCHIVE_SPIN_EDGES`]).
    pub spin_bin: usize,
    /// Generation in which the occupant was evaluated.
    pub generation: usize,
    /// The occupant (the best-scoring leaf that fell into this cell).
    pub individual: Individual,
}

/// What an executor needs to evaluate a generation: where the run lives
/// (shard files go there), the prototype and the settings.
#[derive(Clone, Copy, Debug)]
pub struct Job<'a> {
    /// The run directory.
    pub dir: &'a Path,
    /// The prototype leaf.
    pub proto: &'a LeafSpec,
    /// The run's settings.
    pub settings: &'a BreedSettings,
}

/// Why a run could not start or go on.
#[derive(Debug, thiserror::Error)]
pub enum BreedError {
    /// A file or folder of the run could not be read, written or parsed.
    #[error("{}: {message}", .path.display())]
    File {
        /// The file or folder.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The settings are invalid.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The prototype or the run directory refuse the run, or the run cannot
    /// do what was asked of it now.
    #[error("{0}")]
    Refused(String),
    /// A leaf of the run could not be built or dropped again.
    #[error("leaf {id}: {message}")]
    Leaf {
        /// The individual's id.
        id: u64,
        /// What went wrong.
        message: String,
    },
    /// The shards of a generation could not be evaluated or merged.
    #[error("{0}")]
    Shards(String),
    /// A plot of the run could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// A [`BreedError::File`] for `path`.
pub(crate) fn io_err(path: &Path, e: impl std::fmt::Display) -> BreedError {
    BreedError::File {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Observer of progress (the CLI draws a progress bar with it).
pub trait Progress: Sync {
    /// A generation starts with `size` individuals to evaluate.
    fn start_generation(&self, generation: usize, size: usize);
    /// One individual finished with this outcome.
    fn individual_done(&self, outcome: OutcomeKind, score: f64);
    /// The generation is complete.
    fn finish_generation(&self, summary: &GenerationSummary);
}

/// A [`Progress`] that shows nothing.
pub struct Quiet;

impl Progress for Quiet {
    fn start_generation(&self, _: usize, _: usize) {}
    fn individual_done(&self, _: OutcomeKind, _: f64) {}
    fn finish_generation(&self, _: &GenerationSummary) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An outcome of a class is named as the class is in every file.
    #[test]
    fn outcome_names_are_the_class_names() {
        for class in [
            MotionClass::Floater,
            MotionClass::Spinner,
            MotionClass::Lilter,
            MotionClass::Undetermined,
        ] {
            assert_eq!(OutcomeKind::of_class(class).name(), class.as_str());
        }
        let names: Vec<&str> = OutcomeKind::ALL.iter().map(|k| k.name()).collect();
        assert_eq!(names.last(), Some(&DIVERGED));
        let mut counts = OutcomeCounts::default();
        counts[OutcomeKind::Lilter] += 2;
        assert_eq!(counts.0, [0, 0, 2, 0, 0]);
        assert_eq!(counts.max(), 2);
    }
}
