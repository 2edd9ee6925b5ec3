//! The work-precision sweep (the folder's docs, "The sweep"): every point
//! of every integrator timed and measured against the reference, the
//! reference refined until it validates, the observed orders fitted and
//! the stability limits bisected; what it found, and its rows as
//! accuracy.csv.

use super::error::AccuracyError;
use super::estimate;
use super::run::{
    EndRun, REFERENCE_FACTOR, Reference, finer_reference, reference, rms_difference, run_steps,
    smooth_model, step_size,
};
use super::settings::{MAX_STEPS_LOG2, SweepSettings};
use crate::physics::model::Model;
use crate::physics::params::Integrator;
use crate::physics::stability;
use crate::physics::state::State;
use crate::util::setting::Setting;
use nalgebra::Vector3;
use serde::Serialize;

type V3 = Vector3<f64>;

/// Only errors at least this many times the reference's self-difference
/// enter the order fit: the reference error then moves them by ≤ 1 %.
pub const FIT_FLOOR_FACTOR: f64 = 100.0;
/// Errors above this (in chords) are outside the asymptotic regime and stay
/// out of the order fit.
pub const FIT_MAX_ERROR: f64 = 1e-2;
/// The accuracy targets of the summary table, in chords.
pub const TOLERANCES: [f64; 2] = [1e-3, 1e-6];
/// The stability-limit bisection stops when the step count is known to
/// this relative precision.
const LIMIT_PRECISION: f64 = 0.01;

/// A reference that did not validate and was refined: its step h_ref/2
/// and its self-difference.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RefinedFrom {
    /// h_ref/2, s.
    pub dt: f64,
    /// Its RMS difference from the run at h_ref, chords.
    pub self_difference: f64,
}

/// One point of the sweep: one CSV row.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SweepRow {
    /// The integrator.
    pub integrator: Integrator,
    /// The step, s.
    pub dt: f64,
    /// RMS particle position error at T over the chord; `None` if the run
    /// diverged or rang (its end state is no solution to measure).
    pub error: Option<f64>,
    /// Median wall time of the stepping loop over the timed runs, s (up to
    /// the divergence for diverged runs).
    pub wall_s: f64,
    /// Force evaluations of one run.
    pub force_evals: u64,
    /// The run stopped before T.
    pub diverged: bool,
    /// The run reached T in a bounded step-to-step oscillation of its
    /// unstable mode ([`EndRun::oscillating`]).
    pub oscillating: bool,
}

impl SweepRow {
    /// Whether the step is above the stable limit: the run stopped or rang.
    pub fn unstable(&self) -> bool {
        self.diverged || self.oscillating
    }
}

/// The cheapest run that reached an error target.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Cheapest {
    /// The target, chords.
    pub tolerance: f64,
    /// The run's step, s.
    pub dt: f64,
    /// Its error, chords.
    pub error: f64,
    /// Its median wall time, s.
    pub wall_s: f64,
    /// Its force evaluations.
    pub force_evals: u64,
}

/// Per-integrator findings of a sweep.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// The integrator.
    pub integrator: Integrator,
    /// Its theoretical order.
    pub expected_order: u32,
    /// Least-squares slope of log error against log h over the fit points.
    pub order: Option<f64>,
    /// How many points the fit used.
    pub fit_points: usize,
    /// log₂(e(h)/e(h/2)) for consecutive fit points, largest h first.
    pub pairwise_orders: Vec<f64>,
    /// The largest step that reached T without diverging (after bisection).
    pub largest_stable_dt: Option<f64>,
    /// The smallest step that diverged (after bisection).
    pub smallest_diverged_dt: Option<f64>,
    /// The stable step `check` predicts (`None`: unconditionally stable;
    /// `Some(0)`: never stable).
    pub predicted_dt_max: Option<f64>,
    /// The cheapest run (least wall time) reaching each of [`TOLERANCES`].
    pub cheapest: Vec<Option<Cheapest>>,
    /// For each of [`TOLERANCES`] that no run reached: the step and cost it
    /// would take, extrapolated from the finest run with the fitted order.
    pub extrapolated: Vec<Option<Extrapolation>>,
}

/// What an error target no run reached would cost, extrapolated from the
/// finest non-diverged run (h₀, e₀, wall₀) with the fitted order p:
/// h = h₀ (tol/e₀)^(1/p), wall = wall₀ h₀/h, evaluations likewise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Extrapolation {
    /// The target, chords.
    pub tolerance: f64,
    /// The step it needs, s.
    pub dt: f64,
    /// The wall time it would take, s.
    pub wall_s: f64,
    /// The force evaluations it would take.
    pub force_evals: f64,
}

/// Everything a sweep found.
#[derive(Clone, Debug, Serialize)]
pub struct SweepReport {
    /// Simulated duration, s.
    pub seconds: f64,
    /// Timed runs per point.
    pub runs: usize,
    /// The length scale of the errors (the model's chord), m.
    pub chord: f64,
    /// Springs whose breaking was switched off for the sweep.
    pub breaking_disabled: usize,
    /// The reference.
    pub reference: Reference,
    /// The reference first computed, where it did not validate and was
    /// halved until it did ([`SweepSettings::refine_reference`]).
    pub refined_from: Option<RefinedFrom>,
    /// The smallest error plotted, chords.
    pub smallest_error: Option<f64>,
    /// Whether the reference passed self-convergence validation.
    pub reference_valid: bool,
    /// One row per (integrator, dt) of the sweep, in sweep order.
    pub rows: Vec<SweepRow>,
    /// Per-integrator findings, in [`Integrator::ALL`] order.
    pub summaries: Vec<Summary>,
    /// Things the user must know to read the results.
    pub warnings: Vec<String>,
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// One untimed warm-up run (whose end state gives the error: every run is
/// identical, bit for bit), then `runs` timed runs; returns the warm-up run
/// with the median wall time. The warm-up takes the cold caches and page
/// faults that would otherwise inflate the first timing.
fn timed(
    model: &Model,
    initial: &State,
    integrator: Integrator,
    dt: f64,
    steps: u64,
    runs: usize,
) -> EndRun {
    let first = run_steps(model, initial, integrator, dt, steps);
    let mut walls: Vec<f64> = (0..runs)
        .map(|_| run_steps(model, initial, integrator, dt, steps).wall_s)
        .collect();
    EndRun {
        wall_s: median(&mut walls),
        ..first
    }
}

/// Sweeps every integrator of `settings` on `model` from `initial` (the
/// model is used as given: call [`smooth_model`] first to switch breaking
/// off, as [`sweep_leaf`] does).
pub fn sweep(
    model: &Model,
    initial: &State,
    settings: &SweepSettings,
) -> Result<SweepReport, AccuracyError> {
    settings.validate()?;
    let seconds = settings.seconds;
    let chord = model.chord();
    let mut reference = reference(model, initial, seconds, settings.reference_j)?;
    let est = stability::estimate(model);
    let mut rows = Vec::new();
    // Each row's end positions, to measure again against a refined
    // reference (`None` where the row has no error).
    let mut ends: Vec<Option<Vec<V3>>> = Vec::new();
    let mut summaries = Vec::new();
    for range in &settings.ranges {
        let integrator = range.integrator;
        let start = rows.len();
        for j in range.j_min..=range.j_max {
            let dt = step_size(seconds, j);
            let run = timed(model, initial, integrator, dt, 1 << j, settings.runs);
            let diverged = run.error.is_some();
            let oscillating = run.oscillating(&reference);
            ends.push((!diverged && !oscillating).then(|| run.state.position.clone()));
            rows.push(SweepRow {
                integrator,
                dt,
                error: (!diverged && !oscillating)
                    .then(|| rms_difference(&run.state.position, &reference.positions, chord)),
                wall_s: run.wall_s,
                force_evals: run.force_evals,
                diverged,
                oscillating,
            });
        }
        let mine = &rows[start..];
        let (stable, diverged) = if settings.locate_limits {
            locate_limit(model, initial, integrator, seconds, mine, &reference)
        } else {
            stability_bracket(mine)
        };
        summaries.push(Summary {
            integrator,
            expected_order: integrator.order(),
            order: None,
            fit_points: 0,
            pairwise_orders: Vec::new(),
            largest_stable_dt: stable,
            smallest_diverged_dt: diverged,
            predicted_dt_max: est.dt_max(integrator),
            // Filled below, once the reference is final.
            cheapest: Vec::new(),
            extrapolated: Vec::new(),
        });
    }
    let smallest = |rows: &[SweepRow]| {
        rows.iter()
            .filter_map(|r| r.error)
            .filter(|e| *e > 0.0)
            .min_by(f64::total_cmp)
    };
    let valid = |reference: &Reference, smallest: Option<f64>| match smallest {
        Some(e) => reference.self_difference < REFERENCE_FACTOR * e,
        None => true,
    };
    // A law whose forces have kinks (the unsteady law's angle of attack,
    // edge-on and broadside) holds RK4 to second order, and its reference
    // at the default step then does not validate: halve it until it does,
    // as the error estimate does (`estimate`), and measure every point
    // again against it.
    let mut refined_from = None;
    let mut refining_s = 0.0;
    let mut over_budget = None;
    while settings.refine_reference
        && !valid(&reference, smallest(&rows))
        && reference.self_difference >= estimate::ROUND_OFF_CHORDS
        && (2.0 * seconds / reference.dt).round() <= f64::from(2u32.pow(MAX_STEPS_LOG2))
    {
        let next_s = 2.0 * reference.wall_s;
        if refining_s + next_s > settings.refine_budget_s {
            over_budget = Some(next_s);
            break;
        }
        refining_s += next_s;
        let finer = finer_reference(model, initial, seconds, &reference.positions, reference.dt)?;
        refined_from.get_or_insert(RefinedFrom {
            dt: reference.dt,
            self_difference: reference.self_difference,
        });
        reference = finer;
        for (row, end) in rows.iter_mut().zip(&ends) {
            if let Some(end) = end {
                row.error = Some(rms_difference(end, &reference.positions, chord));
            }
        }
    }
    for summary in &mut summaries {
        let mine: Vec<SweepRow> = rows
            .iter()
            .filter(|r| r.integrator == summary.integrator)
            .cloned()
            .collect();
        summary.cheapest = TOLERANCES.iter().map(|&tol| cheapest(&mine, tol)).collect();
    }
    let smallest_error = smallest(&rows);
    let mut warnings = Vec::new();
    let reference_valid = valid(&reference, smallest_error);
    if let Some(next_s) = over_budget {
        warnings.push(format!(
            "reference refinement stopped at h_ref/2 = {:.3e} s: the next halving would take \
             about {next_s:.0} s, past the {:.0} s allowed; {} pins a finer one",
            reference.dt,
            settings.refine_budget_s,
            Setting::ReferenceJ
        ));
    }
    if !reference_valid {
        warnings.push(format!(
            "reference not converged: RK4 at h_ref = {:.3e} s and h_ref/2 differ by {:.3e} chords, \
             more than {REFERENCE_FACTOR} × the smallest error plotted ({:.3e}); \
             errors near that level are unreliable: use a finer reference",
            2.0 * reference.dt,
            reference.self_difference,
            smallest_error.unwrap_or(f64::NAN)
        ));
    }
    for s in &mut summaries {
        fit_order(s, &rows, reference.self_difference, &mut warnings);
    }
    Ok(SweepReport {
        seconds,
        runs: settings.runs,
        chord,
        breaking_disabled: 0,
        reference,
        refined_from,
        smallest_error,
        reference_valid,
        rows,
        summaries,
        warnings,
    })
}

/// Fits `s`'s order of convergence to its integrator's errors in `rows`
/// between [`FIT_FLOOR_FACTOR`] × the reference's `self_difference` and
/// [`FIT_MAX_ERROR`], and extrapolates the tolerances it does not reach;
/// says in `warnings` when too few points lie there.
fn fit_order(s: &mut Summary, rows: &[SweepRow], self_difference: f64, warnings: &mut Vec<String>) {
    let fit: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.integrator == s.integrator)
        .filter_map(|r| r.error.map(|e| (r.dt, e)))
        .filter(|&(_, e)| e >= FIT_FLOOR_FACTOR * self_difference && e <= FIT_MAX_ERROR)
        .collect();
    s.fit_points = fit.len();
    s.order = (fit.len() >= 3).then(|| loglog_slope(&fit));
    s.pairwise_orders = fit
        .windows(2)
        .map(|w| (w[0].1 / w[1].1).ln() / (w[0].0 / w[1].0).ln())
        .collect();
    let finest = rows
        .iter()
        .filter(|r| r.integrator == s.integrator && r.error.is_some_and(|e| e > 0.0))
        .min_by(|a, b| a.dt.total_cmp(&b.dt));
    s.extrapolated = TOLERANCES
        .iter()
        .zip(&s.cheapest)
        .map(|(&tolerance, reached)| match (reached, s.order, finest) {
            (None, Some(p), Some(f)) if p > 0.0 => {
                let e0 = f.error.unwrap_or(f64::NAN);
                let ratio = (e0 / tolerance).powf(1.0 / p);
                Some(Extrapolation {
                    tolerance,
                    dt: f.dt / ratio,
                    wall_s: f.wall_s * ratio,
                    force_evals: f.force_evals as f64 * ratio,
                })
            }
            _ => None,
        })
        .collect();
    if s.order.is_none() {
        warnings.push(format!(
            "{}: only {} point(s) between {:.0} × the reference's self-difference and \
             {FIT_MAX_ERROR:.0e} chords; no order fitted",
            s.integrator,
            fit.len(),
            FIT_FLOOR_FACTOR
        ));
    }
}

/// [`sweep`] on a copy of `model` with breaking switched off, noting it.
pub fn sweep_leaf(
    model: &Model,
    initial: &State,
    settings: &SweepSettings,
) -> Result<SweepReport, AccuracyError> {
    let (smooth, disabled) = smooth_model(model);
    let mut report = sweep(&smooth, initial, settings)?;
    report.breaking_disabled = disabled;
    if disabled > 0 {
        report.warnings.push(format!(
            "spring breaking switched off for the sweep ({disabled} breakable springs): \
             a break is an event that limits every scheme to first order"
        ));
    }
    Ok(report)
}

/// Slope of the least-squares line through (ln x, ln y).
pub fn loglog_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (mut sx, mut sy) = (0.0, 0.0);
    for &(x, y) in points {
        sx += x.ln();
        sy += y.ln();
    }
    let (mx, my) = (sx / n, sy / n);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for &(x, y) in points {
        let (dx, dy) = (x.ln() - mx, y.ln() - my);
        sxy += dx * dy;
        sxx += dx * dx;
    }
    sxy / sxx
}

/// The largest stable step below every unstable one (diverged or ringing),
/// and the smallest unstable step above it, from the sweep's points alone.
fn stability_bracket(rows: &[SweepRow]) -> (Option<f64>, Option<f64>) {
    // Rows go from large to small h; the limit is where instability stops.
    let last_unstable = rows.iter().rposition(SweepRow::unstable);
    match last_unstable {
        None => (rows.first().map(|r| r.dt), None),
        Some(k) => (rows.get(k + 1).map(|r| r.dt), Some(rows[k].dt)),
    }
}

/// [`stability_bracket`] refined by bisecting the step count n (h = T/n)
/// between the stable and the diverged step.
fn locate_limit(
    model: &Model,
    initial: &State,
    integrator: Integrator,
    seconds: f64,
    rows: &[SweepRow],
    reference: &Reference,
) -> (Option<f64>, Option<f64>) {
    let (stable, diverged) = stability_bracket(rows);
    let (Some(hs), Some(hd)) = (stable, diverged) else {
        return (stable, diverged);
    };
    let mut n_stable = (seconds / hs).round() as u64;
    let mut n_diverged = (seconds / hd).round() as u64;
    while n_stable > n_diverged + 1
        && (n_stable - n_diverged) as f64 > LIMIT_PRECISION * n_stable as f64
    {
        let mid = n_diverged + (n_stable - n_diverged) / 2;
        let run = run_steps(model, initial, integrator, seconds / mid as f64, mid);
        if run.unstable(reference) {
            n_diverged = mid;
        } else {
            n_stable = mid;
        }
    }
    (
        Some(seconds / n_stable as f64),
        Some(seconds / n_diverged as f64),
    )
}

fn cheapest(rows: &[SweepRow], tolerance: f64) -> Option<Cheapest> {
    rows.iter()
        .filter_map(|r| r.error.filter(|&e| e <= tolerance).map(|e| (r, e)))
        .min_by(|a, b| a.0.wall_s.total_cmp(&b.0.wall_s))
        .map(|(r, error)| Cheapest {
            tolerance,
            dt: r.dt,
            error,
            wall_s: r.wall_s,
            force_evals: r.force_evals,
        })
}

/// The header of `accuracy.csv`.
pub const CSV_HEADER: &str = "integrator,dt,error,wall_s,force_evals,diverged,oscillating";

/// The rows as CSV (header [`CSV_HEADER`]); numbers in Rust's shortest
/// round-trip form; `error` is empty for unstable rows (a diverged run
/// stopped before T; an oscillating one ended ringing, no solution).
pub fn csv(rows: &[SweepRow]) -> String {
    use std::fmt::Write as _;
    let mut out = String::from(CSV_HEADER);
    out.push('\n');
    for r in rows {
        let error = r.error.map_or(String::new(), |e| e.to_string());
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{}",
            r.integrator, r.dt, error, r.wall_s, r.force_evals, r.diverged, r.oscillating
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loglog_slope_recovers_a_power_law() {
        let points: Vec<(f64, f64)> = (0..6)
            .map(|k| {
                let h = 0.1 / f64::from(2u32.pow(k));
                (h, 3.0 * h.powi(4))
            })
            .collect();
        assert!((loglog_slope(&points) - 4.0).abs() < 1e-12);
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
    }

    fn row(dt: f64, diverged: bool) -> SweepRow {
        SweepRow {
            integrator: Integrator::Verlet,
            dt,
            error: (!diverged).then_some(dt),
            wall_s: 1.0 / dt,
            force_evals: 1,
            diverged,
            oscillating: false,
        }
    }

    #[test]
    fn the_bracket_is_where_divergence_stops() {
        let rows = [
            row(4.0, true),
            row(2.0, true),
            row(1.0, false),
            row(0.5, false),
        ];
        assert_eq!(stability_bracket(&rows), (Some(1.0), Some(2.0)));
        assert_eq!(stability_bracket(&rows[2..]), (Some(1.0), None));
        assert_eq!(stability_bracket(&rows[..2]), (None, Some(2.0)));
    }

    #[test]
    fn cheapest_takes_the_least_wall_time_within_tolerance() {
        let rows = [
            row(4.0, true),
            row(1e-2, false),
            row(1e-3, false),
            row(1e-4, false),
        ];
        let c = cheapest(&rows, 2e-3).unwrap();
        assert_eq!(c.dt, 1e-3);
        assert!(cheapest(&rows, 1e-5).is_none());
    }

    /// A row that reached T ringing: no error, not stopped.
    fn ringing_row(dt: f64) -> SweepRow {
        SweepRow {
            error: None,
            oscillating: true,
            ..row(dt, false)
        }
    }

    #[test]
    fn csv_leaves_the_error_of_diverged_rows_empty() {
        let ringing = ringing_row(2.0);
        let text = csv(&[row(4.0, true), ringing, row(0.5, false)]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], CSV_HEADER);
        assert_eq!(lines[1], "verlet,4,,0.25,1,true,false");
        assert_eq!(lines[2], "verlet,2,,0.5,1,false,true");
        assert_eq!(lines[3], "verlet,0.5,0.5,2,1,false,false");
    }

    /// A step that reached T ringing bounds the stable range as a diverged
    /// one does.
    #[test]
    fn ringing_rows_are_unstable() {
        let ringing = ringing_row(2.0);
        let rows = [row(4.0, true), ringing, row(1.0, false), row(0.5, false)];
        assert_eq!(stability_bracket(&rows), (Some(1.0), Some(2.0)));
    }
}
