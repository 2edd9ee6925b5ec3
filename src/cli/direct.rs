//! `direct`: searches a scene's free parameters for values that meet its
//! goals, writes the solved scene and the history, and reports each goal
//! against random search with the same budget.

use super::args::DirectArgs;
use anyhow::Result;
use leafmagic::breed::verify::content_hash;
use leafmagic::direct::files::{CHECKPOINT_FILE, Checkpoint, read_checkpoint};
use leafmagic::direct::{self, Problem, Settings};
use serde_json::json;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `direct`: loads the problem (and the checkpoint to resume from), says
/// the work, searches, writes, reports.
pub fn direct(args: DirectArgs) -> Result<()> {
    let problem = Problem::load(&args.file)?;
    let scene_hash = content_hash(
        &std::fs::read(&args.file).map_err(|e| anyhow::anyhow!("{}: {e}", args.file.display()))?,
    );
    let resumed = match &args.resume {
        Some(dir) => Some(resumable(&args, dir, &scene_hash)?),
        None => None,
    };
    let settings = Settings {
        budget: args
            .budget
            .or(resumed.as_ref().map(|c| c.budget))
            .unwrap_or(200),
        seed: args.seed.or(resumed.as_ref().map(|c| c.seed)).unwrap_or(0),
        threads: args.threads.unwrap_or(0),
    };
    if settings.budget == 0 {
        anyhow::bail!("--budget: a budget of 0 scene runs: give at least 1");
    }
    let particle_steps = bound_work(&args, &problem, &settings)?;
    let out = args.resume.clone().or(args.out.clone()).unwrap_or_else(|| {
        PathBuf::from("runs").join(format!("direct-{}-s{}", problem.spec.name, settings.seed))
    });
    let started = Instant::now();
    let terminal = std::io::stderr().is_terminal();
    let total = 2 * settings.budget;
    let scene = args.file.display().to_string();
    let start = resumed.map(|c| c.state);
    if let Some(state) = &start {
        eprintln!(
            "direct: resuming {} at {}/{total} runs",
            out.display(),
            state.history.len()
        );
    }
    let outcome = direct::search(&problem, &settings, start, |state, best| {
        direct::files::write_checkpoint(
            &out,
            &Checkpoint {
                scene: scene.clone(),
                scene_hash: scene_hash.clone(),
                budget: settings.budget,
                seed: settings.seed,
                state: state.clone(),
            },
        )
        .map_err(|e| anyhow::anyhow!("{}: {e}", out.join(CHECKPOINT_FILE).display()))?;
        let done = state.history.len();
        if terminal || done == total || done == settings.budget {
            eprintln!(
                "direct: {done}/{total} runs, best {} so far: objective {:.4}, {:.0} % met ({:.0} s)",
                best.method.name(),
                best.evaluation.objective,
                100.0 * best.evaluation.met_fraction(),
                started.elapsed().as_secs_f64()
            );
        }
        Ok::<(), anyhow::Error>(())
    })?;
    let wall = started.elapsed().as_secs_f64();
    let files = direct::files::write(&out, &problem, &settings, &outcome)?;
    report(
        &args,
        &problem,
        &settings,
        &outcome,
        &files,
        wall,
        &out,
        particle_steps,
    )
}

/// The search's work, said before it starts and refused past
/// `--max-work`: particle-steps over the budget's runs and the baseline's.
fn bound_work(args: &DirectArgs, problem: &Problem, settings: &Settings) -> Result<f64> {
    let work = problem
        .scene
        .work(Some(problem.seconds))
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.file.display()))?;
    let runs = 2 * settings.budget;
    let total = work.particle_steps() * runs as f64;
    if total > args.max_work {
        anyhow::bail!(
            "{}: this search needs about {total:.2e} particle-steps ({runs} runs of {} particles × {:.0} steps, the baseline's included), more than the limit of {:.1e}: lower --budget, or raise the limit with `--max-work {:.1e}`",
            args.file.display(),
            work.particles,
            work.steps,
            args.max_work,
            total * 1.01
        );
    }
    eprintln!(
        "direct: {} free parameters, {} goals; {} runs of {:.2} s ({} CMA-ES, {} random), each {} particles × {:.0} steps: {:.2e} particle-steps in all",
        problem.free.len(),
        problem.goals.len(),
        runs,
        problem.seconds,
        settings.budget,
        settings.budget,
        work.particles,
        work.steps,
        total
    );
    Ok(total)
}

/// The search's result: each goal's met fraction and distance against
/// random search's with the same budget, the solved values and the files
/// (with `--json`, as one JSON document).
#[allow(clippy::too_many_arguments)]
fn report(
    args: &DirectArgs,
    problem: &Problem,
    settings: &Settings,
    outcome: &direct::Outcome,
    files: &[PathBuf],
    wall: f64,
    out: &Path,
    particle_steps: f64,
) -> Result<()> {
    let (best, base) = (outcome.best(), outcome.baseline());
    let goal_json = |r: &direct::Record| {
        problem
            .goals
            .iter()
            .zip(&r.evaluation.goals)
            .map(|(g, e)| {
                json!({
                    "name": g.name,
                    "leaves": g.leaves.len(),
                    "met_fraction": e.met_fraction,
                    "mean_distance": e.mean_distance,
                })
            })
            .collect::<Vec<_>>()
    };
    if args.json {
        let report = json!({
            "scene": problem.spec.name,
            "goals": goal_json(best),
            "objective": best.evaluation.objective,
            "met_fraction": best.evaluation.met_fraction(),
            "parameters": problem.free.iter().zip(&best.values).map(|(f, v)| json!({
                "parameter": f.parameter, "value": v, "min": f.min, "max": f.max, "written": f.written,
            })).collect::<Vec<_>>(),
            "evaluations": settings.budget,
            "generations": outcome.generations,
            "baseline_evaluations": settings.budget,
            "baseline_met_fraction": base.evaluation.met_fraction(),
            "baseline_objective": base.evaluation.objective,
            "baseline_goals": goal_json(base),
            "baseline_parameters": base.values,
            "particle_steps": particle_steps,
            "wall_s": wall,
            "out": out,
            "files": files,
        });
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    println!(
        "direct {}: CMA-ES, {} runs in {} generations (seed {}), {:.1} s wall",
        args.file.display(),
        settings.budget,
        outcome.generations,
        settings.seed,
        wall
    );
    println!(
        "{:<24} {:>8} {:>12} {:>14} {:>14}",
        "goal", "leaves", "met", "distance (m)", "random: met"
    );
    for ((g, e), b) in problem
        .goals
        .iter()
        .zip(&best.evaluation.goals)
        .zip(&base.evaluation.goals)
    {
        println!(
            "{:<24} {:>8} {:>11.0}% {:>14.4} {:>13.0}%",
            g.name,
            g.leaves.len(),
            100.0 * e.met_fraction,
            e.mean_distance,
            100.0 * b.met_fraction
        );
    }
    println!(
        "objective {:.4} (random search, same budget: {:.4})",
        best.evaluation.objective, base.evaluation.objective
    );
    for (f, v) in problem.free.iter().zip(&best.values) {
        println!(
            "  {:<28} = {:>10.4}   ({} to {}; the file had {})",
            f.parameter, v, f.min, f.max, f.written
        );
    }
    println!(
        "wrote {} (a plain scene: leafmagic scene runs it) and {}",
        files[0].display(),
        files[1].display()
    );
    Ok(())
}

/// The checkpoint in `dir`, refused when the scene file's bytes, the
/// budget or the seed asked for are not the search's (the thread count is
/// free), or when --out names another directory.
fn resumable(args: &DirectArgs, dir: &Path, scene_hash: &str) -> Result<Checkpoint> {
    if let Some(out) = &args.out
        && out != dir
    {
        anyhow::bail!(
            "--out {} with --resume {}: a resumed search writes where it began; leave --out out",
            out.display(),
            dir.display()
        );
    }
    let cp = read_checkpoint(dir)?;
    let at = dir.join(CHECKPOINT_FILE);
    if cp.scene_hash != scene_hash {
        anyhow::bail!(
            "{}: not the scene the search in {} began on ({}, as {} records it): its bytes differ; resume with that file unchanged, or start a new search",
            args.file.display(),
            dir.display(),
            cp.scene,
            at.display()
        );
    }
    if let Some(b) = args.budget
        && b != cp.budget
    {
        anyhow::bail!(
            "--budget {b}: the search in {} has a budget of {} ({}); leave --budget out to go on with it",
            dir.display(),
            cp.budget,
            at.display()
        );
    }
    if let Some(s) = args.seed
        && s != cp.seed
    {
        anyhow::bail!(
            "--seed {s}: the search in {} has seed {} ({}); leave --seed out to go on with it",
            dir.display(),
            cp.seed,
            at.display()
        );
    }
    Ok(cp)
}
