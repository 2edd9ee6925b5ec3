//! The human reports of `scene`: what the compiled scene keeps and leaves
//! out (`--explain`), and the summary of a run.

use super::text;
use leafmagic::formats::Format;
use leafmagic::formats::clip::Clip;
use leafmagic::physics::run::StepError;
use leafmagic::physics::terms::Decision;
use leafmagic::sim::scene::{RunStats, Scene};
use std::fmt::Write as _;
use std::path::Path;

/// `scene --explain`: the compiled model's size, the integrator and its
/// step (or why there is none), each term kept or left out, and what the
/// compiler pruned.
pub fn explain(
    scene: &Scene,
    dt: &Result<f64, StepError>,
    why: Option<&str>,
    decisions: &[Decision],
) -> String {
    text(|out| {
        writeln!(
            out,
            "scene       {} ({}): {} objects, {} particles, {} springs, {} triangles, {} hinges, {} rigid bodies",
            scene.name,
            scene.source,
            scene.objects.len(),
            scene.model.len(),
            scene.model.springs.len(),
            scene.model.triangles.len(),
            scene.model.hinges.len(),
            scene.model.rigid.len()
        )?;
        match dt {
            Ok(dt) => writeln!(out, "integrator  {} (dt = {dt:.4e} s)", scene.integrator)?,
            Err(e) => writeln!(out, "integrator  {} ({e})", scene.integrator)?,
        }
        if let Some(why) = why {
            writeln!(out, "{:<11} {why}", "step")?;
        }
        for d in decisions {
            let verdict = if d.kept { "kept" } else { "left out" };
            writeln!(out, "{verdict:<11} {:<29} {}", d.name, d.reason)?;
        }
        for p in &scene.pruned {
            writeln!(out, "{:<11} {p}", "pruned")?;
        }
        let skips = scene.wind_skips(0.0);
        if !skips.is_empty() {
            writeln!(
                out,
                "{:<11} {:<29} per object and force evaluation, a primitive whose keys are 0, or whose bounds' or front's falloff band the object's bounding box lies beyond, is not evaluated at its particles (it would add exact zeros), nor any for an object that reads no wind; at t = 0:",
                "skipping", "wind primitives"
            )?;
            for g in &skips {
                let why: Vec<String> = g
                    .skipped
                    .iter()
                    .map(|(i, why)| format!("wind[{i}] ({why})"))
                    .collect();
                let reached: Vec<String> = g.reached.iter().map(|i| format!("wind[{i}]")).collect();
                writeln!(
                    out,
                    "{:<11} {:<29} skips {}; evaluates {}",
                    "",
                    g.objects,
                    if why.is_empty() {
                        "none".to_string()
                    } else {
                        why.join(", ")
                    },
                    if reached.is_empty() {
                        "none".to_string()
                    } else {
                        reached.join(", ")
                    }
                )?;
            }
        }
        Ok(())
    })
}

/// What `scene --export` wrote (one line, without its newline; also the
/// `export` field of `--json`): `files` files of `bytes` in all, in
/// `elapsed_s`.
pub fn export_note(
    format: Format,
    clip: &Clip,
    files: usize,
    bytes: u64,
    elapsed_s: f64,
) -> String {
    format!(
        "{format}: {files} files, {:.2} MB, {} frames at {} fps, in {elapsed_s:.3} s",
        bytes as f64 / 1e6,
        clip.frames,
        clip.fps,
    )
}

/// `scene`: the run's numbers, where its `files` files went, and the export
/// note if it was exported.
pub fn summary(
    scene: &Scene,
    s: &RunStats,
    dir: &Path,
    files: usize,
    export_note: Option<&str>,
) -> String {
    text(|out| {
        writeln!(
            out,
            "scene           {} ({} objects, {} particles)",
            scene.name,
            scene.objects.len(),
            scene.model.len()
        )?;
        writeln!(
            out,
            "law             {} aerodynamics",
            scene.model.aero.name()
        )?;
        writeln!(
            out,
            "integrator      {} (dt = {:.4e} s, {} steps, {} force evaluations)",
            s.integrator, s.dt, s.steps, s.force_evaluations
        )?;
        writeln!(
            out,
            "simulated       {:.3} s in {:.4} s wall ({:.2e} wall s per simulated s)",
            s.simulated_s,
            s.wall_s,
            s.wall_s / s.simulated_s
        )?;
        writeln!(
            out,
            "events          {} ground contacts resolved, {} springs broken",
            s.contacts_resolved, s.broken_springs
        )?;
        let k = s.skips;
        if k.wind_skipped + k.wind_evaluated > 0 {
            writeln!(
                out,
                "skipped         {} of {} wind primitive evaluations (object × primitive × force evaluation): the primitive could not reach the object",
                k.wind_skipped,
                k.wind_skipped + k.wind_evaluated
            )?;
        }
        writeln!(out, "output          {} ({files} files)", dir.display())?;
        if let Some(note) = export_note {
            writeln!(out, "export          {note}")?;
        }
        Ok(())
    })
}
