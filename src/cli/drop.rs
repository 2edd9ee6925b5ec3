//! `drop` and `check`: one leaf's fall in still air, and the stable time
//! steps of a leaf (or, with `--stress`, every integrator on stiff and
//! extreme cases of it).

use super::args::{CheckArgs, DropArgs, law_word};
use super::{input, report};
use anyhow::{Context, Result, bail};
use leafmagic::motion::classify;
use leafmagic::physics::params::{Integrator, TimeStep};
use leafmagic::physics::stability;
use leafmagic::sim::drop::{self, DropParams};
use leafmagic::sim::stress;
use serde_json::json;
use std::time::Instant;

/// `drop`: drops the leaf, writes what was asked for and reports the fall.
pub fn drop(args: DropArgs) -> Result<()> {
    let (spec, model) = input::leaf(&args.leaf, args.law)?;
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
                eprintln!("{}", report::drop::step_warning(h, args.integrator, limit));
            }
        }
    }
    let failed = |e: &dyn std::fmt::Display| anyhow::anyhow!("{}: {e}", args.leaf);
    let work = drop::drop_work(&model, &params).map_err(|e| failed(&e))?;
    let frame_dt = 1.0 / drop::FRAME_RATE;
    let mut bar = super::progress::long_run(&work, &model, frame_dt, "drop", args.max_work);
    let mut tick = |k: u64, _: u64| {
        if let Some(b) = &bar {
            b.set_position(k);
        }
    };
    let result = drop::drop_leaf_with_work(
        &model,
        &params,
        &work,
        args.max_work,
        bar.is_some()
            .then_some(&mut tick as &mut dyn FnMut(u64, u64)),
    )
    .map_err(|e| failed(&e))?;
    if let Some(b) = bar.take() {
        b.finish_and_clear();
    }
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
            "law": law_word(spec.aero.law),
            "aero_law": spec.aero.law,
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
        print!(
            "{}",
            report::drop::fall(&named(&spec), &model, stats, &class, args.out.as_deref())
        );
    }
    Ok(())
}

/// A leaf's name and law for a report: `leaf-a, paper law`.
fn named(spec: &leafmagic::leaf::LeafSpec) -> String {
    format!("{}, {} law", spec.name, law_word(spec.aero.law))
}

/// `check`: the stability estimate of a leaf and each integrator's stable
/// and automatic steps; with `--stress`, the stress matrix.
pub fn check(args: CheckArgs) -> Result<()> {
    if args.stress {
        return check_stress(args);
    }
    let (spec, model) = input::leaf(&args.leaf, args.law)?;
    let est = stability::estimate(&model);
    // What `drop` refuses, `check` refuses, with the same message.
    leafmagic::physics::run::check_estimate(&est)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.leaf))?;
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
            "law": law_word(spec.aero.law),
            "aero_law": spec.aero.law,
            "omega_max": est.omega_max,
            "omega_bounds": [est.omega_lower, est.omega_upper],
            "power_iteration_converged": est.power_converged,
            "omega_with_added_mass": est.with_added_mass,
            "zeta": est.zeta,
            "drag_rate": est.drag_rate,
            "damping_rate_max": est.damping_rate_max,
            "tumbling_rate": est.tumbling_rate,
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
    print!(
        "{}",
        report::drop::stability(&named(&spec), &model, &est, &rows)
    );
    Ok(())
}

/// `check --stress`: every stress case of the leaf with every integrator.
fn check_stress(args: CheckArgs) -> Result<()> {
    let started = Instant::now();
    let (name, model, initial) = input::problem(&args.leaf, args.law)?;
    let cases = stress::cases(&model, &initial)
        .map_err(|e| anyhow::anyhow!("{}: cannot build a stress case: {e}", args.leaf))?;
    let rows = stress::run_matrix(&cases, args.explicit, args.substep_cap);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
        return Ok(());
    }
    print!(
        "{}",
        report::drop::stress(
            &name,
            &cases,
            &rows,
            args.explicit,
            started.elapsed().as_secs_f64()
        )
    );
    Ok(())
}
