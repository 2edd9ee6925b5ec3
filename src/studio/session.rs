//! A studio session: a tree of generations bred from a person's picks, and
//! the run directory that records it.
//!
//! Files (every one written atomically, `studio.json` last, so a session
//! killed at any moment reopens at its last completed action):
//!
//! - `studio.json`: the settings, the tree (each generation's parent, the
//!   picks it was bred from (and whether the machine made them), its
//!   random seed and variation scale, its ids), the generation on screen
//!   and the collection of kept leaves;
//! - `prototype.toml`: the prototype, so a session reopens without its
//!   source file;
//! - `gen-NNN.json`: generation NNN's candidates: how each was made, its
//!   parents, genome and evaluation;
//! - `gen-NNN-motion.json`: the fall each candidate is shown with;
//! - `gen-NNN/leaf-ID.toml`: every candidate as a leaf file;
//! - `example.csv`: the example fall given at the start (`--like`), as
//!   read, so a session reopens with it;
//! - `run.toml`, `gen-NNN.csv`, `generations.csv`, `checkpoint.json`: the
//!   session as a breeding run ([`crate::breed::run::write_record`]), so
//!   `export` and `preview` read it as any run; rewritten before
//!   `studio.json` at every action.

use super::preference::{Preference, features};
use super::variation::{Child, Origin, children_of, first_generation};
use crate::breed::evaluate;
use crate::breed::population::{Evaluation, Individual};
use crate::breed::run::{RunRecord, write_record};
use crate::breed::selection::{MAX_SCALE, MIN_SCALE, stream_seed, summarise};
use crate::breed::settings::{BreedSettings, DEFAULT_RELEASES};
use crate::formats::clip::Motion;
use crate::leaf::LeafSpec;
use crate::leaf::genome::Genome;
use crate::motion::classify::MotionClass;
use crate::motion::describe::MotionTarget;
use crate::output::export::drop_clip_released;
use crate::util::io::write_atomic;
use crate::util::setting::Setting;
use base64::Engine as _;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The session file.
pub const SESSION_FILE: &str = "studio.json";
/// The prototype as the session bred from it.
pub const PROTOTYPE_FILE: &str = "prototype.toml";
/// Version of the session files' format.
pub const FORMAT: u32 = 1;
/// Candidates per generation by default: 12, in the range interactive
/// evolution found workable (Sims 1991: 4–20; more makes each too small).
pub const DEFAULT_GRID: usize = 12;
/// Fewest and most candidates per generation.
pub const GRID_RANGE: [usize; 2] = [4, 20];
/// Each generation's default variation scale is its parent's times this:
/// the paper's "smaller variation" in each later round.
pub const SHRINK: f64 = 0.8;
/// Frames per second of the falls shown: enough for smooth motion in a
/// small view, few enough that a grid of 10 s falls stays small.
pub const MOTION_FPS: f64 = 20.0;
/// "More like this" evaluates this many times the grid and keeps the
/// grid's worth closest: the machine's volume between two looks.
pub const LIKE_POOL: usize = 3;
/// Candidates the machine picks in a generation it breeds alone
/// ([`Session::auto_picks`]): two, so crossovers join the variations.
pub const AUTO_PICKS: usize = 2;
/// Most generations one "Auto N" request may breed: enough to cover the
/// 5–20 generations interactive sessions last (Sims 1991).
pub const MAX_AUTO: usize = 20;
/// The example fall's file in the session.
pub const EXAMPLE_FILE: &str = "example.csv";
/// Stream slot of a generation's step seed in [`stream_seed`] (never an
/// individual's id nor breed's selection stream).
const STEP_STREAM: u64 = u64::MAX - 2;

/// What defines a session (the command line's flags).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudioSettings {
    /// The prototype as given (`a`, `b` or a file).
    pub prototype: String,
    /// The class the falls are scored against (what `kept` counts).
    pub target: MotionClass,
    /// Seed of every random stream.
    pub seed: u64,
    /// Candidates per generation.
    pub grid: usize,
    /// Simulated seconds of each drop.
    pub seconds: f64,
    /// Release attitudes each candidate is dropped from.
    pub releases: usize,
}

impl StudioSettings {
    /// Checks the settings, naming the bad one.
    pub fn validate(&self) -> Result<(), StudioError> {
        if !(GRID_RANGE[0]..=GRID_RANGE[1]).contains(&self.grid) {
            return Err(StudioError::Input(format!(
                "{} must be {} to {}, got {}",
                Setting::Grid,
                GRID_RANGE[0],
                GRID_RANGE[1],
                self.grid
            )));
        }
        self.breed_settings()
            .validate()
            .map_err(|e| StudioError::Input(e.to_string()))
    }

    /// The breeding settings the candidates are evaluated with (breed's,
    /// one generation of `grid`, no elites).
    pub fn breed_settings(&self) -> BreedSettings {
        BreedSettings {
            prototype: self.prototype.clone(),
            target: self.target,
            population: self.grid,
            generations: 1,
            seed: self.seed,
            seconds: self.seconds,
            elites: 0,
            releases: self.releases,
            ..BreedSettings::default_run()
        }
    }

    /// The default settings for `prototype`.
    pub fn new(prototype: &str, target: MotionClass, seed: u64) -> StudioSettings {
        StudioSettings {
            prototype: prototype.to_string(),
            target,
            seed,
            grid: DEFAULT_GRID,
            seconds: 10.0,
            releases: DEFAULT_RELEASES,
        }
    }
}

/// One node of the session's tree.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GenerationNode {
    /// Its index: generations are numbered in the order they were made.
    pub index: usize,
    /// The generation it was bred from (none for generation 0).
    pub parent: Option<usize>,
    /// The ids picked in the parent that it was bred from.
    pub picks: Vec<u64>,
    /// The seed of the step that made it.
    pub seed: u64,
    /// The variation scale of its children.
    pub scale: f64,
    /// Its candidates' ids, in grid order.
    pub ids: Vec<u64>,
    /// The picks were the machine's ([`Session::plan_auto`]), not the
    /// person's.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub auto: bool,
    /// "More like this": the candidate whose fall the generation was bred
    /// toward ([`Session::plan_like`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub like: Option<u64>,
    /// Bred toward the session's example fall: its distances are to the
    /// example's ([`Session::plan_auto`] with an example).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub example: bool,
    /// Bred toward descriptors the person gave ("Auto N toward descent=0.8,
    /// …", [`Session::plan_auto`]): its distances are to them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub toward: Option<MotionTarget>,
}

/// The session file: settings and the tree.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SessionFile {
    /// [`FORMAT`].
    pub format: u32,
    /// The settings.
    pub settings: StudioSettings,
    /// The generation on screen.
    pub current: usize,
    /// The id the next candidate gets (ids are unique over the tree).
    pub next_id: u64,
    /// Every generation, by index.
    pub generations: Vec<GenerationNode>,
    /// The collection: the ids of the kept candidates, in the order kept.
    #[serde(default)]
    pub kept: Vec<u64>,
    /// The example fall's name (the file it was read from, as given), if
    /// the session has one ([`EXAMPLE_FILE`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub example: Option<String>,
}

/// The example fall beside the leaves: what it is shown as and what Auto N
/// breeds toward.
#[derive(Clone, Debug)]
pub struct Example {
    /// Its name (the file it was read from).
    pub name: String,
    /// Its class, as described at the prototype's chord.
    pub class: MotionClass,
    /// The target of breeding toward it (breed's `--like` target).
    pub target: MotionTarget,
    /// Its fall as shown: a plate of the prototype's chord (or a marker,
    /// without attitudes), at [`MOTION_FPS`].
    pub motion: CandidateMotion,
}

impl Example {
    /// The example `trajectory` named `name`, described at `proto`'s chord
    /// (breed's `--like` at the prototype's size); one whose fall cannot be
    /// described is refused with the reason.
    pub fn of(
        name: &str,
        trajectory: &crate::motion::trajectory::Trajectory,
        proto: &LeafSpec,
    ) -> Result<Example, StudioError> {
        use crate::motion::describe::Descriptors;
        let refuse = |why: String| StudioError::Input(format!("the example {name}: {why}"));
        let chord = proto.model().map_err(|e| refuse(e.to_string()))?.chord();
        let described = Descriptors::of(&crate::motion::classify::classify(trajectory, chord))
            .map_err(|e| refuse(format!("its fall is undetermined ({})", e.reason)))?;
        let clip =
            crate::output::preview::from_record("example", trajectory, chord, Some(MOTION_FPS))
                .map_err(|e| refuse(e.to_string()))?;
        let object = clip
            .objects
            .into_iter()
            .next()
            .ok_or_else(|| refuse("nothing to show".to_string()))?;
        Ok(Example {
            name: name.to_string(),
            class: described.class,
            target: MotionTarget::like(name, chord, &described),
            motion: shown_motion(u64::MAX, &object),
        })
    }
}

/// One candidate of a generation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// Unique id in the session.
    pub id: u64,
    /// How it was made.
    pub origin: Origin,
    /// The candidates it was bred from (none for a wild card).
    pub parents: Vec<u64>,
    /// Its genome.
    pub genome: Genome,
    /// Its evaluation (the lower-median release's fall, with how many of
    /// the releases kept the target class).
    pub evaluation: Evaluation,
}

/// The fall a candidate is shown with: its lower-median release, dropped
/// again exactly as evaluated, every vertex at [`MOTION_FPS`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CandidateMotion {
    /// The candidate.
    pub id: u64,
    /// Vertices per frame.
    pub vertices: usize,
    /// Triangles as vertex indices, flat.
    pub triangles: Vec<u32>,
    /// Frames.
    pub frames: usize,
    /// Vertex positions frame after frame (x, y, z, metres, z up) as
    /// little-endian float32, base64: a third of the size of decimal text.
    pub positions: String,
    /// Why there is no motion (a diverged drop), else empty.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub error: String,
}

/// A generation's candidates and their falls.
#[derive(Clone, Debug, PartialEq)]
pub struct Generation {
    /// Its candidates, in grid order.
    pub candidates: Vec<Candidate>,
    /// Their falls, in the same order.
    pub motion: Vec<CandidateMotion>,
}

/// What can go wrong in a session.
#[derive(Debug, thiserror::Error)]
pub enum StudioError {
    /// A request or setting that cannot be honoured: the reason.
    #[error("{0}")]
    Input(String),
    /// A file of the session could not be read or written.
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

fn file_error(path: &Path, e: impl std::fmt::Display) -> StudioError {
    StudioError::File {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// A session in memory, with its directory.
#[derive(Debug)]
pub struct Session {
    dir: PathBuf,
    proto: LeafSpec,
    file: SessionFile,
    generations: Vec<Generation>,
    example: Option<Example>,
}

impl Session {
    /// Starts a session in `dir` (created; one holding a session already
    /// is refused: reopen it with [`Session::open`]) and breeds and writes
    /// generation 0: half varied copies of the prototype, half uniform
    /// draws over its bounds, as `breed` starts.
    pub fn create(
        dir: &Path,
        settings: StudioSettings,
        proto: LeafSpec,
    ) -> Result<Session, StudioError> {
        settings.validate()?;
        if dir.join(SESSION_FILE).exists() {
            return Err(StudioError::Input(format!(
                "{} already holds a studio session; reopen it with {}",
                dir.display(),
                Setting::Resume.set(dir.display())
            )));
        }
        std::fs::create_dir_all(dir).map_err(|e| file_error(dir, e))?;
        let path = dir.join(PROTOTYPE_FILE);
        write_atomic(&path, proto.to_toml().as_bytes()).map_err(|e| file_error(&path, e))?;
        let bs = settings.breed_settings();
        let children = first_generation(&bs, &proto);
        let node = GenerationNode {
            index: 0,
            parent: None,
            picks: Vec::new(),
            seed: step_seed(settings.seed, 0),
            scale: bs.initial_scale,
            ids: children.iter().map(|c| c.id).collect(),
            auto: false,
            like: None,
            example: false,
            toward: None,
        };
        let mut session = Session {
            dir: dir.to_path_buf(),
            file: SessionFile {
                format: FORMAT,
                next_id: 0,
                settings,
                current: 0,
                generations: Vec::new(),
                kept: Vec::new(),
                example: None,
            },
            proto,
            generations: Vec::new(),
            example: None,
        };
        let pending = session.pending(node, children);
        session.commit(pending.evaluate(|_, _, _| {}))?;
        Ok(session)
    }

    /// Reopens the session in `dir` where it was.
    pub fn open(dir: &Path) -> Result<Session, StudioError> {
        let path = dir.join(SESSION_FILE);
        let text = std::fs::read_to_string(&path).map_err(|e| file_error(&path, e))?;
        let file: SessionFile = serde_json::from_str(&text).map_err(|e| file_error(&path, e))?;
        if file.format != FORMAT {
            return Err(file_error(
                &path,
                format!("format {} (this leafmagic reads {FORMAT})", file.format),
            ));
        }
        file.settings.validate()?;
        let proto_path = dir.join(PROTOTYPE_FILE);
        let proto = LeafSpec::read(&proto_path).map_err(|e| file_error(&proto_path, e))?;
        let mut generations = Vec::with_capacity(file.generations.len());
        for (k, node) in file.generations.iter().enumerate() {
            let bad = |m: &str| file_error(&path, format!("generation {k}: {m}"));
            if node.index != k || node.parent.is_some_and(|p| p >= k) {
                return Err(bad("out of order (its index or parent)"));
            }
            let read = |name: String| {
                let p = dir.join(name);
                std::fs::read_to_string(&p).map_err(|e| file_error(&p, e))
            };
            let candidates: Vec<Candidate> = serde_json::from_str(&read(candidates_file(k))?)
                .map_err(|e| file_error(&dir.join(candidates_file(k)), e))?;
            let motion: Vec<CandidateMotion> = serde_json::from_str(&read(motion_file(k))?)
                .map_err(|e| file_error(&dir.join(motion_file(k)), e))?;
            let ids: Vec<u64> = candidates.iter().map(|c| c.id).collect();
            if ids != node.ids || motion.iter().map(|m| m.id).ne(ids.iter().copied()) {
                return Err(bad("its files list other candidates than studio.json"));
            }
            for c in &candidates {
                c.genome
                    .check(&proto)
                    .map_err(|e| bad(&format!("candidate {}: {e}", c.id)))?;
            }
            generations.push(Generation { candidates, motion });
        }
        if file.current >= generations.len() {
            return Err(file_error(&path, "the current generation does not exist"));
        }
        let example = match &file.example {
            None => None,
            Some(name) => {
                let p = dir.join(EXAMPLE_FILE);
                let t = crate::motion::trajectory::Trajectory::read_csv(&p)
                    .map_err(|e| file_error(&p, e))?;
                Some(Example::of(name, &t, &proto)?)
            }
        };
        Ok(Session {
            dir: dir.to_path_buf(),
            proto,
            file,
            generations,
            example,
        })
    }

    /// Gives the session an example fall, `trajectory` read from the file
    /// `name` (once, by the caller): copied into the session as read
    /// ([`EXAMPLE_FILE`]), shown beside the kept leaves, and what Auto N
    /// breeds toward. A session has one example, given at its start.
    pub fn set_example(
        &mut self,
        name: &str,
        trajectory: &crate::motion::trajectory::Trajectory,
    ) -> Result<(), StudioError> {
        if self.example.is_some() {
            return Err(StudioError::Input(
                "the session has an example already".to_string(),
            ));
        }
        let example = Example::of(name, trajectory, &self.proto)?;
        let p = self.dir.join(EXAMPLE_FILE);
        let bytes = trajectory
            .try_to_csv_bytes()
            .map_err(|e| file_error(&p, e))?;
        self.write(EXAMPLE_FILE, &bytes)?;
        self.file.example = Some(name.to_string());
        if let Err(e) = self.write_session() {
            self.file.example = None;
            return Err(e);
        }
        self.example = Some(example);
        Ok(())
    }

    /// The session's example fall, if it has one.
    pub fn example(&self) -> Option<&Example> {
        self.example.as_ref()
    }

    /// The session directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The session file's contents: settings and tree.
    pub fn file(&self) -> &SessionFile {
        &self.file
    }

    /// The generation on screen: its node and candidates.
    pub fn current(&self) -> (&GenerationNode, &Generation) {
        let k = self.file.current;
        (&self.file.generations[k], &self.generations[k])
    }

    /// The default variation scale of the next generation bred from the
    /// current one: its scale times [`SHRINK`], within breed's range.
    pub fn next_scale(&self) -> f64 {
        (self.current().0.scale * SHRINK).clamp(MIN_SCALE, MAX_SCALE)
    }

    /// Breeds the next generation from `picks` (ids of the current
    /// generation) with variation `scale` ([`Session::next_scale`] if
    /// none), evaluates it on all cores, writes it and makes it current:
    /// [`Session::plan`], [`Pending::evaluate`] and [`Session::commit`] in
    /// one.
    pub fn breed(&mut self, picks: &[u64], scale: Option<f64>) -> Result<(), StudioError> {
        let pending = self.plan(picks, scale)?;
        self.commit(pending.evaluate(|_, _, _| {}))
    }

    /// The next generation bred from `picks` with variation `scale`, made
    /// but not evaluated: the evaluation needs no session, so a server
    /// can run it while the session answers other requests. Refuses picks
    /// that are not in the current generation and a scale out of range.
    pub fn plan(&self, picks: &[u64], scale: Option<f64>) -> Result<Pending, StudioError> {
        let (node, generation) = self.current();
        if picks.is_empty() {
            return Err(StudioError::Input(
                "pick at least one candidate to breed from".to_string(),
            ));
        }
        let mut chosen = Vec::with_capacity(picks.len());
        for (k, id) in picks.iter().enumerate() {
            if picks[..k].contains(id) {
                return Err(StudioError::Input(format!(
                    "candidate {id} is picked twice"
                )));
            }
            match generation.candidates.iter().find(|c| c.id == *id) {
                Some(c) => chosen.push(c),
                None => {
                    return Err(StudioError::Input(format!(
                        "candidate {id} is not in generation {} (its ids: {:?})",
                        node.index, node.ids
                    )));
                }
            }
        }
        let scale = scale.unwrap_or_else(|| self.next_scale());
        if !(MIN_SCALE..=MAX_SCALE).contains(&scale) {
            return Err(StudioError::Input(format!(
                "the variation scale must be {MIN_SCALE} to {MAX_SCALE}, got {scale}"
            )));
        }
        let index = self.file.generations.len();
        let seed = step_seed(self.file.settings.seed, index as u64);
        let parents: Vec<(u64, &Genome)> = chosen.iter().map(|c| (c.id, &c.genome)).collect();
        let children = children_of(
            &parents,
            self.archive_offer(index),
            &self.proto,
            self.file.settings.grid,
            scale,
            seed,
            self.file.next_id,
        );
        let node = GenerationNode {
            index,
            parent: Some(node.index),
            picks: picks.to_vec(),
            seed,
            scale,
            ids: children.iter().map(|c| c.id).collect(),
            auto: false,
            like: None,
            example: false,
            toward: None,
        };
        Ok(self.pending(node, children))
    }

    /// The fall of candidate `id` of the current generation as a target to
    /// breed toward (what "More like this" and "Auto N toward #id" aim at):
    /// its shown drop's descriptors, gated on its class.
    pub fn fall_target(&self, id: u64) -> Result<MotionTarget, StudioError> {
        like_target(&self.proto, self.on_grid(id)?, self.file.settings.seconds)
    }

    /// Candidate `id` of the current generation; refused if it is not there.
    fn on_grid(&self, id: u64) -> Result<&Candidate, StudioError> {
        let (node, generation) = self.current();
        generation
            .candidates
            .iter()
            .find(|c| c.id == id)
            .ok_or_else(|| {
                StudioError::Input(format!(
                    "candidate {id} is not in generation {} (its ids: {:?})",
                    node.index, node.ids
                ))
            })
    }

    /// `pending` turned toward `target`: [`LIKE_POOL`] times the grid of
    /// children of `parents` (variations, crossovers and wild cards at its
    /// scale and seed), evaluated by their distance to `target`, the
    /// grid's worth closest kept ([`Pending::evaluate`]).
    fn toward_target(
        &self,
        pending: &mut Pending,
        parents: &[(u64, &Genome)],
        target: MotionTarget,
    ) {
        let grid = self.file.settings.grid;
        let children = children_of(
            parents,
            self.archive_offer(pending.node.index),
            &self.proto,
            grid * LIKE_POOL,
            pending.node.scale,
            pending.node.seed,
            self.file.next_id,
        );
        pending.node.ids = children.iter().map(|c| c.id).collect();
        pending.children = children;
        pending.settings.like = Some(target);
        pending.keep = Some(grid);
    }

    /// "More like this": a generation bred from candidate `id` of the
    /// current generation toward its own fall (breed's `--like`: the
    /// distance of each fall's descriptors to those of `id`'s shown fall,
    /// gated on its class). The machine does the volume: [`LIKE_POOL`]
    /// times the grid of variations (and wild cards) are evaluated and the
    /// grid's worth closest kept ([`Pending::evaluate`]).
    pub fn plan_like(&self, id: u64, scale: Option<f64>) -> Result<Pending, StudioError> {
        let c = self.on_grid(id)?;
        let target = like_target(&self.proto, c, self.file.settings.seconds)?;
        let mut pending = self.plan(&[id], scale)?;
        self.toward_target(&mut pending, &[(id, &c.genome)], target);
        pending.node.like = Some(id);
        Ok(pending)
    }

    /// The model of the person's taste fitted to every pick they made
    /// ([`super::preference`]): in each generation a person bred from, the
    /// candidates picked against those passed over. None before the
    /// person has both picked and passed over a leaf that fell.
    pub fn preference(&self) -> Option<Preference> {
        let mut judgements = Vec::new();
        for node in &self.file.generations {
            let Some(parent) = node.parent else { continue };
            if node.auto || node.like.is_some() || node.example || node.toward.is_some() {
                continue;
            }
            for c in &self.generations[parent].candidates {
                if let Some(x) = features(&c.evaluation) {
                    judgements.push((x, node.picks.contains(&c.id)));
                }
            }
        }
        Preference::fit(&judgements)
    }

    /// The candidates of the current generation the machine picks when
    /// it breeds alone: the [`AUTO_PICKS`] best toward the session's
    /// target by breed's score, ties to the earlier in the grid; in a
    /// generation bred toward the example or given descriptors, the
    /// [`AUTO_PICKS`] closest to them (no distance: last).
    pub fn auto_picks(&self) -> Vec<u64> {
        let (node, generation) = self.current();
        let mut ranked: Vec<&Candidate> = generation.candidates.iter().collect();
        if node.example || node.toward.is_some() {
            let key = |c: &Candidate| {
                let d = c.evaluation.distance.filter(|d| d.is_finite());
                d.unwrap_or(f64::INFINITY)
            };
            ranked.sort_by(|a, b| key(a).total_cmp(&key(b)));
            return ranked.iter().take(AUTO_PICKS).map(|c| c.id).collect();
        }
        // A stable sort keeps grid order among ties; a NaN score ranks last.
        ranked.sort_by(|a, b| {
            let key = |c: &Candidate| {
                let s = c.evaluation.score;
                if s.is_nan() { f64::NEG_INFINITY } else { s }
            };
            key(b).total_cmp(&key(a))
        });
        ranked.iter().take(AUTO_PICKS).map(|c| c.id).collect()
    }

    /// The next generation bred from [`Session::auto_picks`] at the
    /// default scale, marked as the machine's choice. Toward `toward`
    /// (descriptors the person gave) or else the session's example, as
    /// "More like this" breeds toward a candidate's fall: [`LIKE_POOL`]
    /// times the grid evaluated by their distance to the target's
    /// descriptors, the grid's worth closest kept. With neither, toward the
    /// session's class by breed's score.
    pub fn plan_auto(&self, toward: Option<&MotionTarget>) -> Result<Pending, StudioError> {
        let picks = self.auto_picks();
        let mut pending = self.plan(&picks, None)?;
        pending.node.auto = true;
        let target = match toward {
            Some(t) => Some(t.clone()),
            None => self.example.as_ref().map(|e| e.target.clone()),
        };
        if let Some(target) = target {
            let generation = self.current().1;
            let parents: Vec<(u64, &Genome)> = picks
                .iter()
                .filter_map(|id| generation.candidates.iter().find(|c| c.id == *id))
                .map(|c| (c.id, &c.genome))
                .collect();
            self.toward_target(&mut pending, &parents, target);
            match toward {
                Some(t) => pending.node.toward = Some(t.clone()),
                None => pending.node.example = true,
            }
        }
        Ok(pending)
    }

    fn pending(&self, node: GenerationNode, children: Vec<Child>) -> Pending {
        Pending {
            first_id: self.file.next_id,
            node,
            children,
            proto: self.proto.clone(),
            settings: self.file.settings.breed_settings(),
            keep: None,
        }
    }

    /// Makes generation `index` current: going back, or to any generation
    /// of the tree to branch from it.
    pub fn go_to(&mut self, index: usize) -> Result<(), StudioError> {
        if index >= self.generations.len() {
            return Err(StudioError::Input(format!(
                "there is no generation {index} (the session has {})",
                self.generations.len()
            )));
        }
        let before = self.file.current;
        self.file.current = index;
        self.write_session()
            .inspect_err(|_| self.file.current = before)
    }

    /// Makes the current generation's parent current (generation 0 has
    /// none: refused).
    pub fn back(&mut self) -> Result<(), StudioError> {
        match self.current().0.parent {
            Some(p) => self.go_to(p),
            None => Err(StudioError::Input(
                "generation 0 has no generation before it".to_string(),
            )),
        }
    }

    /// Writes an evaluated generation's files and then the session file,
    /// which makes it part of the session, and makes it current. The
    /// generation must be the next one planned from this session (no other
    /// generation committed since its plan).
    pub fn commit(&mut self, evaluated: Evaluated) -> Result<(), StudioError> {
        let Evaluated {
            node,
            candidates,
            motion,
            first_id,
            reserved,
        } = evaluated;
        let k = node.index;
        if k != self.generations.len() || first_id != self.file.next_id {
            return Err(StudioError::Input(format!(
                "generation {k} was planned from another state of the session (it has {} \
                 generations now)",
                self.generations.len()
            )));
        }
        let leaves = self.dir.join(format!("gen-{k:03}"));
        std::fs::create_dir_all(&leaves).map_err(|e| file_error(&leaves, e))?;
        for c in &candidates {
            let leaf = c.genome.to_leaf(&self.proto).to_toml();
            self.write(&format!("gen-{k:03}/leaf-{}.toml", c.id), leaf.as_bytes())?;
        }
        self.write(&candidates_file(k), &pretty(&candidates)?)?;
        self.write(&motion_file(k), &pretty(&motion)?)?;
        // The session file last: until it is written, the generation is
        // not part of the session (a kill before leaves files nothing
        // names).
        let before = (self.file.next_id, self.file.current);
        self.file.next_id += reserved;
        self.file.current = k;
        self.file.generations.push(node);
        self.generations.push(Generation { candidates, motion });
        if let Err(e) = self.write_session() {
            (self.file.next_id, self.file.current) = before;
            self.file.generations.pop();
            self.generations.pop();
            return Err(e);
        }
        Ok(())
    }

    /// The candidate `id` wherever it is in the tree, with its fall and
    /// the index of its generation.
    pub fn find(&self, id: u64) -> Option<(usize, &Candidate, &CandidateMotion)> {
        self.generations.iter().enumerate().find_map(|(k, g)| {
            let i = g.candidates.iter().position(|c| c.id == id)?;
            Some((k, &g.candidates[i], &g.motion[i]))
        })
    }

    /// The prototype the session breeds from.
    pub fn prototype(&self) -> &LeafSpec {
        &self.proto
    }

    /// Adds candidate `id` (of any generation) to the collection, or with
    /// `keep` false takes it out; recorded at once.
    pub fn keep(&mut self, id: u64, keep: bool) -> Result<(), StudioError> {
        if self.find(id).is_none() {
            return Err(StudioError::Input(format!(
                "there is no candidate {id} in the session"
            )));
        }
        let before = self.file.kept.clone();
        let at = self.file.kept.iter().position(|k| *k == id);
        match (keep, at) {
            (true, None) => self.file.kept.push(id),
            (false, Some(i)) => {
                self.file.kept.remove(i);
            }
            _ => return Ok(()),
        }
        self.write_session()
            .inspect_err(|_| self.file.kept = before)
    }

    fn write_session(&self) -> Result<(), StudioError> {
        self.write_run()?;
        self.write(SESSION_FILE, &pretty(&self.file)?)
    }

    /// The session's MAP-Elites archive: every candidate evaluated so far
    /// binned as breed bins them ([`crate::breed::archive`]), the best
    /// score of each cell kept (ties to the lower id), sorted by cell.
    pub fn archive(&self) -> Vec<crate::breed::population::ArchiveEntry> {
        let mut archive = Vec::new();
        for (k, g) in self.generations.iter().enumerate() {
            let members: Vec<Individual> = g.candidates.iter().map(member).collect();
            crate::breed::archive::update_archive(&mut archive, k, &members);
        }
        archive
    }

    /// The elite the first wild card of generation `index`, bred from the
    /// current one, varies ([`super::variation::archive_elite`]): from a
    /// cell the current generation does not show.
    fn archive_offer(&self, index: usize) -> Option<(u64, &Genome)> {
        let shown: Vec<(usize, usize)> = self
            .current()
            .1
            .candidates
            .iter()
            .filter_map(|c| c.evaluation.fall())
            .map(|f| crate::breed::archive::cell(f.descent_m_s, f.spin_rad_s))
            .collect();
        let archive = self.archive();
        let id = super::variation::archive_elite(&archive, &shown, index)?.id;
        self.find(id).map(|(_, c, _)| (c.id, &c.genome))
    }

    /// The members `Session::write_run` gives the run's last generation:
    /// the collection when it holds at least two leaves (breed's smallest
    /// population: `export --top` then ranks the kept leaves), else the
    /// generation on screen with the collection's one leaf if any.
    pub fn run_members(&self) -> Vec<u64> {
        let kept = &self.file.kept;
        let mut ids = if kept.len() >= 2 {
            kept.clone()
        } else {
            let mut ids = self.current().0.ids.clone();
            if let Some(k) = kept.first().filter(|k| !ids.contains(k)) {
                ids.push(*k);
            }
            ids
        };
        ids.sort_unstable();
        ids
    }

    /// Writes the session as a breeding run's directory beside
    /// `studio.json` (`run.toml`, `gen-NNN.csv`, `generations.csv`,
    /// `checkpoint.json`), so the commands that read a run (`export`,
    /// `preview`) read a session: its generations in the order they were
    /// made, the last one's population [`Session::run_members`].
    fn write_run(&self) -> Result<(), StudioError> {
        let mut generations = Vec::with_capacity(self.generations.len());
        let mut history = Vec::with_capacity(self.generations.len());
        for (k, g) in self.generations.iter().enumerate() {
            let mut members: Vec<Individual> = g.candidates.iter().map(member).collect();
            members.sort_by_key(|i| i.id);
            // Breed's success rate: the children that scored at least as
            // well as the parent they were bred from.
            let judged: Vec<bool> = g
                .candidates
                .iter()
                .filter_map(|c| {
                    let (_, parent, _) = self.find(*c.parents.first()?)?;
                    Some(c.evaluation.score >= parent.evaluation.score)
                })
                .collect();
            let success = if judged.is_empty() {
                0.0
            } else {
                judged.iter().filter(|b| **b).count() as f64 / judged.len() as f64
            };
            history.push(summarise(
                k,
                &members,
                self.file.generations[k].scale,
                success,
                Some(self.file.settings.target),
            ));
            generations.push(members);
        }
        let population = self
            .run_members()
            .iter()
            .filter_map(|id| self.find(*id).map(|(_, c, _)| member(c)))
            .collect();
        let record = RunRecord {
            settings: self.file.settings.breed_settings(),
            proto: &self.proto,
            generations,
            history,
            population,
            scale: self.next_scale(),
            next_id: self.file.next_id,
        };
        write_record(&self.dir, record).map_err(|e| StudioError::Input(e.to_string()))
    }

    fn write(&self, name: &str, bytes: &[u8]) -> Result<(), StudioError> {
        let path = self.dir.join(name);
        write_atomic(&path, bytes).map_err(|e| file_error(&path, e))
    }
}

/// A generation made from picks but not yet evaluated ([`Session::plan`]):
/// it carries what its evaluation needs, so it runs apart from the session.
#[derive(Debug)]
pub struct Pending {
    node: GenerationNode,
    children: Vec<Child>,
    proto: LeafSpec,
    settings: BreedSettings,
    /// The first id its children take (the session's next, when planned).
    first_id: u64,
    /// Keep only this many, the closest to the target (else all).
    keep: Option<usize>,
}

/// A generation evaluated, in grid order, ready for [`Session::commit`].
#[derive(Debug)]
pub struct Evaluated {
    node: GenerationNode,
    candidates: Vec<Candidate>,
    motion: Vec<CandidateMotion>,
    first_id: u64,
    /// Ids used, kept or not (each id names one evaluation, kept or not).
    reserved: u64,
}

impl Pending {
    /// Its place in the tree.
    pub fn node(&self) -> &GenerationNode {
        &self.node
    }

    /// Drops per candidate.
    pub fn releases(&self) -> usize {
        self.settings.releases
    }

    /// Candidates evaluated (more than the grid for "More like this").
    pub fn evaluations(&self) -> usize {
        self.children.len()
    }

    /// Evaluates every candidate on the rayon pool, calling `finished`
    /// with its grid slot as each is done (in whatever order they finish,
    /// from whatever thread), and gathers them in grid order: the files
    /// written from the result do not depend on the order of evaluation.
    pub fn evaluate(
        self,
        finished: impl Fn(usize, &Candidate, &CandidateMotion) + Sync,
    ) -> Evaluated {
        let Pending {
            mut node,
            children,
            proto,
            settings,
            first_id,
            keep,
        } = self;
        let reserved = children.len() as u64;
        let evaluated: Vec<(Candidate, CandidateMotion)> = children
            .into_par_iter()
            .enumerate()
            .map(|(slot, c)| {
                let (candidate, motion) = evaluate_child(&proto, c, &settings);
                finished(slot, &candidate, &motion);
                (candidate, motion)
            })
            .collect();
        let evaluated = match keep {
            None => evaluated,
            Some(n) => closest(evaluated, n),
        };
        node.ids = evaluated.iter().map(|(c, _)| c.id).collect();
        let (candidates, motion) = evaluated.into_iter().unzip();
        Evaluated {
            node,
            candidates,
            motion,
            first_id,
            reserved,
        }
    }
}

/// The `n` of `evaluated` closest to the target (no distance: last; ties
/// to the lower id), in the order they were made: the files do not depend
/// on the order the evaluations finished in.
fn closest(
    evaluated: Vec<(Candidate, CandidateMotion)>,
    n: usize,
) -> Vec<(Candidate, CandidateMotion)> {
    let mut order: Vec<(f64, u64)> = evaluated
        .iter()
        .map(|(c, _)| {
            let d = c.evaluation.distance.filter(|d| d.is_finite());
            (d.unwrap_or(f64::INFINITY), c.id)
        })
        .collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let chosen: Vec<u64> = order.iter().take(n).map(|(_, id)| *id).collect();
    evaluated
        .into_iter()
        .filter(|(c, _)| chosen.contains(&c.id))
        .collect()
}

/// The target of "More like this" from candidate `c`: the descriptors of
/// the fall it is shown with (its lower-median release, dropped again as
/// it was evaluated), gated on that fall's class.
fn like_target(
    proto: &LeafSpec,
    c: &Candidate,
    seconds: f64,
) -> Result<crate::motion::describe::MotionTarget, StudioError> {
    use crate::motion::describe::{Descriptors, MotionTarget};
    let refuse = |why: String| {
        StudioError::Input(format!(
            "candidate {}: no fall to breed toward: {why}",
            c.id
        ))
    };
    if c.evaluation.fall().is_none() {
        return Err(refuse("its drop diverged".to_string()));
    }
    let model = c.genome.model(proto).map_err(|e| refuse(e.to_string()))?;
    let params = crate::sim::drop::DropParams {
        seconds,
        tilt_deg: c.evaluation.release_deg,
        ..crate::sim::drop::DropParams::default()
    };
    let fall = crate::sim::drop::drop_leaf(&model, &params).map_err(|e| refuse(e.to_string()))?;
    let described = Descriptors::of(&crate::motion::classify::classify(
        &fall.trajectory,
        model.chord(),
    ))
    .map_err(|e| refuse(format!("its fall is undetermined ({})", e.reason)))?;
    Ok(MotionTarget::like(
        &format!("leaf-{}", c.id),
        model.chord(),
        &described,
    ))
}

/// One child evaluated as breed evaluates it, with the fall it is shown
/// with.
pub fn evaluate_child(
    proto: &LeafSpec,
    c: Child,
    settings: &BreedSettings,
) -> (Candidate, CandidateMotion) {
    let evaluation = evaluate(proto, c.id, &c.genome, settings);
    let motion = motion_of(proto, &c, &evaluation, settings.seconds);
    let candidate = Candidate {
        id: c.id,
        origin: c.origin,
        parents: c.parents,
        genome: c.genome,
        evaluation,
    };
    (candidate, motion)
}

/// A candidate as a member of a breeding run's population.
fn member(c: &Candidate) -> Individual {
    Individual {
        id: c.id,
        parent: c.parents.first().copied(),
        elite: false,
        genome: c.genome.clone(),
        eval: c.evaluation.clone(),
    }
}

/// The seed of the step that makes generation `index`.
fn step_seed(seed: u64, index: u64) -> u64 {
    stream_seed(seed, index, STEP_STREAM)
}

fn candidates_file(k: usize) -> String {
    format!("gen-{k:03}.json")
}

fn motion_file(k: usize) -> String {
    format!("gen-{k:03}-motion.json")
}

fn pretty<T: Serialize>(value: &T) -> Result<Vec<u8>, StudioError> {
    let mut bytes = serde_json::to_vec_pretty(value)
        .map_err(|e| StudioError::Input(format!("could not write JSON: {e}")))?;
    bytes.push(b'\n');
    Ok(bytes)
}

/// The fall `child` is shown with: its lower-median release dropped again
/// as breeding dropped it (export's re-drop, the same fall to the bit).
fn motion_of(
    proto: &LeafSpec,
    child: &Child,
    evaluation: &Evaluation,
    seconds: f64,
) -> CandidateMotion {
    let empty = |error: String| CandidateMotion {
        id: child.id,
        vertices: 0,
        triangles: Vec::new(),
        frames: 0,
        positions: String::new(),
        error,
    };
    if evaluation.fall().is_none() {
        return empty("the drop diverged".to_string());
    }
    let model = match child.genome.model(proto) {
        Ok(m) => m,
        Err(e) => return empty(format!("invalid leaf: {e}")),
    };
    let name = format!("leaf-{}", child.id);
    let clip = drop_clip_released(
        &name,
        evaluation.class_name(),
        &model,
        seconds,
        MOTION_FPS,
        evaluation.release_deg,
    );
    match clip {
        Ok(object) => shown_motion(child.id, &object),
        Err(e) => empty(e.to_string()),
    }
}

/// A clip object's fall as the page draws it: every vertex per frame.
fn shown_motion(id: u64, object: &crate::formats::clip::ClipObject) -> CandidateMotion {
    let frames: Vec<Vec<nalgebra::Vector3<f64>>> = match &object.motion {
        Motion::Deforming { frames } => frames.clone(),
        Motion::Rigid {
            local,
            translation,
            rotation,
        } => translation
            .iter()
            .zip(rotation)
            .map(|(t, q)| local.iter().map(|v| t + q * v).collect())
            .collect(),
    };
    let mut bytes = Vec::with_capacity(frames.len() * frames.first().map_or(0, Vec::len) * 12);
    for frame in &frames {
        for v in frame {
            for c in v.iter() {
                bytes.extend_from_slice(&(*c as f32).to_le_bytes());
            }
        }
    }
    CandidateMotion {
        id,
        vertices: frames.first().map_or(0, Vec::len),
        triangles: object.triangles.iter().flatten().copied().collect(),
        frames: frames.len(),
        positions: base64::engine::general_purpose::STANDARD.encode(bytes),
        error: String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    /// A fresh session of 4 candidates with 1 s drops in a scratch folder.
    fn small(name: &str) -> Session {
        let dir = std::env::temp_dir().join(format!("leafmagic-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let settings = StudioSettings {
            grid: 4,
            seconds: 1.0,
            ..StudioSettings::new("a", MotionClass::Floater, 7)
        };
        Session::create(&dir, settings, LeafSpec::load("a").unwrap()).unwrap()
    }

    #[test]
    fn each_candidate_is_reported_once_as_it_finishes_and_lands_in_its_slot() {
        let mut s = small("studio-evaluate");
        let ids = s.current().0.ids.clone();
        let pending = s.plan(&ids[..2], None).unwrap();
        let seen = Mutex::new(Vec::new());
        let evaluated = pending.evaluate(|slot, c, m| {
            assert_eq!(c.id, m.id);
            seen.lock().unwrap().push((slot, c.clone()));
        });
        let mut seen = seen.into_inner().unwrap();
        seen.sort_by_key(|(slot, _)| *slot);
        assert_eq!(
            seen.iter().map(|(k, _)| *k).collect::<Vec<_>>(),
            [0, 1, 2, 3]
        );
        for ((_, reported), kept) in seen.iter().zip(&evaluated.candidates) {
            assert_eq!(reported, kept, "what was shown is what is recorded");
        }
        // Nothing is on disk or in the tree before the commit.
        assert_eq!(s.file().generations.len(), 1);
        assert!(!s.dir().join(candidates_file(1)).exists());
        s.commit(evaluated).unwrap();
        assert_eq!(s.file().generations.len(), 2);
        assert_eq!(s.file().current, 1);
        assert_eq!(s.file().generations[1].picks, ids[..2]);
        let _ = std::fs::remove_dir_all(s.dir());
    }

    #[test]
    fn wild_cards_come_from_archive_cells_the_grid_did_not_show() {
        use crate::breed::archive::cell;
        let mut s = small("studio-archive");
        let cell_of = |c: &Candidate| {
            c.evaluation
                .fall()
                .map(|f| cell(f.descent_m_s, f.spin_rad_s))
        };
        let mut from_archive = 0;
        for _ in 0..6 {
            let (_, shown) = s.current();
            let shown_cells: Vec<_> = shown.candidates.iter().filter_map(cell_of).collect();
            let archive = s.archive();
            let unshown = archive
                .iter()
                .filter(|e| !shown_cells.contains(&(e.descent_bin, e.spin_bin)))
                .count();
            let pick = shown.candidates[0].id;
            s.breed(&[pick], None).unwrap();
            let wild = s.current().1.candidates.last().unwrap().clone();
            if unshown == 0 {
                assert_eq!(
                    wild.origin,
                    Origin::Wild,
                    "every cell shown: a uniform draw"
                );
                continue;
            }
            from_archive += 1;
            assert_eq!(wild.origin, Origin::Archive);
            let (k, elite, _) = s.find(wild.parents[0]).unwrap();
            assert!(
                k + 1 < s.file().generations.len(),
                "an earlier generation's"
            );
            let elite_cell = cell_of(elite).unwrap();
            assert!(
                !shown_cells.contains(&elite_cell),
                "from a cell not on screen"
            );
            assert_ne!(
                Some(elite_cell),
                cell_of(s.find(pick).unwrap().1),
                "not the pick's"
            );
            // The cell's elite: no earlier candidate of that cell scored better.
            for g in &s.generations[..s.generations.len() - 1] {
                for c in g
                    .candidates
                    .iter()
                    .filter(|c| cell_of(c) == Some(elite_cell))
                {
                    assert!(c.evaluation.score <= elite.evaluation.score, "{}", c.id);
                }
            }
        }
        assert!(
            from_archive > 0,
            "the archive offered no cell in 6 generations"
        );
        let _ = std::fs::remove_dir_all(s.dir());
    }

    #[test]
    fn a_generation_planned_from_an_older_state_is_refused() {
        let mut s = small("studio-stale");
        let ids = s.current().0.ids.clone();
        let first = s.plan(&ids[..1], None).unwrap();
        let second = s.plan(&ids[1..2], None).unwrap();
        s.commit(first.evaluate(|_, _, _| {})).unwrap();
        let err = s.commit(second.evaluate(|_, _, _| {})).unwrap_err();
        assert!(err.to_string().contains("another state"), "{err}");
        assert_eq!(s.file().generations.len(), 2);
        // Keeping: only what exists, once, and recorded.
        assert!(s.keep(999, true).is_err());
        s.keep(ids[0], true).unwrap();
        s.keep(ids[0], true).unwrap();
        assert_eq!(s.file().kept, [ids[0]]);
        let reopened = Session::open(s.dir()).unwrap();
        assert_eq!(reopened.file().kept, [ids[0]]);
        s.keep(ids[0], false).unwrap();
        assert!(s.file().kept.is_empty());
        let _ = std::fs::remove_dir_all(s.dir());
    }
}
