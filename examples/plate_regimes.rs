//! The literature order of falling plates under the unsteady law: disks of
//! 3 and 5 cm over a sweep of the dimensionless moment of inertia
//! I*_disk = π σ / (64 ρ d) (Field et al. 1997: flutter below about 0.01,
//! chaos between, tumbling above about 0.04; docs/falling-plates.md), each
//! let go flat (5°, 2°) and at 30°, 8 s; then strips of aspect 5 over
//! areal density ×8 and width ×4, let go at 60° about the long axis, with
//! the fit Ω ∝ σ^p w^q over those that tumble (Mahadevan, Ryu & Samuel
//! 1999: p = 1/2, q = −1). Coefficients as in a leaf file, `KEY=VALUE`.
//!
//! cargo run --release --example plate_regimes [-- KEY=VALUE ...]

use leafmagic::leaf::plates::{PlateShape, plate};
use leafmagic::leaf::{AeroLawName, AeroSpec};
use leafmagic::motion::classify::classify;
use leafmagic::sim::drop::{DropParams, drop_leaf};
use rayon::prelude::*;

/// Density of air at 20 °C, the law's default, kg/m³.
const RHO: f64 = 1.204;

struct Fall {
    regime: String,
    omega: f64,
    descent: f64,
    drift: f64,
    rocking: f64,
}

fn fall(
    shape: PlateShape,
    size: f64,
    aspect: f64,
    sigma: f64,
    tilt: [f64; 2],
    aero: &AeroSpec,
) -> Fall {
    let model = plate(shape, size, aspect, sigma, aero.clone())
        .expect("a valid plate")
        .model()
        .expect("a valid model");
    let params = DropParams {
        seconds: 8.0,
        tilt_deg: tilt,
        ..Default::default()
    };
    let run = drop_leaf(&model, &params).expect("the drop runs");
    let c = classify(&run.trajectory, model.chord());
    let f = &c.features;
    let window = (f.t_end_s - f.t_start_s).max(f64::MIN_POSITIVE);
    Fall {
        regime: c.regime.to_string(),
        omega: std::f64::consts::TAU * f.net_turns.abs() / window,
        descent: f.mean_descent_speed_m_s,
        drift: f.drift_ratio,
        rocking: f.rocking_amplitude_deg,
    }
}

fn main() {
    let aero = AeroSpec::named(AeroLawName::Unsteady);
    let extra: Vec<String> = std::env::args().skip(1).filter(|a| a != "--").collect();
    let aero = aero
        .with_lines(&extra)
        .unwrap_or_else(|e| panic!("bad [aero] key: {e}"));

    println!("## Disks: regime against I*_disk (Field et al. 1997)\n");
    println!(
        "| d cm | I*_disk | σ g/m² | let go | regime | Ω rad/s | descent m/s | drift | rocking ° |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut cases = Vec::new();
    for d in [0.03, 0.05] {
        for istar in [0.005, 0.01, 0.02, 0.04, 0.08, 0.16] {
            for tilt in [[5.0, 2.0], [30.0, 0.0]] {
                cases.push((d, istar, tilt));
            }
        }
    }
    let disks: Vec<Fall> = cases
        .par_iter()
        .map(|&(d, istar, tilt)| {
            let sigma = istar * 64.0 * RHO * d / std::f64::consts::PI;
            fall(PlateShape::Circle, d, 1.0, sigma, tilt, &aero)
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

    println!("\n## Strips (aspect 5, let go at 60° about the long axis): Ω ∝ σ^p w^q\n");
    println!("| σ g/m² | w cm | regime | Ω rad/s | descent m/s | drift |");
    println!("|---|---|---|---|---|---|");
    let mut strips = Vec::new();
    for sigma in [0.035, 0.07, 0.14, 0.28] {
        for w in [0.01, 0.02, 0.04] {
            strips.push((sigma, w));
        }
    }
    let falls: Vec<Fall> = strips
        .par_iter()
        .map(|&(sigma, w)| fall(PlateShape::Rectangle, w, 5.0, sigma, [60.0, 0.0], &aero))
        .collect();
    let mut fit = Vec::new();
    for (&(sigma, w), f) in strips.iter().zip(&falls) {
        println!(
            "| {:.0} | {:.0} | {} | {:.1} | {:.3} | {:.2} |",
            sigma * 1000.0,
            w * 100.0,
            f.regime,
            f.omega,
            f.descent,
            f.drift
        );
        if f.regime == "tumble" && f.omega > 0.0 {
            fit.push((sigma.ln(), w.ln(), f.omega.ln()));
        }
    }
    // Least squares ln Ω = c + p ln σ + q ln w over the tumbling strips.
    if fit.len() >= 4 {
        let mut a = nalgebra::Matrix3::<f64>::zeros();
        let mut b = nalgebra::Vector3::<f64>::zeros();
        for &(s, w, o) in &fit {
            let row = nalgebra::Vector3::new(1.0, s, w);
            a += row * row.transpose();
            b += row * o;
        }
        match a.try_inverse() {
            Some(inv) => {
                let x = inv * b;
                println!(
                    "\nfit over {} tumbling strips: p = {:.2}, q = {:.2} (target 0.5 ± 0.1, −1.0 ± 0.1)",
                    fit.len(),
                    x[1],
                    x[2]
                );
            }
            None => println!("\nthe tumbling strips do not span σ and w: no fit"),
        }
    } else {
        println!(
            "\nonly {} of {} strips tumble: too few to fit p and q",
            fit.len(),
            strips.len()
        );
    }
}
