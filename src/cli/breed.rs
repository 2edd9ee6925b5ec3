//! `breed`, `shard` and `merge`: a breeding run, started or resumed and
//! evaluated by the executor asked for, or one shard of a generation
//! evaluated, or a generation's shards merged into the run.

use super::args::{BreedArgs, ExecutorKind, MergeArgs, ShardArgs, law_word};
use super::progress::Bar;
use super::{input, report};
use anyhow::{Context, Result, bail};
use leafmagic::breed::executor::Executor;
use leafmagic::breed::{self, BreedSettings, Run};
use leafmagic::leaf::LeafSpec;
use leafmagic::motion::classify::{self, MotionClass};
use leafmagic::motion::describe::{self, Descriptors, MotionTarget};
use std::path::PathBuf;
use std::time::Instant;

/// `breed`: creates the run (or opens it with `--resume`), evaluates its
/// generations and reports them.
pub fn breed(args: BreedArgs) -> Result<()> {
    let mut run = match &args.resume {
        Some(dir) => {
            let run = Run::resume(dir, &mut |m| eprintln!("leafmagic: {m}"))?;
            // A run is bred under one law: --resume with another is refused.
            let law = run.proto.aero.law;
            if let Some(asked) = args.law {
                if asked.law() != law {
                    bail!(
                        "--resume {}: the run was bred under --law {} ({} aerodynamics), not --law \
                         {} ({}); resume it without --law or with --law {}, or breed anew with --out",
                        dir.display(),
                        law_word(law),
                        law.as_str(),
                        law_word(asked.law()),
                        asked.law().as_str(),
                        law_word(law)
                    );
                }
            }
            run
        }
        None => {
            // The run started from, read (and checked) once.
            let from = match &args.start_from {
                Some(dir) => Some(
                    Run::load(dir).with_context(|| format!("--start-from {}", dir.display()))?,
                ),
                None => None,
            };
            // The --like example, read once (notes printed once), in
            // whatever form it came: it is described at the size the
            // chosen prototype needs, and copied into the run as read.
            let example = match &args.like {
                Some(path) => Some(input::read_record(
                    path,
                    input::CsvUnits {
                        up: args.up,
                        scale: args.scale,
                        frame_rate: args.frame_rate,
                    },
                    input::Pick {
                        object: args.object.as_deref(),
                        animation: args.animation.as_deref(),
                        policy: Some(&args.reading.policy()),
                    },
                )?),
                None => None,
            };
            let (prototype, like) = choose_prototype(&args, from.as_ref(), example.as_ref())?;
            // run.toml's settings name --law when given (a run without it is
            // the bytes it always was); its prototype_leaf is under the law.
            let settings = BreedSettings {
                prototype,
                law: args.law.map(|l| l.law()),
                initial_scale: args.initial_scale,
                target: args.target.unwrap_or(MotionClass::Floater),
                population: args.population,
                generations: args.generations,
                seed: args.seed,
                seconds: args.seconds,
                archive: args.archive,
                releases: args.releases,
                strategy: args.strategy.into(),
                ..BreedSettings::default_run()
            };
            // Keep elites at a tenth of the population (at least one).
            let settings = BreedSettings {
                elites: (settings.population / 10).max(1),
                target: like
                    .as_ref()
                    .and_then(|t| t.class)
                    .unwrap_or(settings.target),
                like,
                ..settings
            };
            let settings = match &from {
                None => settings,
                Some(from) => {
                    let proto = LeafSpec::load(&settings.prototype)?;
                    let start = breed::start_leaves(from, &proto)?;
                    let settings = BreedSettings {
                        start: start.genomes,
                        ..settings
                    };
                    let places = breed::selection::initial_copies(&settings);
                    eprintln!(
                        "leafmagic: --start-from {}: {} of generation 0's {} leaves from {}",
                        from.dir.display(),
                        settings.start.len().min(places),
                        settings.population,
                        start.source
                    );
                    settings
                }
            };
            settings.validate()?;
            let dir = args
                .out
                .clone()
                .unwrap_or_else(|| default_run_dir(&settings, args.law.is_some()));
            let run = match example {
                Some(example) => {
                    Run::create_like(&dir, settings, args.max_work, example.trajectory)?
                }
                None => Run::create_within(&dir, settings, args.max_work)?,
            };
            // A breed prints nothing until its first generation is done:
            // one that will take minutes says so before it starts.
            let work = run.work()?;
            if work.core_seconds() > BREED_NOTE_SECONDS {
                eprintln!("{}", super::progress::note(&work, "breed"));
            }
            run
        }
    };
    if args.create_only {
        println!("{}", report::breed::run_directory(&run.dir));
        return Ok(());
    }
    let executor = executor(&args)?;
    // A driver only waits and merges (and estimates the prototype's error
    // beside generation 0): two threads are plenty.
    let threads = match args.executor {
        ExecutorKind::Local => args.threads.unwrap_or(0),
        _ => 2,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("cannot start the worker threads")?;
    let bar = Bar::new();
    pool.install(|| run.run_with(executor.as_ref(), &bar))?;
    print!(
        "{}",
        report::breed::generations(run.history(), run.settings().like.is_some())
    );
    let law = run.proto.aero.law;
    println!("law: {} ({} aerodynamics)", law_word(law), law.as_str());
    if let Some(target) = &run.settings().like {
        print_like(&run, target)?;
    }
    println!("{}", report::breed::run_directory(&run.dir));
    Ok(())
}

/// A new breed estimated to take longer than this (s of one core, every
/// drop of every generation) says so before it starts.
const BREED_NOTE_SECONDS: f64 = 60.0;

/// The example's (or the target's) descriptors beside the best leaf's.
fn print_like(run: &Run, target: &MotionTarget) -> Result<()> {
    let Some(cp) = &run.checkpoint else {
        return Ok(());
    };
    let best = breed::selection::rank(&cp.population)[0];
    let fall = run.best_fall(best)?;
    let chord = best.genome.model(&run.proto)?.chord();
    let c = classify::classify(&fall, chord);
    let Ok(best_d) = Descriptors::of(&c) else {
        println!("{}", report::breed::undescribed_best(best.id));
        return Ok(());
    };
    let reference = match run.example() {
        Some(example) => {
            let size = target.size_m.unwrap_or(chord);
            Descriptors::of(&classify::classify(&example, size))
                .map(|ex| ("example", ex))
                .map_err(|e| anyhow::anyhow!("example: {e}"))
        }
        None => Ok(("target", target_descriptors(target, &best_d))),
    };
    // The report's blank line comes first: an example that cannot be
    // described is an error after it.
    println!();
    let (name, reference) = reference?;
    print!(
        "{}",
        report::breed::like((name, &reference), (best.id, &best_d), best.eval.distance)
    );
    Ok(())
}

/// The target of `--target-features` as a column beside the best leaf's:
/// its descriptors (NaN where free), its class or else the best's.
fn target_descriptors(target: &MotionTarget, best: &Descriptors) -> Descriptors {
    let mut wanted = best.clone();
    for (k, name) in describe::NAMES.iter().enumerate() {
        wanted.values[k] = target.descriptors.get(*name).copied().unwrap_or(f64::NAN);
    }
    wanted.class = target.class.unwrap_or(best.class);
    wanted
}

/// The cores of this machine (1 if unknown).
fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The executor `breed` asked for, with its defaults filled in.
fn executor(args: &BreedArgs) -> Result<Box<dyn Executor>> {
    use leafmagic::breed::executor::{Local, Processes, Slurm, SlurmMode, slurm_mode_from_env};
    if args.shards == Some(0) {
        bail!("--shards must be at least 1");
    }
    if args.threads == Some(0) && args.executor != ExecutorKind::Local {
        bail!("--threads must be at least 1");
    }
    let program =
        || std::env::current_exe().context("cannot find the leafmagic binary to start shards");
    Ok(match args.executor {
        ExecutorKind::Local => {
            if args.shards.is_some() {
                bail!("--shards needs --executor processes or slurm");
            }
            Box::new(Local)
        }
        ExecutorKind::Processes => {
            let shards = args.shards.unwrap_or_else(cores);
            Box::new(Processes {
                program: program()?,
                shards,
                // Share the cores between the shards.
                threads: args.threads.unwrap_or((cores() / shards).max(1)),
            })
        }
        ExecutorKind::Slurm => {
            let mode = slurm_mode_from_env();
            let shards = match (args.shards, mode) {
                (Some(n), _) => n,
                (None, SlurmMode::Step { allocated: Some(n) }) => n,
                (None, _) => bail!(
                    "--executor slurm outside an allocation (no SLURM_JOB_ID, SLURM_NTASKS) needs --shards"
                ),
            };
            Box::new(Slurm {
                program: program()?,
                shards,
                threads: args.threads.unwrap_or(1),
                mode,
            })
        }
    })
}

/// `shard`: evaluates one shard of a generation and writes its shard file.
pub fn shard(args: ShardArgs) -> Result<()> {
    let split = breed::shard::resolve_split(args.index, args.count, |k| std::env::var(k).ok())?;
    let threads = match args.threads {
        Some(t) => t,
        None => std::env::var("SLURM_CPUS_PER_TASK")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(0),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("cannot start the worker threads")?;
    let start = Instant::now();
    let outcome = pool
        .install(|| breed::worker::run_shard(&args.run, args.generation, split, args.skip_done))?;
    println!(
        "{}",
        report::breed::shard(
            args.generation,
            (split.index, split.count),
            &outcome,
            start.elapsed().as_secs_f64()
        )
    );
    Ok(())
}

/// `merge`: merges a generation's shard files into the run, as `breed`
/// would have.
pub fn merge(args: MergeArgs) -> Result<()> {
    if args.count == 0 {
        bail!("--count must be at least 1");
    }
    let mut run = Run::open(&args.run)?;
    let next = run.checkpoint.as_ref().map_or(0, |c| c.generation + 1);
    if args.generation < next {
        println!(
            "{}",
            report::breed::already_merged(args.generation, next - 1)
        );
        return Ok(());
    }
    if args.generation > next || run.is_complete() {
        bail!(
            "{}: generation {} cannot be merged: the next generation is {next} of {}",
            args.run.display(),
            args.generation,
            run.settings().generations
        );
    }
    let merge = breed::executor::Merge { shards: args.count };
    // Two threads: the prototype's error estimate (generation 0) and the merge.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .context("cannot start the worker threads")?;
    pool.install(|| run.step_with(&merge, &breed::Quiet))?;
    if run.is_complete() {
        run.write_best()?;
    }
    let history = run.history();
    print!(
        "{}",
        report::breed::generations(&history[history.len() - 1..], run.settings().like.is_some())
    );
    println!(
        "{}",
        report::breed::merged(&run.dir, args.generation, run.is_complete())
    );
    Ok(())
}

/// The default run directory,
/// `runs/<prototype>-<aim>-s<seed>-n<population>-g<generations>`, the aim
/// being the target class, `like-<example>` or `[<class>-]features`; a
/// `--law` given names itself after the prototype (`a-real-floater-…`), so
/// the same breed under each law has its own directory.
fn default_run_dir(s: &BreedSettings, law_given: bool) -> PathBuf {
    let stem = |p: &str| {
        std::path::Path::new(p)
            .file_stem()
            .map_or_else(|| p.to_string(), |f| f.to_string_lossy().into_owned())
    };
    let aim = match &s.like {
        None => s.target.to_string(),
        Some(t) if t.source == "features" => match t.class {
            Some(c) => format!("{c}-features"),
            None => "features".to_string(),
        },
        Some(t) => format!("like-{}", stem(&t.source)),
    };
    let law = match s.law {
        Some(law) if law_given => format!("-{}", law_word(law)),
        _ => String::new(),
    };
    PathBuf::from("runs").join(format!(
        "{}{law}-{aim}-s{}-n{}-g{}",
        stem(&s.prototype),
        s.seed,
        s.population,
        s.generations
    ))
}

/// The prototype to breed from and the motion target: `--prototype auto`
/// chooses from the target's class ([`breed::auto::choose`]) and says which
/// and why on stderr. An example without `--size` is described at the
/// chosen prototype's chord (at A's to choose, then again if B is chosen).
/// Started `from` an earlier run, `auto` is that run's prototype.
fn choose_prototype(
    args: &BreedArgs,
    from: Option<&Run>,
    example: Option<&input::Record>,
) -> Result<(String, Option<MotionTarget>)> {
    if let (Some(from), true) = (from, args.prototype == breed::auto::AUTO) {
        let name = from.settings().prototype.clone();
        eprintln!(
            "leafmagic: --prototype auto: {name} (the prototype of the run started from, {})",
            from.dir.display()
        );
        return Ok((name.clone(), motion_target(args, &name, example)?));
    }
    if args.prototype != breed::auto::AUTO {
        return Ok((
            args.prototype.clone(),
            motion_target(args, &args.prototype, example)?,
        ));
    }
    let first = motion_target(args, "a", example)?;
    let (class, regime) = match &first {
        Some(t) => (t.class, t.regime),
        None => (Some(args.target.unwrap_or(MotionClass::Floater)), None),
    };
    let (name, why) = breed::auto::choose(class, regime);
    eprintln!("leafmagic: --prototype auto: {name} ({why})");
    let like = if name == "a" || given_size(args, example).is_some() {
        first
    } else {
        motion_target(args, name, example)?
    };
    Ok((name.to_string(), like))
}

/// The example's chord when something gives it: `--size`, else an
/// animation's own mesh; else it is described at the prototype's.
fn given_size(args: &BreedArgs, example: Option<&input::Record>) -> Option<f64> {
    args.size.or(example.and_then(|e| e.chord))
}

/// The motion target of `breed --like` / `--target-features`, checked
/// before anything is bred or written. The example is described at
/// `--size`, else at its own chord (an animation's mesh), else at the
/// prototype's chord.
fn motion_target(
    args: &BreedArgs,
    prototype: &str,
    example: Option<&input::Record>,
) -> Result<Option<MotionTarget>> {
    if let (Some(path), Some(record)) = (&args.like, example) {
        input::check_size(args.size)?;
        let size = match given_size(args, example) {
            Some(s) => s,
            None => LeafSpec::load_with_model(prototype)?.1.chord(),
        };
        let c = classify::classify(&record.trajectory, size);
        let described = input::describe(path, &c)?;
        return Ok(Some(MotionTarget::like(
            &path.to_string_lossy(),
            size,
            &described,
        )));
    }
    match &args.target_features {
        Some(text) => Ok(Some(MotionTarget::parse_features(text, args.target)?)),
        None => Ok(None),
    }
}
