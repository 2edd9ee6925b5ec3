//! `accuracy`: error against cost of every integrator over a sweep of time
//! steps (accuracy.csv, accuracy.svg), or with `--long`, classes and
//! statistics of a long fall across steps (accuracy-long.csv).

use super::args::AccuracyArgs;
use super::{input, report};
use anyhow::{Context, Result, bail};
use leafmagic::physics::model::Model;
use leafmagic::physics::run::approximate_duration;
use leafmagic::sim::accuracy::{self, SweepSettings, long::LongReport, long::LongSettings};
use std::time::Instant;

/// A sweep estimated to take longer than this (s of one core) says so
/// before it starts.
const LONG_SWEEP_S: f64 = 60.0;

/// `accuracy`: runs the sweep (or the long comparison), writes its files
/// and reports it.
pub fn accuracy(args: AccuracyArgs) -> Result<()> {
    let started = Instant::now();
    let (name, model, initial) = input::problem(&args.leaf, args.law)?;
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
    // The reference was chosen from RK4's range, swept or not.
    if !args.integrators.is_empty() {
        settings
            .ranges
            .retain(|r| args.integrators.contains(&r.integrator));
    }
    settings.runs = args.runs;
    if let Some(j) = args.reference_j {
        settings.reference_j = j;
        settings.refine_reference = false;
    }
    let cost = accuracy::estimated_cost(&accuracy::smooth_model(&model).0, &initial, &settings);
    // Refining the reference may at most double the sweep (at least a
    // minute): each halving costs twice the last.
    settings.refine_budget_s = cost.total_s().max(LONG_SWEEP_S);
    if cost.total_s() > LONG_SWEEP_S {
        let parts: Vec<String> = cost
            .per_integrator
            .iter()
            .map(|(integrator, s)| format!("{integrator} {}", approximate_duration(*s)))
            .chain(std::iter::once(format!(
                "reference {}",
                approximate_duration(cost.reference_s)
            )))
            .collect();
        eprintln!(
            "note: this sweep needs {} of one core ({}; from a short run of each), up to \
             twice that if the reference must be refined; --seconds shortens every run, \
             --runs 1 times each point once, --integrators sweeps only those named",
            approximate_duration(cost.total_s()),
            parts.join(", "),
        );
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
    print!(
        "{}",
        report::accuracy::sweep(
            &name,
            model.len(),
            seconds,
            &report,
            (&csv_path, &svg_path),
            started.elapsed().as_secs_f64()
        )
    );
    Ok(())
}

/// `accuracy --long`: the long comparison across steps, into
/// accuracy-long.csv.
fn accuracy_long(
    args: &AccuracyArgs,
    name: &str,
    model: &Model,
    seconds: f64,
    started: Instant,
) -> Result<()> {
    let defaults = LongSettings::default();
    let settings = LongSettings {
        seconds,
        integrators: if args.integrators.is_empty() {
            defaults.integrators.clone()
        } else {
            defaults
                .integrators
                .iter()
                .copied()
                .filter(|i| args.integrators.contains(i))
                .collect()
        },
        ..defaults
    };
    let report = accuracy::long::long_sweep(model, &settings)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.leaf))?;
    let path = args.out.join("accuracy-long.csv");
    leafmagic::util::io::write_atomic(&path, long_csv(&report).as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))?;
    print!(
        "{}",
        report::accuracy::long(
            name,
            &settings,
            &report,
            &path,
            started.elapsed().as_secs_f64()
        )
    );
    Ok(())
}

/// accuracy-long.csv: a row per (integrator, step); empty cells where a
/// statistic or the class is missing.
fn long_csv(report: &LongReport) -> String {
    use std::fmt::Write as _;
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
    csv
}
