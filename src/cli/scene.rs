//! `scene`: runs a scene file and writes its trajectories and summary (and,
//! asked, an export of the run), or explains what the compiled scene keeps.

use super::args::SceneArgs;
use super::{input, output, report};
use anyhow::Result;
use leafmagic::direct;
use leafmagic::physics::model::AeroLaw;
use leafmagic::physics::params::TimeStep;
use leafmagic::physics::run;
use leafmagic::sim::scene::{self, Scene};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `scene`: loads, compiles and runs a scene file, or with `--explain`
/// lists its decisions and stops.
pub fn scene(args: SceneArgs) -> Result<()> {
    // Held to the limits from the parsed file on, before any object is built.
    let limits = scene::Limits {
        max_work: args.max_work,
        max_memory: args.max_memory,
        seconds: args.seconds,
        law: args.law.map(|l| l.law()),
    };
    let scene = Scene::load_within(&args.file, &limits).map_err(|e| {
        let hint = (input::toml_kind(&args.file) == Some(input::TomlKind::Leaf)).then(|| {
            format!(
                "\nhint: {} is a leaf file ([[particle]] and [[triangle]] tables), not a scene: `leafmagic drop {}` drops it, and a scene places it with [[leaf]] file = \"...\"",
                args.file.display(),
                args.file.display()
            )
        });
        anyhow::anyhow!("{e}{}", hint.unwrap_or_default())
    })?;
    let frame = 1.0 / scene.frame_rate;
    if args.explain {
        return explain(&args, &scene);
    }
    let failed = |e: &dyn std::fmt::Display| anyhow::anyhow!("{}: {e}", args.file.display());
    let work = scene.work(args.seconds).map_err(|e| failed(&e))?;
    let mut bar = super::progress::long_run(&work, &scene.model, frame, "scene", args.max_work);
    // A directed scene's goals are judged on the run, as `direct` judges
    // them, for `preview` to show (goals.json).
    let text = std::fs::read_to_string(&args.file).map_err(|e| failed(&e))?;
    let goals = direct::record::goals_of(&text, &args.file.display().to_string(), &scene)?;
    let mut judging = (!goals.is_empty()).then(|| direct::record::Judging::new(&scene, goals));
    let run = scene
        .run_watched(args.seconds, |k, _, state| {
            if let Some(b) = &bar {
                b.set_position(k);
            }
            if let Some(j) = &mut judging {
                j.record(&scene, &state.position);
            }
        })
        .map_err(|e| failed(&e))?;
    let verdicts = judging.map(|j| j.finish(&scene));
    if let Some(b) = bar.take() {
        b.finish_and_clear();
    }
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| scene::default_out_dir(&scene));
    // The directory is written as a whole, the export with it: a failure
    // leaves the previous output as it was and names the file.
    let staged = scene::Staged::new(&dir)?;
    let mut written = run.write_staged(&scene, &staged)?;
    if let Some(v) = &verdicts {
        let json = serde_json::to_string_pretty(v)?;
        let path = staged.write(scene::GOALS_FILE, json.as_bytes())?;
        written.push(staged.final_path(&path));
    }
    let export_note = match args.export {
        Some(format) => Some(export_into(
            &args,
            format,
            &scene,
            &run,
            &staged,
            &dir,
            &mut written,
        )?),
        None => None,
    };
    staged.commit()?;
    let s = &run.stats;
    if args.json {
        let out = json!({
            "scene": scene.name,
            "law": law_of(&scene),
            "aero_law": scene.model.aero.name(),
            "stats": s,
            "wall_s": s.wall_s,
            "wall_per_simulated_s": s.wall_s / s.simulated_s,
            "out": dir,
            "export": export_note,
            "files": written,
            "goals": verdicts.as_ref().map(|v| v.goals.iter().map(|g| json!({
                "name": g.name,
                "met_fraction": g.met_fraction,
                "mean_distance": g.mean_distance,
            })).collect::<Vec<_>>()),
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    print!(
        "{}",
        report::scene::summary(&scene, s, &dir, written.len(), export_note.as_deref())
    );
    for g in verdicts.iter().flat_map(|v| &v.goals) {
        println!(
            "goal {}: {:.0} % of {} leaves met it, mean distance {:.4} m",
            g.name,
            100.0 * g.met_fraction,
            g.leaves.len(),
            g.mean_distance
        );
    }
    Ok(())
}

/// `scene --explain`: what the compiled scene keeps and leaves out, and
/// its step.
fn explain(args: &SceneArgs, scene: &Scene) -> Result<()> {
    let decisions = scene.explain();
    let frame = 1.0 / scene.frame_rate;
    let dt = run::resolve_dt(&scene.model, scene.integrator, scene.dt, frame);
    let why = dt.as_ref().ok().map(|&h| step_reason(scene, h));
    if args.json {
        let out = json!({
            "scene": scene.name,
            "law": law_of(scene),
            "aero_law": scene.model.aero.name(),
            "particles": scene.model.len(),
            "springs": scene.model.springs.len(),
            "triangles": scene.model.triangles.len(),
            "hinges": scene.model.hinges.len(),
            "rigid_bodies": scene.model.rigid.len(),
            "integrator": scene.integrator,
            "dt": dt.as_ref().ok(),
            "dt_reason": why,
            "kept": decisions.iter().filter(|d| d.kept).map(|d| json!({"term": d.name, "reason": d.reason})).collect::<Vec<_>>(),
            "left_out": decisions.iter().filter(|d| !d.kept).map(|d| json!({"term": d.name, "reason": d.reason})).collect::<Vec<_>>(),
            "pruned": scene.pruned,
            "wind_skips_at_start": scene.wind_skips(0.0).iter().map(|g| json!({
                "objects": g.objects,
                "evaluated": g.reached,
                "skipped": g.skipped.iter().map(|(i, why)| json!({"primitive": i, "why": why})).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    print!(
        "{}",
        report::scene::explain(scene, &dt, why.as_deref(), &decisions)
    );
    Ok(())
}

/// `scene --export`: the run written as an animation file into the staged
/// output (named as it will be once committed), its files added to
/// `written`; the note the report prints.
fn export_into(
    args: &SceneArgs,
    format: leafmagic::formats::Format,
    scene: &Scene,
    run: &scene::SceneRun,
    staged: &scene::Staged,
    dir: &Path,
    written: &mut Vec<PathBuf>,
) -> Result<String> {
    let started = Instant::now();
    let clip = leafmagic::output::export::from_scene_run(scene, run, args.export_fps)?;
    let files = output::write_clip(
        &clip,
        format,
        staged.path(),
        &scene.name,
        args.export_host_fps,
    )
    .map_err(|e| {
        // Name the file as it would have been in the output.
        let message = format!("{e:#}").replace(
            &staged.path().display().to_string(),
            &dir.display().to_string(),
        );
        anyhow::anyhow!("{message}; nothing was changed in {}", dir.display())
    })?;
    let bytes: u64 = files
        .iter()
        .filter_map(|f| std::fs::metadata(f).ok())
        .map(|m| m.len())
        .sum();
    let files: Vec<_> = files.iter().map(|f| staged.final_path(f)).collect();
    let note = report::scene::export_note(
        format,
        &clip,
        files.len(),
        bytes,
        started.elapsed().as_secs_f64(),
    );
    written.extend(files);
    Ok(note)
}

/// The scene's law as `--law` names it.
fn law_of(scene: &Scene) -> &'static str {
    scene
        .model
        .aero
        .name()
        .parse()
        .map_or("unknown", super::args::law_word)
}

/// Why the scene steps at `dt`, as `scene --explain` prints it: the fixed
/// step, the output frame, or the stability limit that sets the auto step
/// ([`run::Work::why`]), and, where the air's rate sets it in wind, the
/// wind's speed bound that the rate is taken at (the air's rates grow with
/// the relative speed, which the wind can raise to its bound).
fn step_reason(scene: &Scene, dt: f64) -> String {
    let frame = 1.0 / scene.frame_rate;
    let auto = scene.dt == TimeStep::Auto;
    let work = run::Work::of(
        &scene.model,
        scene.integrator,
        dt,
        auto,
        scene.duration,
        frame,
    )
    .explained(&scene.model, frame);
    let why = work.why();
    let wind = scene.model.wind.speed_bound();
    match &work.reason {
        run::StepReason::Frame => format!(
            "the output frame's 1/{} s: every stability limit of {} is longer",
            scene.frame_rate, scene.integrator
        ),
        run::StepReason::Stability {
            bound: run::StepBound::Drag,
            ..
        } if wind > 0.0 && scene.model.aero != AeroLaw::Linear => format!(
            "{why}; under the {} law the air's rates grow with the relative speed, and are taken at speeds up to the wind's bound, {wind:.2} m/s (the fastest group of its primitives whose regions can meet), plus twice the fastest fall in still air",
            scene.model.aero.name()
        ),
        _ => why,
    }
}
