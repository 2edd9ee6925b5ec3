//! The real-falls experiment (docs/real-falls.md): the real side of the
//! table computed from tests/data/real-falls/squares, and the simulated
//! side under the unsteady law with its one default set of coefficients.
//! Of the targets (score ≤ 0.6, descent within 10 %, drift within
//! ×1.5, Ω within 15 % in every bin) only the last is met today; these
//! tests hold what is reached, so a change that makes it worse fails. Also
//! the strips' scaling law, as far as it is reached.

use leafmagic::leaf::plates::{PlateShape, plate};
use leafmagic::leaf::{AeroLawName, AeroSpec};
use leafmagic::motion::class::Regime;
use leafmagic::motion::classify::{Classification, classify};
use leafmagic::physics::model::AIR_DENSITY_20C;
use leafmagic::sim::drop::{DropParams, drop_leaf};
use leafmagic::sim::real_falls::{self, Label};
use std::path::Path;

fn squares() -> Vec<real_falls::RealSegment> {
    real_falls::read_squares(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real-falls/squares"),
    )
    .unwrap()
}

/// The real table: small squares tumble, large ones fall chaotically, all
/// descend at 0.73–0.81 m/s and turn at 26 → 12.6 rad/s (Howison, Hughes
/// & Iida 2020, as docs/real-falls.md summarises them).
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

/// The simulated experiment (4 releases per bin here, 12 in the example)
/// runs in every bin without diverging; what it reaches with the default
/// coefficients is held (measured at 4 releases, seed 1): the score no
/// worse than 1.2 (1.04; 1.48 under the earlier APW defaults, 2.44 before
/// drag stopped seeing the plate's rotation; the target 0.6 is missed),
/// small squares let go flat tumble as real ones do (3.2 cm: 1.00 of the
/// simulated drops, real 0.79) and the largest do not (9 cm: 0.00, real
/// 0.04), the tumbling rate within 15 % of the real one in every bin (the
/// issue's per-bin target; 0.92–1.10) and descent within 35 % (1.05–1.30
/// of real: the simulated squares fall too fast, most in the smallest bin).
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
        assert!((omega - 1.0).abs() < 0.15, "{} m: Ω ratio {omega}", r.side);
        let descent = s.descent / r.descent;
        assert!(
            (descent - 1.0).abs() < 0.35,
            "{} m: descent ratio {descent}",
            r.side
        );
    }
    println!("score {:.2}", cmp.score());
    assert!(cmp.score() <= 1.2, "score {}", cmp.score());
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
    let model = plate(shape, size, aspect, sigma, aero)
        .unwrap()
        .model()
        .unwrap();
    let params = DropParams {
        seconds: 8.0,
        tilt_deg: tilt,
        ..Default::default()
    };
    let run = drop_leaf(&model, &params).unwrap();
    classify(&run.trajectory, model.chord())
}

/// Strips of aspect 5 let go at 60° about their long axis tumble, faster
/// when heavier and slower when wider (Mahadevan, Ryu & Samuel 1999:
/// Ω ∝ σ^(1/2) w^(−1)). The four corners of the sweep of
/// `examples/plate_regimes.rs` (σ 35 and 280 g/m², w 1 and 4 cm): all four
/// tumble, and the exponents of their fit have the law's signs and the
/// sizes reached today (p = 0.34, q = −0.53 over the corners; 0.39 and
/// −0.65 over all twelve strips; the 0.5 ± 0.1 and −1.0 ± 0.1 are
/// missed, docs/real-falls.md).
#[test]
fn strips_tumble_faster_when_heavier_and_slower_when_wider() {
    let omega = |sigma: f64, w: f64| {
        let c = plate_fall(PlateShape::Rectangle, w, 5.0, sigma, [60.0, 0.0]);
        assert_eq!(c.regime, Regime::Tumble, "σ {sigma}, w {w}: {:?}", c.reason);
        let f = &c.features;
        std::f64::consts::TAU * f.net_turns.abs() / (f.t_end_s - f.t_start_s)
    };
    let (light, heavy, narrow, wide) = (0.035, 0.28, 0.01, 0.04);
    let o = [
        [omega(light, narrow), omega(light, wide)],
        [omega(heavy, narrow), omega(heavy, wide)],
    ];
    println!("Ω rad/s: σ {light}: {:?}; σ {heavy}: {:?}", o[0], o[1]);
    // A 2 × 2 design: the least-squares exponents are the mean log ratios.
    let p = ((o[1][0] / o[0][0]).ln() + (o[1][1] / o[0][1]).ln()) / 2.0 / (heavy / light).ln();
    let q = ((o[0][1] / o[0][0]).ln() + (o[1][1] / o[1][0]).ln()) / 2.0 / (wide / narrow).ln();
    println!("p = {p:.3}, q = {q:.3}");
    assert!((0.2..0.6).contains(&p), "p = {p}");
    assert!((-1.1..-0.3).contains(&q), "q = {q}");
}

/// Disks let go nearly flat go through the literature's order as their
/// dimensionless moment of inertia I*_disk = π σ / (64 ρ d) rises (Field et
/// al. 1997: flutter below about 0.01, chaos between, tumbling above about
/// 0.04): a 3 cm disk flutters at 0.005, falls chaotically at 0.02 and
/// tumbles at 0.08 and at 0.16 (under the earlier defaults the heaviest
/// rocked in place and never turned over; docs/real-falls.md).
#[test]
fn disks_flutter_then_fall_chaotically_then_tumble_as_they_get_heavier() {
    let d = 0.03;
    for (istar, expected) in [
        (0.005, Regime::Flutter),
        (0.02, Regime::Chaotic),
        (0.08, Regime::Tumble),
        (0.16, Regime::Tumble),
    ] {
        // The law's default air, as examples/plate_regimes.rs.
        let sigma = istar * 64.0 * AIR_DENSITY_20C * d / std::f64::consts::PI;
        let c = plate_fall(PlateShape::Circle, d, 1.0, sigma, [5.0, 2.0]);
        assert_eq!(c.regime, expected, "I* {istar}: {:?}", c.reason);
    }
}
