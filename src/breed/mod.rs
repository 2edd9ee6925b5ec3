//! Breeding: the paper's section 4.1 loop, automated. A prototype is copied
//! into a population of variants ([`crate::leaf::genome`]), each is dropped in
//! still air ([`crate::sim::drop::drop_leaf`]) on the rayon pool, every fall is
//! classified ([`crate::motion::classify`]), the best are kept and the next
//! generation is bred from them with a variation scale that shrinks as the
//! population converges.
//!
//! Reproducibility: every random draw comes from a stream seeded by
//! (seed, generation, id) or (seed, generation, "selection"), never from a
//! shared generator, and results are gathered in id order; so the same seed
//! gives the same bytes whatever the number of threads. Every file is
//! written atomically, and a checkpoint after each generation lets
//! `--resume` finish a killed run with the same bytes as an uninterrupted one.

use crate::breed::executor::Executor;
use crate::leaf::LeafSpec;
use crate::leaf::genome::{Genome, mutate};
use crate::motion::classify::{MotionClass, classify};
use crate::motion::describe::{Descriptors, MotionTarget};
use crate::motion::trajectory::Trajectory;
use crate::physics::params::TimeStep;
use crate::sim::drop::{DropParams, drop_leaf};
use crate::util::io::write_atomic;
use rand::RngExt;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Everything that defines a breeding run (written to `run.toml`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BreedSettings {
    /// Prototype name as given (`a`, `b` or a path).
    pub prototype: String,
    /// The motion class bred for.
    pub target: MotionClass,
    /// Individuals per generation.
    pub population: usize,
    /// Generations in all, numbered from 0: generation 0 is the prototype's
    /// copies, each later one is bred from the one before.
    pub generations: usize,
    /// Seed of every random stream.
    pub seed: u64,
    /// Simulated seconds of each drop.
    pub seconds: f64,
    /// Variation scale of generation 0 (the paper's first round).
    pub initial_scale: f64,
    /// Individuals copied unchanged into the next generation.
    pub elites: usize,
    /// Tournament size for parent selection.
    pub tournament: usize,
    /// Keep a MAP-Elites archive: the best leaf of every cell of descent
    /// speed × rotation rate seen over the whole run.
    #[serde(default)]
    pub archive: bool,
    /// Breed toward motion descriptors (`--like`, `--target-features`)
    /// instead of toward the class alone; see [`crate::motion::describe`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub like: Option<MotionTarget>,
}

impl BreedSettings {
    /// The embedded default: prototype A, floaters, 100 × 8 generations of
    /// 10 s falls, seed 1991 (the year of the paper).
    pub fn default_run() -> BreedSettings {
        BreedSettings {
            prototype: "a".to_string(),
            target: MotionClass::Floater,
            population: 100,
            generations: 8,
            seed: 1991,
            seconds: 10.0,
            initial_scale: 1.0,
            elites: 10,
            tournament: 3,
            archive: false,
            like: None,
        }
    }

    /// Checks the settings, naming the bad one.
    pub fn validate(&self) -> Result<(), String> {
        if self.population < 2 {
            return Err(format!(
                "--population must be at least 2, got {}",
                self.population
            ));
        }
        if self.generations == 0 {
            return Err("--generations must be at least 1".to_string());
        }
        if self.target == MotionClass::Undetermined {
            return Err("--target must be floater, spinner or lilter".to_string());
        }
        if !(self.seconds > 0.0 && self.seconds.is_finite()) {
            return Err(format!(
                "--seconds must be a positive number, got {}",
                self.seconds
            ));
        }
        if !(self.initial_scale > 0.0 && self.initial_scale.is_finite()) {
            return Err(format!(
                "the initial scale must be positive, got {}",
                self.initial_scale
            ));
        }
        if self.elites >= self.population {
            return Err(format!(
                "elites ({}) must be fewer than the population ({})",
                self.elites, self.population
            ));
        }
        if self.tournament == 0 {
            return Err("the tournament size must be at least 1".to_string());
        }
        Ok(())
    }
}

/// What one drop of one individual showed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    /// `floater`, `spinner`, `lilter`, `undetermined`, or `diverged`.
    pub class: String,
    /// The sub-regime (empty when diverged).
    pub regime: String,
    /// Selection score (see [`score`]).
    pub score: f64,
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
    #[serde(default)]
    pub spin_rad_s: f64,
    /// Pitch reversals in the analysis window.
    pub reversals: usize,
    /// Normal flips in the analysis window.
    pub flips: usize,
    /// Mean tilt of the leaf plane from horizontal, degrees.
    pub tilt_deg: f64,
    /// The time step used, s.
    pub dt: f64,
    /// The simulator's error for a diverged fall.
    pub error: String,
    /// Distance to the run's motion target ([`crate::motion::describe`]), when it
    /// has one and the fall passes its class gate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distance: Option<f64>,
}

/// Score of a fall bred toward motion descriptors: as [`score`] for the
/// gate's class, but within it 1 + 1/(1 + d), so that the closest falls
/// rank first and every fall that passes the class gate outranks every one
/// that does not.
pub fn like_score(class: &str, margin: f64, distance: Option<f64>) -> f64 {
    match distance {
        Some(d) if d.is_finite() => 1.0 + 1.0 / (1.0 + d),
        _ if class == "diverged" => -1.0,
        _ if class == "undetermined" => 0.0,
        _ => 0.1 * margin,
    }
}

/// Score of a fall for a target class: diverged −1 (worst), undetermined 0,
/// another class 0.1 × its margin (a clear motion is a better parent than
/// none, but never as good as the target), the target 1 + margin, so that
/// among members of the target class those far from every class boundary
/// (robust to small changes) rank first.
pub fn score(class: &str, margin: f64, target: MotionClass) -> f64 {
    if class == "diverged" {
        -1.0
    } else if class == target.to_string() {
        1.0 + margin
    } else if class == "undetermined" {
        0.0
    } else {
        0.1 * margin
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

/// A generation before evaluation: what [`Run::plan`] derives from the
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
}

/// Per-generation summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GenerationSummary {
    /// Generation index.
    pub generation: usize,
    /// Counts of floater, spinner, lilter, undetermined, diverged.
    pub counts: [usize; 5],
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
}

/// Edges of the archive's descent-speed bins, m/s (log-spaced: gentle
/// floaters at 0.2–0.5 m/s, edge-on divers at 3–10 m/s).
pub const ARCHIVE_DESCENT_EDGES: [f64; 9] = [0.0, 0.25, 0.4, 0.6, 0.9, 1.4, 2.2, 3.5, 5.5];
/// Edges of the archive's rotation-rate bins, rad/s (steady floaters below
/// 0.5; autorotating spinners at 5–70, notes §4e).
pub const ARCHIVE_SPIN_EDGES: [f64; 9] = [0.0, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0];

/// One occupied cell of the archive.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArchiveEntry {
    /// Descent-speed bin (index into [`ARCHIVE_DESCENT_EDGES`]).
    pub descent_bin: usize,
    /// Rotation-rate bin (index into [`ARCHIVE_SPIN_EDGES`]).
    pub spin_bin: usize,
    /// Generation in which the occupant was evaluated.
    pub generation: usize,
    /// The occupant (the best-scoring leaf that fell into this cell).
    pub individual: Individual,
}

fn bin(edges: &[f64], value: f64) -> usize {
    edges.iter().rposition(|&e| value >= e).unwrap_or(0)
}

/// Adds a generation's evaluated individuals to the archive: each cell keeps
/// the highest score (ties: the lower id). Diverged falls have no
/// descriptors and are not archived. Entries stay sorted by cell.
fn update_archive(archive: &mut Vec<ArchiveEntry>, generation: usize, population: &[Individual]) {
    for ind in population
        .iter()
        .filter(|i| !i.elite && i.eval.class != "diverged")
    {
        let cell = (
            bin(&ARCHIVE_DESCENT_EDGES, ind.eval.descent_m_s),
            bin(&ARCHIVE_SPIN_EDGES, ind.eval.spin_rad_s),
        );
        let better = |e: &ArchiveEntry| {
            ind.eval.score > e.individual.eval.score
                || (ind.eval.score == e.individual.eval.score && ind.id < e.individual.id)
        };
        match archive.binary_search_by_key(&cell, |e| (e.descent_bin, e.spin_bin)) {
            Ok(k) if better(&archive[k]) => {
                archive[k] = ArchiveEntry {
                    descent_bin: cell.0,
                    spin_bin: cell.1,
                    generation,
                    individual: ind.clone(),
                }
            }
            Ok(_) => {}
            Err(k) => archive.insert(
                k,
                ArchiveEntry {
                    descent_bin: cell.0,
                    spin_bin: cell.1,
                    generation,
                    individual: ind.clone(),
                },
            ),
        }
    }
}

/// Variation scale rule (Rechenberg's 1/5 success rule): after each
/// generation, if more than a fifth of the children scored at least as well
/// as their parents, widen the variation by 1.22 (e^0.2), else narrow it by
/// 0.82 (e^-0.2); clamped to [`MIN_SCALE`, `MAX_SCALE`]. As the population
/// converges on the target fewer children improve, so the variation shrinks
/// as the paper's second round did by hand.
pub const SUCCESS_TARGET: f64 = 0.2;
/// Smallest variation scale.
pub const MIN_SCALE: f64 = 0.05;
/// Largest variation scale.
pub const MAX_SCALE: f64 = 2.0;

fn next_scale(scale: f64, success_rate: f64) -> f64 {
    let factor = if success_rate > SUCCESS_TARGET {
        0.2f64.exp()
    } else {
        (-0.2f64).exp()
    };
    (scale * factor).clamp(MIN_SCALE, MAX_SCALE)
}

/// A well-mixed 64-bit seed for one random stream (SplitMix64 finaliser).
pub fn stream_seed(seed: u64, generation: u64, id: u64) -> u64 {
    let mut z = seed
        .wrapping_add(generation.wrapping_mul(0x9E37_79B9_7F4A_7C15))
        .wrapping_add(id.wrapping_mul(0xBF58_476D_1CE4_E5B9))
        .wrapping_add(0x94D0_49BB_1331_11EB);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The stream id used for parent selection (never an individual's id).
const SELECTION_STREAM: u64 = u64::MAX;

/// Drops one variant and scores its fall.
pub fn evaluate(proto: &LeafSpec, genome: &Genome, settings: &BreedSettings) -> Evaluation {
    let failed = |class: &str, error: String| Evaluation {
        class: class.to_string(),
        regime: String::new(),
        score: score(class, 0.0, settings.target),
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
        error,
        distance: None,
    };
    let model = match genome.model(proto) {
        Ok(m) => m,
        Err(e) => return failed("diverged", format!("invalid model: {e}")),
    };
    let params = DropParams {
        seconds: settings.seconds,
        dt: TimeStep::Auto,
        ..Default::default()
    };
    match drop_leaf(&model, &params) {
        Err(e) => failed("diverged", e.to_string()),
        Ok(result) => {
            let c = classify(&result.trajectory, model.chord());
            let class = c.class.to_string();
            let f = &c.features;
            let distance = settings.like.as_ref().and_then(|target| {
                let d = target.distance(&Descriptors::of(&c).ok()?);
                d.is_finite().then_some(d)
            });
            let score = match &settings.like {
                Some(_) => like_score(&class, f.margin, distance),
                None => score(&class, f.margin, settings.target),
            };
            Evaluation {
                score,
                distance,
                class,
                regime: c.regime.to_string(),
                margin: f.margin,
                descent_m_s: f.mean_descent_speed_m_s,
                drift_ratio: f.drift_ratio,
                net_turns: f.net_turns,
                yaw_turns: f.yaw_turns,
                spin_rad_s: std::f64::consts::TAU * (f.net_turns.abs() + f.yaw_turns.abs())
                    / (f.t_end_s - f.t_start_s).max(f64::MIN_POSITIVE),
                reversals: f.reversals,
                flips: f.normal_flips,
                tilt_deg: f.tilt_mean_deg,
                dt: result.stats.dt,
                error: String::new(),
            }
        }
    }
}

/// Why a run could not start or go on.
#[derive(Debug)]
pub struct BreedError(pub String);

impl std::fmt::Display for BreedError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BreedError {}

fn io_err(path: &Path, e: impl std::fmt::Display) -> BreedError {
    BreedError(format!("{}: {e}", path.display()))
}

/// Observer of progress (the CLI draws a progress bar with it).
pub trait Progress: Sync {
    /// A generation starts with `size` individuals to evaluate.
    fn start_generation(&self, generation: usize, size: usize);
    /// One individual finished with this class.
    fn individual_done(&self, class: &str, score: f64);
    /// The generation is complete.
    fn finish_generation(&self, summary: &GenerationSummary);
}

/// A [`Progress`] that shows nothing.
pub struct Quiet;

impl Progress for Quiet {
    fn start_generation(&self, _: usize, _: usize) {}
    fn individual_done(&self, _: &str, _: f64) {}
    fn finish_generation(&self, _: &GenerationSummary) {}
}

/// A breeding run bound to its directory.
pub struct Run {
    /// The run directory.
    pub dir: PathBuf,
    /// The prototype leaf.
    pub proto: LeafSpec,
    /// The state after the last completed generation (None before gen 0).
    pub checkpoint: Option<Checkpoint>,
    settings: BreedSettings,
    /// Wall seconds per completed generation. Kept out of the checkpoint so
    /// that every file but timing.csv is identical between identical runs.
    timing: Vec<f64>,
    /// The fall of the best leaf, by id, once [`Run::write_best`] has
    /// dropped it (a `--like` run), so it is not dropped again.
    best_fall: Option<(u64, Trajectory)>,
}

const RUN_FILE: &str = "run.toml";
/// The example fall of a `--like` run.
const EXAMPLE_FILE: &str = "example.csv";
/// The overlay of the example's and the best leaf's falls.
const LIKE_PLOT_FILE: &str = "like.svg";
const CHECKPOINT_FILE: &str = "checkpoint.json";

/// `run.toml`: the settings, the tool version and the prototype itself.
#[derive(Serialize, Deserialize)]
struct RunFile {
    tool: String,
    version: String,
    settings: BreedSettings,
    integrator: String,
    dt: String,
    /// How far the prototype's own fall, at the integrator and step breeding
    /// uses, is from a converged reference after 1 s (issue 3's machinery):
    /// how much to trust the run's trajectories pointwise. Computed alongside
    /// generation 0 and added to run.toml before generation 0's files are
    /// written (absent only while generation 0 runs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    prototype_error: Option<crate::sim::accuracy::ErrorEstimate>,
    prototype_leaf: LeafSpec,
}

/// Simulated seconds over which the prototype's integration error is
/// estimated for run.toml: long enough to include the fall's transient,
/// short enough to stay inside the horizon where pointwise error means
/// something (falls may be chaotic later).
pub const ERROR_ESTIMATE_SECONDS: f64 = 1.0;

/// The prototype's model and the auto step its drops take, refused (naming
/// `source`) if that step would need more than [`crate::physics::run::MAX_STEPS`]
/// steps for `seconds`: a prototype so stiff or light that its runs would
/// take for ever.
fn prototype_step(
    proto: &LeafSpec,
    source: &str,
    seconds: f64,
) -> Result<(crate::physics::model::Model, f64), BreedError> {
    let integrator = DropParams::default().integrator;
    let refuse = |e: String| BreedError(format!("--prototype {source}: {e}"));
    let model = proto.model().map_err(|e| refuse(e.to_string()))?;
    let dt = crate::physics::run::resolve_step(
        &model,
        integrator,
        TimeStep::Auto,
        1.0 / crate::sim::drop::FRAME_RATE,
    )
    .map_err(refuse)?;
    crate::physics::run::check_budget(seconds, dt, crate::sim::drop::FRAME_RATE, integrator)
        .map_err(refuse)?;
    Ok((model, dt))
}

/// The prototype's integration error over about [`ERROR_ESTIMATE_SECONDS`]
/// at the integrator and auto step its drops use.
fn prototype_error(
    proto: &LeafSpec,
    source: &str,
) -> Result<crate::sim::accuracy::ErrorEstimate, BreedError> {
    let (model, dt) = prototype_step(proto, source, ERROR_ESTIMATE_SECONDS)?;
    // The drop's step need not divide a second: estimate over the whole
    // number of steps nearest to ERROR_ESTIMATE_SECONDS.
    let seconds = (ERROR_ESTIMATE_SECONDS / dt).round().max(1.0) * dt;
    crate::sim::accuracy::error_estimate(&model, DropParams::default().integrator, dt, seconds)
        .map_err(|e| BreedError(format!("error estimate of the prototype: {e}")))
}

impl Run {
    /// Prepares a new run in `dir`, or picks up the same run there. A
    /// directory holding a different run (or other files) is refused and
    /// left untouched.
    pub fn create(dir: &Path, settings: BreedSettings) -> Result<Run, BreedError> {
        settings.validate().map_err(BreedError)?;
        let proto = LeafSpec::load(&settings.prototype)
            .map_err(|e| BreedError(format!("--prototype: {e}")))?;
        if dir.join(RUN_FILE).exists() {
            let existing = Run::open(dir)?;
            if existing.settings != settings {
                return Err(BreedError(format!(
                    "{} holds a different run (its run.toml has other settings); choose another --out or --resume it",
                    dir.display()
                )));
            }
            return Ok(existing);
        }
        if dir.exists() {
            let non_empty = std::fs::read_dir(dir)
                .map_err(|e| io_err(dir, e))?
                .next()
                .is_some();
            if non_empty {
                return Err(BreedError(format!(
                    "{} exists and is not a leafmagic run (no run.toml); refusing to write into it",
                    dir.display()
                )));
            }
        }
        let integrator = DropParams::default().integrator;
        // Checked before anything is written: the drops, and the error
        // estimate beside generation 0, must be able to finish.
        let (_, dt) = prototype_step(
            &proto,
            &settings.prototype,
            settings.seconds.max(ERROR_ESTIMATE_SECONDS),
        )?;
        // The example of a --like run is copied in, so the run keeps what it
        // bred toward even if the original moves.
        let example = match &settings.like {
            Some(t) if t.source != "features" => {
                let path = Path::new(&t.source);
                Some(Trajectory::read_csv(path).map_err(|e| io_err(path, e))?)
            }
            _ => None,
        };
        std::fs::create_dir_all(dir).map_err(|e| io_err(dir, e))?;
        let run_file = RunFile {
            tool: "leafmagic".to_string(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            settings: settings.clone(),
            integrator: integrator.to_string(),
            dt: format!("auto: each leaf its own, from its stability estimate (prototype: {dt} s)"),
            prototype_error: None,
            prototype_leaf: proto.clone(),
        };
        let text = toml::to_string(&run_file).map_err(|e| BreedError(e.to_string()))?;
        write_atomic(&dir.join(RUN_FILE), text.as_bytes())
            .map_err(|e| io_err(&dir.join(RUN_FILE), e))?;
        // After run.toml, so a directory holding only the example is never
        // left behind; a run killed before this plots the best alone.
        if let Some(example) = example {
            let path = dir.join(EXAMPLE_FILE);
            let bytes = example.try_to_csv_bytes().map_err(|e| io_err(&path, e))?;
            write_atomic(&path, &bytes).map_err(|e| io_err(&path, e))?;
        }
        Ok(Run {
            dir: dir.to_path_buf(),
            proto,
            checkpoint: None,
            settings,
            timing: Vec::new(),
            best_fall: None,
        })
    }

    /// Opens an existing run directory (for `--resume`). Temporary files left
    /// by a writer that was killed mid-write are removed: the rename never
    /// happened, so they hold nothing the run needs.
    pub fn open(dir: &Path) -> Result<Run, BreedError> {
        for d in [dir.to_path_buf(), dir.join("best")] {
            remove_stale_temporaries(&d);
        }
        Run::load(dir)
    }

    /// Reads a run directory without changing anything in it: what a shard
    /// process uses, since the driver (or other shards) may be writing there
    /// at the same time and their temporary files are not stale.
    pub fn load(dir: &Path) -> Result<Run, BreedError> {
        let path = dir.join(RUN_FILE);
        let text = std::fs::read_to_string(&path).map_err(|e| io_err(&path, e))?;
        let run_file: RunFile = toml::from_str(&text).map_err(|e| io_err(&path, e))?;
        run_file.settings.validate().map_err(|e| io_err(&path, e))?;
        let cp_path = dir.join(CHECKPOINT_FILE);
        let checkpoint = if cp_path.exists() {
            let text = std::fs::read_to_string(&cp_path).map_err(|e| io_err(&cp_path, e))?;
            let cp: Checkpoint = serde_json::from_str(&text).map_err(|e| io_err(&cp_path, e))?;
            if cp.settings != run_file.settings {
                return Err(io_err(
                    &cp_path,
                    "checkpoint does not belong to this run.toml",
                ));
            }
            Some(cp)
        } else {
            None
        };
        // Timing of the generations done before (lost rows read as NaN: the
        // file is informative only).
        let done = checkpoint.as_ref().map_or(0, |c| c.generation + 1);
        let previous: Vec<f64> = std::fs::read_to_string(dir.join("timing.csv"))
            .unwrap_or_default()
            .lines()
            .skip(1)
            .filter_map(|l| l.split(',').nth(1)?.parse().ok())
            .collect();
        let timing = (0..done)
            .map(|g| previous.get(g).copied().unwrap_or(f64::NAN))
            .collect();
        Ok(Run {
            dir: dir.to_path_buf(),
            proto: run_file.prototype_leaf,
            checkpoint,
            settings: run_file.settings,
            timing,
            best_fall: None,
        })
    }

    /// The run's settings.
    pub fn settings(&self) -> &BreedSettings {
        &self.settings
    }

    /// Whether every generation is done.
    pub fn is_complete(&self) -> bool {
        self.checkpoint
            .as_ref()
            .is_some_and(|c| c.generation + 1 >= self.settings.generations)
    }

    /// Runs the remaining generations, writing each one's files and then the
    /// checkpoint.
    pub fn run(&mut self, progress: &dyn Progress) -> Result<(), BreedError> {
        self.run_with(&crate::breed::executor::Local, progress)
    }

    /// [`Run::run`] with the evaluation of each generation done by
    /// `executor` (the rayon pool, child processes, Slurm). The files are the
    /// same bytes whichever does it (all but timing.csv).
    pub fn run_with(
        &mut self,
        executor: &dyn Executor,
        progress: &dyn Progress,
    ) -> Result<(), BreedError> {
        // Shard files of generations already merged (left by a driver killed
        // between its checkpoint and their removal) are of no further use.
        crate::breed::shard::remove_merged(
            &self.dir,
            self.checkpoint.as_ref().map(|c| c.generation),
        );
        while !self.is_complete() {
            self.step_with(executor, progress)?;
        }
        self.write_best()?;
        Ok(())
    }

    /// Breeds, evaluates and records one generation.
    pub fn step(&mut self, progress: &dyn Progress) -> Result<(), BreedError> {
        self.step_with(&crate::breed::executor::Local, progress)
    }

    /// [`Run::step`] in three parts: [`Run::plan`] (the children, from the
    /// checkpoint), evaluation by `executor`, and `Run::finish` (scores,
    /// elites, summary, files, checkpoint).
    pub fn step_with(
        &mut self,
        executor: &dyn Executor,
        progress: &dyn Progress,
    ) -> Result<(), BreedError> {
        let start = std::time::Instant::now();
        let plan = self.plan();
        progress.start_generation(plan.generation, plan.children.len());
        let proto = &self.proto;
        let evaluate_all = || executor.evaluate(self, &plan, progress);
        // run.toml's error estimate is serial work: do it beside generation 0
        // rather than before it, and complete run.toml before gen-000.csv.
        let evals = if plan.generation == 0 {
            let (evals, estimate) = rayon::join(evaluate_all, || {
                prototype_error(proto, &self.settings.prototype)
            });
            let evals = evals?;
            self.complete_run_file(estimate?)?;
            evals
        } else {
            evaluate_all()?
        };
        if evals.len() != plan.children.len() {
            return Err(BreedError(format!(
                "generation {}: {} evaluations for {} children",
                plan.generation,
                evals.len(),
                plan.children.len()
            )));
        }
        self.finish(plan, evals, start, progress)
    }

    /// The next generation before evaluation: its children, derived
    /// deterministically from the checkpoint (none: generation 0, copies of
    /// the prototype), and the elites it keeps. Every random draw comes from
    /// [`stream_seed`] streams, so any process that holds the run directory
    /// derives the same plan.
    pub fn plan(&self) -> Plan {
        let s = &self.settings;
        let (generation, scale, next_id, children) = match &self.checkpoint {
            None => {
                // Generation 0: copies of the prototype with the first round's variation.
                let g0 = Genome::of_prototype(&self.proto);
                let children: Vec<Child> = (0..s.population as u64)
                    .map(|id| {
                        let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(s.seed, 0, id));
                        Child {
                            id,
                            parent: None,
                            genome: mutate(&g0, &self.proto.bounds, s.initial_scale, &mut rng),
                            parent_score: f64::NAN,
                        }
                    })
                    .collect();
                (0, s.initial_scale, s.population as u64, children)
            }
            Some(cp) => {
                let generation = cp.generation + 1;
                let parents = rank(&cp.population);
                let mut sel = Xoshiro256PlusPlus::seed_from_u64(stream_seed(
                    s.seed,
                    generation as u64,
                    SELECTION_STREAM,
                ));
                let mut next_id = cp.next_id;
                let mut children = Vec::with_capacity(s.population - s.elites);
                for _ in 0..s.population - s.elites {
                    // Tournament: the best of `tournament` uniformly drawn members.
                    let pick = (0..s.tournament)
                        .map(|_| sel.random_range(0..parents.len()))
                        .min()
                        .expect("tournament size ≥ 1");
                    let parent = parents[pick];
                    let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(
                        s.seed,
                        generation as u64,
                        next_id,
                    ));
                    let genome = mutate(&parent.genome, &self.proto.bounds, cp.scale, &mut rng);
                    children.push(Child {
                        id: next_id,
                        parent: Some(parent.id),
                        genome,
                        parent_score: parent.eval.score,
                    });
                    next_id += 1;
                }
                (generation, cp.scale, next_id, children)
            }
        };
        let elites: Vec<Individual> = match &self.checkpoint {
            None => Vec::new(),
            Some(cp) => rank(&cp.population)
                .into_iter()
                .take(s.elites)
                .map(|i| Individual {
                    elite: true,
                    ..i.clone()
                })
                .collect(),
        };
        Plan {
            generation,
            scale,
            next_id,
            children,
            elites,
        }
    }

    /// Everything after evaluation: success rate, population, summary,
    /// archive, the generation's files and the checkpoint. `evals` holds one
    /// evaluation per child of `plan`, in the plan's order.
    fn finish(
        &mut self,
        plan: Plan,
        evals: Vec<Evaluation>,
        start: std::time::Instant,
        progress: &dyn Progress,
    ) -> Result<(), BreedError> {
        let s = &self.settings;
        let Plan {
            generation,
            scale,
            mut next_id,
            children,
            elites,
        } = plan;
        let evaluated: Vec<(Individual, f64)> = children
            .into_iter()
            .zip(evals)
            .map(|(c, eval)| {
                (
                    Individual {
                        id: c.id,
                        parent: c.parent,
                        elite: false,
                        genome: c.genome,
                        eval,
                    },
                    c.parent_score,
                )
            })
            .collect();
        let successes = evaluated
            .iter()
            .filter(|(i, ps)| ps.is_nan() || i.eval.score >= *ps)
            .count();
        let mut success_rate = successes as f64 / evaluated.len().max(1) as f64;
        if s.like.is_some() {
            // Toward descriptors the step size should follow local progress:
            // only children of parents inside the class gate (score > 1)
            // count, and a success is a child strictly closer than its
            // parent. Children crossing into the class would otherwise keep
            // the rate high and the variation coarse for ever.
            let inside: Vec<&(Individual, f64)> =
                evaluated.iter().filter(|(_, ps)| *ps > 1.0).collect();
            if !inside.is_empty() {
                let closer = inside.iter().filter(|(i, ps)| i.eval.score > *ps).count();
                success_rate = closer as f64 / inside.len() as f64;
            }
        }
        let mut population: Vec<Individual> = elites;
        population.extend(evaluated.into_iter().map(|(i, _)| i));
        population.sort_by_key(|i| i.id);
        let summary = summarise(generation, &population, scale, success_rate);
        let mut history = match &self.checkpoint {
            None => Vec::new(),
            Some(cp) => cp.history.clone(),
        };
        history.push(summary.clone());
        self.timing.truncate(generation);
        self.timing.push(start.elapsed().as_secs_f64());
        next_id = next_id.max(population.iter().map(|i| i.id + 1).max().unwrap_or(0));
        let mut archive = self
            .checkpoint
            .as_ref()
            .map_or_else(Vec::new, |c| c.archive.clone());
        if s.archive {
            update_archive(&mut archive, generation, &population);
        }
        let checkpoint = Checkpoint {
            settings: s.clone(),
            generation,
            population,
            // Generation 0 is the prototype's copies: its successes say
            // nothing about parents, so the scale rule starts from gen 1.
            scale: if generation == 0 {
                scale
            } else {
                next_scale(scale, success_rate)
            },
            next_id,
            history,
            archive,
        };
        self.write_generation(&checkpoint)?;
        // The checkpoint now holds the generation: its shard files (if an
        // executor wrote any) are merged and go.
        crate::breed::shard::remove_merged(&self.dir, Some(generation));
        progress.finish_generation(&summary);
        self.checkpoint = Some(checkpoint);
        Ok(())
    }

    /// Adds the prototype's error estimate to run.toml (if it is not there
    /// yet: a run resumed from generation 0 may have written it already).
    fn complete_run_file(
        &self,
        estimate: crate::sim::accuracy::ErrorEstimate,
    ) -> Result<(), BreedError> {
        let path = self.dir.join(RUN_FILE);
        let text = std::fs::read_to_string(&path).map_err(|e| io_err(&path, e))?;
        let mut run_file: RunFile = toml::from_str(&text).map_err(|e| io_err(&path, e))?;
        if run_file.prototype_error.is_some() {
            return Ok(());
        }
        run_file.prototype_error = Some(estimate);
        let text = toml::to_string(&run_file).map_err(|e| BreedError(e.to_string()))?;
        write_atomic(&path, text.as_bytes()).map_err(|e| io_err(&path, e))
    }

    fn write(&self, name: &str, bytes: &[u8]) -> Result<(), BreedError> {
        let path = self.dir.join(name);
        write_atomic(&path, bytes).map_err(|e| io_err(&path, e))
    }

    /// Writes gen-NNN.csv, generations.csv, timing.csv, generations.svg
    /// (class counts per generation), then the checkpoint
    /// (last, so a kill between them only repeats this generation).
    fn write_generation(&self, cp: &Checkpoint) -> Result<(), BreedError> {
        self.write(
            &format!("gen-{:03}.csv", cp.generation),
            population_csv(cp.generation, &cp.population).as_bytes(),
        )?;
        self.write("generations.csv", generations_csv(&cp.history).as_bytes())?;
        let mut timing = String::from("generation,wall_s\n");
        for (g, t) in self.timing.iter().enumerate() {
            let _ = writeln!(timing, "{g},{t}");
        }
        self.write("timing.csv", timing.as_bytes())?;
        let title = format!(
            "{}: breeding toward {} (population {}, seed {})",
            self.proto.name, self.settings.target, self.settings.population, self.settings.seed
        );
        let svg = crate::util::svg::generations_svg(&cp.history, &title).map_err(BreedError)?;
        self.write("generations.svg", svg.as_bytes())?;
        let json = serde_json::to_string(cp).map_err(|e| BreedError(e.to_string()))?;
        self.write(CHECKPOINT_FILE, json.as_bytes())
    }

    /// The best individuals of the last generation as leaf files that `drop`
    /// and scenes accept (`best/leaf-<id>.toml`), best first, with an index;
    /// with an archive, also `archive/` (one leaf per occupied cell) and
    /// `archive.csv`.
    pub fn write_best(&mut self) -> Result<(), BreedError> {
        let Some(cp) = &self.checkpoint else {
            return Ok(());
        };
        if self.settings.archive {
            let dir = self.dir.join("archive");
            std::fs::create_dir_all(&dir).map_err(|e| io_err(&dir, e))?;
            let members: Vec<&Individual> = cp.archive.iter().map(|e| &e.individual).collect();
            export_leaves(&self.proto, &members, &dir)?;
            let mut csv = String::from(
                "descent_min_m_s,descent_max_m_s,spin_min_rad_s,spin_max_rad_s,generation,id,class,regime,score,descent_m_s,spin_rad_s,file\n",
            );
            let edge = |edges: &[f64], k: usize| {
                edges
                    .get(k + 1)
                    .map_or(String::from("inf"), |e| e.to_string())
            };
            for e in &cp.archive {
                let i = &e.individual;
                let _ = writeln!(
                    csv,
                    "{},{},{},{},{},{},{},{},{},{},{},archive/leaf-{}.toml",
                    ARCHIVE_DESCENT_EDGES[e.descent_bin],
                    edge(&ARCHIVE_DESCENT_EDGES, e.descent_bin),
                    ARCHIVE_SPIN_EDGES[e.spin_bin],
                    edge(&ARCHIVE_SPIN_EDGES, e.spin_bin),
                    e.generation,
                    i.id,
                    i.eval.class,
                    i.eval.regime,
                    i.eval.score,
                    i.eval.descent_m_s,
                    i.eval.spin_rad_s,
                    i.id
                );
            }
            self.write("archive.csv", csv.as_bytes())?;
        }
        let best: Vec<&Individual> = rank(&cp.population).into_iter().take(5).collect();
        let dir = self.dir.join("best");
        std::fs::create_dir_all(&dir).map_err(|e| io_err(&dir, e))?;
        export_leaves(&self.proto, &best, &dir)?;
        if let (Some(target), Some(first)) = (&self.settings.like, best.first()) {
            let fall = self.best_fall(first)?;
            self.best_fall = Some((first.id, fall.clone()));
            let example = self.example();
            let title = format!(
                "{} bred like {}: leaf {} ({}, distance {})",
                self.proto.name,
                target.source,
                first.id,
                first.eval.class,
                first
                    .eval
                    .distance
                    .map_or("∞, another class".to_string(), |d| format!("{d:.3}"))
            );
            let svg =
                crate::util::svg::like_svg(example.as_ref(), &fall, &title).map_err(BreedError)?;
            self.write(LIKE_PLOT_FILE, svg.as_bytes())?;
        }
        Ok(())
    }

    /// The fall of a member, dropped again exactly as it was evaluated.
    pub fn best_fall(&self, member: &Individual) -> Result<Trajectory, BreedError> {
        if let Some((id, fall)) = &self.best_fall
            && *id == member.id
        {
            return Ok(fall.clone());
        }
        let model = member
            .genome
            .model(&self.proto)
            .map_err(|e| BreedError(format!("leaf {}: {e}", member.id)))?;
        let params = DropParams {
            seconds: self.settings.seconds,
            dt: TimeStep::Auto,
            ..Default::default()
        };
        drop_leaf(&model, &params)
            .map(|r| r.trajectory)
            .map_err(|e| BreedError(format!("leaf {}: {e}", member.id)))
    }

    /// The example fall of a `--like` run, as copied into the run directory
    /// (none for `--target-features`, or if it could not be read).
    pub fn example(&self) -> Option<Trajectory> {
        Trajectory::read_csv(&self.dir.join(EXAMPLE_FILE)).ok()
    }

    /// Summaries of the completed generations.
    pub fn history(&self) -> &[GenerationSummary] {
        self.checkpoint.as_ref().map_or(&[], |c| &c.history)
    }
}

/// Removes `.<name>.<pid>.tmp` files (see [`crate::util::io::write_atomic`]).
fn remove_stale_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') && name.ends_with(".tmp") {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// Writes each individual as `leaf-<id>.toml` plus `index.csv` into `dir`.
pub fn export_leaves(
    proto: &LeafSpec,
    chosen: &[&Individual],
    dir: &Path,
) -> Result<(), BreedError> {
    let mut index = String::from("rank,id,file,class,regime,score,descent_m_s\n");
    for (rank, ind) in chosen.iter().enumerate() {
        let mut leaf = ind.genome.to_leaf(proto);
        leaf.name = format!("{}-{}", proto.name, ind.id);
        let file = format!("leaf-{}.toml", ind.id);
        let text = format!(
            "# Bred by leafmagic from {}: individual {} ({} / {}, score {}).\n{}",
            proto.name,
            ind.id,
            ind.eval.class,
            ind.eval.regime,
            ind.eval.score,
            leaf.to_toml()
        );
        let path = dir.join(&file);
        write_atomic(&path, text.as_bytes()).map_err(|e| io_err(&path, e))?;
        let _ = writeln!(
            index,
            "{},{},{},{},{},{},{}",
            rank + 1,
            ind.id,
            file,
            ind.eval.class,
            ind.eval.regime,
            ind.eval.score,
            ind.eval.descent_m_s
        );
    }
    let path = dir.join("index.csv");
    write_atomic(&path, index.as_bytes()).map_err(|e| io_err(&path, e))
}

/// Members best first; ties broken by id so the order is deterministic.
pub fn rank(population: &[Individual]) -> Vec<&Individual> {
    let mut v: Vec<&Individual> = population.iter().collect();
    v.sort_by(|a, b| b.eval.score.total_cmp(&a.eval.score).then(a.id.cmp(&b.id)));
    v
}

const CLASSES: [&str; 5] = ["floater", "spinner", "lilter", "undetermined", "diverged"];

fn summarise(
    generation: usize,
    population: &[Individual],
    scale: f64,
    success_rate: f64,
) -> GenerationSummary {
    let mut counts = [0; 5];
    for i in population {
        if let Some(k) = CLASSES.iter().position(|c| *c == i.eval.class) {
            counts[k] += 1;
        }
    }
    let best = rank(population)[0];
    GenerationSummary {
        generation,
        counts,
        best_score: best.eval.score,
        mean_score: population.iter().map(|i| i.eval.score).sum::<f64>() / population.len() as f64,
        best_id: best.id,
        scale,
        success_rate,
        best_distance: best.eval.distance,
    }
}

/// generations.csv: one row per completed generation.
pub fn generations_csv(history: &[GenerationSummary]) -> String {
    let mut out = String::from(
        "generation,floater,spinner,lilter,undetermined,diverged,best_score,mean_score,best_id,scale,success_rate,best_distance\n",
    );
    for h in history {
        let c = h.counts;
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{}",
            h.generation,
            c[0],
            c[1],
            c[2],
            c[3],
            c[4],
            h.best_score,
            h.mean_score,
            h.best_id,
            h.scale,
            h.success_rate,
            h.best_distance.map_or(String::new(), |d| d.to_string())
        );
    }
    out
}

/// gen-NNN.csv: one row per individual, in id order.
pub fn population_csv(generation: usize, population: &[Individual]) -> String {
    let mut out = String::from("generation,id,parent,elite");
    if let Some(first) = population.first() {
        for (name, _) in first.genome.values() {
            let _ = write!(out, ",{name}");
        }
    }
    out.push_str(
        ",class,regime,score,margin,descent_m_s,drift_ratio,net_turns,yaw_turns,reversals,flips,tilt_deg,dt,distance,error\n",
    );
    for i in population {
        let parent = i.parent.map_or(String::new(), |p| p.to_string());
        let _ = write!(out, "{generation},{},{parent},{}", i.id, i.elite);
        for (_, v) in i.genome.values() {
            let _ = write!(out, ",{v}");
        }
        let e = &i.eval;
        // Errors may contain commas: quote them for CSV.
        let error = if e.error.is_empty() {
            String::new()
        } else {
            format!("\"{}\"", e.error.replace('"', "\"\""))
        };
        let _ = writeln!(
            out,
            ",{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            e.class,
            e.regime,
            e.score,
            e.margin,
            e.descent_m_s,
            e.drift_ratio,
            e.net_turns,
            e.yaw_turns,
            e.reversals,
            e.flips,
            e.tilt_deg,
            e.dt,
            e.distance.map_or(String::new(), |d| d.to_string()),
            error
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn score_orders_diverged_undetermined_other_target() {
        let t = MotionClass::Floater;
        let s = |c: &str, m: f64| score(c, m, t);
        assert!(s("diverged", 0.0) < s("undetermined", 0.0));
        assert!(s("undetermined", 0.0) <= s("spinner", 0.0));
        assert!(s("spinner", 1.0) < s("floater", 0.0));
        assert!(s("floater", 0.2) < s("floater", 0.9));
    }

    #[test]
    fn one_fifth_rule_widens_on_success_and_narrows_otherwise() {
        assert!(next_scale(1.0, 0.5) > 1.0);
        assert!(next_scale(1.0, 0.1) < 1.0);
        assert_eq!(next_scale(MIN_SCALE, 0.0), MIN_SCALE);
        assert_eq!(next_scale(MAX_SCALE, 1.0), MAX_SCALE);
    }

    #[test]
    fn streams_differ_by_generation_and_id() {
        let a = stream_seed(1, 0, 0);
        assert_ne!(a, stream_seed(1, 0, 1));
        assert_ne!(a, stream_seed(1, 1, 0));
        assert_ne!(a, stream_seed(2, 0, 0));
        assert_eq!(a, stream_seed(1, 0, 0));
    }
}

pub mod executor;
pub mod shard;
