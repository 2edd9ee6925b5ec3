//! The human reports of `accuracy`: the work-precision sweep (orders,
//! stable steps, the cheapest run to each error), and with `--long` the
//! classes and statistics of a long fall across steps.

use super::text;
use leafmagic::sim::accuracy::SweepReport;
use leafmagic::sim::accuracy::long::{self, LongReport, LongSettings, Stat};
use std::fmt::Write as _;
use std::path::Path;

/// `accuracy`: how the sweep of `leaf` (`particles` particles, `seconds`
/// simulated) was measured, a table of each integrator's order and stable
/// step, a table of the cheapest run to each error, the warnings, then the
/// files written (`csv`, `svg`) and the command's wall time.
pub fn sweep(
    leaf: &str,
    particles: usize,
    seconds: f64,
    report: &SweepReport,
    (csv, svg): (&Path, &Path),
    elapsed_s: f64,
) -> String {
    text(|out| {
        let r = &report.reference;
        writeln!(
            out,
            "leaf         {leaf} ({particles} particles, chord {:.4} m), released as `drop` releases it; T = {seconds} s",
            report.chord
        )?;
        writeln!(
            out,
            "error        RMS particle position error at T / chord, against the reference"
        )?;
        writeln!(
            out,
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
        )?;
        if let Some(first) = &report.refined_from {
            writeln!(
                out,
                "             (halved from h = {:.4e} s, which differed by {:.2e} chords: not valid)",
                first.dt, first.self_difference
            )?;
        }
        writeln!(
            out,
            "events       {}",
            if report.breaking_disabled > 0 {
                format!(
                    "spring breaking switched off for the sweep ({} breakable springs); no ground",
                    report.breaking_disabled
                )
            } else {
                "none (no breakable springs, no ground)".to_string()
            }
        )?;
        writeln!(
            out,
            "work         median wall time of {} runs per point (stepping only), force evaluations",
            report.runs
        )?;
        writeln!(out)?;
        orders_table(out, report)?;
        writeln!(out)?;
        cheapest_table(out, report)?;
        for w in &report.warnings {
            writeln!(out, "warning: {w}")?;
        }
        writeln!(out)?;
        writeln!(
            out,
            "wrote        {} ({} rows), {}",
            csv.display(),
            report.rows.len(),
            svg.display()
        )?;
        writeln!(out, "finished in  {elapsed_s:.1} s")
    })
}

/// The table of each integrator's fitted order, pairwise orders and
/// stable step against the estimate's.
fn orders_table(out: &mut String, report: &SweepReport) -> std::fmt::Result {
    writeln!(
        out,
        "{:<11} {:>6} {:>4} {:>4}  {:<22} {:>12} {:>12} {:>12} {:>7}",
        "integrator",
        "order",
        "exp.",
        "pts",
        "pairwise (finest 3)",
        "stable dt",
        "unstable at",
        "check dt_max",
        "ratio"
    )?;
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
        writeln!(
            out,
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
        )?;
    }
    Ok(())
}

/// The table of the cheapest run to each error, or its extrapolation.
fn cheapest_table(out: &mut String, report: &SweepReport) -> std::fmt::Result {
    writeln!(
        out,
        "{:<11} {:<44} cheapest run to error ≤ 1e-6",
        "integrator", "cheapest run to error ≤ 1e-3"
    )?;
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
        writeln!(
            out,
            "{:<11} {:<44} {}",
            s.integrator.name(),
            cells[0],
            cells[1]
        )?;
    }
    Ok(())
}

/// A wall time in seconds from one second up, else in milliseconds.
fn ms(seconds: f64) -> String {
    if seconds >= 1.0 {
        format!("{seconds:.2} s")
    } else {
        format!("{:.3} ms", seconds * 1e3)
    }
}

/// `accuracy --long`: the ensemble and the horizon of pointwise error, a
/// row per (integrator, step) with its class and statistics, then from
/// which step each integrator agrees with its finest, the file written
/// (`csv`) and the command's wall time.
pub fn long(
    leaf: &str,
    settings: &LongSettings,
    report: &LongReport,
    csv: &Path,
    elapsed_s: f64,
) -> String {
    let seconds = settings.seconds;
    text(|out| {
        writeln!(
            out,
            "leaf         {leaf}: {} drops per step, tilts {:.2}°…{:.2}° about x, {seconds} s each",
            settings.ensemble,
            10.0 - settings.tilt_spread_deg / 2.0,
            10.0 + settings.tilt_spread_deg / 2.0
        )?;
        match report.horizon_s {
            Some(t) => writeln!(
                out,
                "horizon      twin RK4 drops {:.0e} chords apart separate by {:.0e} chords at t = {t:.2} s \
                 (h = {:.3e} s): pointwise error means nothing after that",
                long::TWIN_SEPARATION,
                long::HORIZON_SEPARATION,
                report.horizon_dt
            )?,
            None => writeln!(
                out,
                "horizon      twin RK4 drops {:.0e} chords apart stay within {:.0e} chords for the whole {seconds} s",
                long::TWIN_SEPARATION,
                long::HORIZON_SEPARATION
            )?,
        }
        writeln!(out)?;
        writeln!(
            out,
            "{:<11} {:>11}  {:<22} {:>22} {:>22}",
            "integrator", "dt (s)", "class (agreement)", "descent m/s (±95 %)", "rotation turns/s"
        )?;
        let fmt_stat = |s: Option<Stat>| {
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
            writeln!(
                out,
                "{:<11} {:>11.4e}  {:<22} {:>22} {:>22}",
                r.integrator.name(),
                r.dt,
                class,
                fmt_stat(r.descent_speed),
                fmt_stat(r.rotation_rate)
            )?;
        }
        writeln!(out)?;
        for s in &report.summaries {
            let class = s
                .finest_class
                .map_or("no class".to_string(), |c| c.to_string());
            let from = |h: Option<f64>| {
                h.map_or("never (not even the finest)".to_string(), |h| {
                    format!("dt ≤ {h:.4e} s")
                })
            };
            writeln!(
                out,
                "{:<11} class {class} from {}; descent speed and rotation rate agree from {}",
                s.integrator.name(),
                from(s.class_stable_from),
                from(s.stats_stable_from)
            )?;
        }
        writeln!(out)?;
        writeln!(out, "wrote        {}", csv.display())?;
        writeln!(out, "finished in  {elapsed_s:.1} s")
    })
}
