//! `scene`: runs a scene file and writes its trajectories and summary (and,
//! asked, an export of the run), or explains what the compiled scene keeps.

use super::args::SceneArgs;
use super::{output, report};
use anyhow::{Context, Result};
use leafmagic::physics::run;
use leafmagic::sim::scene::{self, Scene};
use serde_json::json;
use std::time::Instant;

/// `scene`: loads, compiles and runs a scene file, or with `--explain`
/// lists its decisions and stops.
pub fn scene(args: SceneArgs) -> Result<()> {
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
        print!("{}", report::scene::explain(&scene, &dt, &decisions));
        return Ok(());
    }
    let run = scene
        .run(args.seconds)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.file.display()))?;
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| scene::default_out_dir(&scene));
    let mut written = run
        .write(&scene, &dir)
        .with_context(|| format!("cannot write to {}", dir.display()))?;
    let mut export_note = None;
    if let Some(format) = args.export {
        let started = Instant::now();
        let clip = leafmagic::output::export::from_scene_run(&scene, &run, args.export_fps)?;
        let files = output::write_clip(&clip, format, &dir, &scene.name, args.export_host_fps)?;
        let bytes: u64 = files
            .iter()
            .filter_map(|f| std::fs::metadata(f).ok())
            .map(|m| m.len())
            .sum();
        export_note = Some(report::scene::export_note(
            format,
            &clip,
            files.len(),
            bytes,
            started.elapsed().as_secs_f64(),
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
    print!(
        "{}",
        report::scene::summary(&scene, s, &dir, written.len(), export_note.as_deref())
    );
    Ok(())
}
