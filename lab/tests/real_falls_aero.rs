//! The real-falls experiment (docs/lab/real-falls.md): the real side of the
//! table computed from tests/data/real-falls/squares, and the simulated
//! side under the unsteady law with its one default set of coefficients.
//! Of the targets (score ≤ 0.6, descent within 10 %, drift within
//! ×1.5, Ω within 15 % in every bin) the score and the descent are met
//! (docs/lab/real-falls.md); these tests hold what is reached, so a change that
//! makes it worse fails. Like for like, against the films re-weighted to
//! the simulated mix of releases, the drift bound holds in every bin too
//! (docs/lab/real-falls.md, "The films at the simulated mix"). Also the strips'
//! scaling law (met over equal scaled times), the disks' regimes and the
//! predictions for the held-out shapes.

use leafmagic::leaf::plates::{PlateShape, plate};
use leafmagic::leaf::{AeroLawName, AeroSpec};
use leafmagic::motion::class::Regime;
use leafmagic::motion::classify::{Classification, classify};
use leafmagic::physics::aero::unsteady::AIR_DENSITY_20C;
use leafmagic::sim::drop::{DropParams, drop_leaf};
use leafmagic_lab::real_falls::{self, Label};
use std::path::Path;

fn squares() -> Vec<real_falls::RealSegment> {
    real_falls::read_squares(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/real-falls/squares"),
    )
    .unwrap()
}

/// One bin of the experiment as `compare` runs it, labelled by the films'
/// centres: squares of side `side` under `aero` in bin `bin` (which seeds
/// the releases with `seed`), `releases` drops of which the first `flat`
/// are let go flat, as `protocol` says.
fn simulate_squares(
    aero: &AeroSpec,
    side: f64,
    bin: usize,
    [releases, flat]: [usize; 2],
    seed: u64,
    protocol: real_falls::Protocol,
) -> (real_falls::BinStats, Vec<real_falls::SimulatedDrop>) {
    let run = real_falls::BinReleases {
        bin,
        releases,
        flat,
        seed,
        protocol,
    };
    let centres = real_falls::centres(&squares());
    real_falls::simulate_bin(PlateShape::Square, side, aero, &run, &centres).unwrap()
}

/// The real table: small squares tumble, large ones fall chaotically, all
/// descend at 0.73–0.81 m/s and turn at 26 → 12.6 rad/s (Howison, Hughes
/// & Iida 2020, as docs/lab/real-falls.md summarises them).
#[test]
fn the_real_table_is_read_from_the_tracked_squares() {
    let real = squares();
    assert_eq!(real.len(), 127);
    assert!(real.iter().any(|s| s.human == Label::Steady));
    let table = real_falls::real_table(&real);
    let counts: Vec<[usize; 3]> = table.iter().map(|b| b.counts).collect();
    assert_eq!(
        counts,
        [[11, 3, 1], [9, 2, 5], [3, 10, 7], [4, 26, 13], [1, 23, 9]]
    );
    for (k, b) in table.iter().enumerate() {
        println!(
            "{:.1} cm: fT {:.2}, v {:.3} m/s, drift {:.2}, Ω {:.1} rad/s",
            b.side * 100.0,
            b.tumbling,
            b.descent,
            b.drift,
            b.omega
        );
        assert!((0.73..0.82).contains(&b.descent));
        assert!((0.25..0.72).contains(&b.drift));
        if k < 2 {
            assert!(b.tumbling > 0.75 && (20.0..27.0).contains(&b.omega));
        } else {
            assert!(b.tumbling < 0.25 && (12.0..16.0).contains(&b.omega));
        }
    }
}

/// The real side's bootstrap: every interval brackets the real table's own
/// value, a bin whose drops are all one drop has no spread at all (every
/// resample is that drop), and the same seed gives the same intervals.
#[test]
fn the_real_sides_bootstrap_brackets_its_values_and_collapses_on_one_drop() {
    let real = squares();
    let table = real_falls::real_table(&real);
    let intervals = real_falls::real_intervals(&real, 400, 7);
    assert_eq!(intervals, real_falls::real_intervals(&real, 400, 7));
    for (b, i) in table.iter().zip(&intervals) {
        for (value, [lo, hi]) in [
            (b.tumbling, i.tumbling),
            (b.descent, i.descent),
            (b.drift, i.drift),
            (b.omega, i.omega),
        ] {
            assert!(lo <= value && value <= hi, "{value} outside [{lo}, {hi}]");
            assert!(lo < hi, "a bin of 11–30 moving drops has spread");
        }
    }
    // The smallest bin, its first tumbling drop copied over all of them.
    let (lo, hi) = real_falls::SQUARE_BINS[0];
    let one = real
        .iter()
        .find(|s| (lo..hi).contains(&s.radius) && s.human == Label::Tumbling)
        .unwrap()
        .clone();
    let copied: Vec<_> = real
        .iter()
        .map(|s| {
            if (lo..hi).contains(&s.radius) {
                one.clone()
            } else {
                s.clone()
            }
        })
        .collect();
    let alone = real_falls::real_table(&copied)[0];
    let i = real_falls::real_intervals(&copied, 50, 7)[0];
    assert_eq!(i.tumbling, [1.0, 1.0]);
    assert_eq!(i.descent, [alone.descent; 2]);
    assert_eq!(i.drift, [alone.drift; 2]);
    assert_eq!(i.omega, [alone.omega; 2]);
}

/// The simulated experiment (4 releases per bin here, 12 in the example)
/// runs in every bin without diverging; what it reaches with the default
/// coefficients is held (measured at 4 releases, seed 1): the score no
/// worse than 0.7 (0.56; 1.04 under the defaults before the refit at the
/// coarser step; the 0.6 is met at 24 releases on ten fresh seeds,
/// docs/lab/real-falls.md), small squares let go flat tumble as real ones do
/// (3.2 cm: 1.00 of the simulated drops, real 0.79) and the largest mostly
/// do not (9 cm: 0.25, one drop of the four, at the bound; real 0.04),
/// descent within 10 % of real in every bin (the per-bin target;
/// 0.94–1.07), the tumbling rate within 25 % (0.83–1.08: the large squares
/// turn too slowly) and the drift within a factor 1.5 in every bin but the
/// smallest (0.83–1.19; the 3.2 cm squares glide 0.42 of the real drift).
#[test]
fn the_simulated_experiment_holds_what_it_reaches() {
    let real = squares();
    let cmp = real_falls::compare(&real, &AeroSpec::unsteady(), 4, 1).unwrap();
    for (r, s) in cmp.real.iter().zip(&cmp.sim) {
        println!(
            "{:.1} cm: fT {:.2}/{:.2}, v {:.3}/{:.3}, drift {:.2}/{:.2}, Ω {:.1}/{:.1}",
            r.side * 100.0,
            r.tumbling,
            s.tumbling,
            r.descent,
            s.descent,
            r.drift,
            s.drift,
            r.omega,
            s.omega
        );
        assert_eq!(s.drops, 4);
        assert!(s.descent.is_finite() && s.descent > 0.0);
        let omega = s.omega / r.omega;
        assert!((omega - 1.0).abs() < 0.25, "{} m: Ω ratio {omega}", r.side);
        let descent = s.descent / r.descent;
        assert!(
            (descent - 1.0).abs() < 0.1,
            "{} m: descent ratio {descent}",
            r.side
        );
        if r.side > 0.035 {
            let drift = s.drift / r.drift;
            assert!(
                (1.0 / 1.5..1.5).contains(&drift),
                "{} m: drift ratio {drift}",
                r.side
            );
        }
    }
    println!("score {:.2}", cmp.score());
    assert!(cmp.score() <= 0.7, "score {}", cmp.score());
    // Like for like: the films re-weighted to the simulated bins' mix of
    // releases (0.45 at these 4 releases; 0.39 at 24).
    let like = cmp.score_against(&cmp.films_at_simulated_mix(&real));
    println!("score at the simulated mix {like:.2}");
    assert!(like <= 0.6, "score at the simulated mix {like}");
    assert!(
        cmp.sim[0].tumbling >= 0.5,
        "3.2 cm: {}",
        cmp.sim[0].tumbling
    );
    let last = cmp.sim.len() - 1;
    assert!(
        cmp.sim[last].tumbling <= 0.25,
        "9 cm: {}",
        cmp.sim[last].tumbling
    );
}

/// An 8 s fall of a plate (`size`, `aspect`, areal density `sigma`) under
/// the unsteady law's defaults, let go at `tilt`, classified as
/// examples/plate_regimes.rs does.
fn plate_fall(
    shape: PlateShape,
    size: f64,
    aspect: f64,
    sigma: f64,
    tilt: [f64; 2],
) -> Classification {
    let aero = AeroSpec::named(AeroLawName::Unsteady);
    leafmagic_lab::strips::classify_plate_fall(shape, size, aspect, sigma, tilt, 8.0, &aero)
        .unwrap()
}

/// A plate tumbling at `--dt auto` falls as it does at half that step:
/// the step bounds the turn per step
/// ([`leafmagic::physics::stability::MAX_TURN_PER_STEP`]) as well as the
/// air's rates. Before it did, a 1 cm × 5 cm strip of 280 g/m² card
/// tumbled at the auto step (4.2e-3 s) at 1.59 m/s where it falls at 2.19
/// and rocks and flips, and a 3.2 cm square of paper (7.2e-3 s at the
/// experiment's 98 fps) tumbled 12 % too fast; Verlet is second order, so
/// the difference to half the step is three quarters of the error.
#[test]
fn a_tumbling_plate_falls_at_the_auto_step_as_at_half_of_it() {
    use leafmagic::physics::params::{Integrator, TimeStep};
    use leafmagic::physics::run::resolve_step;
    for (shape, size, aspect, sigma) in [
        (PlateShape::Square, 0.032, 1.0, 0.07),
        (PlateShape::Rectangle, 0.01, 5.0, 0.28),
    ] {
        let model = plate(shape, size, aspect, sigma, AeroSpec::unsteady())
            .unwrap()
            .model()
            .unwrap();
        let auto = resolve_step(&model, Integrator::Verlet, TimeStep::Auto, 1.0 / 240.0).unwrap();
        let fall = |dt: f64| {
            let params = DropParams {
                seconds: 4.0,
                tilt_deg: [60.0, 0.0],
                dt: TimeStep::Fixed(dt),
                ..Default::default()
            };
            let run = drop_leaf(&model, &params).unwrap();
            classify(&run.trajectory, model.chord()).features
        };
        let (a, b) = (fall(auto), fall(0.5 * auto));
        println!(
            "{size} m x{aspect}, {sigma} kg/m², dt {auto:.3e}: descent {:.4} / {:.4} m/s, turns {:.2} / {:.2}",
            a.mean_descent_speed_m_s, b.mean_descent_speed_m_s, a.net_turns, b.net_turns
        );
        let descent = a.mean_descent_speed_m_s / b.mean_descent_speed_m_s;
        assert!(
            (descent - 1.0).abs() < 0.02,
            "{size} m: descent ratio {descent}"
        );
        let turns = a.net_turns.abs() / b.net_turns.abs().max(1.0);
        assert!((turns - 1.0).abs() < 0.05, "{size} m: turns ratio {turns}");
    }
}

/// The strips' scaling law, as issue 17 states it: twelve strips of aspect
/// 5 over areal density ×8 (35–280 g/m²) and width ×4 (1–4 cm), let go at
/// 60° about the long axis and each falling 300 scaled times
/// ([`leafmagic_lab::strips`]), all tumble, and the fit Ω ∝ σ^p w^q gives
/// p = 0.5 ± 0.1 and q = −1.0 ± 0.1 (Mahadevan, Ryu & Samuel 1999: ½ and
/// −1). Measured under the defaults: 0.42 and −0.92 (0.50 and −0.97 with
/// the lag's couple along the unit in-plane direction, before it was made
/// continuous); without the lagged centre of pressure
/// (`pressure_lag_gain = 0`) 0.35 and −0.83, which this test would fail
/// (docs/lab/real-falls.md, "The defaults").
#[test]
fn strips_tumble_at_the_scaling_law_over_equal_scaled_times() {
    use leafmagic_lab::strips::{
        SCALED_DURATION, SIGMAS, WIDTHS, fit_exponents, strip_fall, strip_seconds,
    };
    use rayon::prelude::*;
    let aero = AeroSpec::named(AeroLawName::Unsteady);
    let sweep: Vec<(f64, f64)> = SIGMAS
        .iter()
        .flat_map(|&s| WIDTHS.iter().map(move |&w| (s, w)))
        .collect();
    let falls: Vec<_> = sweep
        .par_iter()
        .map(|&(sigma, w)| {
            let seconds = strip_seconds(sigma, w, SCALED_DURATION, AIR_DENSITY_20C);
            strip_fall(sigma, w, seconds, &aero).unwrap()
        })
        .collect();
    for f in &falls {
        println!(
            "σ {} kg/m², w {} m, {:.1} s: {} at {:.1} rad/s",
            f.sigma, f.width, f.seconds, f.regime, f.omega
        );
        assert_eq!(f.regime, Regime::Tumble, "σ {}, w {}", f.sigma, f.width);
    }
    let (p, q) = fit_exponents(&falls).expect("twelve tumbling strips span σ and w");
    println!("p = {p:.3}, q = {q:.3}");
    assert!((p - 0.5).abs() <= 0.1, "p = {p}");
    assert!((q + 1.0).abs() <= 0.1, "q = {q}");
}

/// Disks let go nearly flat flutter when light and tumble when heavy as
/// their dimensionless moment of inertia I*_disk = π σ / (64 ρ d) rises
/// (Field et al. 1997: flutter below about 0.01, chaos between, tumbling
/// above about 0.04): a 3 cm disk flutters at 0.005 and 0.01, does not yet
/// tumble at 0.02, falls chaotically at 0.025, inside Field's band (the
/// lagged centre of pressure gives it: with `pressure_lag_gain = 0` it
/// flutters there and the switch to tumbling is sharp), and tumbles at
/// 0.04 and 0.16 (docs/lab/real-falls.md).
#[test]
fn disks_flutter_when_light_and_tumble_when_heavy() {
    let d = 0.03;
    for (istar, expected) in [
        (0.005, Some(Regime::Flutter)),
        (0.01, Some(Regime::Flutter)),
        (0.02, None),
        (0.025, Some(Regime::Chaotic)),
        (0.04, Some(Regime::Tumble)),
        (0.16, Some(Regime::Tumble)),
    ] {
        // The law's default air, as examples/plate_regimes.rs.
        let sigma = istar * 64.0 * AIR_DENSITY_20C * d / std::f64::consts::PI;
        let c = plate_fall(PlateShape::Circle, d, 1.0, sigma, [5.0, 2.0]);
        match expected {
            Some(regime) => assert_eq!(c.regime, regime, "I* {istar}: {:?}", c.reason),
            None => assert_ne!(c.regime, Regime::Tumble, "I* {istar}: {:?}", c.reason),
        }
    }
}

/// The prediction path for the held-out shapes is the experiment's own: for
/// squares it gives, bit for bit, the simulated side that `compare` scores.
/// For circles (held back; predicted in docs/lab/real-falls.md) it holds what
/// the law gives every shape: the smallest plates tumble at least as often
/// as the largest, and every bin falls at a finite speed within 25 % of
/// the squares' (a circle of diameter d has 0.79 of a square's area and
/// mass per area alike, so its face-on terminal speed is the square's).
#[test]
fn held_out_shapes_are_predicted_by_the_experiments_own_path() {
    let real = squares();
    let aero = AeroSpec::unsteady();
    let cmp = real_falls::compare(&real, &aero, 4, 1).unwrap();
    let same =
        real_falls::predict(PlateShape::Square, &real, &aero, 4, 1, &Default::default()).unwrap();
    let bits = |b: &real_falls::BinStats| {
        (
            b.counts,
            [b.tumbling, b.descent, b.drift, b.omega, b.side].map(f64::to_bits),
        )
    };
    for (a, b) in cmp.sim.iter().zip(&same) {
        assert_eq!(bits(a), bits(b));
    }
    let circles =
        real_falls::predict(PlateShape::Circle, &real, &aero, 4, 1, &Default::default()).unwrap();
    assert_eq!(circles.len(), cmp.sim.len());
    for (c, s) in circles.iter().zip(&cmp.sim) {
        assert_eq!(c.drops, 4);
        let v = c.descent / s.descent;
        assert!(
            (0.75..1.25).contains(&v),
            "{} m: circle/square descent {v}",
            c.side
        );
    }
    let (first, last) = (&circles[0], &circles[circles.len() - 1]);
    assert!(
        first.tumbling >= last.tumbling,
        "circles: {} tumbling at {} m, {} at {} m",
        first.tumbling,
        first.side,
        last.tumbling,
        last.side
    );
}

/// Crosses are predicted by the same path with arms `--cross-arm` of the
/// span wide: without an arm width they are refused naming it, and their
/// bins descend within 25 % of the squares' (their face-on terminal speed
/// depends on the paper alone), the smallest tumbling at least as often as
/// the largest.
#[test]
fn crosses_are_predicted_with_the_arm_width_given() {
    let real = squares();
    let aero = AeroSpec::unsteady();
    let err = real_falls::predict(PlateShape::Cross, &real, &aero, 2, 1, &Default::default())
        .unwrap_err()
        .to_string();
    // Named as the library names it (the command line spells it --arm-width).
    let arm_width = leafmagic::util::setting::Setting::ArmWidth.to_string();
    assert!(err.contains(&arm_width), "{err}");
    let protocol = real_falls::Protocol {
        cross_arm: Some(1.0 / 3.0),
        ..Default::default()
    };
    assert!(
        real_falls::Protocol {
            cross_arm: Some(1.0),
            ..Default::default()
        }
        .check()
        .is_err()
    );
    let squares = real_falls::predict(PlateShape::Square, &real, &aero, 4, 1, &protocol).unwrap();
    let crosses = real_falls::predict(PlateShape::Cross, &real, &aero, 4, 1, &protocol).unwrap();
    assert_eq!(crosses.len(), squares.len());
    for (c, s) in crosses.iter().zip(&squares) {
        assert_eq!(c.drops, 4);
        let v = c.descent / s.descent;
        assert!(
            (0.75..1.25).contains(&v),
            "{} m: cross/square descent {v}",
            c.side
        );
    }
    let (first, last) = (&crosses[0], &crosses[crosses.len() - 1]);
    assert!(first.tumbling >= last.tumbling, "{first:?} {last:?}");
}

/// Each bin's share of flat releases, read from the labels file itself (an
/// independent reading of `release_vertical` and people's label): what
/// `--mix filmed` lets go flat, and what [`real_falls::real_by_release`]
/// splits the bin's moving drops into.
#[test]
fn the_filmed_mix_and_the_split_by_release_follow_the_labels() {
    let real = squares();
    let labels = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/real-falls/squares/labels.csv"),
    )
    .unwrap();
    let mut flat = [0usize; 5];
    let mut edge = [0usize; 5];
    for line in labels.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let radius: f64 = f[2].parse().unwrap();
        // People's label 3 is steady: a flat release's start, not a drop.
        if f[5] == "3" {
            continue;
        }
        if let Some(b) = real_falls::SQUARE_BINS
            .iter()
            .position(|&(lo, hi)| (lo..hi).contains(&radius))
        {
            if f[4] == "1" {
                edge[b] += 1;
            } else {
                flat[b] += 1;
            }
        }
    }
    let shares = real_falls::real_flat_share(&real);
    let split = real_falls::real_by_release(&real);
    let table = real_falls::real_table(&real);
    for b in 0..5 {
        let share = flat[b] as f64 / (flat[b] + edge[b]) as f64;
        assert_eq!(shares[b], share, "bin {b}");
        assert_eq!(
            (split[b].flat.drops, split[b].edge.drops),
            (flat[b], edge[b])
        );
        assert_eq!(split[b].flat.drops + split[b].edge.drops, table[b].drops);
        // Only flat releases have a steady start.
        assert_eq!(split[b].edge.steady_drops, 0);
        for n in [4, 12, 24] {
            let k = real_falls::flat_releases(real_falls::ReleaseMix::AsFilmed, n, share);
            assert_eq!(k, (n as f64 * share).round() as usize);
            let protocol = real_falls::Protocol {
                mix: real_falls::ReleaseMix::AsFilmed,
                ..Default::default()
            };
            let lets_go_flat = (0..n)
                .filter(|&i| !real_falls::release(&protocol, 1, b, i, k).on_edge)
                .count();
            assert_eq!(lets_go_flat, k);
            assert_eq!(
                real_falls::flat_releases(real_falls::ReleaseMix::Halves, n, share),
                n.div_ceil(2)
            );
        }
    }
}

/// The films' flat drops, joined from their segments: 50 of the 92 drops
/// (the data's README), 35 of them cut in two (people's label 3, then a
/// moving segment) and 15 left whole. Over
/// each one's first five frames the two silhouettes grow at least 2.5
/// times while the plate is still flat (a tilt of a few degrees changes
/// them by a few per cent): the steady cut times that artefact. Measured
/// from where the silhouette is whole, the drops depart 0.2 r sideways
/// later the larger they are, as a time of order side / descent speed
/// would (docs/lab/real-falls.md, "When a flat release departs").
#[test]
fn the_films_flat_drops_depart_past_their_first_frames_artefact() {
    let real = squares();
    let drops = real_falls::departure::flat_drops(&real);
    assert_eq!(drops.len(), 50);
    let label = |name: &str| real.iter().find(|s| s.name == name).unwrap().human;
    let steady_first = drops.iter().filter(|d| d.segments.len() == 2).count();
    let steady_segments = real.iter().filter(|s| s.human == Label::Steady).count();
    assert_eq!((steady_first, steady_segments), (35, 35));
    for d in &drops {
        assert!(d.segments.len() <= 2, "{:?}", d.segments);
        let first = label(&d.segments[0]);
        assert_eq!(first == Label::Steady, d.segments.len() == 2);
        assert!(d.segments[1..].iter().all(|n| label(n) != Label::Steady));
    }
    let departures = real_falls::departure::real_departures(&real);
    assert_eq!(departures.len(), 50);
    for d in &departures {
        assert!(d.growth > 2.5, "{d:?}");
        assert!(d.whole_from >= 3, "{d:?}");
        assert!(d.departs.is_some(), "{d:?}");
    }
    let medians: Vec<f64> = real_falls::real_by_release(&real)
        .iter()
        .map(|b| b.flat.departs)
        .collect();
    println!("real flat drops depart (median per bin, s): {medians:.3?}");
    assert!(medians.windows(2).all(|w| w[0] < w[1]), "{medians:?}");
    assert!(medians[4] > 2.0 * medians[0], "{medians:?}");
    // Far past the steady cut's 3-7 frames.
    assert!(medians.iter().all(|&m| m > 0.1), "{medians:?}");
}

/// A flat release's tilt sets how soon it departs from its flat fall: the
/// cross-check's 1–5° from rest take 0.76–1.05 s, 20–40° about 0.1 s, and
/// the films' flat drops, measured the same way past their first frames,
/// fall between (0.13–0.37 s; docs/lab/real-falls.md, "When a flat release
/// departs"). Measured on a 5.6 cm square, two flat releases each.
#[test]
fn a_more_tilted_flat_release_departs_sooner_and_the_films_fall_between() {
    let real = squares();
    let aero = real_falls::experiment_air(AeroSpec::unsteady());
    let departs = |tilt: [f64; 2]| {
        let protocol = real_falls::Protocol {
            flat_tilt_deg: tilt,
            ..Default::default()
        };
        let (_, drops) = simulate_squares(&aero, 0.056, 2, [2, 2], 1, protocol);
        let by = real_falls::sim_by_release(&drops);
        assert_eq!(by.edge.drops, 0);
        assert_eq!(by.flat.departs_drops, 2, "both depart");
        by.flat.departs
    };
    let (slight, steep) = (departs([1.0, 5.0]), departs([20.0, 40.0]));
    println!("departs: 1–5° {slight:.3} s, 20–40° {steep:.3} s");
    assert!(slight > 3.0 * steep, "{slight} against {steep}");
    let filmed = real_falls::real_by_release(&real)[2].flat;
    assert_eq!(filmed.departs_drops, 7);
    assert!(
        steep < filmed.departs && filmed.departs < slight,
        "{} against {steep}-{slight}",
        filmed.departs
    );
}

/// A flat tilt range outside 0 ≤ lo ≤ hi ≤ 90° is refused with the range.
#[test]
fn a_bad_flat_tilt_is_refused() {
    for bad in [[5.0, 1.0], [-1.0, 5.0], [1.0, 95.0], [f64::NAN, 5.0]] {
        let p = real_falls::Protocol {
            flat_tilt_deg: bad,
            ..Default::default()
        };
        let err = p.check().unwrap_err();
        assert!(err.contains("flat tilt"), "{err}");
        // The experiment refuses it before it lets anything go.
        let run = real_falls::BinReleases {
            bin: 0,
            releases: 2,
            flat: 2,
            seed: 1,
            protocol: p,
        };
        let centres = real_falls::centres(&squares());
        let refused = real_falls::simulate_bin(
            PlateShape::Square,
            0.03,
            &AeroSpec::unsteady(),
            &run,
            &centres,
        )
        .unwrap_err()
        .to_string();
        assert!(refused.contains("release protocol: flat tilt"), "{refused}");
    }
    assert!(real_falls::Protocol::default().check().is_ok());
    assert!("filmed".parse::<real_falls::ReleaseMix>().is_ok());
    assert!("thirds".parse::<real_falls::ReleaseMix>().is_err());
}

/// `Film::fastest_descent` is exact on a fall at constant acceleration
/// (the central difference of a quadratic is its derivative at the middle
/// frame) and at constant speed, and needs three frames.
#[test]
fn the_fastest_descent_is_exact_on_a_free_fall_and_a_steady_one() {
    let film = |z: &dyn Fn(f64) -> f64, n: usize| {
        let mut f = real_falls::Film::default();
        for k in 0..n {
            let t = k as f64 / real_falls::FPS;
            f.position.push(nalgebra::Vector3::new(0.0, 0.0, z(t)));
            f.area[0].push(1.0);
            f.area[1].push(1.0);
        }
        f
    };
    let g = 9.81;
    let n = 40;
    let free = film(&|t| 1.16 - 0.5 * g * t * t, n);
    let last_middle = (n - 2) as f64 / real_falls::FPS;
    let fastest = free.fastest_descent().unwrap();
    assert!((fastest - g * last_middle).abs() < 1e-9, "{fastest}");
    let steady = film(&|t| 1.0 - 0.77 * t, n);
    assert!((steady.fastest_descent().unwrap() - 0.77).abs() < 1e-9);
    assert_eq!(film(&|t| 1.0 - t, 2).fastest_descent(), None);
}

/// Real paper dives: the films' on-edge drops of the 5.6–9 cm bins reach
/// over 1.5 times the fastest steady fall the unsteady law allows their
/// plates (edge-on, its weight carried by in-plane drag), and the 9 cm
/// ones over twice it, while no simulated drop gets past that speed by
/// more than 5 % (docs/lab/real-falls.md, "How fast real paper dives").
#[test]
fn real_paper_dives_faster_than_the_laws_steady_edge_on_fall() {
    use leafmagic::physics::aero::unsteady;
    use leafmagic::physics::model::AeroLaw;
    let real = squares();
    let aero = real_falls::experiment_air(AeroSpec::unsteady());
    let table = real_falls::real_table(&real);
    let by_real = real_falls::real_by_release(&real);
    for bin in [0, 2, 4] {
        let side = table[bin].side;
        let model = plate(
            PlateShape::Square,
            side,
            1.0,
            real_falls::PAPER,
            aero.clone(),
        )
        .unwrap()
        .model()
        .unwrap();
        let AeroLaw::Unsteady(law) = &model.aero else {
            panic!("the unsteady law")
        };
        let edge_on = unsteady::edge_on_speed(law, &model);
        let (_, drops) = simulate_squares(&aero, side, bin, [4, 2], 1, Default::default());
        for d in &drops {
            let fastest = d.fastest.unwrap();
            assert!(
                fastest < 1.05 * edge_on,
                "{side} m: {fastest} against {edge_on}"
            );
        }
        let dives = by_real[bin].edge.fastest;
        println!("{side} m: real on-edge dives {dives:.2} m/s, steady edge-on {edge_on:.2} m/s");
        match bin {
            0 => assert!(dives > edge_on, "{dives} against {edge_on}"),
            2 => assert!(dives > 1.5 * edge_on, "{dives} against {edge_on}"),
            _ => assert!(dives > 2.0 * edge_on, "{dives} against {edge_on}"),
        }
    }
}

/// A segment file with a value that is not a finite number, or a labels
/// file that names a missing segment, is refused with the file, the line
/// and the reason, before anything is measured.
#[test]
fn bad_real_fall_files_are_refused_with_file_line_and_reason() {
    let dir = std::env::temp_dir().join(format!("leafmagic-bad-squares-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("labels.csv"),
        "name,shape,radius_m,width_px,release_vertical,human,auto,rows\nsquare_000,square,0.0150,156,1,1,1,3\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("square_000.csv"),
        "t,x,y,z,area1,area2\n0.0,0.0,0.0,1.0,10.0,10.0\n0.0102,0.0,0.0,NaN,10.0,10.0\n",
    )
    .unwrap();
    let err = real_falls::read_squares(&dir).unwrap_err().to_string();
    assert!(err.contains("square_000.csv"), "{err}");
    assert!(err.contains("line 3") && err.contains("z is NaN"), "{err}");
    std::fs::remove_file(dir.join("square_000.csv")).unwrap();
    let err = real_falls::read_squares(&dir).unwrap_err().to_string();
    assert!(
        err.contains("square_000.csv") && err.contains("cannot read"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Another shape's films, in the squares' format, are compared with
/// plates of that shape: the squares' own films relabelled as circles give
/// the squares' real table to the bit, and a simulated side that is the
/// circles' prediction to the bit (`predict`: the same bins, centres,
/// releases and seed) and not the squares'.
#[test]
fn another_shapes_films_are_compared_with_plates_of_that_shape() {
    let dir = std::env::temp_dir().join(format!("leafmagic-circle-films-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/real-falls/squares");
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        let text = if path.file_name().unwrap() == "labels.csv" {
            text.replace(",square,", ",circle,")
        } else {
            text
        };
        std::fs::write(dir.join(path.file_name().unwrap()), text).unwrap();
    }
    let films = real_falls::read_films(&dir, None).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let squares = squares();
    assert_eq!(films.len(), squares.len());
    assert!(films.iter().all(|f| f.shape == PlateShape::Circle));
    let aero = AeroSpec::unsteady();
    let protocol = real_falls::Protocol::default();
    let circles = real_falls::compare_with(&films, &aero, 4, 1, &protocol).unwrap();
    let predicted =
        real_falls::predict(PlateShape::Circle, &squares, &aero, 4, 1, &protocol).unwrap();
    let as_squares = real_falls::compare_with(&squares, &aero, 4, 1, &protocol).unwrap();
    assert_eq!(
        circles.real, as_squares.real,
        "the same films, the same table"
    );
    assert_eq!(circles.sim, predicted, "plates of the films' shape");
    assert_ne!(circles.sim, as_squares.sim, "not squares");
    println!(
        "circles against the squares' films: score {:.2} (squares {:.2})",
        circles.score(),
        as_squares.score()
    );
}

/// Films of a shape the experiment has no plate for, of two shapes, of the
/// wrong shape for the reader, or of no size are refused with the file,
/// the line, the column and the reason; segments of two shapes handed to
/// the comparison are refused by name.
#[test]
fn films_of_no_one_shape_are_refused_by_line_and_name() {
    let dir = std::env::temp_dir().join(format!("leafmagic-shaped-films-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let film = "t,x,y,z,area1,area2\n0.0,0.0,0.0,1.0,10.0,10.0\n0.0102,0.0,0.0,0.99,10.0,10.0\n";
    for name in ["a", "b"] {
        std::fs::write(dir.join(format!("{name}.csv")), film).unwrap();
    }
    let head = "name,shape,radius_m,width_px,release_vertical,human,auto,rows\n";
    let refused = |rows: &str, only: Option<PlateShape>| {
        std::fs::write(dir.join("labels.csv"), format!("{head}{rows}")).unwrap();
        real_falls::read_films(&dir, only).unwrap_err().to_string()
    };
    let err = refused("a,star,0.02,100,0,1,1,2\n", None);
    assert!(
        err.contains("labels.csv") && err.contains("line 2") && err.contains("column 2 (shape)"),
        "{err}"
    );
    let err = refused(
        "a,circle,0.02,100,0,1,1,2\nb,hexagon,0.02,100,0,1,1,2\n",
        None,
    );
    assert!(
        err.contains("line 3") && err.contains("hexagon") && err.contains("rows above are circle"),
        "{err}"
    );
    let err = refused("a,circle,0.02,100,0,1,1,2\n", Some(PlateShape::Square));
    assert!(
        err.contains("line 2") && err.contains("wants square"),
        "{err}"
    );
    let err = refused("a,circle,0,100,0,1,1,2\n", None);
    assert!(
        err.contains("line 2") && err.contains("column 3 (radius_m)"),
        "{err}"
    );
    std::fs::write(
        dir.join("labels.csv"),
        format!("{head}a,circle,0.02,100,0,1,1,2\nb,circle,0.02,100,0,1,1,2\n"),
    )
    .unwrap();
    let mut films = real_falls::read_films(&dir, None).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    films[1].shape = PlateShape::Hexagon;
    let aero = AeroSpec::unsteady();
    let err = real_falls::compare(&films, &aero, 1, 1)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("a is a circle") && err.contains("b a hexagon"),
        "{err}"
    );
    let err = real_falls::compare(&[], &aero, 1, 1)
        .unwrap_err()
        .to_string();
    assert!(err.contains("none to compare"), "{err}");
}

/// With the wake's couple on (`wake_couple = 1.25`, docs/lab/real-falls.md,
/// "A wake that rocks the face-on fall"), a 5.6 cm square let go flat at
/// the cross-check's 1–5° departs within half to one and a half times the
/// films' 0.296 s, where without it it takes over twice as long.
#[test]
fn the_wakes_couple_lets_a_flat_release_depart_as_the_films_do() {
    let real = squares();
    let departs = |aero: &AeroSpec| {
        let (_, drops) = simulate_squares(aero, 0.056, 2, [2, 2], 1, Default::default());
        let by = real_falls::sim_by_release(&drops);
        assert_eq!(by.flat.departs_drops, 2, "both depart");
        by.flat.departs
    };
    let plain = real_falls::experiment_air(AeroSpec::unsteady());
    let woken = plain
        .clone()
        .with_lines(&["wake_couple = 1.25".to_string()])
        .unwrap();
    let films = real_falls::real_by_release(&real)[2].flat.departs;
    let (without, with) = (departs(&plain), departs(&woken));
    println!("departs: films {films:.3} s, law {without:.3} s, with the wake {with:.3} s");
    assert!(without > 2.0 * films, "{without} against {films}");
    assert!(
        (0.5 * films..1.5 * films).contains(&with),
        "{with} against {films}"
    );
}

/// With the wake on, the Munk relief (`munk_relief = 1`; docs/lab/real-falls.md,
/// "Munk relief near broadside") lets a departed flat release glide instead
/// of rocking about face-on at the Munk couple's period: 4 cm squares let
/// go flat (twelve, two seeds) drift at least 1.5 times as far as with the
/// wake alone, which leaves them under half the films' flat releases, and
/// closer to the films; they still depart as the films do.
#[test]
fn the_munk_relief_lets_a_departed_flat_release_glide() {
    let real = squares();
    let flat_falls = |aero: &AeroSpec| {
        let drops: Vec<_> = [1, 2]
            .into_iter()
            .flat_map(|seed| simulate_squares(aero, 0.040, 1, [6, 6], seed, Default::default()).1)
            .collect();
        real_falls::sim_by_release(&drops).flat
    };
    let woken = real_falls::experiment_air(AeroSpec::unsteady())
        .with_lines(&["wake_couple = 1.25".to_string()])
        .unwrap();
    let relieved = woken
        .clone()
        .with_lines(&["munk_relief = 1".to_string()])
        .unwrap();
    let films = real_falls::real_by_release(&real)[1].flat;
    let (wake, both) = (flat_falls(&woken), flat_falls(&relieved));
    println!(
        "4 cm flat releases: drift films {:.3}, wake {:.3}, wake and relief {:.3}; \
         departs films {:.3} s, wake and relief {:.3} s; Ω films {:.1}, wake {:.1}, both {:.1}",
        films.drift,
        wake.drift,
        both.drift,
        films.departs,
        both.departs,
        films.omega,
        wake.omega,
        both.omega
    );
    assert!(
        wake.drift < 0.5 * films.drift,
        "{} against {}",
        wake.drift,
        films.drift
    );
    assert!(
        both.drift > 1.5 * wake.drift,
        "{} against {}",
        both.drift,
        wake.drift
    );
    assert!(
        both.drift < films.drift,
        "{} against {}",
        both.drift,
        films.drift
    );
    assert!(
        (0.5 * films.departs..1.5 * films.departs).contains(&both.departs),
        "{} against {}",
        both.departs,
        films.departs
    );
}

/// `release_mismatch` is |ln(sim/real)| of each release's median drift and
/// tumbling rate, exactly, and nothing where a side has no median.
#[test]
fn the_like_for_like_mismatch_is_the_log_ratio_of_each_release() {
    use real_falls::{ByRelease, ReleaseStats};
    let stats = |drift: f64, omega: f64| ReleaseStats {
        drift,
        omega,
        ..ReleaseStats::default()
    };
    let real = ByRelease {
        flat: stats(0.2, 10.0),
        edge: stats(0.6, f64::NAN),
    };
    let sim = ByRelease {
        flat: stats(0.1, 10.0 * std::f64::consts::E),
        edge: stats(0.6, 12.0),
    };
    let m = real_falls::release_mismatch(&real, &sim);
    assert!((m[0].unwrap() - 2f64.ln()).abs() < 1e-15, "{m:?}");
    assert!((m[1].unwrap() - 1.0).abs() < 1e-15, "{m:?}");
    assert_eq!(m[2], Some(0.0));
    assert_eq!(m[3], None);
    // Symmetric in which side is further: the same distance both ways.
    let back = real_falls::release_mismatch(&sim, &real);
    assert_eq!(back[0], m[0]);
}

/// How far a path turns ([`real_falls::Film::path_turn`]), on films whose
/// answer is known: a straight glide turns 0°; an arc through Θ sampled
/// evenly turns 2Θ/3 between the chords of its first and last thirds
/// (headings Θ/6 and 5Θ/6 along it), either way round and across ±180°;
/// a film too short, or a third that hardly moves sideways, has no turn.
#[test]
fn the_path_turn_reads_a_line_as_none_and_an_arc_as_two_thirds_of_it() {
    use nalgebra::Vector3;
    use real_falls::Film;
    let film = |points: Vec<Vector3<f64>>| Film {
        area: [vec![1.0; points.len()], vec![1.0; points.len()]],
        position: points,
    };
    let n = 61;
    let line = film(
        (0..n)
            .map(|k| Vector3::new(0.01 * k as f64, -0.004 * k as f64, 1.0 - 0.02 * k as f64))
            .collect(),
    );
    assert!(line.path_turn().unwrap().abs() < 1e-9);
    for (theta_deg, start_deg) in [(60.0, 0.0), (-90.0, 30.0), (60.0, 160.0), (-60.0, -160.0)] {
        let (theta, start) = (f64::to_radians(theta_deg), f64::to_radians(start_deg));
        // Along a circle of radius 0.3 m: heading start + θ s at arc fraction s.
        let arc = film(
            (0..n)
                .map(|k| {
                    let s = k as f64 / (n - 1) as f64;
                    let phi = start + theta * s - theta.signum() * std::f64::consts::FRAC_PI_2;
                    Vector3::new(0.3 * phi.cos(), 0.3 * phi.sin(), 1.0 - s)
                })
                .collect(),
        );
        let turn = arc.path_turn().unwrap();
        // The thirds are whole frames: 0..20 and 40..60 of 61, exactly.
        assert!(
            (turn - 2.0 * theta_deg / 3.0).abs() < 1e-9,
            "arc {theta_deg}° from {start_deg}°: {turn}"
        );
    }
    let short = film(line.position[..5].to_vec());
    assert_eq!(short.path_turn(), None);
    let straight_down = film(
        (0..n)
            .map(|k| Vector3::new(0.0001 * k as f64, 0.0, 1.0 - 0.02 * k as f64))
            .collect(),
    );
    assert_eq!(straight_down.path_turn(), None);
}

/// The films' tumbling and chaotic squares do not glide on straight lines:
/// from the first third of their filmed segment to the last, the path of
/// the on-edge drops of the three smallest bins turns a median 16–43°
/// (each bin; 110–125° in the two largest, which fall chaotically), and
/// the flat drops' too (20–116°). The law's plates tumble in one plane and
/// turn 0° at its defaults (docs/lab/real-falls.md, "How far a tumbling path
/// turns").
#[test]
fn the_films_paths_turn_as_they_fall() {
    let by = real_falls::real_by_release(&squares());
    let edge: Vec<f64> = by.iter().map(|b| b.edge.turn).collect();
    let flat: Vec<f64> = by.iter().map(|b| b.flat.turn).collect();
    println!("median |turn|, on edge {edge:.0?}, flat {flat:.0?} degrees");
    for (k, b) in by.iter().enumerate() {
        assert!(
            b.edge.turn_drops >= 4,
            "bin {k}: {} drops",
            b.edge.turn_drops
        );
        let least = if k < 3 { 10.0 } else { 60.0 };
        assert!(b.edge.turn > least, "bin {k}: {}", b.edge.turn);
        assert!(b.flat.turn > 10.0, "bin {k}: {}", b.flat.turn);
    }
}

/// Among the films' large squares (the 6.9 and 9 cm bins, where they fall
/// chaotically), the drops whose paths turn least swing as fast as those
/// whose paths turn most: the straighter half's median Ω c/U (c the side,
/// U the segment's descent) is within 10 % of the wandering half's, and
/// both are above 1.35, where the law's planar swing gives 1.2
/// (docs/lab/real-falls.md, "Paper that bends, and a draught in the room").
/// The faster swing does not come with the wandering.
#[test]
fn the_films_large_squares_swing_as_fast_whether_or_not_their_paths_turn() {
    let mut drops: Vec<(f64, f64)> = squares()
        .iter()
        .filter(|s| s.human != Label::Steady)
        .filter(|s| real_falls::bin_of(s.radius).is_some_and(|b| b >= 3))
        .filter_map(|s| {
            let omega = s.film.tumbling_rate()?;
            let turn = s.film.path_turn()?.abs();
            let descent = s.film.features()?.descent();
            Some((turn, omega * 2.0 * s.radius / descent))
        })
        .collect();
    assert!(drops.len() >= 30, "{} drops", drops.len());
    drops.sort_by(|a, b| a.0.total_cmp(&b.0));
    let half = drops.len() / 2;
    let median = |part: &[(f64, f64)], k: usize| match k {
        0 => real_falls::median(part.iter().map(|d| d.0)),
        _ => real_falls::median(part.iter().map(|d| d.1)),
    };
    let (straight, wandering) = (&drops[..half], &drops[half..]);
    let (s_turn, s_rate) = (median(straight, 0), median(straight, 1));
    let (w_turn, w_rate) = (median(wandering, 0), median(wandering, 1));
    println!(
        "{} drops: turning least {s_turn:.0}° at Ω c/U {s_rate:.2}, most {w_turn:.0}° at {w_rate:.2}",
        drops.len()
    );
    assert!(w_turn > 2.0 * s_turn, "{s_turn} against {w_turn}");
    assert!(
        (s_rate / w_rate - 1.0).abs() < 0.1,
        "{s_rate} against {w_rate}"
    );
    assert!(s_rate.min(w_rate) > 1.35, "{s_rate}, {w_rate}");
}

/// The weighted median is the median where the weights are equal (any
/// length, odd or even, any common weight), and otherwise follows the
/// weights: the value where the cumulative weight passes half, or the mean
/// of the two either side where it meets half exactly.
#[test]
fn the_weighted_median_is_the_median_at_equal_weights_and_follows_the_weights() {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(17);
    for _ in 0..500 {
        let n = rng.random_range(1..30);
        let values: Vec<f64> = (0..n).map(|_| rng.random_range(-5.0..5.0)).collect();
        let weight = rng.random_range(1e-3..1e3);
        let plain = real_falls::median(values.iter().copied());
        let weighted = real_falls::weighted_median(values.iter().map(|&v| (v, weight)));
        assert_eq!(plain, weighted, "{values:?} at weight {weight}");
    }
    let wm = |pairs: &[(f64, f64)]| real_falls::weighted_median(pairs.iter().copied());
    assert_eq!(wm(&[(1.0, 1.0), (2.0, 1.0), (3.0, 3.0)]), 3.0);
    assert_eq!(wm(&[(1.0, 2.0), (2.0, 1.0)]), 1.0);
    assert_eq!(wm(&[(1.0, 1.0), (2.0, 3.0), (4.0, 4.0)]), 3.0);
    assert_eq!(wm(&[(f64::NAN, 9.0), (2.0, 1.0), (7.0, 0.0)]), 2.0);
    assert!(wm(&[(1.0, 0.0)]).is_nan());
}

/// The films re-weighted to their own mix of releases are their table;
/// re-weighted to half flat and half on edge, as the simulation lets go,
/// the smallest squares' median drift falls from 0.71 (a bin of 9 on-edge
/// drops to 5 flat ones, drifting 0.72 and 0.26) to between the two kinds'
/// medians and below two thirds of the pooled value: a law that fell
/// exactly as each kind of the films' releases does would miss the issue's
/// ×1.5 drift bound in that bin against the films' pooled median
/// (docs/lab/real-falls.md, "The films at the simulated mix").
#[test]
fn the_films_at_their_own_mix_are_their_table_and_at_halves_drift_less() {
    let real = squares();
    let table = real_falls::real_table(&real);
    let own = real_falls::real_table_at_mix(&real, &real_falls::real_flat_share(&real));
    for (a, b) in table.iter().zip(&own) {
        for (x, y) in [
            (a.tumbling, b.tumbling),
            (a.descent, b.descent),
            (a.drift, b.drift),
            (a.omega, b.omega),
        ] {
            assert!((x - y).abs() <= 1e-12 * x.abs(), "{x} against {y}");
        }
        assert_eq!((a.counts, a.side), (b.counts, b.side));
    }
    let halves = real_falls::real_table_at_mix(&real, &[0.5; 5]);
    let by = &real_falls::real_by_release(&real)[0];
    let drift = halves[0].drift;
    println!(
        "3.2 cm drift: pooled {:.3}, at halves {drift:.3}; flat {:.3}, on edge {:.3}",
        table[0].drift, by.flat.drift, by.edge.drift
    );
    assert!(by.flat.drift < drift && drift < by.edge.drift);
    assert!(drift / table[0].drift < 1.0 / real_falls::DRIFT_FACTOR);
}

/// The per-bin bounds, at and either side of each edge: descent
/// within 10 %, drift within ×1.5 either way, Ω within 15 %; a statistic
/// the simulation cannot give misses.
#[test]
fn the_per_bin_bounds_name_each_statistic_outside_them() {
    use real_falls::BinStats;
    let real = BinStats {
        descent: 0.8,
        drift: 0.4,
        omega: 20.0,
        ..Default::default()
    };
    let sim = |descent: f64, drift: f64, omega: f64| BinStats {
        descent: 0.8 * descent,
        drift: 0.4 * drift,
        omega: 20.0 * omega,
        ..Default::default()
    };
    let names = |s: BinStats| -> Vec<&str> {
        real_falls::bounds_missed(&real, &s)
            .into_iter()
            .map(|(n, _)| n)
            .collect()
    };
    assert!(names(sim(1.09, 1.49, 0.86)).is_empty());
    assert!(names(sim(0.91, 1.0 / 1.49, 1.14)).is_empty());
    assert_eq!(names(sim(1.11, 1.0, 1.0)), ["v"]);
    assert_eq!(names(sim(1.0, 1.0 / 1.51, 1.0)), ["drift"]);
    assert_eq!(names(sim(1.0, 1.51, 0.84)), ["drift", "Ω"]);
    assert_eq!(names(sim(f64::NAN, 1.0, 1.0)), ["v"]);
    let (name, ratio) = real_falls::bounds_missed(&real, &sim(1.0, 1.0, 0.8))[0];
    assert_eq!(name, "Ω");
    assert!((ratio - 0.8).abs() < 1e-12);
}

/// Like for like, the smallest squares drift as the films do: 24 releases
/// of the 3.2 cm bin at the cross-check's protocol (half flat, half on
/// edge) drift within ×1.5 of the films re-weighted to the same mix, at two
/// seeds, where against the films' own pooled median (9 on-edge drops to 5
/// flat ones) they drift under 2/3 of it (docs/lab/real-falls.md, "The films at
/// the simulated mix").
#[test]
fn the_smallest_squares_drift_as_the_films_do_at_the_same_mix() {
    let real = squares();
    let table = real_falls::real_table(&real);
    let aero = real_falls::experiment_air(AeroSpec::unsteady());
    for seed in [1, 2] {
        let (sim, drops) =
            simulate_squares(&aero, table[0].side, 0, [24, 12], seed, Default::default());
        let by = real_falls::sim_by_release(&drops);
        let share = real_falls::sim_flat_share(&drops);
        let remixed = real_falls::real_table_at_mix(&real, &[share; 5]);
        let (like, pooled) = (sim.drift / remixed[0].drift, sim.drift / table[0].drift);
        println!(
            "seed {seed}: drift {:.6} (flat {:.4}, edge {:.4}); flat share {share:.2}; against the films at that mix {like:.2}, against their pooled median {pooled:.2}",
            sim.drift, by.flat.drift, by.edge.drift
        );
        assert!(
            real_falls::bounds_missed(&remixed[0], &sim)
                .iter()
                .all(|(name, _)| *name != "drift"),
            "seed {seed}: drift ratio {like}"
        );
        assert!(
            pooled < 1.0 / real_falls::DRIFT_FACTOR,
            "seed {seed}: {pooled}"
        );
    }
}

/// The experiment is converged in the plates' mesh: the same releases of
/// the 5.6 cm and 9 cm squares (the transition and the chaotic bins), 12
/// each, on `leafmagic plate`'s mesh and on one twice as fine across, fall
/// at the same speed within 2 %, turn at the same rate within 5 % and
/// drift within 10 % (docs/lab/real-falls.md, "Is the experiment converged?";
/// over ten seeds of 24 releases the scores agree to 0.001). A refinement
/// of 0 is refused.
#[test]
fn the_experiment_is_converged_in_the_mesh() {
    let aero = real_falls::experiment_air(AeroSpec::unsteady());
    for (bin, side) in [(2, 0.056), (4, 0.09)] {
        let stats = |refine: usize| {
            let protocol = real_falls::Protocol {
                refine,
                ..Default::default()
            };
            simulate_squares(&aero, side, bin, [12, 6], 3, protocol).0
        };
        let (coarse, fine) = (stats(1), stats(2));
        let ratio = |a: f64, b: f64| b / a;
        let (v, drift, omega) = (
            ratio(coarse.descent, fine.descent),
            ratio(coarse.drift, fine.drift),
            ratio(coarse.omega, fine.omega),
        );
        println!(
            "{side} m, twice as fine over as coarse: descent {v:.3}, drift {drift:.3}, Ω {omega:.3}"
        );
        assert!((v - 1.0).abs() < 0.02, "{side}: descent {v}");
        assert!((omega - 1.0).abs() < 0.05, "{side}: Ω {omega}");
        assert!((drift - 1.0).abs() < 0.1, "{side}: drift {drift}");
    }
    let p = real_falls::Protocol {
        refine: 0,
        ..Default::default()
    };
    assert!(p.check().unwrap_err().contains("refinement"));
}

/// A draught is the Ornstein–Uhlenbeck wind it says (each horizontal
/// component of 3,000 s sampled at its keys: standard deviation within 3 %
/// of σ, mean within 0.06 σ, autocorrelation after one correlation time
/// within 0.05 of e⁻¹, the two components uncorrelated within 0.05,
/// nothing vertical); the same release gets the same draught, another
/// release or seed another; a draught without a positive speed and
/// correlation time is refused.
#[test]
fn a_draught_is_an_ornstein_uhlenbeck_wind_of_its_speed_and_correlation() {
    use nalgebra::Vector3;
    let draught = real_falls::Draught {
        speed: 0.05,
        correlation: 0.3,
    };
    let field = real_falls::draught_field(&draught, 7, 2, 5, 3000.0);
    let h = draught.correlation / real_falls::DRAUGHT_KEYS_PER_CORRELATION;
    let at = |f: &leafmagic::physics::field::WindField, t: f64| f.velocity(&Vector3::zeros(), t);
    let samples: Vec<Vector3<f64>> = (0..(3000.0 / h) as usize)
        .map(|n| at(&field, n as f64 * h))
        .collect();
    let n = samples.len() as f64;
    let lag = real_falls::DRAUGHT_KEYS_PER_CORRELATION as usize;
    for axis in 0..2 {
        let x: Vec<f64> = samples.iter().map(|v| v[axis]).collect();
        let mean = x.iter().sum::<f64>() / n;
        let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
        let auto = x
            .windows(lag + 1)
            .map(|w| (w[0] - mean) * (w[lag] - mean))
            .sum::<f64>()
            / (x.len() - lag) as f64
            / var;
        println!(
            "axis {axis}: mean {mean:.5}, sd {:.5}, autocorrelation at τ {auto:.3}",
            var.sqrt()
        );
        assert!(
            (var.sqrt() / draught.speed - 1.0).abs() < 0.03,
            "{}",
            var.sqrt()
        );
        assert!(mean.abs() < 0.06 * draught.speed, "{mean}");
        assert!((auto - (-1f64).exp()).abs() < 0.05, "{auto}");
    }
    let cross =
        samples.iter().map(|v| v.x * v.y).sum::<f64>() / n / (draught.speed * draught.speed);
    assert!(cross.abs() < 0.05, "{cross}");
    assert!(samples.iter().all(|v| v.z == 0.0));
    let short = |seed, k| real_falls::draught_field(&draught, seed, 2, k, 2.0);
    for t in [0.0, 0.31, 1.7] {
        assert_eq!(at(&short(7, 5), t), at(&short(7, 5), t));
        assert_ne!(at(&short(7, 5), t), at(&short(7, 6), t));
        assert_ne!(at(&short(7, 5), t), at(&short(8, 5), t));
    }
    for (speed, correlation) in [(0.0, 0.3), (-0.05, 0.3), (0.05, 0.0), (f64::NAN, 0.3)] {
        let p = real_falls::Protocol {
            draught: Some(real_falls::Draught { speed, correlation }),
            ..Default::default()
        };
        assert!(
            p.check().unwrap_err().contains("draught"),
            "{speed} {correlation}"
        );
    }
}

/// In still air the law's 3.2 cm squares let go on edge tumble in one plane
/// and their paths do not turn; in a draught of 5 cm/s they turn, as the
/// films' do (16° on edge) and more (docs/lab/real-falls.md, "Paper that bends,
/// and a draught in the room").
#[test]
fn a_draught_turns_the_small_squares_paths() {
    let aero = real_falls::experiment_air(AeroSpec::unsteady());
    let turns = |draught| {
        let protocol = real_falls::Protocol {
            draught,
            ..Default::default()
        };
        let (_, drops) = simulate_squares(&aero, 0.032, 0, [6, 0], 1, protocol);
        real_falls::median(drops.iter().filter_map(|d| d.turn).map(f64::abs))
    };
    let still = turns(None);
    let draught = turns(Some(real_falls::Draught {
        speed: 0.05,
        correlation: 0.3,
    }));
    println!("3.2 cm on edge, median path turn: still air {still:.1}°, draught {draught:.0}°");
    assert!(still < 1.0, "{still}");
    assert!(draught > 16.0, "{draught}");
}

/// `rotation_of` names a fall from its orientations with the motion
/// classifier's kinematics: a steady turn end over end at 20 rad/s for 1 s
/// is tumbling, a swing of ±0.8 rad at 2 Hz for 2 s fluttering (about
/// either horizontal axis), a swing of ±2.5 rad, which turns the plate over
/// and back past the flip's ±30° hysteresis, mixed, and a plate falling
/// flat at rest steady.
#[test]
fn the_rotation_of_a_fall_reads_tumbling_fluttering_and_both() {
    use leafmagic::motion::trajectory::Trajectory;
    use nalgebra::{UnitQuaternion, Vector3};
    use real_falls::Rotation;
    let fps = real_falls::FPS;
    let fall = |seconds: f64, axis: Vector3<f64>, angle: &dyn Fn(f64) -> f64| {
        let time: Vec<f64> = (0..=(seconds * fps) as usize)
            .map(|k| k as f64 / fps)
            .collect();
        Trajectory {
            position: time.iter().map(|t| Vector3::new(0.0, 0.0, -t)).collect(),
            orientation: time
                .iter()
                .map(|&t| UnitQuaternion::from_scaled_axis(axis * angle(t)))
                .collect(),
            time,
            areas: Vec::new(),
        }
    };
    let size = 0.05;
    let swing = |amplitude: f64| move |t: f64| amplitude * (std::f64::consts::TAU * 2.0 * t).sin();
    let x = Vector3::x();
    assert_eq!(
        real_falls::rotation_of(&fall(1.0, x, &|t| 20.0 * t), size),
        Rotation::Tumbling
    );
    for axis in [x, Vector3::y()] {
        assert_eq!(
            real_falls::rotation_of(&fall(2.0, axis, &swing(0.8)), size),
            Rotation::Fluttering
        );
        assert_eq!(
            real_falls::rotation_of(&fall(2.0, axis, &swing(2.5)), size),
            Rotation::Mixed
        );
    }
    assert_eq!(
        real_falls::rotation_of(&fall(1.0, x, &|_| 0.0), size),
        Rotation::Steady
    );
}

/// What the law's 9 cm squares do in the experiment, read from their
/// rotation: let go on edge they tumble end over end without once swinging
/// back, let go flat they flutter without once turning over; none does
/// both, as a chaotic fall would. The experiment's rule still labels the
/// tumbling ones chaotic: they turn at about 3.3 area maxima per second,
/// nearer the films' chaotic centre (4.3) than their tumbling one (7.2),
/// because a large plate turns slowly (docs/lab/real-falls.md, "What the law's
/// falls are, by their rotation").
#[test]
fn the_laws_large_squares_tumble_or_flutter_and_the_rule_calls_the_tumbles_chaotic() {
    let aero = real_falls::experiment_air(AeroSpec::unsteady());
    let (_, drops) = simulate_squares(&aero, 0.09, 4, [8, 4], 1, Default::default());
    assert_eq!(real_falls::rotation_counts(&drops, true), [4, 0, 0, 0]);
    assert_eq!(real_falls::rotation_counts(&drops, false), [0, 4, 0, 0]);
    for d in drops.iter().filter(|d| d.on_edge) {
        assert_eq!(d.moving_label(), Some(Label::Chaotic), "{d:?}");
    }
}

/// The experiment's protocol refuses a bending stiffness that is not a
/// positive number, naming it.
#[test]
fn a_protocol_refuses_a_bending_stiffness_that_is_not_positive() {
    for bad in [0.0, -1.0, f64::NAN] {
        let protocol = real_falls::Protocol {
            bending: Some(bad),
            ..Default::default()
        };
        let err = protocol.check().unwrap_err();
        assert!(err.contains("bending stiffness"), "{err}");
    }
}
