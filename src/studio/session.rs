//! A studio session: a tree of generations bred from a person's picks, and
//! the run directory that records it.
//!
//! Files (every one written atomically, `studio.json` last, so a session
//! killed at any moment reopens at its last completed action):
//!
//! - `studio.json`: the settings, the tree (each generation's parent, the
//!   picks it was bred from, its random seed and variation scale, its ids)
//!   and the generation on screen;
//! - `prototype.toml`: the prototype, so a session reopens without its
//!   source file;
//! - `gen-NNN.json`: generation NNN's candidates: how each was made, its
//!   parents, genome and evaluation;
//! - `gen-NNN-motion.json`: the fall each candidate is shown with;
//! - `gen-NNN/leaf-ID.toml`: every candidate as a leaf file.

use super::variation::{Child, Origin, children_of, first_generation};
use crate::breed::evaluate;
use crate::breed::population::Evaluation;
use crate::breed::selection::{MAX_SCALE, MIN_SCALE, stream_seed};
use crate::breed::settings::{BreedSettings, DEFAULT_RELEASES};
use crate::formats::clip::Motion;
use crate::leaf::LeafSpec;
use crate::leaf::genome::Genome;
use crate::motion::classify::MotionClass;
use crate::output::export::drop_clip_released;
use crate::util::io::write_atomic;
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
                "--grid must be {} to {}, got {}",
                GRID_RANGE[0], GRID_RANGE[1], self.grid
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
                "{} already holds a studio session; reopen it with --resume {}",
                dir.display(),
                dir.display()
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
        };
        let mut session = Session {
            dir: dir.to_path_buf(),
            file: SessionFile {
                format: FORMAT,
                next_id: children.len() as u64,
                settings,
                current: 0,
                generations: Vec::new(),
            },
            proto,
            generations: Vec::new(),
        };
        session.add(node, children)?;
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
        Ok(Session {
            dir: dir.to_path_buf(),
            proto,
            file,
            generations,
        })
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
    /// none), evaluates it on all cores, writes it and makes it current.
    pub fn breed(&mut self, picks: &[u64], scale: Option<f64>) -> Result<(), StudioError> {
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
        };
        self.file.next_id += children.len() as u64;
        self.file.current = index;
        self.add(node, children)
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
        self.file.current = index;
        self.write_session()
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

    /// Evaluates `children` (on the rayon pool, gathered in order), writes
    /// their files and then the session file, which makes them part of it.
    fn add(&mut self, node: GenerationNode, children: Vec<Child>) -> Result<(), StudioError> {
        let settings = self.file.settings.breed_settings();
        let proto = &self.proto;
        let evaluated: Vec<(Candidate, CandidateMotion)> = children
            .into_par_iter()
            .map(|c| {
                let evaluation = evaluate(proto, c.id, &c.genome, &settings);
                let motion = motion_of(proto, &c, &evaluation, settings.seconds);
                let candidate = Candidate {
                    id: c.id,
                    origin: c.origin,
                    parents: c.parents,
                    genome: c.genome,
                    evaluation,
                };
                (candidate, motion)
            })
            .collect();
        let (candidates, motion): (Vec<_>, Vec<_>) = evaluated.into_iter().unzip();
        let k = node.index;
        let leaves = self.dir.join(format!("gen-{k:03}"));
        std::fs::create_dir_all(&leaves).map_err(|e| file_error(&leaves, e))?;
        for c in &candidates {
            let leaf = c.genome.to_leaf(proto).to_toml();
            self.write(&format!("gen-{k:03}/leaf-{}.toml", c.id), leaf.as_bytes())?;
        }
        self.write(&candidates_file(k), &pretty(&candidates)?)?;
        self.write(&motion_file(k), &pretty(&motion)?)?;
        self.file.generations.push(node);
        self.generations.push(Generation { candidates, motion });
        self.write_session()
    }

    fn write_session(&self) -> Result<(), StudioError> {
        self.write(SESSION_FILE, &pretty(&self.file)?)
    }

    fn write(&self, name: &str, bytes: &[u8]) -> Result<(), StudioError> {
        let path = self.dir.join(name);
        write_atomic(&path, bytes).map_err(|e| file_error(&path, e))
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
    let object = match clip {
        Ok(o) => o,
        Err(e) => return empty(e.to_string()),
    };
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
    let mut bytes = Vec::with_capacity(frames.len() * model.len() * 12);
    for frame in &frames {
        for v in frame {
            for c in v.iter() {
                bytes.extend_from_slice(&(*c as f32).to_le_bytes());
            }
        }
    }
    CandidateMotion {
        id: child.id,
        vertices: frames.first().map_or(0, Vec::len),
        triangles: object.triangles.iter().flatten().copied().collect(),
        frames: frames.len(),
        positions: base64::engine::general_purpose::STANDARD.encode(bytes),
        error: String::new(),
    }
}
