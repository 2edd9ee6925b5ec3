//! The literature order of falling plates under the unsteady law: disks of
//! 3 and 5 cm over a sweep of the dimensionless moment of inertia
//! I*_disk = π σ / (64 ρ d) (Field et al. 1997: flutter below about 0.01,
//! chaos between, tumbling above about 0.04; docs/design/falling-plates.md), each
//! let go flat (5°, 2°) and at 30°, 8 s; then strips of aspect 5 over
//! areal density ×8 and width ×4, let go at 60° about the long axis, each
//! falling 8 s and over two equal scaled durations, with the fit
//! Ω ∝ σ^p w^q over those that tumble (Mahadevan, Ryu & Samuel 1999:
//! p = 1/2, q = −1; docs/lab/real-falls.md, "The strips' exponents and the
//! protocol"). Coefficients as in a leaf file, `KEY=VALUE`.
//!
//! cargo run --release --example plate_regimes [-- KEY=VALUE ...]

use leafmagic::leaf::plates::{PlateShape, plate};
use leafmagic::leaf::{AeroLawName, AeroSpec};
use leafmagic::motion::class::Regime;
use leafmagic::physics::aero::unsteady::AIR_DENSITY_20C;
use leafmagic::physics::model::STANDARD_GRAVITY as G;
use leafmagic_lab::strips::{
    SCALED_DURATION, SIGMAS, StripFall, WIDTHS, classify_plate_fall, fit_exponents, strip_fall,
    strip_seconds,
};
use rayon::prelude::*;
use std::process::ExitCode;

/// Density of air at 20 °C, the law's default, kg/m³.
const RHO: f64 = AIR_DENSITY_20C;

struct Fall {
    regime: String,
    omega: f64,
    descent: f64,
    drift: f64,
    rocking: f64,
}

/// A disk's fall (`classify_plate_fall`) as the table shows it.
fn fall(size: f64, sigma: f64, tilt: [f64; 2], aero: &AeroSpec) -> Fall {
    let c = classify_plate_fall(PlateShape::Circle, size, 1.0, sigma, tilt, 8.0, aero)
        .expect("the disk falls");
    let f = &c.features;
    Fall {
        regime: c.regime.to_string(),
        omega: f.tumbling_rate_rad_s(),
        descent: f.mean_descent_speed_m_s,
        drift: f.drift_ratio,
        rocking: f.rocking_amplitude_deg,
    }
}

fn main() -> ExitCode {
    leafmagic::util::pipe::quiet_broken_pipe();
    let extra: Vec<String> = std::env::args().skip(1).filter(|a| a != "--").collect();
    // Keys that read one by one can still make a law that is refused as a
    // whole (translational lift above half the normal drag): build a plate
    // with it first, so bad input is one line and exit 1, not a panic in
    // a worker thread.
    let aero = match AeroSpec::named(AeroLawName::Unsteady)
        .with_lines(&extra)
        .map_err(|e| e.to_string())
        .and_then(|aero| {
            plate(PlateShape::Circle, 0.03, 1.0, 0.07, aero.clone())
                .map_err(|e| e.to_string())
                .and_then(|spec| spec.model().map_err(|e| e.to_string()))
                .map(|_| aero)
        }) {
        Ok(aero) => aero,
        Err(e) => {
            eprintln!("plate_regimes: bad [aero] table: {e}");
            return ExitCode::FAILURE;
        }
    };

    println!("## Disks: regime against I*_disk (Field et al. 1997)\n");
    println!(
        "| d cm | I*_disk | σ g/m² | let go | regime | Ω rad/s | descent m/s | drift | rocking ° |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut cases = Vec::new();
    for d in [0.03, 0.05] {
        for istar in [0.005, 0.01, 0.02, 0.025, 0.03, 0.04, 0.08, 0.16] {
            for tilt in [[5.0, 2.0], [30.0, 0.0]] {
                cases.push((d, istar, tilt));
            }
        }
    }
    let disks: Vec<Fall> = cases
        .par_iter()
        .map(|&(d, istar, tilt)| {
            let sigma = istar * 64.0 * RHO * d / std::f64::consts::PI;
            fall(d, sigma, tilt, &aero)
        })
        .collect();
    for (&(d, istar, tilt), f) in cases.iter().zip(&disks) {
        let sigma = istar * 64.0 * RHO * d / std::f64::consts::PI;
        println!(
            "| {:.0} | {istar} | {:.1} | {}° | {} | {:.1} | {:.3} | {:.2} | {:.0} |",
            d * 100.0,
            sigma * 1000.0,
            tilt[0],
            f.regime,
            f.omega,
            f.descent,
            f.drift,
            f.rocking
        );
    }

    // Strips: a fall depends on σ and w only through I* = σ/(ρ w) and
    // the scaled time t U/w, U = √(σ g/ρ) (tests/integration/unsteady.rs,
    // `a_plate_scaled_by_powers_of_two_falls_the_same_scaled_fall`), and
    // the strips' tumbling changes over hundreds of scaled times. So each
    // is measured over the same scaled duration τ as well as over 8 s.
    println!("\n## Strips (aspect 5, let go at 60° about the long axis): Ω ∝ σ^p w^q\n");
    println!(
        "Each strip falls for 8 s, and for τ = {} and {} scaled times (t √(σ g/ρ) / w); \
         the classifier's window is the last 60 % of the fall.\n",
        SCALED_DURATIONS[0], SCALED_DURATIONS[1]
    );
    println!(
        "| σ g/m² | w cm | I* | fall | regime | Ω rad/s | descent m/s | drift | Ω w/√(σg/ρ) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut strips = Vec::new();
    for sigma in SIGMAS {
        for w in WIDTHS {
            for duration in PROTOCOLS {
                strips.push((sigma, w, duration));
            }
        }
    }
    let falls: Vec<StripFall> = strips
        .par_iter()
        .map(|&(sigma, w, duration)| {
            let seconds = duration.map_or(8.0, |tau| strip_seconds(sigma, w, tau, RHO));
            strip_fall(sigma, w, seconds, &aero).expect("the strip falls")
        })
        .collect();
    for (&(sigma, w, duration), f) in strips.iter().zip(&falls) {
        println!(
            "| {:.0} | {:.0} | {:.1} | {} | {} | {:.1} | {:.3} | {:.2} | {:.2} |",
            sigma * 1000.0,
            w * 100.0,
            sigma / (RHO * w),
            duration.map_or("8 s".to_string(), |tau| format!("τ {tau}")),
            f.regime,
            f.omega,
            f.descent,
            f.drift,
            f.omega * w / (sigma * G / RHO).sqrt()
        );
    }
    for duration in PROTOCOLS {
        let group: Vec<StripFall> = strips
            .iter()
            .zip(&falls)
            .filter(|((_, _, d), _)| *d == duration)
            .map(|(_, f)| f.clone())
            .collect();
        let tumbling = group.iter().filter(|f| f.regime == Regime::Tumble).count();
        let label = duration.map_or("over 8 s".to_string(), |tau| format!("at τ = {tau}"));
        match fit_exponents(&group) {
            Some((p, q)) => println!(
                "\nfit {label} over {tumbling} tumbling strips: p = {p:.2}, q = {q:.2} (target 0.5 ± 0.1, −1.0 ± 0.1)"
            ),
            None => println!(
                "\n{label}: only {tumbling} of 12 strips tumble, or they do not span σ and w: no fit"
            ),
        }
    }
    ExitCode::SUCCESS
}

/// The scaled durations τ = t √(σ g/ρ) / w over which the strips are
/// compared besides 8 s: 150 (most strips still glide as they tumble) and
/// [`SCALED_DURATION`], the one the law is held at (docs/lab/real-falls.md).
const SCALED_DURATIONS: [f64; 2] = [150.0, SCALED_DURATION];

/// How long each strip falls: 8 s (`None`), then each of
/// [`SCALED_DURATIONS`].
const PROTOCOLS: [Option<f64>; 3] = [None, Some(SCALED_DURATIONS[0]), Some(SCALED_DURATIONS[1])];
