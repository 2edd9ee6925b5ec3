//! The driver of a breeding run: the run directory, the generation loop
//! (plan, evaluate, finish) and resume.

use super::archive::{ARCHIVE_DESCENT_EDGES, ARCHIVE_SPIN_EDGES, update_archive};
use super::executor::{Executor, Local};
use super::files::{export_leaves, generations_csv, population_csv, remove_stale_temporaries};
use super::novelty;
use super::plot;
use super::population::{
    BreedError, Checkpoint, Evaluation, GenerationSummary, Individual, Job, Plan, Progress, io_err,
};
use super::selection::{self, next_scale, rank, summarise};
use super::settings::BreedSettings;
use super::shard;
use super::strategy;
use super::verify::{
    Damage, RUN_FILE, check_checkpoint, check_generation_file, content_hash, decode_checkpoint,
    encode_checkpoint,
};
use crate::leaf::LeafSpec;
use crate::leaf::genome::Genome;
use crate::motion::trajectory::Trajectory;
use crate::physics::model::Model;
use crate::physics::params::TimeStep;
use crate::physics::run::{MAX_BREED_WORK, RunKind, Work, check_budget, resolve_step};
use crate::sim::accuracy::{ErrorEstimate, error_estimate};
use crate::sim::drop::{DropParams, FRAME_RATE, drop_leaf};
use crate::util::io::write_atomic;
use crate::util::setting::Setting;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

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
    /// Set when this process wrote run.toml ([`Run::create`]): whether it
    /// also made the directory. A run that fails before generation 0 is
    /// recorded takes back what it wrote, so nothing half-started is left.
    created: Option<bool>,
    /// The work estimate a new run was checked against ([`Run::create_within`]),
    /// kept for [`Run::work`]: it measures generation 0's variants' steps.
    estimated: Option<(Model, Work)>,
}

/// The example fall of a `--like` run.
const EXAMPLE_FILE: &str = "example.csv";
/// The overlay of the example's and the best leaf's falls.
const LIKE_PLOT_FILE: &str = "like.svg";
const CHECKPOINT_FILE: &str = "checkpoint.json";
/// How many leaves `best/` holds at most.
pub const BEST_LEAVES: usize = 5;

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
    prototype_error: Option<ErrorEstimate>,
    prototype_leaf: LeafSpec,
}

/// The leaves an earlier run offers a new one to start from
/// (`breed --start-from`), and where in that run they come from.
#[derive(Clone, Debug)]
pub struct StartLeaves {
    /// The genomes, clamped into the new prototype's bounds: the archive's
    /// in cell order, or the last generation's from best to worst.
    pub genomes: Vec<Genome>,
    /// "its archive (N cells)" or "its last generation (N leaves)".
    pub source: String,
}

/// The leaves a new run of `proto` can start from in the earlier `run`
/// (opened with [`Run::load`]): the cells of its MAP-Elites archive when
/// it kept one, else its last generation ranked, diverged leaves left
/// out. Refused, naming the setting ([`Setting::StartFrom`]) and the directory, when the run has
/// no completed generation or its leaves are not variants of a prototype
/// shaped as `proto` (folds, particles, stiffness groups).
pub fn start_leaves(run: &Run, proto: &LeafSpec) -> Result<StartLeaves, BreedError> {
    let refuse = |why: String| {
        BreedError::Refused(format!(
            "{}: {why}",
            Setting::StartFrom.set(run.dir.display())
        ))
    };
    let cp = run
        .checkpoint
        .as_ref()
        .ok_or_else(|| refuse("the run has no completed generation yet".to_string()))?;
    let (members, source): (Vec<&Individual>, String) = if cp.archive.is_empty() {
        let ranked: Vec<&Individual> = rank(&cp.population)
            .into_iter()
            .filter(|i| i.eval.fall().is_some())
            .collect();
        let n = ranked.len();
        (ranked, format!("its last generation ({n} leaves)"))
    } else {
        let cells: Vec<&Individual> = cp.archive.iter().map(|e| &e.individual).collect();
        let n = cells.len();
        (cells, format!("its archive ({n} cells)"))
    };
    let genomes = members
        .iter()
        .map(|i| {
            let g = i.genome.clamped(&proto.bounds);
            g.check(proto).map(|()| g).map_err(|e| {
                refuse(format!(
                    "its leaves are variants of prototype {} and do not fit this run's \
                     prototype: {e}",
                    run.settings.prototype
                ))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    if genomes.is_empty() {
        return Err(refuse(
            "the run has no leaf that did not diverge".to_string(),
        ));
    }
    Ok(StartLeaves { genomes, source })
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
) -> Result<(Model, f64), BreedError> {
    let integrator = DropParams::default().integrator;
    let refuse = |e: &dyn std::fmt::Display| {
        BreedError::Refused(format!("{}: {e}", Setting::Prototype.set(source)))
    };
    let model = proto.model().map_err(|e| refuse(&e))?;
    let dt = resolve_step(&model, integrator, TimeStep::Auto, 1.0 / FRAME_RATE)
        .map_err(|e| refuse(&e))?;
    check_budget(seconds, dt, FRAME_RATE, integrator).map_err(|e| refuse(&e))?;
    Ok((model, dt))
}

/// The work of a whole run, from the prototype (its variants differ by the
/// bounded factors of their genomes): every drop of every generation, and
/// the error estimate's run. Refused, naming the prototype, past `limit`.
fn check_run_work(
    proto: &LeafSpec,
    settings: &BreedSettings,
    limit: f64,
) -> Result<(Model, Work), BreedError> {
    let (model, work) = run_work(proto, settings)?;
    work.check(&model, 1.0 / FRAME_RATE, limit, RunKind::Breed)
        .map_err(|e| {
            BreedError::Refused(format!(
                "{}: {e}",
                Setting::Prototype.set(&settings.prototype)
            ))
        })?;
    Ok((model, work))
}

/// The prototype's model and the work of every drop of the run
/// ([`check_run_work`]).
fn run_work(proto: &LeafSpec, settings: &BreedSettings) -> Result<(Model, Work), BreedError> {
    let source = &settings.prototype;
    let (model, dt) = prototype_step(proto, source, settings.seconds.max(ERROR_ESTIMATE_SECONDS))?;
    let frame_dt = 1.0 / FRAME_RATE;
    let integrator = DropParams::default().integrator;
    let mut work = Work::of(&model, integrator, dt, true, settings.seconds, frame_dt);
    // Every leaf is dropped once per release attitude.
    work.runs = (settings.population * settings.generations * settings.releases) as f64;
    work.variant_steps = variant_steps(proto, settings, dt);
    Ok((model, work))
}

/// How many times the prototype's steps (at its auto step `dt`) a variant
/// takes, on average over generation 0, whose genomes are known before the
/// run starts ([`selection::plan`]): a variant's lighter particles, stiffer
/// springs and smaller size shorten its auto step, and generation 0's
/// uniform half spans the whole of the bounds. Later generations are bred
/// from it. Without this a bending plate's breed quoted 80 s of one core and
/// took 680. A variant that has no usable step (it will be scored as
/// diverged, after no steps) counts as none.
fn variant_steps(proto: &LeafSpec, settings: &BreedSettings, dt: f64) -> f64 {
    /// At most this many of generation 0's variants are measured.
    const VARIANT_SAMPLE: usize = 256;
    use rayon::prelude::*;
    let plan = selection::plan(settings, proto, None);
    let integrator = DropParams::default().integrator;
    // Every k-th child, so that both halves of generation 0 are sampled
    // and a population of a million costs no more than VARIANT_SAMPLE
    // stability estimates before its run is refused or begins.
    let stride = plan.children.len().div_ceil(VARIANT_SAMPLE).max(1);
    let steps: Vec<f64> = plan
        .children
        .par_iter()
        .step_by(stride)
        .map(|child| {
            child
                .genome
                .model(proto)
                .ok()
                .and_then(|m| resolve_step(&m, integrator, TimeStep::Auto, 1.0 / FRAME_RATE).ok())
                .map_or(0.0, |h| dt / h)
        })
        .collect();
    if steps.is_empty() {
        1.0
    } else {
        steps.iter().sum::<f64>() / steps.len() as f64
    }
}

/// The prototype's integration error over about [`ERROR_ESTIMATE_SECONDS`]
/// at the integrator and auto step its drops use.
fn prototype_error(proto: &LeafSpec, source: &str) -> Result<ErrorEstimate, BreedError> {
    let (model, dt) = prototype_step(proto, source, ERROR_ESTIMATE_SECONDS)?;
    // The drop's step need not divide a second: estimate over the whole
    // number of steps nearest to ERROR_ESTIMATE_SECONDS.
    let seconds = (ERROR_ESTIMATE_SECONDS / dt).round().max(1.0) * dt;
    error_estimate(&model, DropParams::default().integrator, dt, seconds).map_err(|e| {
        BreedError::Refused(format!(
            "{}: the prototype's own fall, which run.toml records as the \
             run's error estimate, failed: {e}",
            Setting::Prototype.set(source)
        ))
    })
}

impl Run {
    /// Prepares a new run in `dir`, or picks up the same run there. A
    /// directory holding a different run (or other files) is refused and
    /// left untouched.
    pub fn create(dir: &Path, settings: BreedSettings) -> Result<Run, BreedError> {
        Run::create_within(dir, settings, MAX_BREED_WORK)
    }

    /// The estimated work of every drop of the run, with why its step is
    /// what it is ([`Work::describe`], [`Work::why`]): what `breed` says
    /// before a long run starts.
    ///
    /// # Errors
    /// As [`Run::create`] for a prototype with no usable step.
    pub fn work(&self) -> Result<Work, BreedError> {
        let (model, work) = match &self.estimated {
            Some(known) => known.clone(),
            None => run_work(&self.proto, &self.settings)?,
        };
        Ok(Work {
            // A breed drops with Verlet alone: no implicit step to offer.
            implicit_steps: None,
            ..work.explained(&model, 1.0 / FRAME_RATE)
        })
    }

    /// [`Run::create`], refusing a new run whose estimated work (every drop
    /// of every generation, in particle-steps) exceeds `max_work`.
    pub fn create_within(
        dir: &Path,
        settings: BreedSettings,
        max_work: f64,
    ) -> Result<Run, BreedError> {
        Run::create_inner(dir, settings, max_work, None)
    }

    /// [`Run::create_within`] for a `--like` run whose example the caller
    /// has read already (in any form: a CSV record with its vertical axis,
    /// a glTF animation's fall), copied into the run as given. Without it,
    /// the example is read again from `settings.like`'s source as a z-up
    /// CSV record.
    pub fn create_like(
        dir: &Path,
        settings: BreedSettings,
        max_work: f64,
        example: Trajectory,
    ) -> Result<Run, BreedError> {
        Run::create_inner(dir, settings, max_work, Some(example))
    }

    fn create_inner(
        dir: &Path,
        settings: BreedSettings,
        max_work: f64,
        given_example: Option<Trajectory>,
    ) -> Result<Run, BreedError> {
        settings.validate()?;
        let proto = LeafSpec::load(&settings.prototype)
            .map_err(|e| BreedError::Refused(format!("{}: {e}", Setting::Prototype)))?;
        let proto = match settings.law {
            Some(law) => proto.under_law(law),
            None => proto,
        };
        // Every variant lies within the bounds, and generation 0 and CMA-ES
        // start from the prototype: bounds that exclude it define no search.
        Genome::of_prototype(&proto).check(&proto).map_err(|e| {
            BreedError::Refused(format!(
                "{}: its [bounds] exclude the prototype itself: {e}; widen the \
                 bounds to contain the prototype's own genes (fold angles as the file gives \
                 them, factor 1 for masses, stiffness and size)",
                Setting::Prototype.set(&settings.prototype)
            ))
        })?;
        if dir.join(RUN_FILE).exists() {
            let existing = Run::resume(dir, &mut |m| eprintln!("leafmagic: {m}"))?;
            if existing.settings != settings {
                return Err(BreedError::Refused(format!(
                    "{} holds a different run (its run.toml has other settings); choose another {} or {} it",
                    dir.display(),
                    Setting::Out,
                    Setting::Resume
                )));
            }
            return Ok(existing);
        }
        if dir.exists() && !dir.is_dir() {
            return Err(BreedError::Refused(format!(
                "{}: is a file, not a directory; a run directory is a folder (created if \
                 absent): name another {} or remove the file",
                Setting::Out.set(dir.display()),
                Setting::Out
            )));
        }
        if dir.exists() {
            // A run killed while writing run.toml leaves its temporary
            // only: the run never started, and may be started again here.
            remove_stale_temporaries(dir);
            let non_empty = std::fs::read_dir(dir)
                .map_err(|e| io_err(dir, e))?
                .next()
                .is_some();
            if non_empty {
                return Err(BreedError::Refused(format!(
                    "{} exists and is not a leafmagic run (no run.toml); refusing to write into it",
                    dir.display()
                )));
            }
        }
        let integrator = DropParams::default().integrator;
        // Checked before anything is written: the drops, and the error
        // estimate beside generation 0, must be able to finish, and the
        // whole run must fit its work limit.
        let (_, dt) = prototype_step(
            &proto,
            &settings.prototype,
            settings.seconds.max(ERROR_ESTIMATE_SECONDS),
        )?;
        let estimated = check_run_work(&proto, &settings, max_work)?;
        let created_dir = !dir.exists();
        // The example of a --like run is copied in, so the run keeps what it
        // bred toward even if the original moves.
        let example = match (given_example, &settings.like) {
            (Some(example), _) => Some(example),
            (None, Some(t)) if t.source != "features" => {
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
        let text = toml::to_string(&run_file).map_err(|e| io_err(&dir.join(RUN_FILE), e))?;
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
            created: Some(created_dir),
            estimated: Some(estimated),
        })
    }

    /// Opens an existing run directory, checked ([`Run::load`]) but not
    /// repaired (what `merge`, `export` and `preview` use). Temporary files
    /// left by a writer that was killed mid-write are removed: the rename
    /// never happened, so they hold nothing the run needs.
    pub fn open(dir: &Path) -> Result<Run, BreedError> {
        for d in [dir.to_path_buf(), dir.join("best")] {
            remove_stale_temporaries(&d);
        }
        Run::load(dir)
    }

    /// Opens a run directory to go on with it (`breed --resume`): checked
    /// as [`Run::load`] does, and what is damaged but can be recomputed is
    /// repaired, each repair said through `note`. A generation file that
    /// differs from what the checkpoint recorded, or a checkpoint that
    /// fails its digest or any check, is recomputed: the run directory
    /// keeps the state of its last generation only, so the generations are
    /// run again from the last state that is intact (generation 0, or the
    /// checkpoint itself for its own generation's files). The run is
    /// deterministic, so the result is byte-identical to an uninterrupted
    /// run. A damaged `run.toml` cannot be recomputed and is refused.
    pub fn resume(dir: &Path, note: &mut dyn FnMut(&str)) -> Result<Run, BreedError> {
        for d in [dir.to_path_buf(), dir.join("best")] {
            remove_stale_temporaries(&d);
        }
        let (mut run, finding) = Run::inspect(dir)?;
        match finding {
            None => {}
            Some(Finding::Replay(damage)) => {
                note(&format!(
                    "{damage}; recomputing the run from generation 0 (the run is deterministic: \
                     every file comes out as an uninterrupted run's)"
                ));
                run.checkpoint = None;
                run.timing.clear();
            }
            Some(Finding::Rewrite(damage)) => {
                note(&format!(
                    "{damage}; rewriting it from checkpoint.json, which holds that generation"
                ));
                if let Some(cp) = &mut run.checkpoint {
                    let name = generation_file(cp.generation);
                    let path = run.dir.join(&name);
                    let bytes = population_csv(cp.generation, &cp.population);
                    write_atomic(&path, bytes.as_bytes()).map_err(|e| io_err(&path, e))?;
                    // The damage may have been the recorded hash itself
                    // (the file was right): record the true one, or the
                    // next reader finds the same damage again.
                    let hash = content_hash(bytes.as_bytes());
                    if cp.fnv1a64.get(&name) != Some(&hash) {
                        cp.fnv1a64.insert(name, hash);
                        let cp_path = run.dir.join(CHECKPOINT_FILE);
                        let json = encode_checkpoint(cp).map_err(|e| io_err(&cp_path, e))?;
                        write_atomic(&cp_path, json.as_bytes()).map_err(|e| io_err(&cp_path, e))?;
                    }
                }
            }
        }
        run.restore_checkpoint_text(note)?;
        run.restore_tables(note)?;
        Ok(run)
    }

    /// Reads a run directory without changing anything in it: what a shard
    /// process uses, since the driver (or other shards) may be writing there
    /// at the same time and their temporary files are not stale. Every file
    /// is checked first ([`super::verify`]); a damaged one is refused,
    /// naming the file, the field and the reason (`breed --resume` repairs
    /// what can be recomputed).
    pub fn load(dir: &Path) -> Result<Run, BreedError> {
        match Run::inspect(dir)? {
            (run, None) => Ok(run),
            (_, Some(Finding::Replay(d) | Finding::Rewrite(d))) => Err(BreedError::File {
                path: d.file.clone(),
                message: format!(
                    "{}: {}; resuming the run (`{}`) recomputes it",
                    d.field,
                    d.reason,
                    Setting::Resume.set(dir.display())
                ),
            }),
        }
    }

    /// Reads and checks a run directory: run.toml (an error if damaged),
    /// then the checkpoint and the generation files (a [`Finding`]).
    fn inspect(dir: &Path) -> Result<(Run, Option<Finding>), BreedError> {
        let path = dir.join(RUN_FILE);
        if !dir.is_dir() {
            // Said for every reader of a run (resume, --start-from,
            // export, merge, shard, preview), not as a resume's.
            return Err(BreedError::Refused(format!(
                "{}: {}; a breeding run's directory (what breeding wrote: its {}) is needed",
                dir.display(),
                if dir.exists() {
                    "is a file, not a run directory"
                } else {
                    "no such directory"
                },
                Setting::Out
            )));
        }
        if !path.exists() {
            return Err(BreedError::Refused(format!(
                "{}: no run.toml, so no run was set up there: a run stopped before it wrote \
                 run.toml has bred nothing and cannot be resumed; start it again with the same \
                 settings and `{}` (a directory that is empty but for temporaries is reused)",
                dir.display(),
                Setting::Out.set(dir.display())
            )));
        }
        let run_toml = std::fs::read(&path).map_err(|e| io_err(&path, e))?;
        let text = String::from_utf8(run_toml.clone())
            .map_err(|_| io_err(&path, "not UTF-8 text: damaged"))?;
        let run_file: RunFile = toml::from_str(&text).map_err(|e| io_err(&path, e))?;
        run_file.settings.validate().map_err(|e| io_err(&path, e))?;
        run_file
            .prototype_leaf
            .model()
            .map_err(|e| io_err(&path, format!("prototype_leaf: {e}")))?;
        let proto = run_file.prototype_leaf;
        let settings = run_file.settings;
        let cp_path = dir.join(CHECKPOINT_FILE);
        let mut finding = None;
        let checkpoint = if cp_path.exists() {
            let cp = std::fs::read(&cp_path)
                .map_err(|e| Damage::new(&cp_path, "(file)", format!("cannot be read: {e}")))
                .and_then(|b| {
                    String::from_utf8(b)
                        .map_err(|_| Damage::new(&cp_path, "(file)", "not UTF-8 text: damaged"))
                })
                .and_then(|t| decode_checkpoint(&t, &cp_path))
                .and_then(|cp| {
                    check_checkpoint(&cp, &settings, &proto, &run_toml, &cp_path)?;
                    Ok(cp)
                });
            match cp {
                Ok(cp) => Some(cp),
                // run.toml changed under the checkpoint: nothing to recompute from.
                Err(d) if d.file == path => {
                    return Err(BreedError::File {
                        path: d.file,
                        message: format!("{}: {}", d.field, d.reason),
                    });
                }
                Err(d) => {
                    finding = Some(Finding::Replay(d));
                    None
                }
            }
        } else {
            None
        };
        if let Some(cp) = &checkpoint {
            finding = check_generation_files(dir, cp);
        }
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
        let run = Run {
            dir: dir.to_path_buf(),
            proto,
            checkpoint,
            settings,
            timing,
            best_fall: None,
            created: None,
            estimated: None,
        };
        Ok((run, finding))
    }

    /// Rewrites checkpoint.json in leafmagic's own form when another JSON
    /// writer re-saved it (spaces, key order) with its content intact: the
    /// run's files then come out as an uninterrupted run's.
    fn restore_checkpoint_text(&self, note: &mut dyn FnMut(&str)) -> Result<(), BreedError> {
        let Some(cp) = &self.checkpoint else {
            return Ok(());
        };
        let path = self.dir.join(CHECKPOINT_FILE);
        let json = encode_checkpoint(cp).map_err(|e| io_err(&path, e))?;
        if std::fs::read(&path).ok().as_deref() != Some(json.as_bytes()) {
            note(&format!(
                "{}: its content is intact but not written as leafmagic writes it; rewritten",
                path.display()
            ));
            self.write(CHECKPOINT_FILE, json.as_bytes())?;
        }
        Ok(())
    }

    /// Rewrites generations.csv and generations.svg where they differ from
    /// what the checkpoint's history gives (they are rewritten after every
    /// generation, so only damage makes them differ).
    fn restore_tables(&self, note: &mut dyn FnMut(&str)) -> Result<(), BreedError> {
        let Some(cp) = &self.checkpoint else {
            return Ok(());
        };
        let tables = [
            ("generations.csv", generations_csv(&cp.history).into_bytes()),
            (
                "generations.svg",
                plot::generations_svg(&cp.history, &self.plot_title())?.into_bytes(),
            ),
        ];
        for (name, bytes) in tables {
            let path = self.dir.join(name);
            if std::fs::read(&path).ok().as_deref() != Some(&bytes[..]) {
                note(&format!(
                    "{}: missing or not what checkpoint.json gives; rewritten from it",
                    path.display()
                ));
                self.write(name, &bytes)?;
            }
        }
        Ok(())
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
        self.run_with(&Local, progress)
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
        shard::remove_merged(&self.dir, self.checkpoint.as_ref().map(|c| c.generation));
        while !self.is_complete() {
            self.step_with(executor, progress)?;
        }
        self.write_best()?;
        Ok(())
    }

    /// Breeds, evaluates and records one generation.
    pub fn step(&mut self, progress: &dyn Progress) -> Result<(), BreedError> {
        self.step_with(&Local, progress)
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
        let evaluate_all = || executor.evaluate(&self.job(), &plan, progress);
        // run.toml's error estimate is serial work: do it beside generation 0
        // rather than before it, and complete run.toml before gen-000.csv.
        let evals = if plan.generation == 0 {
            let (evals, estimate) = rayon::join(evaluate_all, || {
                prototype_error(proto, &self.settings.prototype)
            });
            // A failed estimate takes back the run this process created (a
            // failed evaluation keeps it: its shard files are resumable).
            let evals = evals?;
            match estimate {
                Ok(estimate) => self.complete_run_file(estimate)?,
                Err(e) => {
                    self.take_back();
                    return Err(e);
                }
            }
            evals
        } else {
            evaluate_all()?
        };
        if evals.len() != plan.children.len() {
            return Err(BreedError::Shards(format!(
                "generation {}: {} evaluations for {} children",
                plan.generation,
                evals.len(),
                plan.children.len()
            )));
        }
        self.finish(plan, evals, start, progress)
    }

    /// The next generation before evaluation ([`selection::plan`]): what
    /// any process that holds the run directory derives from it.
    pub fn plan(&self) -> Plan {
        selection::plan(&self.settings, &self.proto, self.checkpoint.as_ref())
    }

    /// What an executor needs to evaluate this run's generations.
    pub fn job(&self) -> Job<'_> {
        Job {
            dir: &self.dir,
            proto: &self.proto,
            settings: &self.settings,
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
            cma_children,
            model_children,
        } = plan;
        let bred = children.len() - cma_children - model_children;
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
        let mut population: Vec<Individual> = elites;
        population.extend(evaluated.iter().map(|(i, _)| i.clone()));
        population.sort_by_key(|i| i.id);
        // Toward a class, the leaves that hold it are scored among the
        // whole generation, elites included (novelty, issue 60): before
        // anything reads a score.
        let class_target = s.like.is_none().then_some(s.target);
        if let Some(target) = class_target.filter(|_| s.novelty) {
            novelty::rescore(&mut population, target);
        }
        let member = |id: u64| -> &Individual {
            let k = population
                .binary_search_by_key(&id, |i| i.id)
                .expect("every child is a member");
            &population[k]
        };
        // The 1/5 rule steers the GA's children only: CMA-ES has its own
        // step size.
        let ga_children: Vec<(&Individual, f64)> = evaluated[..bred]
            .iter()
            .map(|(i, ps)| (member(i.id), *ps))
            .collect();
        let successes = ga_children
            .iter()
            .filter(|(i, ps)| ps.is_nan() || i.eval.score >= *ps)
            .count();
        let mut success_rate = successes as f64 / ga_children.len().max(1) as f64;
        if s.like.is_some() {
            // Toward descriptors the step size should follow local progress:
            // only children of parents inside the class gate (score > 1)
            // count, and a success is a child strictly closer than its
            // parent. Children crossing into the class would otherwise keep
            // the rate high and the variation coarse for ever.
            let inside: Vec<&(&Individual, f64)> =
                ga_children.iter().filter(|(_, ps)| *ps > 1.0).collect();
            if !inside.is_empty() {
                let closer = inside.iter().filter(|(i, ps)| i.eval.score > *ps).count();
                success_rate = closer as f64 / inside.len() as f64;
            }
        }
        let sampled: Vec<&Individual> = evaluated[bred + model_children..]
            .iter()
            .map(|(i, _)| member(i.id))
            .collect();
        let ga_ids: Vec<u64> = ga_children.iter().map(|(i, _)| i.id).collect();
        let summary = summarise(generation, &population, scale, success_rate, class_target);
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
        // Generation 0 is the prototype's copies: its successes say nothing
        // about parents, so the scale rule starts from gen 1; a generation
        // without GA children leaves it as it was.
        let next = if generation == 0 || bred == 0 {
            scale
        } else {
            next_scale(scale, success_rate)
        };
        let cmaes = strategy::advance(
            s,
            &self.proto,
            self.checkpoint.as_ref().and_then(|c| c.cmaes.as_ref()),
            &sampled,
            &ga_ids,
            &population,
            next,
        );
        let mut checkpoint = Checkpoint {
            settings: s.clone(),
            generation,
            population,
            scale: next,
            next_id,
            history,
            archive,
            cmaes,
            // The hashes of the earlier generations' files, to which
            // write_generation adds this one's and run.toml's.
            fnv1a64: self
                .checkpoint
                .as_ref()
                .map(|c| c.fnv1a64.clone())
                .unwrap_or_default()
                .into_iter()
                .filter(|(name, _)| {
                    name.starts_with("gen-") && name.as_str() < generation_file(generation).as_str()
                })
                .collect(),
        };
        self.write_generation(&mut checkpoint)?;
        // The checkpoint now holds the generation: its shard files (if an
        // executor wrote any) are merged and go.
        shard::remove_merged(&self.dir, Some(generation));
        progress.finish_generation(&summary);
        self.checkpoint = Some(checkpoint);
        Ok(())
    }

    /// Removes what [`Run::create`] wrote (run.toml, the example, shard
    /// files of generation 0, the directory if it made it) when generation
    /// 0 cannot be completed: a run that never recorded a generation is not
    /// left behind to be taken for a started one. Does nothing for a run
    /// this process did not create.
    fn take_back(&mut self) {
        let Some(made_dir) = self.created.take() else {
            return;
        };
        if self.checkpoint.is_some() {
            return;
        }
        for name in [RUN_FILE, EXAMPLE_FILE] {
            let _ = std::fs::remove_file(self.dir.join(name));
        }
        let _ = std::fs::remove_dir_all(self.dir.join(shard::SHARDS_DIR));
        remove_stale_temporaries(&self.dir);
        if made_dir {
            // Only succeeds when empty.
            let _ = std::fs::remove_dir(&self.dir);
        }
    }

    /// Adds the prototype's error estimate to run.toml (if it is not there
    /// yet: a run resumed from generation 0 may have written it already).
    fn complete_run_file(&self, estimate: ErrorEstimate) -> Result<(), BreedError> {
        let path = self.dir.join(RUN_FILE);
        let text = std::fs::read_to_string(&path).map_err(|e| io_err(&path, e))?;
        let mut run_file: RunFile = toml::from_str(&text).map_err(|e| io_err(&path, e))?;
        if run_file.prototype_error.is_some() {
            return Ok(());
        }
        run_file.prototype_error = Some(estimate);
        let text = toml::to_string(&run_file).map_err(|e| io_err(&path, e))?;
        write_atomic(&path, text.as_bytes()).map_err(|e| io_err(&path, e))
    }

    fn write(&self, name: &str, bytes: &[u8]) -> Result<(), BreedError> {
        let path = self.dir.join(name);
        write_atomic(&path, bytes).map_err(|e| io_err(&path, e))
    }

    /// Writes gen-NNN.csv, generations.csv, timing.csv, generations.svg
    /// (class counts per generation), then the checkpoint
    /// (last, so a kill between them only repeats this generation).
    fn write_generation(&self, cp: &mut Checkpoint) -> Result<(), BreedError> {
        let table = population_csv(cp.generation, &cp.population);
        let run_toml = self.dir.join(RUN_FILE);
        let run_bytes = std::fs::read(&run_toml).map_err(|e| io_err(&run_toml, e))?;
        cp.fnv1a64
            .insert(RUN_FILE.to_string(), content_hash(&run_bytes));
        cp.fnv1a64.insert(
            generation_file(cp.generation),
            content_hash(table.as_bytes()),
        );
        self.write(&generation_file(cp.generation), table.as_bytes())?;
        self.write("generations.csv", generations_csv(&cp.history).as_bytes())?;
        let mut timing = String::from("generation,wall_s\n");
        for (g, t) in self.timing.iter().enumerate() {
            let _ = writeln!(timing, "{g},{t}");
        }
        self.write("timing.csv", timing.as_bytes())?;
        let svg = plot::generations_svg(&cp.history, &self.plot_title())?;
        self.write("generations.svg", svg.as_bytes())?;
        let json = encode_checkpoint(cp).map_err(|e| io_err(&self.dir.join(CHECKPOINT_FILE), e))?;
        self.write(CHECKPOINT_FILE, json.as_bytes())
    }

    /// The title of generations.svg.
    fn plot_title(&self) -> String {
        format!(
            "{}: breeding toward {} (population {}, seed {})",
            self.proto.name, self.settings.target, self.settings.population, self.settings.seed
        )
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
            // The top bins are open above: their upper edge is empty, never
            // `inf` (no output file holds a non-finite number); the note
            // line says so before the header.
            let mut csv = String::from(
                "# descent_max_m_s and spin_max_rad_s are empty for the top bins, which are open above\n\
                 descent_min_m_s,descent_max_m_s,spin_min_rad_s,spin_max_rad_s,generation,id,class,regime,score,descent_m_s,spin_rad_s,file\n",
            );
            let edge =
                |edges: &[f64], k: usize| edges.get(k + 1).map_or(String::new(), f64::to_string);
            for e in &cp.archive {
                let i = &e.individual;
                let r = i.eval.record();
                let _ = writeln!(
                    csv,
                    "{},{},{},{},{},{},{},{},{},{},{},archive/leaf-{}.toml",
                    ARCHIVE_DESCENT_EDGES[e.descent_bin],
                    edge(&ARCHIVE_DESCENT_EDGES, e.descent_bin),
                    ARCHIVE_SPIN_EDGES[e.spin_bin],
                    edge(&ARCHIVE_SPIN_EDGES, e.spin_bin),
                    e.generation,
                    i.id,
                    r.class,
                    r.regime,
                    r.score,
                    r.descent_m_s,
                    r.spin_rad_s,
                    i.id
                );
            }
            self.write("archive.csv", csv.as_bytes())?;
        }
        let ranked = rank(&cp.population);
        // Toward a class: the best leaves of it, each kept by every release,
        // that fall pairwise apart (issue 60), or, before any is, the five
        // best.
        let apart = match &self.settings.like {
            None if self.settings.novelty => {
                novelty::distinct(&ranked, self.settings.target, BEST_LEAVES)
            }
            _ => Vec::new(),
        };
        let best: Vec<&Individual> = if apart.is_empty() {
            ranked.into_iter().take(BEST_LEAVES).collect()
        } else {
            apart
        };
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
                first.eval.class_name(),
                first
                    .eval
                    .distance
                    .map_or("∞, another class".to_string(), |d| format!("{d:.3}"))
            );
            let svg = plot::like_svg(example.as_ref(), &fall, &title)?;
            self.write(LIKE_PLOT_FILE, svg.as_bytes())?;
        }
        Ok(())
    }

    /// The fall of a member, dropped again exactly as it was evaluated (its
    /// lower-median release).
    pub fn best_fall(&self, member: &Individual) -> Result<Trajectory, BreedError> {
        if let Some((id, fall)) = &self.best_fall
            && *id == member.id
        {
            return Ok(fall.clone());
        }
        let model = member
            .genome
            .model(&self.proto)
            .map_err(|e| BreedError::Leaf {
                id: member.id,
                message: e.to_string(),
            })?;
        // The drop its score is that of: the lower median of its releases.
        let params = DropParams {
            seconds: self.settings.seconds,
            dt: TimeStep::Auto,
            tilt_deg: member.eval.release_deg,
            ..Default::default()
        };
        drop_leaf(&model, &params)
            .map(|r| r.trajectory)
            .map_err(|e| BreedError::Leaf {
                id: member.id,
                message: e.to_string(),
            })
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

/// A run recorded from outside the generation loop: generations bred some
/// other way (the studio's picks) written as a run directory that `export`,
/// `preview` and `merge` read as any run's ([`write_record`]).
#[derive(Debug)]
pub struct RunRecord<'a> {
    /// The settings; `population` and `generations` are set from the
    /// record ([`write_record`]).
    pub settings: BreedSettings,
    /// The prototype.
    pub proto: &'a LeafSpec,
    /// Every generation's members, in id order.
    pub generations: Vec<Vec<Individual>>,
    /// Their summaries, one per generation.
    pub history: Vec<GenerationSummary>,
    /// The last generation's population as the checkpoint holds it (what
    /// `export --top` ranks), in id order.
    pub population: Vec<Individual>,
    /// Variation scale for the next generation.
    pub scale: f64,
    /// Next id to assign.
    pub next_id: u64,
}

/// Writes `record` into `dir` as a completed run: `run.toml`, every
/// `gen-NNN.csv` that is missing or differs, `generations.csv`, then
/// `checkpoint.json` with their content hashes (each atomically, the
/// checkpoint last, so a reader sees the previous state or the new one).
/// The bytes depend on the record only.
pub fn write_record(dir: &Path, record: RunRecord<'_>) -> Result<(), BreedError> {
    let RunRecord {
        mut settings,
        proto,
        generations,
        history,
        mut population,
        scale,
        next_id,
    } = record;
    if generations.is_empty() || generations.len() != history.len() {
        return Err(BreedError::Refused(format!(
            "a run record needs one summary per generation ({} generations, {} summaries)",
            generations.len(),
            history.len()
        )));
    }
    population.sort_by_key(|i| i.id);
    settings.population = population.len();
    settings.generations = generations.len();
    settings.elites = 0;
    settings.validate()?;
    let write = |name: &str, bytes: &[u8]| {
        let path = dir.join(name);
        write_atomic(&path, bytes).map_err(|e| io_err(&path, e))
    };
    let run_file = RunFile {
        tool: "leafmagic".to_string(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        settings: settings.clone(),
        integrator: DropParams::default().integrator.to_string(),
        dt: "auto: each leaf its own, from its stability estimate".to_string(),
        prototype_error: None,
        prototype_leaf: proto.clone(),
    };
    let run_toml = toml::to_string(&run_file).map_err(|e| io_err(&dir.join(RUN_FILE), e))?;
    let mut fnv1a64 = std::collections::BTreeMap::new();
    fnv1a64.insert(RUN_FILE.to_string(), content_hash(run_toml.as_bytes()));
    write(RUN_FILE, run_toml.as_bytes())?;
    for (g, members) in generations.iter().enumerate() {
        let name = generation_file(g);
        let csv = population_csv(g, members);
        fnv1a64.insert(name.clone(), content_hash(csv.as_bytes()));
        // Earlier generations do not change: written once.
        if std::fs::read(dir.join(&name)).ok().as_deref() != Some(csv.as_bytes()) {
            write(&name, csv.as_bytes())?;
        }
    }
    write("generations.csv", generations_csv(&history).as_bytes())?;
    let cp = Checkpoint {
        settings,
        generation: generations.len() - 1,
        population,
        scale,
        next_id,
        history,
        archive: Vec::new(),
        cmaes: None,
        fnv1a64,
    };
    let path = dir.join(CHECKPOINT_FILE);
    check_checkpoint(&cp, &cp.settings, proto, run_toml.as_bytes(), &path)
        .map_err(|d| io_err(&d.file, format!("{}: {}", d.field, d.reason)))?;
    let json = encode_checkpoint(&cp).map_err(|e| io_err(&path, e))?;
    write(CHECKPOINT_FILE, json.as_bytes())
}

/// What a check of a run directory found to repair.
enum Finding {
    /// The checkpoint, or the file of an earlier generation than its own,
    /// is damaged: the run must be recomputed from generation 0.
    Replay(Damage),
    /// The file of the checkpoint's own generation is damaged: it is
    /// rewritten from the checkpoint.
    Rewrite(Damage),
}

/// `gen-NNN.csv`.
fn generation_file(generation: usize) -> String {
    format!("gen-{generation:03}.csv")
}

/// Checks every generation file up to the checkpoint's against the hashes
/// it recorded. A hash missing is a damage of the checkpoint (every
/// checkpoint records one per generation file): a file left unchecked
/// would be trusted.
fn check_generation_files(dir: &Path, cp: &Checkpoint) -> Option<Finding> {
    let own = generation_file(cp.generation);
    for g in 0..=cp.generation {
        let name = generation_file(g);
        let path = dir.join(&name);
        let checked = match cp.fnv1a64.get(&name) {
            Some(recorded) => check_generation_file(&path, recorded),
            None => Err(Damage::new(
                &dir.join(CHECKPOINT_FILE),
                format!("fnv1a64.\"{name}\""),
                format!(
                    "missing: the checkpoint of generation {} records the content hash of every \
                     generation file from {} to {own}, so {name} cannot be checked",
                    cp.generation,
                    generation_file(0)
                ),
            )),
        };
        if let Err(d) = checked {
            return Some(if name == own && d.file == path {
                Finding::Rewrite(d)
            } else {
                Finding::Replay(d)
            });
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run whose generation 0 cannot be completed (the prototype's error
    /// estimate failed) is taken back: run.toml goes, and so does the
    /// directory if this process made it; a directory that was there before
    /// stays, empty again.
    #[test]
    fn a_run_that_never_completed_generation_0_is_taken_back() {
        let dir = std::env::temp_dir().join(format!("leafmagic-take-back-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut run = Run::create(&dir, BreedSettings::default_run()).unwrap();
        assert!(dir.join(RUN_FILE).exists());
        run.take_back();
        assert!(!dir.exists(), "the directory it made is left");

        std::fs::create_dir_all(&dir).unwrap();
        let mut run = Run::create(&dir, BreedSettings::default_run()).unwrap();
        assert!(dir.join(RUN_FILE).exists());
        run.take_back();
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert!(dir.is_dir() && left.is_empty(), "{left:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
