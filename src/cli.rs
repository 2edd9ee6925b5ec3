//! The command line (clap derive): parsing and the thin glue from arguments
//! to library calls. Everything that computes lives in the library.

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use leafmagic::classify::{self, Classification};
use leafmagic::integrate::Integrator;
use leafmagic::leaf::LeafSpec;
use leafmagic::scene::{self, Scene};
use leafmagic::sim::{self, DropParams, TimeStep};
use leafmagic::stability;
use leafmagic::trajectory::Trajectory;
use serde_json::json;
use std::path::PathBuf;

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
    /// Drop a leaf from rest in still air and record its fall.
    Drop(DropArgs),
    /// Report the stable time step of a leaf for each integrator, with warnings.
    Check(CheckArgs),
    /// Name the motion of a recorded fall (pose CSV t,x,y,z,qw,qx,qy,qz).
    Classify(ClassifyArgs),
    /// Run a scene file and write per-object trajectories and a summary.
    Scene(SceneArgs),
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
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
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
        Command::Drop(args) => drop(args),
        Command::Check(args) => check(args),
        Command::Classify(args) => classify(args),
        Command::Scene(args) => run_scene(args),
    }
}

fn run_scene(args: SceneArgs) -> Result<()> {
    let scene = Scene::load(&args.file)?;
    let decisions = scene.explain();
    let frame = 1.0 / scene.frame_rate;
    if args.explain {
        let dt = sim::resolve_dt(&scene.model, scene.integrator, scene.dt, frame);
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
    let s = &run.stats;
    if args.json {
        let out = json!({
            "scene": scene.name,
            "stats": s,
            "wall_s": s.wall_s,
            "wall_per_simulated_s": s.wall_s / s.simulated_s,
            "out": dir,
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
        sim::drop_leaf(&model, &params).map_err(|e| anyhow::anyhow!("{}: {e}", args.leaf))?;
    if let Some(path) = &args.out {
        result
            .trajectory
            .write_csv(path)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if let (Some(path), Some(frames)) = (&args.particles, &result.particles) {
        let bytes = leafmagic::io::particle_csv(&result.trajectory.time, frames);
        leafmagic::io::write_atomic(path, &bytes)
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
    if !(args.size > 0.0 && args.size.is_finite()) {
        bail!(
            "--size must be a positive number of metres, got {}",
            args.size
        );
    }
    let traj = Trajectory::read_csv(&args.trajectory)?;
    let c = classify::classify(&traj, args.size);
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
    let spec = LeafSpec::load(&args.leaf)?;
    let model = spec
        .model()
        .with_context(|| format!("{}: invalid leaf", args.leaf))?;
    let est = stability::estimate(&model);
    let frame = 1.0 / sim::FRAME_RATE;
    let rows: Vec<_> = Integrator::ALL
        .iter()
        .map(|&i| (i, est.dt_max(i), est.auto_dt(i, frame)))
        .collect();
    if args.json {
        let per: serde_json::Map<String, serde_json::Value> = rows
            .iter()
            .map(|(i, m, a)| (i.name().to_string(), json!({ "dt_max": m, "dt_auto": a })))
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
    println!(
        "{:<12} {:>14} {:>14}",
        "integrator", "dt_max (s)", "dt auto (s)"
    );
    for (i, m, a) in rows {
        let m = match m {
            None => "unbounded".to_string(),
            Some(v) if v <= 0.0 => "unstable".to_string(),
            Some(v) => format!("{v:.4e}"),
        };
        let a = a.map_or("none".to_string(), |v| format!("{v:.4e}"));
        println!("{:<12} {:>14} {:>14}", i.name(), m, a);
    }
    for w in &est.warnings {
        println!("warning: {w}");
    }
    Ok(())
}
