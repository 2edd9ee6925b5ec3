//! The command line (clap derive): parsing and the thin glue from arguments
//! to library calls. Everything that computes lives in the library.

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use leafmagic::breed::{self, BreedSettings, GenerationSummary, Run};
use leafmagic::leaf::LeafSpec;
use leafmagic::motion::classify::{self, Classification, MotionClass};
use leafmagic::motion::describe::{self, Descriptors, MotionTarget};
use leafmagic::motion::trajectory::Trajectory;
use leafmagic::physics::model::Model;
use leafmagic::physics::params::Integrator;
use leafmagic::physics::params::TimeStep;
use leafmagic::physics::run;
use leafmagic::physics::stability;
use leafmagic::physics::state::State;
use leafmagic::sim::accuracy::{self, SweepSettings, long::LongSettings};
use leafmagic::sim::drop::{self, DropParams};
use leafmagic::sim::scene::{self, Scene};
use leafmagic::sim::stress::{self, ExplicitPolicy, Outcome};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

/// Breed falling-leaf motion in a mass-spring simulator with potential-flow wind.
#[derive(Parser, Debug)]
#[command(name = "leafmagic", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Breed leaf variants toward a motion class (the paper's section 4.1, automated).
    Breed(BreedArgs),
    /// Write chosen leaves of a breeding run as leaf files.
    Export(ExportArgs),
    /// Drop a leaf from rest in still air and record its fall.
    Drop(DropArgs),
    /// Report the stable time step of a leaf for each integrator, with warnings.
    Check(CheckArgs),
    /// Name the motion of a recorded fall (pose CSV t,x,y,z,qw,qx,qy,qz).
    Classify(ClassifyArgs),
    /// Error against cost of every integrator over a sweep of time steps
    /// (work-precision), or with --long, classes and statistics across steps.
    Accuracy(AccuracyArgs),
    /// Run a scene file and write per-object trajectories and a summary.
    Scene(SceneArgs),
    /// Motion descriptors of two falls side by side, and their distance.
    Compare(CompareArgs),
    /// Write one self-contained HTML page that plays a breeding run's best
    /// leaves, a scene's output or a .glb file in 3-D (works offline).
    Preview(PreviewArgs),
    /// Evaluate one shard of a generation of a breeding run and write its shard file
    /// (what `breed --executor processes|slurm` starts; see the README, "Beyond one machine").
    Shard(ShardArgs),
    /// Merge the shard files of a generation that something else evaluated (a Kubernetes
    /// Indexed Job, a Slurm array) into the run: its files and checkpoint, as breed would.
    Merge(MergeArgs),
}

/// Arguments of `preview`.
#[derive(clap::Args, Debug)]
pub struct PreviewArgs {
    /// A breeding run directory, a scene output directory or a .glb file.
    pub input: PathBuf,
    /// The HTML file to write [default: INPUT/preview.html for a directory, INPUT with .html for a file].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// For a breeding run: show the K best leaves of the last generation.
    #[arg(long, default_value_t = 5)]
    pub top: usize,
    /// Frames per second of the embedded motion [default: 30, or the .glb's own].
    #[arg(long)]
    pub fps: Option<f64>,
}

/// Arguments of `merge`.
#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// A breeding run directory.
    pub run: PathBuf,
    /// The generation whose shards to merge (the one after the checkpoint's).
    #[arg(long)]
    pub generation: usize,
    /// Shards in the generation.
    #[arg(long)]
    pub count: usize,
}

/// Who evaluates each generation of `breed`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExecutorKind {
    /// This process's thread pool.
    Local,
    /// `--shards` child processes (`leafmagic shard`) on this machine.
    Processes,
    /// Slurm: one `srun` step per generation inside an allocation (sbatch/salloc the driver),
    /// else one `sbatch --wait --array` per generation.
    Slurm,
}

/// Arguments of `shard`.
#[derive(clap::Args, Debug)]
pub struct ShardArgs {
    /// A breeding run directory (run.toml, and checkpoint.json after generation 0).
    pub run: PathBuf,
    /// The generation to evaluate: the one after the checkpoint's.
    #[arg(long)]
    pub generation: usize,
    /// This shard's index, from 0 [default: from SLURM_PROCID, SLURM_ARRAY_TASK_ID,
    /// JOB_COMPLETION_INDEX or AWS_BATCH_JOB_ARRAY_INDEX].
    #[arg(long, requires = "count")]
    pub index: Option<usize>,
    /// Shards in the generation [default: SLURM_NTASKS or SLURM_ARRAY_TASK_COUNT].
    #[arg(long)]
    pub count: Option<usize>,
    /// Worker threads (default: SLURM_CPUS_PER_TASK, else all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Do nothing if a valid shard file is already there (a rerun keeps finished work).
    #[arg(long)]
    pub skip_done: bool,
}

/// Arguments of `accuracy`.
#[derive(clap::Args, Debug)]
pub struct AccuracyArgs {
    /// Leaf file (TOML), or `a` / `b` for the embedded prototypes.
    #[arg(default_value = "a")]
    pub leaf: String,
    /// Simulated seconds T [default: 1, or 10 with --long].
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Directory for accuracy.csv and accuracy.svg (accuracy-long.csv with --long); created if missing.
    #[arg(long, default_value = ".")]
    pub out: PathBuf,
    /// Compare motion classes and statistics (descent speed, rotation rate) across steps for a long fall.
    #[arg(long)]
    pub long: bool,
    /// Timed runs per point (the median is reported; at least 5 for published figures).
    #[arg(long, default_value_t = leafmagic::sim::accuracy::DEFAULT_RUNS)]
    pub runs: usize,
    /// Use RK4 at T/2^J as the reference instead of the default (it is validated either way).
    #[arg(long, value_name = "J")]
    pub reference_j: Option<u32>,
}

/// Arguments of `breed`.
#[derive(clap::Args, Debug)]
pub struct BreedArgs {
    /// Prototype: `a`, `b` (embedded) or a leaf file.
    #[arg(long, default_value = "a")]
    pub prototype: String,
    /// Motion class to breed toward: floater, spinner or lilter [default: floater; with
    /// --target-features, none: any class may come close].
    #[arg(long)]
    pub target: Option<MotionClass>,
    /// Individuals per generation.
    #[arg(long, default_value_t = 100)]
    pub population: usize,
    /// Generations in all (generation 0, the prototype's varied copies, counts).
    #[arg(long, default_value_t = 8)]
    pub generations: usize,
    /// Seed of every random stream (same seed, same bytes).
    #[arg(long, default_value_t = 1991)]
    pub seed: u64,
    /// Simulated seconds of each drop.
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Run directory (default: runs/<prototype>-<target>-s<seed>-n<population>-g<generations>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Keep a MAP-Elites archive: the best leaf per cell of descent speed × rotation rate.
    #[arg(long)]
    pub archive: bool,
    /// Breed toward the motion of this fall (pose CSV t,x,y,z,qw,qx,qy,qz): its class and
    /// descriptors (descent, spin, tumble, flips, reversals, drift, period, spreads).
    #[arg(long, value_name = "TRAJ.csv", conflicts_with_all = ["target", "target_features"])]
    pub like: Option<PathBuf>,
    /// The example's chord, metres, for --like [default: the prototype's chord].
    #[arg(long, requires = "like")]
    pub size: Option<f64>,
    /// Breed toward descriptors given in SI units, e.g. `descent=0.6,spin=20` (m/s, rad/s;
    /// unset ones are free), within the class of --target if given (else any class).
    #[arg(long, value_name = "NAME=VALUE,...")]
    pub target_features: Option<String>,
    /// Who evaluates each generation (the run's files are the same bytes with any).
    #[arg(long, value_enum, default_value_t = ExecutorKind::Local)]
    pub executor: ExecutorKind,
    /// Shards per generation with --executor processes (default: the cores) or slurm
    /// (default: SLURM_NTASKS of the allocation). --threads is then per shard.
    #[arg(long)]
    pub shards: Option<usize>,
    /// Write the run directory (run.toml) and stop: the generations are then evaluated by
    /// `leafmagic shard` tasks and merged with `leafmagic merge` (Kubernetes, hand-run arrays).
    #[arg(long, conflicts_with_all = ["resume", "executor", "shards", "threads"])]
    pub create_only: bool,
    /// Finish the run in this directory (after a kill, or to extend nothing: a complete run just reports).
    #[arg(long, conflicts_with_all = ["prototype", "target", "population", "generations", "seed", "seconds", "out", "archive", "like", "size", "target_features"])]
    pub resume: Option<PathBuf>,
}

/// Arguments of `compare`.
#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    /// First fall (pose CSV t,x,y,z,qw,qx,qy,qz).
    pub a: PathBuf,
    /// Second fall.
    pub b: PathBuf,
    /// The leaves' chord, metres (both falls).
    #[arg(long, default_value_t = 0.05)]
    pub size: f64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `export`.
#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// A breeding run directory.
    pub run: PathBuf,
    /// Export the K best of the last generation.
    #[arg(long, conflicts_with = "ids")]
    pub top: Option<usize>,
    /// Export these individuals of the last generation (comma-separated ids).
    #[arg(long, value_delimiter = ',')]
    pub ids: Option<Vec<u64>>,
    /// Output directory for the leaf files and index.csv.
    #[arg(long)]
    pub out: PathBuf,
    /// Also re-drop each leaf as breeding dropped it and write its fall:
    /// `glb` (leaf-<id>.glb) or `pc2` (leaf-<id>.pc2 + leaf-<id>.obj).
    #[arg(long)]
    pub format: Option<leafmagic::output::export::Format>,
    /// Frames per second of the exported motion.
    #[arg(long, default_value_t = leafmagic::output::export::DEFAULT_FPS)]
    pub fps: f64,
}

/// Arguments of `scene`.
#[derive(clap::Args, Debug)]
pub struct SceneArgs {
    /// Scene file (TOML, see scenes/README.md).
    pub file: PathBuf,
    /// Output directory (default runs/scene-<name>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Simulated seconds (default: the scene's duration).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// List what the compiled scene keeps and leaves out, then stop.
    #[arg(long)]
    pub explain: bool,
    /// Also export the run: `glb` (DIR/<scene>.glb) or `pc2` (DIR/<object>.pc2 + .obj).
    #[arg(long)]
    pub export: Option<leafmagic::output::export::Format>,
    /// Frames per second of the exported motion.
    #[arg(long, default_value_t = leafmagic::output::export::DEFAULT_FPS)]
    pub export_fps: f64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `classify`.
#[derive(clap::Args, Debug)]
pub struct ClassifyArgs {
    /// Trajectory CSV: t,x,y,z,qw,qx,qy,qz (z up, quaternion body to world, w first).
    pub trajectory: PathBuf,
    /// The leaf's chord (longest extent), metres; sets the length scale of the tests.
    #[arg(long, default_value_t = 0.05)]
    pub size: f64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `drop`.
#[derive(clap::Args, Debug)]
pub struct DropArgs {
    /// Leaf file (TOML), or `a` / `b` for the embedded prototypes.
    pub leaf: String,
    /// Time integrator.
    #[arg(long, default_value = "verlet")]
    pub integrator: Integrator,
    /// Time step in seconds, or `auto` (from the stability estimate).
    #[arg(long, default_value = "auto", value_parser = parse_dt)]
    pub dt: TimeStep,
    /// Simulated seconds.
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
    /// Release tilt about the leaf's x and y axes, degrees.
    #[arg(long, default_value = "10,2", value_parser = parse_tilt)]
    pub tilt: [f64; 2],
    /// Write the trajectory (t,x,y,z,qw,qx,qy,qz at 240 Hz) to this CSV file.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also write every particle's position per frame to this CSV file.
    #[arg(long)]
    pub particles: Option<PathBuf>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `check`.
#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// Leaf file (TOML), or `a` / `b` for the embedded prototypes.
    pub leaf: String,
    /// Print JSON instead of a table (with --stress: an array of one object per row).
    #[arg(long)]
    pub json: bool,
    /// Run the stiff and extreme matrix: every stress case with every integrator.
    #[arg(long)]
    pub stress: bool,
    /// With --stress: what explicit integrators do with a step above their stable estimate.
    #[arg(long, default_value = "substep", value_parser = parse_policy)]
    pub explicit: ExplicitPolicy,
    /// With --stress --explicit substep: the most sub-steps per step (a warning says when it clamps).
    #[arg(long, default_value_t = stress::DEFAULT_SUBSTEP_CAP)]
    pub substep_cap: u64,
}

fn parse_policy(s: &str) -> Result<ExplicitPolicy, String> {
    s.parse()
}

fn parse_dt(s: &str) -> Result<TimeStep, String> {
    if s == "auto" {
        return Ok(TimeStep::Auto);
    }
    let h: f64 = s
        .parse()
        .map_err(|_| format!("expected a number of seconds or 'auto', got '{s}'"))?;
    if h > 0.0 && h.is_finite() {
        Ok(TimeStep::Fixed(h))
    } else {
        Err(format!(
            "the time step must be a positive number of seconds, got {s}"
        ))
    }
}

fn parse_tilt(s: &str) -> Result<[f64; 2], String> {
    let parts: Vec<&str> = s.split(',').collect();
    let parse = |p: &str| {
        p.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("expected degrees as 'X,Y', got '{s}'"))
    };
    match parts.as_slice() {
        [x] => Ok([parse(x)?, 0.0]),
        [x, y] => Ok([parse(x)?, parse(y)?]),
        _ => Err(format!("expected degrees as 'X,Y', got '{s}'")),
    }
}

/// Runs the parsed command.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Breed(args) => breed(args),
        Command::Export(args) => export(args),
        Command::Drop(args) => drop(args),
        Command::Check(args) => check(args),
        Command::Classify(args) => classify(args),
        Command::Accuracy(args) => accuracy(args),
        Command::Scene(args) => run_scene(args),
        Command::Compare(args) => compare(args),
        Command::Preview(args) => preview(args),
        Command::Shard(args) => shard(args),
        Command::Merge(args) => merge(args),
    }
}

fn run_scene(args: SceneArgs) -> Result<()> {
    let scene = Scene::load(&args.file)?;
    let decisions = scene.explain();
    let frame = 1.0 / scene.frame_rate;
    if args.explain {
        let dt = run::resolve_dt(&scene.model, scene.integrator, scene.dt, frame);
        if args.json {
            let out = json!({
                "scene": scene.name,
                "particles": scene.model.len(),
                "springs": scene.model.springs.len(),
                "triangles": scene.model.triangles.len(),
                "hinges": scene.model.hinges.len(),
                "rigid_bodies": scene.model.rigid.len(),
                "integrator": scene.integrator,
                "dt": dt.as_ref().ok(),
                "kept": decisions.iter().filter(|d| d.kept).map(|d| json!({"term": d.name, "reason": d.reason})).collect::<Vec<_>>(),
                "left_out": decisions.iter().filter(|d| !d.kept).map(|d| json!({"term": d.name, "reason": d.reason})).collect::<Vec<_>>(),
                "pruned": scene.pruned,
            });
            println!("{}", serde_json::to_string_pretty(&out)?);
            return Ok(());
        }
        println!(
            "scene       {} ({}): {} objects, {} particles, {} springs, {} triangles, {} hinges, {} rigid bodies",
            scene.name,
            scene.source,
            scene.objects.len(),
            scene.model.len(),
            scene.model.springs.len(),
            scene.model.triangles.len(),
            scene.model.hinges.len(),
            scene.model.rigid.len()
        );
        match dt {
            Ok(dt) => println!("integrator  {} (dt = {dt:.4e} s)", scene.integrator),
            Err(e) => println!("integrator  {} ({e})", scene.integrator),
        }
        for d in &decisions {
            let verdict = if d.kept { "kept" } else { "left out" };
            println!("{verdict:<11} {:<29} {}", d.name, d.reason);
        }
        for p in &scene.pruned {
            println!("{:<11} {p}", "pruned");
        }
        return Ok(());
    }
    let run = scene
        .run(args.seconds)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.file.display()))?;
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| scene::default_out_dir(&scene));
    let written = run
        .write(&scene, &dir)
        .with_context(|| format!("cannot write to {}", dir.display()))?;
    let mut written = written;
    let mut export_note = None;
    if let Some(format) = args.export {
        let started = Instant::now();
        let clip = leafmagic::output::export::from_scene_run(&scene, &run, args.export_fps)?;
        let files = write_clip(&clip, format, &dir, &scene.name)?;
        let bytes: u64 = files
            .iter()
            .filter_map(|f| std::fs::metadata(f).ok())
            .map(|m| m.len())
            .sum();
        export_note = Some(format!(
            "{format}: {} files, {:.2} MB, {} frames at {} fps, in {:.3} s",
            files.len(),
            bytes as f64 / 1e6,
            clip.frames,
            clip.fps,
            started.elapsed().as_secs_f64()
        ));
        written.extend(files);
    }
    let s = &run.stats;
    if args.json {
        let out = json!({
            "scene": scene.name,
            "stats": s,
            "wall_s": s.wall_s,
            "wall_per_simulated_s": s.wall_s / s.simulated_s,
            "out": dir,
            "export": export_note,
            "files": written,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!(
        "scene           {} ({} objects, {} particles)",
        scene.name,
        scene.objects.len(),
        scene.model.len()
    );
    println!(
        "integrator      {} (dt = {:.4e} s, {} steps, {} force evaluations)",
        s.integrator, s.dt, s.steps, s.force_evaluations
    );
    println!(
        "simulated       {:.3} s in {:.4} s wall ({:.2e} wall s per simulated s)",
        s.simulated_s,
        s.wall_s,
        s.wall_s / s.simulated_s
    );
    println!(
        "events          {} ground contacts resolved, {} springs broken",
        s.contacts_resolved, s.broken_springs
    );
    println!(
        "output          {} ({} files)",
        dir.display(),
        written.len()
    );
    if let Some(note) = export_note {
        println!("export          {note}");
    }
    Ok(())
}

fn drop(args: DropArgs) -> Result<()> {
    let spec = LeafSpec::load(&args.leaf)?;
    let model = spec
        .model()
        .with_context(|| format!("{}: invalid leaf", args.leaf))?;
    if !(args.seconds > 0.0 && args.seconds.is_finite()) {
        bail!("--seconds must be a positive number, got {}", args.seconds);
    }
    let params = DropParams {
        integrator: args.integrator,
        dt: args.dt,
        seconds: args.seconds,
        tilt_deg: args.tilt,
        record_particles: args.particles.is_some(),
    };
    if let TimeStep::Fixed(h) = args.dt {
        if let Some(limit) = stability::estimate(&model).dt_max(args.integrator) {
            if h > limit {
                eprintln!(
                    "warning: dt = {h:.3e} s exceeds the estimated stable step of {} ({limit:.3e} s); \
                     the run will likely diverge",
                    args.integrator
                );
            }
        }
    }
    let result =
        drop::drop_leaf(&model, &params).map_err(|e| anyhow::anyhow!("{}: {e}", args.leaf))?;
    if let Some(path) = &args.out {
        result
            .trajectory
            .write_csv(path)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if let (Some(path), Some(frames)) = (&args.particles, &result.particles) {
        let bytes = leafmagic::util::io::particle_csv(&result.trajectory.time, frames);
        leafmagic::util::io::write_atomic(path, &bytes)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    let stats = &result.stats;
    let chord = model.chord();
    let class = classify::classify(&result.trajectory, chord);
    if args.json {
        let out = json!({
            "leaf": spec.name,
            "integrator": stats.integrator,
            "dt": stats.dt,
            "steps": stats.steps,
            "simulated_s": stats.simulated_s,
            "wall_s": stats.wall_s,
            "force_evals": stats.force_evals,
            "broken_springs": stats.broken_springs,
            "chord_m": chord,
            "class": class.class,
            "regime": class.regime,
            "reason": class.reason,
            "features": class.features,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        println!(
            "leaf            {} (chord {:.4} m, {:.3e} kg)",
            spec.name,
            chord,
            model.total_mass()
        );
        println!(
            "integrator      {} (dt = {:.4e} s, {} steps, {} force evaluations)",
            stats.integrator, stats.dt, stats.steps, stats.force_evals
        );
        println!(
            "simulated       {:.3} s in {:.4} s wall ({:.2e} wall s per simulated s)",
            stats.simulated_s,
            stats.wall_s,
            stats.wall_s / stats.simulated_s
        );
        print_class(&class);
        if let Some(path) = &args.out {
            println!("trajectory      {}", path.display());
        }
    }
    Ok(())
}

fn print_class(c: &Classification) {
    let f = &c.features;
    println!("class           {} ({})", c.class, c.regime);
    if let Some(reason) = &c.reason {
        println!("reason          {reason}");
    }
    println!(
        "descent         {:.3} m/s mean, drift ratio {:.2}, {:.1} chords in the window {:.2}–{:.2} s",
        f.mean_descent_speed_m_s, f.drift_ratio, f.descent_chords, f.t_start_s, f.t_end_s
    );
    println!(
        "rotation        {:.2} net turns, {} reversals, {} flips, {:.2} yaw turns, tilt {:.1}° ± {:.1}°",
        f.net_turns, f.reversals, f.normal_flips, f.yaw_turns, f.tilt_mean_deg, f.tilt_std_deg
    );
}

fn classify(args: ClassifyArgs) -> Result<()> {
    let (traj, c) = classify_file(&args.trajectory, args.size)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&c)?);
    } else {
        println!(
            "trajectory      {} ({} samples)",
            args.trajectory.display(),
            traj.len()
        );
        print_class(&c);
    }
    Ok(())
}

fn check(args: CheckArgs) -> Result<()> {
    if args.stress {
        return check_stress(args);
    }
    let spec = LeafSpec::load(&args.leaf)?;
    let model = spec
        .model()
        .with_context(|| format!("{}: invalid leaf", args.leaf))?;
    let est = stability::estimate(&model);
    let frame = 1.0 / drop::FRAME_RATE;
    let rows: Vec<_> = Integrator::ALL
        .iter()
        .map(|&i| {
            (
                i,
                est.dt_max(i),
                est.auto_step(i, frame),
                est.auto_dt(i, frame),
            )
        })
        .collect();
    if args.json {
        let per: serde_json::Map<String, serde_json::Value> = rows
            .iter()
            .map(|(i, m, a, snapped)| {
                (
                    i.name().to_string(),
                    json!({ "dt_max": m, "dt_auto": a, "dt_auto_frame_divisor": snapped }),
                )
            })
            .collect();
        let out = json!({
            "leaf": spec.name,
            "omega_max": est.omega_max,
            "omega_bounds": [est.omega_lower, est.omega_upper],
            "power_iteration_converged": est.power_converged,
            "zeta": est.zeta,
            "drag_rate": est.drag_rate,
            "drag_time_constant": est.drag_time_constant(),
            "stiffest_spring": est.stiffest_spring,
            "lightest_particle": est.lightest_particle,
            "lightest_mass": model.mass[est.lightest_particle],
            "mass_ratio": est.mass_ratio,
            "integrators": per,
            "warnings": est.warnings,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!(
        "leaf               {} ({} particles, {} springs, {} triangles)",
        spec.name,
        model.len(),
        model.springs.len(),
        model.triangles.len()
    );
    println!(
        "stiffest mode      ω_max = {:.1} rad/s (bounds {:.1} … {:.1}; power iteration {}), ζ = {:.3}",
        est.omega_max,
        est.omega_lower,
        est.omega_upper,
        if est.power_converged {
            "converged"
        } else {
            "not converged, margin applied"
        },
        est.zeta
    );
    if let Some(s) = est.stiffest_spring {
        let sp = &model.springs[s];
        println!(
            "stiffest spring    {s} (particles {}–{}, k = {} N/m)",
            sp.i, sp.j, sp.stiffness
        );
    }
    println!(
        "lightest particle  {} ({:.3e} kg; heaviest/lightest = {:.1})",
        est.lightest_particle, model.mass[est.lightest_particle], est.mass_ratio
    );
    println!(
        "drag time const.   {:.4} s (γ_max = {:.2} 1/s)",
        est.drag_time_constant(),
        est.drag_rate
    );
    println!();
    // Drops interpolate their frames and take the auto step as it is;
    // scenes step onto every frame and take the largest divisor below it.
    println!(
        "{:<12} {:>14} {:>14} {:>14}",
        "integrator", "dt_max (s)", "drop auto (s)", "scene auto (s)"
    );
    for (i, m, a, snapped) in rows {
        let m = match m {
            None => "unbounded".to_string(),
            Some(v) if v <= 0.0 => "unstable".to_string(),
            Some(v) => format!("{v:.4e}"),
        };
        let a = a.map_or("none".to_string(), |v| format!("{v:.4e}"));
        let snapped = snapped.map_or("none".to_string(), |v| format!("{v:.4e}"));
        println!("{:<12} {:>14} {:>14} {:>14}", i.name(), m, a, snapped);
    }
    for w in &est.warnings {
        println!("warning: {w}");
    }
    Ok(())
}

/// A progress bar per generation on a terminal; nothing when piped.
struct Bar {
    bar: Option<indicatif::ProgressBar>,
    counts: [std::sync::atomic::AtomicUsize; 5],
    best: std::sync::Mutex<f64>,
}

impl Bar {
    fn new() -> Bar {
        use std::io::IsTerminal;
        Bar {
            bar: std::io::stderr()
                .is_terminal()
                .then(indicatif::ProgressBar::hidden),
            counts: Default::default(),
            best: std::sync::Mutex::new(f64::NEG_INFINITY),
        }
    }
}

impl breed::Progress for Bar {
    fn start_generation(&self, generation: usize, size: usize) {
        for c in &self.counts {
            c.store(0, std::sync::atomic::Ordering::Relaxed);
        }
        *self.best.lock().expect("progress lock") = f64::NEG_INFINITY;
        if let Some(bar) = &self.bar {
            bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
            bar.reset();
            bar.set_length(size as u64);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "gen {prefix:>3} [{bar:30}] {pos}/{len} {msg} ({elapsed})",
                )
                .expect("valid template")
                .progress_chars("=> "),
            );
            bar.set_prefix(generation.to_string());
        }
    }

    fn individual_done(&self, class: &str, score: f64) {
        use std::sync::atomic::Ordering::Relaxed;
        let k = ["floater", "spinner", "lilter", "undetermined", "diverged"]
            .iter()
            .position(|c| *c == class)
            .unwrap_or(3);
        self.counts[k].fetch_add(1, Relaxed);
        let best = {
            let mut b = self.best.lock().expect("progress lock");
            *b = b.max(score);
            *b
        };
        if let Some(bar) = &self.bar {
            let c: Vec<usize> = self.counts.iter().map(|c| c.load(Relaxed)).collect();
            bar.set_message(format!(
                "F{} S{} L{} U{} D{} best {best:.3}",
                c[0], c[1], c[2], c[3], c[4]
            ));
            bar.inc(1);
        }
    }

    fn finish_generation(&self, _: &GenerationSummary) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

fn default_run_dir(s: &BreedSettings) -> PathBuf {
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
    PathBuf::from("runs").join(format!(
        "{}-{aim}-s{}-n{}-g{}",
        stem(&s.prototype),
        s.seed,
        s.population,
        s.generations
    ))
}

/// Reads and classifies a recorded fall of a leaf of chord `size`.
fn classify_file(path: &std::path::Path, size: f64) -> Result<(Trajectory, Classification)> {
    if !(size > 0.0 && size.is_finite()) {
        bail!("--size must be a positive number of metres, got {size}");
    }
    let traj = Trajectory::read_csv(path)?;
    let c = classify::classify(&traj, size);
    Ok((traj, c))
}

/// Reads and describes a fall, or says why it cannot be described.
fn describe_file(path: &std::path::Path, size: f64) -> Result<Descriptors> {
    let (_, c) = classify_file(path, size)?;
    Descriptors::of(&c).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

/// The motion target of `breed --like` / `--target-features`, checked
/// before anything is bred or written.
fn motion_target(args: &BreedArgs) -> Result<Option<MotionTarget>> {
    if let Some(path) = &args.like {
        let size = match args.size {
            Some(s) => s,
            None => LeafSpec::load(&args.prototype)?.model()?.chord(),
        };
        let example = describe_file(path, size)?;
        return Ok(Some(MotionTarget::like(
            &path.to_string_lossy(),
            size,
            &example,
        )));
    }
    match &args.target_features {
        Some(text) => Ok(Some(
            MotionTarget::parse_features(text, args.target).map_err(anyhow::Error::msg)?,
        )),
        None => Ok(None),
    }
}

fn compare(args: CompareArgs) -> Result<()> {
    let a = describe_file(&args.a, args.size)?;
    let b = describe_file(&args.b, args.size)?;
    let d = describe::distance(&a, &b);
    if args.json {
        let side = |d: &Descriptors| {
            let mut m = serde_json::Map::new();
            m.insert("class".into(), json!(d.class.as_str()));
            m.insert("regime".into(), json!(d.regime.as_str()));
            for (k, name) in describe::NAMES.iter().enumerate() {
                let v = d.values[k];
                m.insert(
                    (*name).into(),
                    if v.is_finite() { json!(v) } else { json!(null) },
                );
            }
            serde_json::Value::Object(m)
        };
        let out = json!({
            "a": { "file": args.a.display().to_string(), "descriptors": side(&a) },
            "b": { "file": args.b.display().to_string(), "descriptors": side(&b) },
            "distance": if d.is_finite() { json!(d) } else { json!(null) },
            "same_class": a.class == b.class,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!("a: {}\nb: {}\n", args.a.display(), args.b.display());
    print!("{}", describe::table(&[("a", &a), ("b", &b)]));
    if d.is_finite() {
        println!(
            "\ndistance    {d:.4} (RMS over descriptors, each in units of its reference spread)"
        );
    } else {
        println!(
            "\ndistance    ∞: different classes ({} vs {}) are never close",
            a.class, b.class
        );
    }
    Ok(())
}

fn breed(args: BreedArgs) -> Result<()> {
    let mut run = match &args.resume {
        Some(dir) => Run::open(dir)?,
        None => {
            let settings = BreedSettings {
                prototype: args.prototype.clone(),
                target: args.target.unwrap_or(MotionClass::Floater),
                population: args.population,
                generations: args.generations,
                seed: args.seed,
                seconds: args.seconds,
                archive: args.archive,
                ..BreedSettings::default_run()
            };
            // Keep elites at a tenth of the population (at least one).
            let like = motion_target(&args)?;
            let settings = BreedSettings {
                elites: (settings.population / 10).max(1),
                target: like
                    .as_ref()
                    .and_then(|t| t.class)
                    .unwrap_or(settings.target),
                like,
                ..settings
            };
            settings.validate().map_err(anyhow::Error::msg)?;
            let dir = args
                .out
                .clone()
                .unwrap_or_else(|| default_run_dir(&settings));
            Run::create(&dir, settings)?
        }
    };
    if args.create_only {
        println!("run directory: {}", run.dir.display());
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
    print_generations(run.history(), run.settings().like.is_some());
    if let Some(target) = &run.settings().like {
        print_like(&run, target)?;
    }
    println!("run directory: {}", run.dir.display());
    Ok(())
}

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
        println!("best leaf {}: undetermined, no descriptors", best.id);
        return Ok(());
    };
    let label = format!("leaf {}", best.id);
    println!();
    match run.example() {
        Some(example) => {
            let size = target.size_m.unwrap_or(chord);
            let ex = Descriptors::of(&classify::classify(&example, size))
                .map_err(|e| anyhow::anyhow!("example: {e}"))?;
            print!(
                "{}",
                describe::table(&[("example", &ex), (label.as_str(), &best_d)])
            );
        }
        None => {
            let mut wanted = best_d.clone();
            for (k, name) in describe::NAMES.iter().enumerate() {
                wanted.values[k] = target.descriptors.get(*name).copied().unwrap_or(f64::NAN);
            }
            wanted.class = target.class.unwrap_or(best_d.class);
            print!(
                "{}",
                describe::table(&[("target", &wanted), (label.as_str(), &best_d)])
            );
        }
    }
    match best.eval.distance {
        Some(d) => println!("distance    {d:.4}"),
        None => println!("distance    ∞ (the best is not of the target's class)"),
    }
    Ok(())
}

fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The executor `breed` asked for, with its defaults filled in.
fn executor(args: &BreedArgs) -> Result<Box<dyn leafmagic::breed::executor::Executor>> {
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

fn shard(args: ShardArgs) -> Result<()> {
    let split =
        leafmagic::breed::shard::resolve_split(args.index, args.count, |k| std::env::var(k).ok())
            .map_err(anyhow::Error::msg)?;
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
    let outcome = pool.install(|| {
        leafmagic::breed::worker::run_shard(&args.run, args.generation, split, args.skip_done)
    })?;
    let (g, i, n) = (args.generation, split.index, split.count);
    match outcome {
        leafmagic::breed::worker::Outcome::Evaluated(k, path) => println!(
            "generation {g}, shard {i} of {n}: {k} individuals in {:.3} s -> {}",
            start.elapsed().as_secs_f64(),
            path.display()
        ),
        leafmagic::breed::worker::Outcome::AlreadyDone(path) => println!(
            "generation {g}, shard {i} of {n}: already done ({})",
            path.display()
        ),
    }
    Ok(())
}

fn merge(args: MergeArgs) -> Result<()> {
    if args.count == 0 {
        bail!("--count must be at least 1");
    }
    let mut run = Run::open(&args.run)?;
    let next = run.checkpoint.as_ref().map_or(0, |c| c.generation + 1);
    if args.generation < next {
        println!(
            "generation {} is already merged (checkpoint.json holds generation {}): nothing to do",
            args.generation,
            next - 1
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
    let merge = leafmagic::breed::executor::Merge { shards: args.count };
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
    print_generations(&history[history.len() - 1..], run.settings().like.is_some());
    println!(
        "run directory: {} ({})",
        run.dir.display(),
        if run.is_complete() {
            "complete".to_string()
        } else {
            format!("next: generation {}", args.generation + 1)
        }
    );
    Ok(())
}

fn print_generations(history: &[GenerationSummary], like: bool) {
    print!(
        "{:>3}  {:>7} {:>7} {:>6} {:>6} {:>6}  {:>10} {:>10} {:>6}",
        "gen", "floater", "spinner", "lilter", "undet.", "diverg", "best", "mean", "scale"
    );
    println!("{}", if like { "  best dist." } else { "" });
    for h in history {
        let c = h.counts;
        print!(
            "{:>3}  {:>7} {:>7} {:>6} {:>6} {:>6}  {:>10.4} {:>10.4} {:>6.3}",
            h.generation, c[0], c[1], c[2], c[3], c[4], h.best_score, h.mean_score, h.scale
        );
        if like {
            print!(
                "  {:>11}",
                h.best_distance
                    .map_or("∞".to_string(), |d| format!("{d:.4}"))
            );
        }
        println!();
    }
}

fn export(args: ExportArgs) -> Result<()> {
    let run = Run::open(&args.run)?;
    let Some(cp) = &run.checkpoint else {
        bail!(
            "{}: the run has no completed generation yet",
            args.run.display()
        );
    };
    let ranked = breed::selection::rank(&cp.population);
    let chosen: Vec<&breed::Individual> = match (&args.top, &args.ids) {
        (Some(k), None) => {
            if *k == 0 {
                bail!("--top must be at least 1");
            }
            ranked.into_iter().take(*k).collect()
        }
        (None, Some(ids)) => ids
            .iter()
            .map(|id| {
                cp.population.iter().find(|i| i.id == *id).ok_or_else(|| {
                    anyhow::anyhow!(
                        "--ids: individual {id} is not in the last generation ({})",
                        cp.generation
                    )
                })
            })
            .collect::<Result<_>>()?,
        _ => bail!("give either --top K or --ids ID,..."),
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    breed::files::export_leaves(&run.proto, &chosen, &args.out)?;
    println!(
        "wrote {} leaves and index.csv to {}",
        chosen.len(),
        args.out.display()
    );
    if let Some(format) = args.format {
        let started = Instant::now();
        let objects = leafmagic::output::export::drop_individuals(&run, &chosen, args.fps)?;
        let mut files = 0;
        for o in objects {
            let name = o.name.clone();
            let clip = leafmagic::output::export::side_by_side(&name, vec![o], args.fps, 0.0)?;
            files += write_clip(&clip, format, &args.out, &name)?.len();
        }
        println!(
            "wrote {files} {format} files of their falls (re-dropped for {} s, {} fps) in {:.2} s",
            run.settings().seconds,
            args.fps,
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// Writes `clip` into `dir` in `format` (`<stem>.glb`, or a `.pc2` and an
/// `.obj` per object); returns the paths.
fn write_clip(
    clip: &leafmagic::output::export::Clip,
    format: leafmagic::output::export::Format,
    dir: &std::path::Path,
    stem: &str,
) -> Result<Vec<PathBuf>> {
    use leafmagic::output::export::{Format, glb, pc2};
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    Ok(match format {
        Format::Glb => {
            let path = dir.join(format!("{stem}.glb"));
            glb::write_glb(clip, &path)?;
            vec![path]
        }
        Format::Pc2 => pc2::write_pc2(clip, dir)?,
    })
}

fn preview(args: PreviewArgs) -> Result<()> {
    if let Some(f) = args.fps
        && !(f > 0.0 && f.is_finite())
    {
        bail!("--fps must be a positive number, got {f}");
    }
    if args.top == 0 {
        bail!("--top must be at least 1");
    }
    let started = Instant::now();
    let (clip, grid) = leafmagic::output::preview::load(&args.input, args.top, args.fps)?;
    let out = args.out.clone().unwrap_or_else(|| {
        if args.input.is_dir() {
            args.input.join("preview.html")
        } else {
            args.input.with_extension("html")
        }
    });
    let html = leafmagic::output::preview::html(&clip, grid)?;
    leafmagic::util::io::write_atomic(&out, html.as_bytes())
        .with_context(|| format!("cannot write {}", out.display()))?;
    println!(
        "wrote {} ({:.2} MB: {} objects, {} frames at {} fps) in {:.2} s",
        out.display(),
        html.len() as f64 / 1e6,
        clip.objects.len(),
        clip.frames,
        clip.fps,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// What `accuracy` and `check --stress` run: a named model and its initial
/// state. A leaf is dropped as `drop` drops it; a scene file, once scenes
/// exist, brings its own model and state through this same function.
fn load_problem(arg: &str) -> Result<(String, Model, State)> {
    let spec = LeafSpec::load(arg)?;
    let model = spec
        .model()
        .with_context(|| format!("{arg}: invalid leaf"))?;
    let initial = accuracy::default_release(&model);
    Ok((spec.name, model, initial))
}

fn ms(seconds: f64) -> String {
    if seconds >= 1.0 {
        format!("{seconds:.2} s")
    } else {
        format!("{:.3} ms", seconds * 1e3)
    }
}

fn accuracy(args: AccuracyArgs) -> Result<()> {
    let started = Instant::now();
    let (name, model, initial) = load_problem(&args.leaf)?;
    let seconds = args.seconds.unwrap_or(if args.long { 10.0 } else { 1.0 });
    if !(seconds > 0.0 && seconds.is_finite()) {
        bail!("--seconds must be a positive number, got {seconds}");
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create the output directory {}", args.out.display()))?;
    if args.long {
        return accuracy_long(&args, &name, &model, seconds, started);
    }
    if args.runs == 0 {
        bail!("--runs must be at least 1");
    }
    let mut settings = SweepSettings::for_model(&model, seconds);
    settings.runs = args.runs;
    if let Some(j) = args.reference_j {
        settings.reference_j = j;
    }
    let report = accuracy::sweep_leaf(&model, &initial, &settings)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.leaf))?;
    let csv_path = args.out.join("accuracy.csv");
    leafmagic::util::io::write_atomic(&csv_path, accuracy::csv(&report.rows).as_bytes())
        .with_context(|| format!("cannot write {}", csv_path.display()))?;
    let svg_path = args.out.join("accuracy.svg");
    let title = format!("work-precision: {name}, T = {seconds} s");
    let svg = leafmagic::sim::accuracy::plot::work_precision_svg(&report, &title)
        .map_err(|e| anyhow::anyhow!("cannot draw {}: {e}", svg_path.display()))?;
    leafmagic::util::io::write_atomic(&svg_path, svg.as_bytes())
        .with_context(|| format!("cannot write {}", svg_path.display()))?;

    let r = &report.reference;
    println!(
        "leaf         {name} ({} particles, chord {:.4} m), released as `drop` releases it; T = {seconds} s",
        model.len(),
        report.chord
    );
    println!("error        RMS particle position error at T / chord, against the reference");
    println!(
        "reference    RK4 at h = {:.4e} s; against h = {:.4e} s it differs by {:.2e} chords, \
         {} 0.1 × the smallest error plotted ({}): {}",
        r.dt,
        2.0 * r.dt,
        r.self_difference,
        if report.reference_valid {
            "below"
        } else {
            "NOT below"
        },
        report
            .smallest_error
            .map_or("none".to_string(), |e| format!("{e:.2e}")),
        if report.reference_valid {
            "valid"
        } else {
            "NOT VALIDATED"
        }
    );
    println!(
        "events       {}",
        if report.breaking_disabled > 0 {
            format!(
                "spring breaking switched off for the sweep ({} breakable springs); no ground",
                report.breaking_disabled
            )
        } else {
            "none (no breakable springs, no ground)".to_string()
        }
    );
    println!(
        "work         median wall time of {} runs per point (stepping only), force evaluations",
        settings.runs
    );
    println!();
    println!(
        "{:<11} {:>6} {:>4} {:>4}  {:<22} {:>12} {:>12} {:>12} {:>7}",
        "integrator",
        "order",
        "exp.",
        "pts",
        "pairwise (finest 3)",
        "stable dt",
        "diverged at",
        "check dt_max",
        "ratio"
    );
    for s in &report.summaries {
        let pairwise: Vec<String> = s
            .pairwise_orders
            .iter()
            .rev()
            .take(3)
            .rev()
            .map(|p| format!("{p:.2}"))
            .collect();
        let predicted = match s.predicted_dt_max {
            None => "unbounded".to_string(),
            Some(m) if m <= 0.0 => "none".to_string(),
            Some(m) => format!("{m:.4e}"),
        };
        let ratio = match (
            s.largest_stable_dt,
            s.predicted_dt_max,
            s.smallest_diverged_dt,
        ) {
            (Some(found), Some(m), Some(_)) if m > 0.0 => format!("{:.3}", found / m),
            _ => "—".to_string(),
        };
        println!(
            "{:<11} {:>6} {:>4} {:>4}  {:<22} {:>12} {:>12} {:>12} {:>7}",
            s.integrator.name(),
            s.order.map_or("—".to_string(), |p| format!("{p:.3}")),
            s.expected_order,
            s.fit_points,
            pairwise.join(" "),
            s.largest_stable_dt
                .map_or("—".to_string(), |h| format!("{h:.4e}")),
            s.smallest_diverged_dt
                .map_or("none".to_string(), |h| format!("{h:.4e}")),
            predicted,
            ratio
        );
    }
    println!();
    println!(
        "{:<11} {:<44} cheapest run to error ≤ 1e-6",
        "integrator", "cheapest run to error ≤ 1e-3"
    );
    for s in &report.summaries {
        let cells: Vec<String> = s
            .cheapest
            .iter()
            .zip(&s.extrapolated)
            .map(|(c, x)| match (c, x) {
                (Some(c), _) => format!(
                    "h {:.3e}: {:.1e} in {} ({} f)",
                    c.dt,
                    c.error,
                    ms(c.wall_s),
                    c.force_evals
                ),
                (None, Some(x)) => format!(
                    "not reached; ≈ h {:.1e}, ≈ {} (extrap.)",
                    x.dt,
                    ms(x.wall_s)
                ),
                (None, None) => "not reached".to_string(),
            })
            .collect();
        println!("{:<11} {:<44} {}", s.integrator.name(), cells[0], cells[1]);
    }
    for w in &report.warnings {
        println!("warning: {w}");
    }
    println!();
    println!(
        "wrote        {} ({} rows), {}",
        csv_path.display(),
        report.rows.len(),
        svg_path.display()
    );
    println!("finished in  {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}

fn accuracy_long(
    args: &AccuracyArgs,
    name: &str,
    model: &Model,
    seconds: f64,
    started: Instant,
) -> Result<()> {
    use std::fmt::Write as _;
    let settings = LongSettings {
        seconds,
        ..LongSettings::default()
    };
    let report = accuracy::long::long_sweep(model, &settings)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.leaf))?;
    let mut csv = String::from(
        "integrator,dt,drops,diverged,class,agreement,descent_m_s,descent_ci95,rotation_turns_s,rotation_ci95\n",
    );
    let stat = |s: Option<accuracy::long::Stat>| {
        s.map_or((String::new(), String::new()), |s| {
            (s.mean.to_string(), s.ci95.to_string())
        })
    };
    for r in &report.rows {
        let (d, dc) = stat(r.descent_speed);
        let (w, wc) = stat(r.rotation_rate);
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{d},{dc},{w},{wc}",
            r.integrator,
            r.dt,
            r.classes.len() + r.diverged,
            r.diverged,
            r.majority.map_or(String::new(), |c| c.to_string()),
            r.agreement
        );
    }
    let path = args.out.join("accuracy-long.csv");
    leafmagic::util::io::write_atomic(&path, csv.as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))?;
    println!(
        "leaf         {name}: {} drops per step, tilts {:.2}°…{:.2}° about x, {seconds} s each",
        settings.ensemble,
        10.0 - settings.tilt_spread_deg / 2.0,
        10.0 + settings.tilt_spread_deg / 2.0
    );
    match report.horizon_s {
        Some(t) => println!(
            "horizon      twin RK4 drops {:.0e} chords apart separate by {:.0e} chords at t = {t:.2} s \
             (h = {:.3e} s): pointwise error means nothing after that",
            accuracy::long::TWIN_SEPARATION,
            accuracy::long::HORIZON_SEPARATION,
            report.horizon_dt
        ),
        None => println!(
            "horizon      twin RK4 drops {:.0e} chords apart stay within {:.0e} chords for the whole {seconds} s",
            accuracy::long::TWIN_SEPARATION,
            accuracy::long::HORIZON_SEPARATION
        ),
    }
    println!();
    println!(
        "{:<11} {:>11}  {:<22} {:>22} {:>22}",
        "integrator", "dt (s)", "class (agreement)", "descent m/s (±95 %)", "rotation turns/s"
    );
    let fmt_stat = |s: Option<accuracy::long::Stat>| {
        s.map_or("—".to_string(), |s| {
            format!("{:.4} ± {:.4}", s.mean, s.ci95)
        })
    };
    for r in &report.rows {
        let class = match r.majority {
            Some(c) if r.diverged == 0 => format!("{c} ({:.0} %)", 100.0 * r.agreement),
            Some(c) => format!("{c} ({:.0} %), {} div.", 100.0 * r.agreement, r.diverged),
            None => format!("diverged ({}/{})", r.diverged, r.diverged),
        };
        println!(
            "{:<11} {:>11.4e}  {:<22} {:>22} {:>22}",
            r.integrator.name(),
            r.dt,
            class,
            fmt_stat(r.descent_speed),
            fmt_stat(r.rotation_rate)
        );
    }
    println!();
    for s in &report.summaries {
        let class = s
            .finest_class
            .map_or("no class".to_string(), |c| c.to_string());
        let from = |h: Option<f64>| {
            h.map_or("never (not even the finest)".to_string(), |h| {
                format!("dt ≤ {h:.4e} s")
            })
        };
        println!(
            "{:<11} class {class} from {}; descent speed and rotation rate agree from {}",
            s.integrator.name(),
            from(s.class_stable_from),
            from(s.stats_stable_from)
        );
    }
    println!();
    println!("wrote        {}", path.display());
    println!("finished in  {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}

fn check_stress(args: CheckArgs) -> Result<()> {
    let started = Instant::now();
    let (name, model, initial) = load_problem(&args.leaf)?;
    let cases = stress::cases(&model, &initial)
        .map_err(|e| anyhow::anyhow!("{}: cannot build a stress case: {e}", args.leaf))?;
    let rows = stress::run_matrix(&cases, args.explicit, args.substep_cap);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
        return Ok(());
    }
    println!(
        "leaf        {name}: {} cases × {} integrators, {} s each (one step at least); explicit above dt_max: {}",
        cases.len(),
        Integrator::ALL.len(),
        stress::STRESS_SECONDS,
        args.explicit
    );
    for c in &cases {
        println!("  {:<19} {}", c.name, c.description);
    }
    println!();
    println!(
        "{:<19} {:<10} {:<6} {:>10} {:>11} {:>5} {:>11} {:>10}  detail",
        "case", "integrator", "result", "dt (s)", "dt_max (s)", "sub", "energy", "strain"
    );
    for r in &rows {
        let dt_max = match r.dt_max {
            None => "unbounded".to_string(),
            Some(m) if m <= 0.0 => "none".to_string(),
            Some(m) => format!("{m:.3e}"),
        };
        let detail = match (&r.failure, r.outcome) {
            (Some(f), _) => format!(
                "{} at step {}{}",
                f.cause,
                f.step,
                f.particle
                    .map_or(String::new(), |p| format!(", particle {p}"))
            ),
            (None, Outcome::Ok) => r.warnings.join("; "),
            (None, Outcome::Error) => r.message.clone(),
        };
        let line = format!(
            "{:<19} {:<10} {:<6} {:>10.1e} {:>11} {:>5} {:>11} {:>10}  {}",
            r.case,
            r.integrator.name(),
            match r.outcome {
                Outcome::Ok => "ok",
                Outcome::Error => "error",
            },
            r.dt,
            dt_max,
            r.substeps,
            r.energy_drift
                .map_or("—".to_string(), |d| format!("{d:+.1e}")),
            r.max_strain.map_or("—".to_string(), |s| format!("{s:.2e}")),
            detail
        );
        println!("{}", line.trim_end());
    }
    let ok = rows.iter().filter(|r| r.outcome == Outcome::Ok).count();
    let finite = rows.iter().filter(|r| r.all_finite).count();
    println!();
    println!(
        "{} rows: {ok} finished finite, {} stopped with a diagnosis; all numbers finite in {finite}/{} rows",
        rows.len(),
        rows.len() - ok,
        rows.len()
    );
    println!(
        "energy = drift (E(T) − E(0) − W_air+dampers) / energy turnover, E = kinetic + gravitational + spring + bending"
    );
    println!("strain = largest |l − L|/L of any spring during the run; sub = sub-steps per step");
    println!("finished in {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}
