//! What `leafmagic shard` does: evaluate one shard of the next generation
//! of a run directory, read-only but for its own shard file.

use super::evaluate::evaluate;
use super::population::{BreedError, Evaluation, io_err};
use super::run::Run;
use super::shard::{ShardFile, Split, encode, generation_dir, plan_hash, read_valid, shard_path};
use crate::util::io::write_atomic;
use crate::util::setting::Setting;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// What [`run_shard`] did.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// Evaluated this many individuals and wrote the file.
    Evaluated(usize, PathBuf),
    /// `skip_done` and a valid file was already there: nothing written.
    AlreadyDone(PathBuf),
}

/// Evaluates shard `split` of generation `generation` of the run in
/// `run_dir` (on the current rayon pool) and writes its file atomically.
/// The generation must be the next one the checkpoint lacks. With
/// `skip_done`, a valid file already there is kept and nothing is
/// evaluated (what a driver wants of a rerun; without it the shard is
/// recomputed, to the same bytes). Reads the run directory only: it never
/// removes or rewrites anything but its own shard file.
pub fn run_shard(
    run_dir: &Path,
    generation: usize,
    split: Split,
    skip_done: bool,
) -> Result<Outcome, BreedError> {
    let run = Run::load(run_dir)?;
    let next = run.checkpoint.as_ref().map_or(0, |c| c.generation + 1);
    if run.is_complete() {
        return Err(BreedError::Refused(format!(
            "{}: the run is complete ({} generations); there is no generation {generation} to evaluate",
            run_dir.display(),
            run.settings().generations
        )));
    }
    if generation != next {
        let held = run.checkpoint.as_ref().map_or_else(
            || "checkpoint.json is absent, so the next is generation 0".to_string(),
            |c| {
                format!(
                    "checkpoint.json holds generation {}, so the next is {next}",
                    c.generation
                )
            },
        );
        return Err(BreedError::Refused(format!(
            "{}: {} cannot be evaluated now: {held}",
            run_dir.display(),
            Setting::Generation.set(generation)
        )));
    }
    let plan = run.plan();
    let path = shard_path(run_dir, generation, split);
    if skip_done && read_valid(run_dir, &plan, split).is_ok() {
        return Ok(Outcome::AlreadyDone(path));
    }
    let members = split.members(&plan.children);
    let settings = run.settings();
    let rows: Vec<(u64, Evaluation)> = members
        .par_iter()
        .map(|c| (c.id, evaluate(&run.proto, c.id, &c.genome, settings)))
        .collect();
    let n = rows.len();
    let text = encode(&ShardFile {
        generation,
        split,
        plan: plan_hash(&members),
        rows,
    })
    .map_err(|e| io_err(&path, e))?;
    let dir = generation_dir(run_dir, generation);
    std::fs::create_dir_all(&dir).map_err(|e| io_err(&dir, e))?;
    write_atomic(&path, text.as_bytes()).map_err(|e| io_err(&path, e))?;
    Ok(Outcome::Evaluated(n, path))
}
