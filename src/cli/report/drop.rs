//! The human reports of `drop` and `check`: a fall's summary, a leaf's
//! stable steps, and the stress matrix of `check --stress`.

use super::text;
use leafmagic::motion::classify::Classification;
use leafmagic::physics::model::Model;
use leafmagic::physics::params::Integrator;
use leafmagic::physics::run::RunStats;
use leafmagic::physics::stability::StabilityEstimate;
use leafmagic::sim::stress::{self, ExplicitPolicy, Outcome, StressCase, StressRow};
use std::fmt::Write as _;
use std::path::Path;

/// The warning `drop` gives before a fixed step `h` above `limit`, the
/// estimated stable step of `integrator` (one line, without its newline).
/// Above the limit the stiffest mode grows every step; it may run away, or
/// the springs' nonlinearity may hold it in a bounded ringing that no
/// divergence check stops (docs/design/accuracy.md, "Stable limits").
pub fn step_warning(h: f64, integrator: Integrator, limit: f64) -> String {
    format!(
        "warning: dt = {h:.3e} s exceeds the estimated stable step of {integrator} ({limit:.3e} s); \
         the stiffest mode grows every step: the run will diverge, or end with its springs \
         ringing step to step, which a 240 Hz trajectory does not show"
    )
}

/// `drop`: the leaf, the run's numbers and the fall's classification, then
/// the trajectory file if one was written.
pub fn fall(
    leaf: &str,
    model: &Model,
    stats: &RunStats,
    class: &Classification,
    trajectory: Option<&Path>,
) -> String {
    text(|out| {
        writeln!(
            out,
            "leaf            {} (chord {:.4} m, {:.3e} kg)",
            leaf,
            model.chord(),
            model.total_mass()
        )?;
        writeln!(
            out,
            "integrator      {} (dt = {:.4e} s, {} steps, {} force evaluations)",
            stats.integrator, stats.dt, stats.steps, stats.force_evals
        )?;
        writeln!(
            out,
            "simulated       {:.3} s in {:.4} s wall ({:.2e} wall s per simulated s)",
            stats.simulated_s,
            stats.wall_s,
            stats.wall_s / stats.simulated_s
        )?;
        out.push_str(&super::motion::class(class));
        if let Some(path) = trajectory {
            writeln!(out, "trajectory      {}", path.display())?;
        }
        Ok(())
    })
}

/// A row of `check`'s table: an integrator, its stable step, and its
/// automatic step in a drop and in a scene, s (`None`: unbounded, none).
pub type Steps = (Integrator, Option<f64>, Option<f64>, Option<f64>);

/// `check`: the stability estimate of `model`, a table of `steps` (one row
/// per integrator), then the estimate's warnings.
pub fn stability(leaf: &str, model: &Model, est: &StabilityEstimate, steps: &[Steps]) -> String {
    text(|out| {
        writeln!(
            out,
            "leaf               {} ({} particles, {} springs, {} triangles)",
            leaf,
            model.len(),
            model.springs.len(),
            model.triangles.len()
        )?;
        writeln!(
            out,
            "stiffest mode      ω_max = {:.1} rad/s{} (bounds {:.1} … {:.1}; power iteration {}), ζ = {:.3}",
            est.omega_max,
            if est.with_added_mass {
                " with the added mass"
            } else {
                ""
            },
            est.omega_lower,
            est.omega_upper,
            if est.power_converged {
                "converged"
            } else {
                "not converged, margin applied"
            },
            est.zeta
        )?;
        if let Some(s) = est.stiffest_spring {
            let sp = &model.springs[s];
            writeln!(
                out,
                "stiffest spring    {s} (particles {}–{}, k = {} N/m)",
                sp.i, sp.j, sp.stiffness
            )?;
        }
        writeln!(
            out,
            "lightest particle  {} ({:.3e} kg; heaviest/lightest = {:.1})",
            est.lightest_particle, model.mass[est.lightest_particle], est.mass_ratio
        )?;
        writeln!(
            out,
            "drag time const.   {:.4} s (γ_max = {:.2} 1/s)",
            est.drag_time_constant(),
            est.drag_rate
        )?;
        writeln!(
            out,
            "fastest damping    {:.2} 1/s (dashpots and air, λ_max of M⁻¹C)",
            est.damping_rate_max
        )?;
        if let Some(step) = est.tumbling_step() {
            writeln!(
                out,
                "tumbling           Ω ≤ {:.1} rad/s (2 U_face / narrowest plate): dt ≤ {step:.4e} s at {} rad per step",
                est.tumbling_rate,
                leafmagic::physics::stability::MAX_TURN_PER_STEP
            )?;
        }
        writeln!(out)?;
        // Drops interpolate their frames and take the auto step as it is;
        // scenes step onto every frame and take the largest divisor below it.
        writeln!(
            out,
            "{:<12} {:>14} {:>14} {:>14}",
            "integrator", "dt_max (s)", "drop auto (s)", "scene auto (s)"
        )?;
        for &(i, m, a, snapped) in steps {
            let m = match m {
                None => "unbounded".to_string(),
                Some(v) if v <= 0.0 => "unstable".to_string(),
                Some(v) => format!("{v:.4e}"),
            };
            let a = a.map_or("none".to_string(), |v| format!("{v:.4e}"));
            let snapped = snapped.map_or("none".to_string(), |v| format!("{v:.4e}"));
            writeln!(out, "{:<12} {:>14} {:>14} {:>14}", i.name(), m, a, snapped)?;
        }
        for w in &est.warnings {
            writeln!(out, "warning: {w}")?;
        }
        Ok(())
    })
}

/// `check --stress`: the cases, one line per (case, integrator) row, the
/// totals and a legend; `elapsed_s` is the command's wall time.
pub fn stress(
    leaf: &str,
    cases: &[StressCase],
    rows: &[StressRow],
    explicit: ExplicitPolicy,
    elapsed_s: f64,
) -> String {
    text(|out| {
        writeln!(
            out,
            "leaf        {leaf}: {} cases × {} integrators, {} s each (one step at least); explicit above dt_max: {explicit}",
            cases.len(),
            Integrator::ALL.len(),
            stress::STRESS_SECONDS,
        )?;
        for c in cases {
            writeln!(out, "  {:<19} {}", c.name, c.description)?;
        }
        writeln!(out)?;
        writeln!(
            out,
            "{:<19} {:<10} {:<6} {:>10} {:>11} {:>5} {:>11} {:>10}  detail",
            "case", "integrator", "result", "dt (s)", "dt_max (s)", "sub", "energy", "strain"
        )?;
        for r in rows {
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
            writeln!(out, "{}", line.trim_end())?;
        }
        let ok = rows.iter().filter(|r| r.outcome == Outcome::Ok).count();
        let finite = rows.iter().filter(|r| r.all_finite).count();
        writeln!(out)?;
        writeln!(
            out,
            "{} rows: {ok} finished finite, {} stopped with a diagnosis; all numbers finite in {finite}/{} rows",
            rows.len(),
            rows.len() - ok,
            rows.len()
        )?;
        writeln!(
            out,
            "energy = drift (E(T) − E(0) − W_air+dampers) / energy turnover, E = kinetic + gravitational + spring + bending"
        )?;
        writeln!(
            out,
            "strain = largest |l − L|/L of any spring during the run; sub = sub-steps per step"
        )?;
        writeln!(out, "finished in {elapsed_s:.1} s")
    })
}
