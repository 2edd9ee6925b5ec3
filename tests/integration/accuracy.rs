//! The accuracy machinery (work-precision sweeps, reference validation, the
//! cached error estimate, the long-horizon comparison) and the stiff and
//! extreme matrix of `check --stress`.

use crate::common::*;
use leafmagic::leaf::LeafSpec;
use leafmagic::physics::field::Flow;
use leafmagic::physics::model::Model;
use leafmagic::physics::params::Integrator;
use leafmagic::physics::stability;
use leafmagic::physics::state::State;
use leafmagic::sim::accuracy::{
    self, ErrorCache, SweepRange, SweepSettings, long::LongSettings, smooth_model,
};
use leafmagic::sim::stress::{self, ExplicitPolicy, Outcome, StressRow};
use std::collections::HashSet;
use std::process::Command;

fn leaf_a() -> Model {
    LeafSpec::load("a").unwrap().model().unwrap()
}

fn settings(seconds: f64, ranges: &[(Integrator, u32, u32)], reference_j: u32) -> SweepSettings {
    SweepSettings {
        seconds,
        runs: 1,
        ranges: ranges
            .iter()
            .map(|&(integrator, j_min, j_max)| SweepRange {
                integrator,
                j_min,
                j_max,
            })
            .collect(),
        reference_j,
        refine_reference: false,
        refine_budget_s: f64::INFINITY,
        locate_limits: false,
    }
}

/// O7 (docs/design/numerics.md, "Oracles") through the sweep: on a lightly damped
/// oscillator (ω = 5 rad/s,
/// ζ = 0.05, stretched by 0.1 m) the fitted orders are 1, 1, 2, 4, 1
/// within ±0.15, and so is every pairwise order of the fit. (Not ω = 2π:
/// at T = one period the O(h) phase error of symplectic Euler, whose
/// positions are leapfrog's from a shifted start, vanishes and the fit
/// would read 1.2.)
#[test]
fn sweep_finds_the_theoretical_orders_on_an_oscillator() {
    let w = 5.0;
    let model = oscillator(1.0, w * w, 2.0 * 0.05 * w);
    let mut initial = State::at_rest(&model);
    initial.position[1].x += 0.1;
    let s = settings(
        1.0,
        &[
            (Integrator::Euler, 9, 15),
            (Integrator::Symplectic, 9, 15),
            (Integrator::Verlet, 6, 12),
            (Integrator::Rk4, 4, 8),
            (Integrator::Implicit, 9, 15),
        ],
        16,
    );
    let report = accuracy::sweep(&model, &initial, &s).unwrap();
    assert!(report.reference_valid, "{:?}", report.warnings);
    for summary in &report.summaries {
        let p = summary.order.expect("an order is fitted");
        let expected = f64::from(summary.integrator.order());
        assert!(
            (p - expected).abs() <= 0.15,
            "{}: order {p} (pairwise {:?})",
            summary.integrator,
            summary.pairwise_orders
        );
        assert!(summary.fit_points >= 4, "{}", summary.integrator);
        for q in &summary.pairwise_orders {
            assert!((q - expected).abs() <= 0.15, "{}: {q}", summary.integrator);
        }
    }
}

/// The same on the leaf itself, for the schemes whose fit window lies in
/// their asymptotic range (RK4 is stable only where its error is already
/// near the reference's floor, see docs/design/accuracy.md).
#[test]
fn sweep_finds_first_and_second_order_on_the_leaf() {
    let model = leaf_a();
    let initial = accuracy::default_release(&model);
    let s = settings(
        0.5,
        &[
            (Integrator::Euler, 12, 16),
            (Integrator::Symplectic, 10, 14),
            (Integrator::Verlet, 9, 13),
            (Integrator::Implicit, 10, 14),
        ],
        13,
    );
    let report = accuracy::sweep_leaf(&model, &initial, &s).unwrap();
    for summary in &report.summaries {
        let p = summary.order.expect("an order is fitted");
        let expected = f64::from(summary.integrator.order());
        assert!((p - expected).abs() <= 0.15, "{}: {p}", summary.integrator);
    }
}

/// accuracy.csv: the header, one row per (integrator, dt), diverged rows at
/// the large steps of every explicit scheme (with no error), finite errors
/// elsewhere; the located stability limits bracket where the sweep changed.
#[test]
fn csv_rows_and_diverged_points() {
    let model = leaf_a();
    let initial = accuracy::default_release(&model);
    let mut s = SweepSettings::for_model(&model, 0.25);
    s.runs = 1;
    for r in &mut s.ranges {
        r.j_max = r.j_min + 3;
    }
    let report = accuracy::sweep_leaf(&model, &initial, &s).unwrap();
    let text = accuracy::csv(&report.rows);
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .unwrap()
        .iter()
        .map(str::to_string)
        .collect();
    assert_eq!(
        header,
        [
            "integrator",
            "dt",
            "error",
            "wall_s",
            "force_evals",
            "diverged",
            "oscillating"
        ]
    );
    let rows: Vec<csv::StringRecord> = reader.records().map(Result::unwrap).collect();
    let expected: usize = s
        .ranges
        .iter()
        .map(|r| (r.j_max - r.j_min + 1) as usize)
        .sum();
    assert_eq!(rows.len(), expected);
    let keys: HashSet<(String, String)> = rows
        .iter()
        .map(|r| (r[0].to_string(), r[1].to_string()))
        .collect();
    assert_eq!(keys.len(), rows.len(), "one row per (integrator, dt)");
    for r in &rows {
        let diverged: bool = r[5].parse().unwrap();
        let oscillating: bool = r[6].parse().unwrap();
        let wall: f64 = r[3].parse().unwrap();
        let evals: u64 = r[4].parse().unwrap();
        assert!(wall >= 0.0 && evals > 0);
        assert!(
            !(diverged && oscillating),
            "a stopped run cannot ring at T: {r:?}"
        );
        if diverged || oscillating {
            assert!(r[2].is_empty(), "an unstable row has no error: {r:?}");
        } else {
            let e: f64 = r[2].parse().unwrap();
            assert!(e.is_finite() && e >= 0.0);
        }
    }
    for integrator in Integrator::EXPLICIT {
        let mine: Vec<_> = report
            .rows
            .iter()
            .filter(|r| r.integrator == integrator)
            .collect();
        assert!(mine[0].diverged, "{integrator} diverges at 4 × its limit");
        assert!(!mine.last().unwrap().unstable(), "{integrator} converges");
        let summary = report
            .summaries
            .iter()
            .find(|s| s.integrator == integrator)
            .unwrap();
        let limit = summary.predicted_dt_max.unwrap();
        // Unstable steps (diverged or ringing) lie above the estimate.
        for r in &mine {
            if r.unstable() {
                assert!(
                    r.dt > limit,
                    "{integrator} diverged below dt_max at {}",
                    r.dt
                );
            }
        }
        assert!(summary.largest_stable_dt.unwrap() < summary.smallest_diverged_dt.unwrap());
    }
    let implicit = report
        .rows
        .iter()
        .filter(|r| r.integrator == Integrator::Implicit);
    assert!(implicit.clone().all(|r| !r.unstable()));
}

/// The bisection puts the observed limit of every explicit scheme over a
/// 1 s fall within 3 % of the estimate `check` prints: the estimate is the
/// exact limit of the leaf linearised at rest, and a step above it is
/// unstable even where no runaway stops the run, because the run ends
/// ringing ([`accuracy::EndRun::oscillating`]). Counting only runaways, the
/// observed limits read 1.2–1.3 × the estimate (forward Euler 1.86 ×).
#[test]
fn located_limits_match_the_estimate() {
    let model = leaf_a();
    let initial = accuracy::default_release(&model);
    let mut s = SweepSettings::for_model(&model, 1.0);
    s.runs = 1;
    s.locate_limits = true;
    s.ranges.retain(|r| r.integrator != Integrator::Implicit);
    for r in &mut s.ranges {
        r.j_max = r.j_min + 3;
    }
    let report = accuracy::sweep_leaf(&model, &initial, &s).unwrap();
    for summary in &report.summaries {
        let found = summary.largest_stable_dt.unwrap();
        let failed = summary.smallest_diverged_dt.unwrap();
        let predicted = summary.predicted_dt_max.unwrap();
        assert!(failed > found && failed < 1.02 * found, "{summary:?}");
        let ratio = found / predicted;
        let band = 0.97..1.03;
        assert!(
            band.contains(&ratio),
            "{}: found {found:e}, predicted {predicted:e}",
            summary.integrator
        );
    }
}

/// Why the runaway check alone is not a stability test: prototype A under
/// Verlet at 1.11 × the estimated stable step falls 3 s without a runaway,
/// its stiffest mode held by the springs' nonlinearity in a bounded
/// step-to-step ringing; the internal acceleration at T sees it, orders of
/// magnitude above the reference's, while 0.95 × the step is smooth.
#[test]
fn a_step_above_the_limit_rings_without_running_away() {
    let model = leaf_a();
    let initial = accuracy::default_release(&model);
    let seconds = 3.0;
    let reference = accuracy::reference(&model, &initial, seconds, 13).unwrap();
    let limit = stability::estimate(&model)
        .dt_max(Integrator::Verlet)
        .unwrap();
    let run = |factor: f64| {
        let steps = (seconds / (factor * limit)).round() as u64;
        accuracy::run_steps(
            &model,
            &initial,
            Integrator::Verlet,
            seconds / steps as f64,
            steps,
        )
    };
    let above = run(1.11);
    assert!(above.error.is_none(), "no runaway: {:?}", above.error);
    assert!(above.oscillating(&reference) && above.unstable(&reference));
    let ringing = above.internal_acceleration.unwrap();
    assert!(
        ringing > 1e4 * (reference.internal_acceleration + accuracy::OSCILLATION_FLOOR),
        "{ringing} against {}",
        reference.internal_acceleration
    );
    let below = run(0.95);
    assert!(
        !below.unstable(&reference),
        "{:?}",
        below.internal_acceleration
    );
}

/// A reference too coarse for the errors plotted is reported, and the same
/// sweep with a fine reference is not.
#[test]
fn a_too_coarse_reference_is_detected() {
    let model = leaf_a();
    let initial = accuracy::default_release(&model);
    let ranges = [(Integrator::Verlet, 9, 13)];
    let coarse = accuracy::sweep(&model, &initial, &settings(0.25, &ranges, 7)).unwrap();
    assert!(!coarse.reference_valid);
    assert!(
        coarse
            .warnings
            .iter()
            .any(|w| w.contains("reference not converged")),
        "{:?}",
        coarse.warnings
    );
    let smallest = coarse.smallest_error.unwrap();
    assert!(coarse.reference.self_difference >= accuracy::REFERENCE_FACTOR * smallest);
    let fine = accuracy::sweep(&model, &initial, &settings(0.25, &ranges, 12)).unwrap();
    assert!(fine.reference_valid, "{:?}", fine.warnings);
    assert!(fine.warnings.is_empty(), "{:?}", fine.warnings);
}

/// A reference that does not validate is halved until it does, and every
/// point measured again against it: the same coarse reference as above,
/// refined, validates, says where it started, and gives the leaf's Verlet
/// its order 2 over the whole range.
#[test]
fn a_reference_that_does_not_validate_is_refined() {
    let model = leaf_a();
    let initial = accuracy::default_release(&model);
    let ranges = [(Integrator::Verlet, 9, 13)];
    let mut refining = settings(0.25, &ranges, 7);
    refining.refine_reference = true;
    let refined = accuracy::sweep(&model, &initial, &refining).unwrap();
    let pinned = accuracy::sweep(&model, &initial, &settings(0.25, &ranges, 7)).unwrap();
    assert!(!pinned.reference_valid && pinned.refined_from.is_none());
    assert!(refined.reference_valid, "{:?}", refined.warnings);
    let from = refined.refined_from.expect("where the reference started");
    assert_eq!(from.dt, pinned.reference.dt);
    assert_eq!(from.self_difference, pinned.reference.self_difference);
    assert!(refined.reference.dt < from.dt);
    let smallest = refined.smallest_error.unwrap();
    assert!(refined.reference.self_difference < accuracy::REFERENCE_FACTOR * smallest);
    // Measured again: the rows differ from the pinned sweep's, and the
    // order over them is Verlet's.
    assert_ne!(refined.rows[4].error, pinned.rows[4].error);
    let verlet = &refined.summaries[0];
    let order = verlet.order.expect("an order fitted");
    assert!((order - 2.0).abs() < 0.1, "order {order}");
    // Without the time for it, the refinement is not started, and the
    // report says why and what to do.
    refining.refine_budget_s = 0.0;
    let broke = accuracy::sweep(&model, &initial, &refining).unwrap();
    assert!(!broke.reference_valid && broke.refined_from.is_none());
    assert!(
        broke
            .warnings
            .iter()
            .any(|w| w.contains("refinement stopped") && w.contains("reference_j")),
        "{:?}",
        broke.warnings
    );
}

/// The cost a sweep announces counts every integrator's points in the
/// sweep's order and the reference, and scales with the steps: forward
/// Euler's 2^10…2^20 steps (times the runs) come out far above RK4's
/// 2^7…2^11 at four evaluations a step, whatever the machine's speed.
#[test]
fn the_sweep_cost_counts_every_integrator_and_the_reference() {
    let model = leaf_a();
    let initial = accuracy::default_release(&model);
    let settings = SweepSettings::for_model(&model, 0.25);
    let cost = accuracy::estimated_cost(&model, &initial, &settings);
    let order: Vec<Integrator> = cost.per_integrator.iter().map(|(i, _)| *i).collect();
    let expected: Vec<Integrator> = settings.ranges.iter().map(|r| r.integrator).collect();
    assert_eq!(order, expected);
    for (integrator, s) in &cost.per_integrator {
        assert!(s.is_finite() && *s > 0.0, "{integrator}: {s}");
    }
    assert!(cost.reference_s > 0.0 && cost.total_s() > cost.reference_s);
    let of = |i: Integrator| cost.per_integrator.iter().find(|(j, _)| *j == i).unwrap().1;
    assert!(
        of(Integrator::Euler) > 10.0 * of(Integrator::Rk4),
        "{:?}",
        cost.per_integrator
    );
}

/// Breaking is switched off for the sweep, and the report says so.
#[test]
fn breaking_is_switched_off_for_the_sweep() {
    let mut spec = LeafSpec::load("a").unwrap();
    for s in spec.springs.iter_mut().take(3) {
        s.break_strain = Some(0.05);
    }
    let model = spec.model().unwrap();
    let (smooth, n) = smooth_model(&model);
    assert_eq!(n, 3);
    assert!(smooth.springs.iter().all(|s| s.break_strain.is_none()));
    let initial = accuracy::default_release(&model);
    let report = accuracy::sweep_leaf(
        &model,
        &initial,
        &settings(0.1, &[(Integrator::Rk4, 8, 9)], 11),
    )
    .unwrap();
    assert_eq!(report.breaking_disabled, 3);
    assert!(report.warnings.iter().any(|w| w.contains("breaking")));
}

/// The estimate breeding records: computed once per model and settings,
/// then served from the cache; it agrees with the sweep's error for the
/// same run; a different model or step is a different key.
#[test]
fn error_estimate_is_cached_and_consistent() {
    let model = leaf_a();
    let initial = accuracy::default_release(&model);
    let dt = 1.0 / 1024.0;
    let mut cache = ErrorCache::new(8);
    let first = cache
        .estimate(&model, &initial, Integrator::Verlet, dt, 0.5)
        .unwrap();
    assert_eq!(cache.computations(), 1);
    let again = cache
        .estimate(&model, &initial, Integrator::Verlet, dt, 0.5)
        .unwrap();
    assert_eq!(first, again);
    assert_eq!((cache.computations(), cache.hits()), (1, 1));
    assert!(first.reference_valid);
    assert!(first.error > 0.0 && first.error < 1e-3);
    assert_eq!(first.key.len(), 16);

    // The sweep measures the same run the same way.
    let report = accuracy::sweep(
        &model,
        &initial,
        &settings(0.5, &[(Integrator::Verlet, 9, 9)], 13),
    )
    .unwrap();
    let swept = report.rows[0].error.unwrap();
    assert!(
        (swept - first.error).abs() < 1e-6 * first.error,
        "{swept} vs {}",
        first.error
    );

    // Another step, another model: new computations, new keys.
    let half = cache
        .estimate(&model, &initial, Integrator::Verlet, dt / 2.0, 0.5)
        .unwrap();
    assert_eq!(cache.computations(), 2);
    // Second order: halving the step quarters the error.
    let ratio = first.error / half.error;
    assert!((ratio - 4.0).abs() < 0.2, "{ratio}");
    let mut spec = LeafSpec::load("a").unwrap();
    spec.particles[0].mass *= 1.01;
    let other = spec.model().unwrap();
    let e = cache
        .estimate(&other, &initial, Integrator::Verlet, dt, 0.5)
        .unwrap();
    assert_eq!(cache.computations(), 3);
    assert_ne!(e.key, first.key);

    // A step that does not divide the duration is refused, naming dt.
    let bad = cache.estimate(&model, &initial, Integrator::Verlet, 0.3, 1.0);
    assert!(bad.unwrap_err().to_string().starts_with("dt:"));
    assert_eq!(cache.computations(), 3);

    // It goes into run.toml as a table.
    let text = toml::to_string(&first).unwrap();
    for field in [
        "integrator = \"verlet\"",
        "dt = ",
        "error = ",
        "reference_valid = true",
    ] {
        assert!(text.contains(field), "{text}");
    }
}

/// The process-wide cache gives the same estimate on the second call.
#[test]
fn global_error_estimate_is_stable() {
    let model = leaf_a();
    let a = accuracy::error_estimate(&model, Integrator::Rk4, 1.0 / 512.0, 0.25).unwrap();
    let b = accuracy::error_estimate(&model, Integrator::Rk4, 1.0 / 512.0, 0.25).unwrap();
    assert_eq!(a, b);
}

/// The long comparison: steps above a scheme's limit diverge in every drop;
/// the others classify; the class and statistics settle at the finest steps.
#[test]
fn long_comparison_reports_where_the_class_settles() {
    let model = leaf_a();
    let settings = LongSettings {
        seconds: 3.0,
        ensemble: 3,
        tilt_spread_deg: 0.1,
        halvings: 3,
        integrators: vec![Integrator::Verlet, Integrator::Implicit],
    };
    let report = accuracy::long::long_sweep(&model, &settings).unwrap();
    assert_eq!(report.rows.len(), 2 * 4);
    let limit = stability::estimate(&model)
        .dt_max(Integrator::Verlet)
        .unwrap();
    for r in &report.rows {
        assert_eq!(r.classes.len() + r.diverged, 3);
        if r.integrator == Integrator::Verlet && r.dt > 2.0 * limit {
            assert_eq!(r.diverged, 3, "verlet at {} > 2 dt_max", r.dt);
        }
        if r.integrator == Integrator::Implicit {
            assert_eq!(r.diverged, 0);
        }
    }
    for s in &report.summaries {
        let from = s.class_stable_from.expect("the class settles");
        let finest = report
            .rows
            .iter()
            .filter(|r| r.integrator == s.integrator)
            .map(|r| r.dt)
            .fold(f64::INFINITY, f64::min);
        assert!(from >= finest);
        for r in report
            .rows
            .iter()
            .filter(|r| r.integrator == s.integrator && r.dt <= from)
        {
            assert_eq!(r.majority, s.finest_class);
        }
    }
    if let Some(t) = report.horizon_s {
        assert!(t > 0.0 && t <= settings.seconds);
    }
}

// ------------------------------------------------------------ stress matrix

const CASES: [&str; 19] = [
    "stiff-1e4",
    "stiff-1e5",
    "stiff-1e6",
    "stiff-1e7",
    "stiff-1e8",
    "light-particle",
    "tiny-mass-1e-6",
    "tiny-mass-1e-9",
    "dt-1e-5",
    "dt-1e-3",
    "dt-1e-1",
    "dt-1e1",
    "wind-1e1",
    "wind-1e2",
    "wind-1e3",
    "vortex-axis",
    "coincident",
    "collinear-triangle",
    "zero-length-spring",
];

fn assert_clear(row: &StressRow) {
    assert!(row.all_finite, "{row:?}");
    for word in row.message.split(|c: char| !c.is_ascii_alphanumeric()) {
        assert!(
            !word.eq_ignore_ascii_case("nan") && !word.eq_ignore_ascii_case("inf"),
            "{}: {}",
            row.case,
            row.message
        );
    }
    match row.outcome {
        Outcome::Ok => {
            assert!(row.failure.is_none());
            let drift = row.energy_drift.unwrap();
            assert!(drift.is_finite() && drift.abs() <= 1.0 + 1e-12, "{row:?}");
            assert!(row.max_strain.unwrap().is_finite());
        }
        Outcome::Error => {
            let f = row.failure.as_ref().expect("an error says where");
            assert!(!f.cause.is_empty());
            assert!(row.message.contains("step"), "{}", row.message);
            assert!(row.message.contains("dt_max"), "{}", row.message);
            if !row.message.contains("implicit solver") {
                assert!(f.particle.is_some() && row.message.contains("particle"));
            }
        }
    }
}

/// Each case is built as described: the oracles are the numbers the case
/// names.
#[test]
fn stress_cases_are_what_they_say() {
    let model = leaf_a();
    let initial = accuracy::default_release(&model);
    let cases = stress::cases(&model, &initial).unwrap();
    let names: Vec<&str> = cases.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, CASES);
    let case = |name: &str| cases.iter().find(|c| c.name == name).unwrap();
    for (name, rate) in CASES[..5].iter().zip(stress::STIFF_RATES) {
        let est = stability::estimate(&case(name).model);
        assert!(
            (est.omega_lower.powi(2) / rate - 1.0).abs() < 1e-9,
            "{name}"
        );
    }
    let light = &case("light-particle").model;
    let est = stability::estimate(light);
    // The lightened particle is 1e-4 of its neighbours: the lightest by far.
    let original = leaf_a();
    let changed: Vec<usize> = (0..light.len())
        .filter(|&i| light.mass[i] != original.mass[i])
        .collect();
    assert_eq!(changed.len(), 1);
    assert_eq!(est.lightest_particle, changed[0]);
    let tag = format!("particle[{}]", changed[0]);
    assert!(est.warnings.iter().any(|w| w.starts_with(&tag)));
    for (name, m) in [("tiny-mass-1e-6", 1e-6), ("tiny-mass-1e-9", 1e-9)] {
        let lightest = case(name).model.mass.iter().copied().fold(1.0, f64::min);
        assert!((lightest / m - 1.0).abs() < 1e-12);
        assert!(!case(name).model.wind.is_still());
    }
    for (name, dt) in [("dt-1e-5", 1e-5), ("dt-1e1", 10.0)] {
        assert_eq!(case(name).dt, dt);
        assert!(case(name).seconds >= dt);
    }
    let w = &case("wind-1e3").model.wind;
    assert!((w.velocity(&V3::zeros(), 0.0).norm() - 1e3).abs() < 1e-9);
    let v = case("vortex-axis");
    let prim = &v.model.wind.primitives()[0];
    assert!(matches!(prim.flow(), Flow::LineVortex(_)));
    let on_axis = v.model.wind.velocity(&v.initial.position[0], 0.0);
    assert!(on_axis.norm() < 1e-9, "{on_axis:?}");
    let c = case("coincident");
    let s0 = &c.model.springs[0];
    assert_eq!(c.initial.position[s0.i], c.initial.position[s0.j]);
    let t = case("collinear-triangle");
    let [a, b, cc] = t.model.triangles[0].corners;
    let x = &t.initial.position;
    assert!((x[b] - x[a]).cross(&(x[cc] - x[a])).norm() < 1e-18);
    let z = case("zero-length-spring");
    assert_eq!(z.model.springs[0].rest_length, 0.0);
}

/// Every case × integrator ends finite with its energy drift and strain, or
/// with a clear error — under both policies for steps above the estimate.
/// Refusing: exactly the explicit runs above dt_max refuse. Sub-stepping:
/// n = ⌈h / (0.7 dt_max)⌉ sub-steps, and every run of the leaf finishes.
#[test]
fn stress_matrix_is_finite_or_clearly_refused() {
    let model = leaf_a();
    let initial = accuracy::default_release(&model);
    let cases = stress::cases(&model, &initial).unwrap();
    for policy in [ExplicitPolicy::Refuse, ExplicitPolicy::Substep] {
        let rows = stress::run_matrix(&cases, policy, stress::DEFAULT_SUBSTEP_CAP);
        assert_eq!(rows.len(), cases.len() * Integrator::ALL.len());
        for row in &rows {
            assert_clear(row);
            let above =
                row.integrator != Integrator::Implicit && row.dt_max.is_some_and(|m| row.dt > m);
            // A leaf with 1 N/m edge springs in a 100–1000 m/s wind is torn
            // apart: those runs may stop with a divergence diagnosis (a clear
            // error, which the issue allows); every other case must finish.
            let extreme_wind = row.case == "wind-1e2" || row.case == "wind-1e3";
            let diverged =
                row.outcome == Outcome::Error && row.message.contains("diverged at step");
            if diverged {
                assert!(extreme_wind, "{row:?}");
                continue;
            }
            match policy {
                ExplicitPolicy::Refuse => {
                    assert_eq!(row.outcome == Outcome::Error, above, "{row:?}");
                    if above {
                        assert!(row.message.contains("exceeds the stability estimate"));
                        assert_eq!(row.steps, 0);
                    }
                }
                ExplicitPolicy::Substep => {
                    assert_eq!(row.outcome, Outcome::Ok, "{row:?}");
                    let expected = if above {
                        (row.dt / (stability::AUTO_SAFETY * row.dt_max.unwrap())).ceil() as u64
                    } else {
                        1
                    };
                    assert_eq!(row.substeps, expected, "{}", row.case);
                }
            }
        }
    }
}

/// Too few sub-steps allowed: the clamp is warned about and the runs that
/// then blow up stop with a diagnosis naming step, particle and dt_max.
#[test]
fn clamped_substeps_warn_and_diverge_with_a_diagnosis() {
    let model = leaf_a();
    let initial = accuracy::default_release(&model);
    let cases: Vec<_> = stress::cases(&model, &initial)
        .unwrap()
        .into_iter()
        .filter(|c| c.name == "stiff-1e8" || c.name == "light-particle")
        .collect();
    let rows = stress::run_matrix(&cases, ExplicitPolicy::Substep, 10);
    let mut diverged = 0;
    for row in &rows {
        assert_clear(row);
        if row.integrator != Integrator::Implicit {
            assert_eq!(row.substeps, 10);
            assert!(row.warnings.iter().any(|w| w.contains("clamped")));
        }
        if row.outcome == Outcome::Error {
            diverged += 1;
            assert!(row.message.contains("diverged"), "{}", row.message);
        }
    }
    assert!(diverged >= 6, "{rows:?}");
}

fn binary() -> Command {
    Command::new(env!("CARGO_BIN_EXE_leafmagic"))
}

/// `check --stress --json`: an array of objects with the documented fields.
#[test]
fn stress_json_has_the_documented_fields() {
    let out = binary()
        .args(["check", "a", "--stress", "--json", "--explicit", "refuse"])
        .output()
        .unwrap();
    crate::common::assert_succeeded(&out);
    let rows: Vec<serde_json::Value> = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(rows.len(), CASES.len() * Integrator::ALL.len());
    for r in &rows {
        assert!(CASES.contains(&r["case"].as_str().unwrap()));
        assert!(
            r["integrator"]
                .as_str()
                .unwrap()
                .parse::<Integrator>()
                .is_ok()
        );
        assert!(matches!(r["outcome"].as_str(), Some("ok" | "error")));
        assert!(!r["message"].as_str().unwrap().is_empty());
        assert_eq!(r["all_finite"].as_bool(), Some(true));
    }
}

/// `accuracy` end to end on a short fall: CSV and SVG written, the table
/// printed; the SVG carries its text as <text> (no font files needed).
#[test]
fn accuracy_command_writes_csv_svg_and_table() {
    let dir = std::env::temp_dir().join(format!("leafmagic-accuracy-{}", std::process::id()));
    let out = binary()
        .args(["accuracy", "a", "--seconds", "0.05", "--runs", "1", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // A sweep of well under a minute says nothing of its cost.
    assert!(!stderr.contains("note: this sweep"), "{stderr}");
    for i in Integrator::ALL {
        assert!(stdout.contains(i.name()), "{stdout}");
    }
    assert!(stdout.contains("valid"), "{stdout}");
    let csv = std::fs::read_to_string(dir.join("accuracy.csv")).unwrap();
    assert!(csv.starts_with(accuracy::CSV_HEADER));
    let svg = std::fs::read_to_string(dir.join("accuracy.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("<text"));
    for i in Integrator::ALL {
        assert!(svg.contains(i.name()));
    }
    // A bad reference is said on stdout.
    let out = binary()
        .args([
            "accuracy",
            "a",
            "--seconds",
            "0.05",
            "--runs",
            "1",
            "--reference-j",
            "5",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("reference not converged"), "{stdout}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Bad input is an error naming the flag, with a non-zero exit.
#[test]
fn accuracy_rejects_a_bad_duration() {
    let out = binary()
        .args(["accuracy", "a", "--seconds", "0"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--seconds"));
    // So long that the reference's step would be above RK4's stable limit:
    // refused before running, saying so (it used to diverge mid-reference).
    let out = binary()
        .args(["accuracy", "a", "--seconds", "1e9"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("above RK4's stable step"), "{err}");
}

/// `--integrators` sweeps only the integrators named (a plate's implicit
/// sweep under the unsteady law takes most of 23 minutes; its explicit ones,
/// seconds), and what it sweeps is what the full sweep gives for them: the
/// same steps, errors and force evaluations, against the same RK4
/// reference. The long comparison takes the flag too; an unknown name is
/// refused naming the flag.
#[test]
fn accuracy_sweeps_only_the_integrators_named() {
    let dir = std::env::temp_dir().join(format!("leafmagic-accuracy-some-{}", std::process::id()));
    // `accuracy a ARGS --out DIR/SUB`, which must succeed.
    let run = |args: &[&str], sub: &str| {
        let out = binary()
            .args(["accuracy", "a"])
            .args(args)
            .arg("--out")
            .arg(dir.join(sub))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        dir.join(sub)
    };
    let sweep = |sub: &str, extra: &[&str]| {
        let mut args = vec!["--seconds", "0.05", "--runs", "1"];
        args.extend(extra);
        let out_dir = run(&args, sub);
        // Every column but the wall time.
        std::fs::read_to_string(out_dir.join("accuracy.csv"))
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| {
                let c: Vec<&str> = l.split(',').collect();
                format!("{},{},{},{},{},{}", c[0], c[1], c[2], c[4], c[5], c[6])
            })
            .collect::<Vec<String>>()
    };
    let all = sweep("all", &[]);
    let some = sweep("some", &["--integrators", "verlet,implicit"]);
    let expected: Vec<String> = all
        .iter()
        .filter(|r| r.starts_with("verlet,") || r.starts_with("implicit,"))
        .cloned()
        .collect();
    assert!(expected.len() >= 4);
    assert_eq!(some, expected);
    let long_dir = run(
        &["--long", "--seconds", "0.3", "--integrators", "rk4"],
        "long",
    );
    let long = std::fs::read_to_string(long_dir.join("accuracy-long.csv")).unwrap();
    let rows: Vec<&str> = long.lines().skip(1).collect();
    assert!(
        !rows.is_empty() && rows.iter().all(|r| r.starts_with("rk4,")),
        "{long}"
    );
    let out = binary()
        .args(["accuracy", "a", "--integrators", "verlet,leapfrog"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--integrators") && err.contains("leapfrog"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
