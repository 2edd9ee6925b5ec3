//! Executors: who evaluates a generation's children. [`Local`] is this
//! process's rayon pool. [`Processes`] and [`Slurm`] are drivers: they have
//! each shard of the generation ([`crate::breed::shard`]) evaluated by a
//! `leafmagic shard` process, check every shard file, rerun the missing or
//! invalid ones a bounded number of times, and merge the results in id
//! order, so the run goes on exactly as the local loop would.
//!
//! A driver killed mid-generation leaves the shard files already written;
//! the resumed driver merges those and runs only the others.

use super::evaluate::evaluate;
use super::population::{BreedError, Evaluation, Job, Plan, Progress, io_err};
use super::shard::{self, Problem, Split};
use crate::util::setting::Setting;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};

/// Evaluates the children of one generation.
pub trait Executor: Sync {
    /// One evaluation per child of `plan`, in the plan's order. Calls
    /// `progress.individual_done` once per child.
    fn evaluate(
        &self,
        job: &Job,
        plan: &Plan,
        progress: &dyn Progress,
    ) -> Result<Vec<Evaluation>, BreedError>;
}

/// The children on the current rayon pool (the default).
pub struct Local;

impl Executor for Local {
    fn evaluate(
        &self,
        job: &Job,
        plan: &Plan,
        progress: &dyn Progress,
    ) -> Result<Vec<Evaluation>, BreedError> {
        let settings = job.settings;
        Ok(plan
            .children
            .par_iter()
            .map(|c| {
                let eval = evaluate(job.proto, c.id, &c.genome, settings);
                progress.individual_done(eval.kind(), eval.score);
                eval
            })
            .collect())
    }
}

/// How many times a driver starts a shard (the first run and the reruns)
/// before it gives up on the run.
pub const SHARD_ATTEMPTS: usize = 3;

/// Starts shard processes and waits for them. Failures of single shards are
/// no error here (the driver reads the shard files afterwards); an error is
/// for what no rerun can mend (the launcher program is missing).
trait Launcher: Sync {
    /// Runs shards `missing` of a `count`-way split of `generation` (an
    /// attempt, numbered from 1); returns a note per shard that failed.
    fn launch(
        &self,
        run_dir: &Path,
        generation: usize,
        count: usize,
        missing: &[usize],
        attempt: usize,
    ) -> Result<BTreeMap<usize, String>, BreedError>;

    /// Where a shard's output goes.
    fn log(&self, run_dir: &Path, generation: usize, split: Split) -> PathBuf {
        shard::log_path(run_dir, generation, split)
    }

    /// Shards per generation.
    fn shards(&self) -> usize;
}

/// Every launcher evaluates a generation the same way: launch, check,
/// rerun, merge (`evaluate_sharded`).
impl<L: Launcher> Executor for L {
    fn evaluate(
        &self,
        job: &Job,
        plan: &Plan,
        progress: &dyn Progress,
    ) -> Result<Vec<Evaluation>, BreedError> {
        evaluate_sharded(self, self.shards(), job, plan, progress)
    }
}

/// `shards/gen-GGG/`, created: the launchers' logs go there.
fn generation_dir(run_dir: &Path, generation: usize) -> Result<PathBuf, BreedError> {
    let dir = shard::generation_dir(run_dir, generation);
    std::fs::create_dir_all(&dir).map_err(|e| io_err(&dir, e))?;
    Ok(dir)
}

fn note(message: &str) {
    eprintln!("leafmagic: {message}");
}

/// The driver: launch, check, rerun, merge.
fn evaluate_sharded(
    launcher: &dyn Launcher,
    count: usize,
    job: &Job,
    plan: &Plan,
    progress: &dyn Progress,
) -> Result<Vec<Evaluation>, BreedError> {
    let dir = job.dir;
    let g = plan.generation;
    let mut results: Vec<Option<Vec<Evaluation>>> = vec![None; count];
    let mut why: BTreeMap<usize, String> = BTreeMap::new();
    for attempt in 0..=SHARD_ATTEMPTS {
        let mut missing = Vec::new();
        let mut reused = 0;
        for (index, slot) in results.iter_mut().enumerate() {
            if slot.is_some() {
                continue;
            }
            let split = Split { index, count };
            match shard::read_valid(dir, plan, split) {
                Ok(evals) => {
                    for e in &evals {
                        progress.individual_done(e.kind(), e.score);
                    }
                    *slot = Some(evals);
                    if attempt == 0 {
                        reused += 1;
                    }
                }
                Err(Problem::Missing) => {
                    missing.push(index);
                    why.entry(index).or_insert_with(|| "no shard file".into());
                }
                Err(Problem::Invalid(reason)) => {
                    let path = shard::shard_path(dir, g, split);
                    note(&format!(
                        "generation {g}: shard {index} of {count} is invalid ({reason}): not merged, re-evaluating ({})",
                        path.display()
                    ));
                    // Out of the way, so a rerun writes a fresh one (a
                    // failure here shows up as that rerun's failure).
                    let _ = std::fs::remove_file(&path);
                    missing.push(index);
                    why.insert(index, format!("invalid shard file: {reason}"));
                }
            }
        }
        if attempt == 0 && reused > 0 {
            note(&format!(
                "generation {g}: reusing {reused} of {count} shards already on disk"
            ));
        }
        if missing.is_empty() {
            break;
        }
        if attempt == SHARD_ATTEMPTS {
            let first = missing[0];
            let log = launcher.log(
                dir,
                g,
                Split {
                    index: first,
                    count,
                },
            );
            let others = if missing.len() > 1 {
                format!(
                    " (and {} more: shards {:?})",
                    missing.len() - 1,
                    &missing[1..]
                )
            } else {
                String::new()
            };
            return Err(BreedError::Shards(format!(
                "generation {g}: shard {first} of {count} failed {SHARD_ATTEMPTS} times ({}){others}; its log: {}",
                why.get(&first).map_or("no shard file", String::as_str),
                log.display()
            )));
        }
        if attempt > 0 {
            note(&format!(
                "generation {g}: shards {missing:?} of {count} missing after attempt {attempt}; rerunning"
            ));
        }
        for (index, reason) in launcher.launch(dir, g, count, &missing, attempt + 1)? {
            why.insert(index, reason);
        }
    }
    // Merge in id order: the k-th child is member k / count of shard k mod count.
    let mut shards: Vec<std::vec::IntoIter<Evaluation>> = results
        .into_iter()
        .map(|r| r.expect("every shard checked").into_iter())
        .collect();
    let evals: Vec<Evaluation> = (0..plan.children.len())
        .map(|k| {
            shards[k % count]
                .next()
                .expect("shard sizes follow the split")
        })
        .collect();
    Ok(evals)
}

fn describe(status: ExitStatus) -> String {
    match status.code() {
        Some(c) => format!("exit status {c}"),
        None => format!("{status}"),
    }
}

/// Appends a line to a log (the driver's own mark of each attempt).
fn append_line(path: &Path, line: &str) -> std::io::Result<std::fs::File> {
    let mut f = OpenOptions::new().create(true).append(true).open(path)?;
    writeln!(f, "{line}")?;
    Ok(f)
}

/// [`append_line`], then the log twice: a child's stdout and stderr.
fn child_log(path: &Path, line: &str) -> std::io::Result<(std::fs::File, std::fs::File)> {
    let f = append_line(path, line)?;
    Ok((f.try_clone()?, f))
}

/// `count` shards per generation, each a `leafmagic shard` child process
/// on this machine (the protocol of a cluster, without the cluster).
pub struct Processes {
    /// The leafmagic binary (the CLI passes its own).
    pub program: PathBuf,
    /// Shards per generation.
    pub shards: usize,
    /// Worker threads of each shard process.
    pub threads: usize,
}

impl Launcher for Processes {
    fn shards(&self) -> usize {
        self.shards
    }

    fn launch(
        &self,
        run_dir: &Path,
        generation: usize,
        count: usize,
        missing: &[usize],
        attempt: usize,
    ) -> Result<BTreeMap<usize, String>, BreedError> {
        generation_dir(run_dir, generation)?;
        let mut children = Vec::new();
        let mut failed = BTreeMap::new();
        for &index in missing {
            let split = Split { index, count };
            let log = shard::log_path(run_dir, generation, split);
            let args = shard_args(run_dir, generation, Some(split), count, self.threads);
            let out = child_log(
                &log,
                &format!(
                    "== attempt {attempt}: {} {}",
                    self.program.display(),
                    args.join(" ")
                ),
            );
            let (stdout, stderr) = match out {
                Ok(o) => o,
                Err(e) => {
                    failed.insert(index, format!("cannot open its log: {e}"));
                    continue;
                }
            };
            let child = Command::new(&self.program)
                .args(&args)
                .stdin(Stdio::null())
                .stdout(stdout)
                .stderr(stderr)
                .spawn()
                .map_err(|e| {
                    BreedError::Shards(format!("cannot start {}: {e}", self.program.display()))
                })?;
            children.push((index, child));
        }
        for (index, mut child) in children {
            match child.wait() {
                Ok(s) if s.success() => {}
                Ok(s) => {
                    failed.insert(index, describe(s));
                }
                Err(e) => {
                    failed.insert(index, e.to_string());
                }
            }
        }
        Ok(failed)
    }
}

/// The arguments of `leafmagic shard` for one launch (`split` None: the
/// index comes from the environment of the engine).
fn shard_args(
    run_dir: &Path,
    generation: usize,
    split: Option<Split>,
    count: usize,
    threads: usize,
) -> Vec<String> {
    let mut args = vec![
        "shard".to_string(),
        run_dir.display().to_string(),
        "--generation".to_string(),
        generation.to_string(),
    ];
    if let Some(s) = split {
        args.extend(["--index".to_string(), s.index.to_string()]);
    }
    args.extend([
        "--count".to_string(),
        count.to_string(),
        "--threads".to_string(),
        threads.to_string(),
        // A rerun keeps what is already done.
        "--skip-done".to_string(),
    ]);
    args
}

/// Merges shard files that something else wrote (a Kubernetes Indexed
/// Job, a Slurm array submitted by hand): starts nothing, and a missing or
/// invalid shard is an error naming it.
pub struct Merge {
    /// Shards per generation.
    pub shards: usize,
}

impl Launcher for Merge {
    fn shards(&self) -> usize {
        self.shards
    }

    fn launch(
        &self,
        run_dir: &Path,
        generation: usize,
        count: usize,
        missing: &[usize],
        _attempt: usize,
    ) -> Result<BTreeMap<usize, String>, BreedError> {
        let first = shard::shard_path(
            run_dir,
            generation,
            Split {
                index: missing[0],
                count,
            },
        );
        Err(BreedError::Shards(format!(
            "generation {generation}: shards {missing:?} of {count} are missing or invalid ({} and so on); \
             run those shards of {} ({}, {}, {}), then merge again",
            first.display(),
            run_dir.display(),
            Setting::Generation.set(generation),
            Setting::Index.set("I"),
            Setting::Count.set(count)
        )))
    }
}

/// How the Slurm executor starts a generation's shards.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlurmMode {
    /// Inside an allocation (`SLURM_JOB_ID` set: the driver was started by
    /// `sbatch` or `salloc`): one `srun` job step of `count` tasks per
    /// generation, each task's index from `SLURM_PROCID`. A step starts in
    /// about a tenth of a second.
    Step {
        /// Tasks of the allocation (`SLURM_NTASKS`), if known: a step of more
        /// shards than that is launched with `--overcommit`.
        allocated: Option<usize>,
    },
    /// Outside an allocation (sites that only allow arrays): one
    /// `sbatch --array` per generation, each element's index from
    /// `SLURM_ARRAY_TASK_ID`, the driver watching `squeue`. Arrays wait
    /// for the scheduler, so a generation costs a second or more.
    Array,
}

/// `count` shards per generation through Slurm.
pub struct Slurm {
    /// The leafmagic binary, at a path every node can run.
    pub program: PathBuf,
    /// Shards per generation.
    pub shards: usize,
    /// CPUs (worker threads) of each shard task.
    pub threads: usize,
    /// Job steps or arrays.
    pub mode: SlurmMode,
}

/// Quotes a word for `sh` (the `--wrap` of sbatch).
fn sh_quote(word: &str) -> String {
    format!("'{}'", word.replace('\'', "'\\''"))
}

impl Launcher for Slurm {
    fn shards(&self) -> usize {
        self.shards
    }

    fn launch(
        &self,
        run_dir: &Path,
        generation: usize,
        count: usize,
        missing: &[usize],
        attempt: usize,
    ) -> Result<BTreeMap<usize, String>, BreedError> {
        let allocated = match self.mode {
            SlurmMode::Array => {
                return self.launch_array(run_dir, generation, count, missing, attempt);
            }
            SlurmMode::Step { allocated } => allocated,
        };
        let gen_dir = generation_dir(run_dir, generation)?;
        let driver_log = gen_dir.join("slurm.log");
        // Every shard in one step: a rerun starts them all again and those
        // already done return at once (--skip-done), which costs less than a
        // step per missing shard.
        let mut cmd = self.command("srun", &gen_dir, generation, count, 't');
        cmd.arg(format!("--ntasks={count}"))
            // One failing task must not take the others down.
            .arg("--kill-on-bad-exit=0")
            .arg("--quiet");
        if allocated.is_some_and(|a| count > a) {
            cmd.arg("--overcommit");
        }
        cmd.arg(&self.program)
            .args(shard_args(run_dir, generation, None, count, self.threads));
        let log = child_log(&driver_log, &format!("== attempt {attempt}: {cmd:?}"))
            .map_err(|e| io_err(&driver_log, e))?;
        let status = cmd
            .stdin(Stdio::null())
            .stdout(log.0)
            .stderr(log.1)
            .status()
            .map_err(|e| {
                BreedError::Shards(format!(
                    "cannot run srun (is Slurm installed and on PATH?): {e}"
                ))
            })?;
        let mut failed = BTreeMap::new();
        if !status.success() {
            for &i in missing {
                failed.insert(
                    i,
                    format!(
                        "srun {}; see also {}",
                        describe(status),
                        driver_log.display()
                    ),
                );
            }
        }
        Ok(failed)
    }
}

impl Slurm {
    /// `srun` or `sbatch` with what steps and arrays share: CPUs per task,
    /// the job name, and each shard's output appended to its own log
    /// (`%t` is a step's task id, `%a` an array's element).
    fn command(
        &self,
        program: &str,
        gen_dir: &Path,
        generation: usize,
        count: usize,
        task: char,
    ) -> Command {
        let mut cmd = Command::new(program);
        cmd.arg(format!("--cpus-per-task={}", self.threads))
            .arg(format!("--job-name=leafmagic-g{generation:03}"))
            .arg(format!(
                "--output={}",
                gen_dir
                    .join(format!("shard-%3{task}-of-{count:03}.log"))
                    .display()
            ))
            .arg("--open-mode=append");
        cmd
    }

    /// One array per attempt: `sbatch --array` of the missing shards, then
    /// the driver watches `squeue` itself every [`ARRAY_POLL`] rather than
    /// `sbatch --wait`, which polls at seconds.
    fn launch_array(
        &self,
        run_dir: &Path,
        generation: usize,
        count: usize,
        missing: &[usize],
        attempt: usize,
    ) -> Result<BTreeMap<usize, String>, BreedError> {
        let gen_dir = generation_dir(run_dir, generation)?;
        let driver_log = gen_dir.join("slurm.log");
        let list = missing
            .iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join(",");
        let wrap = std::iter::once(self.program.display().to_string())
            .chain(shard_args(run_dir, generation, None, count, self.threads))
            .map(|w| sh_quote(&w))
            .collect::<Vec<_>>()
            .join(" ");
        let mut cmd = self.command("sbatch", &gen_dir, generation, count, 'a');
        cmd.arg("--parsable")
            .arg(format!("--array={list}"))
            .arg("--ntasks=1")
            // The index comes from SLURM_ARRAY_TASK_ID, the count from --count
            // (a rerun's array holds only the missing shards).
            .arg(format!("--wrap=exec {wrap}"));
        let _ = append_line(&driver_log, &format!("== attempt {attempt}: {cmd:?}"));
        let out = cmd.stdin(Stdio::null()).output().map_err(|e| {
            BreedError::Shards(format!(
                "cannot run sbatch (is Slurm installed and on PATH?): {e}"
            ))
        })?;
        let _ = append_line(
            &driver_log,
            &format!(
                "{}{}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            ),
        );
        if !out.status.success() {
            return Err(BreedError::Shards(format!(
                "generation {generation}: sbatch refused the array ({}): {}",
                describe(out.status),
                String::from_utf8_lossy(&out.stderr).trim()
            )));
        }
        let stdout = String::from_utf8_lossy(&out.stdout);
        let job = stdout
            .trim()
            .split(';')
            .next()
            .unwrap_or_default()
            .to_string();
        loop {
            std::thread::sleep(ARRAY_POLL);
            // Wait for the elements to leave the queue, not for the files:
            // the next generation's array is scheduled at submission only if
            // their CPUs are free by then. Empty output (or an error, once
            // the job is purged): no element is pending or running. A failed
            // squeue only costs a rerun of what is missing, never a merge.
            let q = Command::new("squeue")
                .args(["-h", "-j", &job, "-o", "%i"])
                .stdin(Stdio::null())
                .stderr(Stdio::null())
                .output();
            match q {
                Ok(q) if q.status.success() && !q.stdout.trim_ascii().is_empty() => {}
                _ => break,
            }
        }
        Ok(missing
            .iter()
            .filter(|&&index| {
                !shard::shard_path(run_dir, generation, Split { index, count }).exists()
            })
            .map(|&index| {
                (
                    index,
                    format!("array element {job}_{index} ended without writing its shard file"),
                )
            })
            .collect())
    }
}

/// How often the array fallback looks at the queue.
pub const ARRAY_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// The Slurm mode for this process's environment: job steps inside an
/// allocation, arrays outside one.
pub fn slurm_mode_from_env() -> SlurmMode {
    match std::env::var("SLURM_JOB_ID") {
        Ok(id) if !id.is_empty() => SlurmMode::Step {
            allocated: std::env::var("SLURM_NTASKS")
                .ok()
                .and_then(|n| n.parse().ok()),
        },
        _ => SlurmMode::Array,
    }
}
