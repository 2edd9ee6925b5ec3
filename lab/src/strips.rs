//! The strips' scaling law (Mahadevan, Ryu & Samuel 1999): a strip tumbling
//! about its long axis turns at Ω ∝ σ^½ w⁻¹, σ its areal density and w its
//! width. This module is the experiment that measures it in leafmagic:
//! strips of aspect 5 over areal density ×8 and width ×4, let go at 60°
//! about the long axis, each falling the same number of scaled times
//! τ = t √(σ g/ρ) / w, and the least-squares fit ln Ω = c + p ln σ + q ln w
//! over those that tumble. A fall depends on σ and w only through
//! I* = σ/(ρ w) and the scaled time (tests/integration/unsteady.rs,
//! `a_plate_scaled_by_powers_of_two_falls_the_same_scaled_fall`), and a
//! strip's tumbling settles over hundreds of scaled times, so equal scaled
//! durations compare like with like where a fixed 8 s would not
//! (docs/lab/real-falls.md, "The strips' exponents and the protocol").

use leafmagic::leaf::AeroSpec;
use leafmagic::leaf::plates::{PlateShape, plate};
use leafmagic::motion::class::Regime;
use leafmagic::motion::classify::{Classification, classify};
use leafmagic::physics::model::STANDARD_GRAVITY;
use leafmagic::sim::drop::{DropParams, drop_leaf};

/// Areal densities of the sweep, kg/m²: 35 to 280 g/m² (×8).
pub const SIGMAS: [f64; 4] = [0.035, 0.07, 0.14, 0.28];
/// Widths of the sweep, m: 1 to 4 cm (×4).
pub const WIDTHS: [f64; 3] = [0.01, 0.02, 0.04];
/// Length over width of every strip.
pub const ASPECT: f64 = 5.0;
/// Release tilt about the long axis, degrees: far enough from flat that
/// every strip of the sweep starts turning.
pub const RELEASE_TILT_DEG: f64 = 60.0;
/// The scaled duration the law is held at: 300 (by then the lightest
/// strips have stopped gliding; docs/lab/real-falls.md).
pub const SCALED_DURATION: f64 = 300.0;

/// What one strip's fall gives the fit.
#[derive(Debug, Clone, PartialEq)]
pub struct StripFall {
    /// Areal density σ, kg/m².
    pub sigma: f64,
    /// Width w, m.
    pub width: f64,
    /// Simulated seconds.
    pub seconds: f64,
    /// The classifier's regime.
    pub regime: Regime,
    /// Mean tumbling rate over the classifier's window, rad/s.
    pub omega: f64,
    /// Mean descent speed, m/s.
    pub descent: f64,
    /// Drift over drop.
    pub drift: f64,
}

/// Seconds for a strip of areal density `sigma` (kg/m²) and width `w` (m)
/// to fall `tau` scaled times in air of density `rho` (kg/m³).
pub fn strip_seconds(sigma: f64, w: f64, tau: f64, rho: f64) -> f64 {
    tau * w / (sigma * STANDARD_GRAVITY / rho).sqrt()
}

/// A plate (`leafmagic plate`'s `shape`, `size`, `aspect`, areal density
/// `sigma`) under `aero`, let go at `tilt` (degrees about x and y) from
/// rest and falling `seconds` as `drop` runs it, classified as every drop
/// is: the fall behind the plate-regime experiments (strips here, disks in
/// examples/plate_regimes.rs). Errors name what failed (the plate, its
/// model or the drop).
pub fn classify_plate_fall(
    shape: PlateShape,
    size: f64,
    aspect: f64,
    sigma: f64,
    tilt: [f64; 2],
    seconds: f64,
    aero: &AeroSpec,
) -> Result<Classification, String> {
    let model = plate(shape, size, aspect, sigma, aero.clone())
        .map_err(|e| e.to_string())?
        .model()
        .map_err(|e| e.to_string())?;
    let params = DropParams {
        seconds,
        tilt_deg: tilt,
        ..Default::default()
    };
    let run = drop_leaf(&model, &params).map_err(|e| e.to_string())?;
    Ok(classify(&run.trajectory, model.chord()))
}

/// One strip of the sweep falling `seconds` under `aero`, let go at
/// [`RELEASE_TILT_DEG`] about its long axis ([`classify_plate_fall`]).
pub fn strip_fall(sigma: f64, w: f64, seconds: f64, aero: &AeroSpec) -> Result<StripFall, String> {
    let c = classify_plate_fall(
        PlateShape::Rectangle,
        w,
        ASPECT,
        sigma,
        [RELEASE_TILT_DEG, 0.0],
        seconds,
        aero,
    )?;
    let f = &c.features;
    Ok(StripFall {
        sigma,
        width: w,
        seconds,
        regime: c.regime,
        omega: f.tumbling_rate_rad_s(),
        descent: f.mean_descent_speed_m_s,
        drift: f.drift_ratio,
    })
}

/// The exponents (p, q) of the least-squares fit ln Ω = c + p ln σ + q ln w
/// over the falls that tumble, or `None` with fewer than four of them or
/// ones that do not span both σ and w.
pub fn fit_exponents(falls: &[StripFall]) -> Option<(f64, f64)> {
    let points: Vec<[f64; 3]> = falls
        .iter()
        .filter(|f| f.regime == Regime::Tumble && f.omega > 0.0)
        .map(|f| [f.sigma.ln(), f.width.ln(), f.omega.ln()])
        .collect();
    if points.len() < 4 {
        return None;
    }
    let mut a = nalgebra::Matrix3::<f64>::zeros();
    let mut b = nalgebra::Vector3::<f64>::zeros();
    for &[s, w, o] in &points {
        let row = nalgebra::Vector3::new(1.0, s, w);
        a += row * row.transpose();
        b += row * o;
    }
    let x = a.try_inverse()? * b;
    Some((x[1], x[2]))
}
