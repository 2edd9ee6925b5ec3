//! The quadratic law's coefficients, their sources, defaults and leaf-file
//! keys, its one validation and the rate bound of its corner forces (the
//! equations: [`crate::physics::aero::quadratic`]). Adding a coefficient is
//! a field, its default, its key and its line in [`QuadraticAero::from_keys`]
//! here.

use crate::physics::aero::keys::{AeroKeys, Key};
use crate::physics::model::error::ModelError;
use serde::{Deserialize, Serialize};

/// Density of air at 20 °C and sea level, kg/m³.
pub const AIR_DENSITY: f64 = 1.2;
/// Drag coefficient of a plate moving in its own plane (α = 0); Wang, Birch
/// & Dickinson 2004 / APW 2005: 1.4 − cos 0.
pub const CD_PARALLEL: f64 = 0.4;
/// Drag coefficient of a plate moving face-on (α = π/2): 1.4 − cos π.
pub const CD_NORMAL: f64 = 2.4;
/// Amplitude of the lift coefficient C_L = C_L★ sin 2α (WBD 2004, APW 2005).
pub const CL_AMPLITUDE: f64 = 1.2;
/// Position of the centre of pressure at α → 0, as a fraction of the chord
/// behind the leading edge (thin-aerofoil theory's quarter chord).
pub const COP_LEADING: f64 = 0.25;

/// C_R of the rotational circulation: 0 by default (see the module docs);
/// APW 2005 use π ([`APW_ROTATIONAL_LIFT`]).
pub const ROTATIONAL_LIFT: f64 = 0.0;

/// Andersen, Pesavento & Wang's C_R (docs/design/falling-plates.md, "APW
/// quasi-steady model"), available as an override.
pub const APW_ROTATIONAL_LIFT: f64 = std::f64::consts::PI;

/// Coefficients of the quadratic law (see the module docs for the
/// equations). The defaults are the literature's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct QuadraticAero {
    /// Air density ρ, kg/m³.
    pub air_density: f64,
    /// C_D at zero angle of attack (edge-on).
    pub cd_parallel: f64,
    /// C_D at 90° (face-on).
    pub cd_normal: f64,
    /// C_L★ in C_L = C_L★ sin 2α.
    pub cl_amplitude: f64,
    /// Centre of pressure at α → 0, fraction of the chord behind the leading
    /// edge (0.5 = the centre at every angle).
    pub cop_leading: f64,
    /// C_R of the rotational circulation Γ = ½ C_R c² ω (0 = none).
    pub rotational_lift: f64,
}

impl Default for QuadraticAero {
    fn default() -> Self {
        QuadraticAero {
            air_density: AIR_DENSITY,
            cd_parallel: CD_PARALLEL,
            cd_normal: CD_NORMAL,
            cl_amplitude: CL_AMPLITUDE,
            cop_leading: COP_LEADING,
            rotational_lift: ROTATIONAL_LIFT,
        }
    }
}

impl QuadraticAero {
    /// The `[aero]` keys of `law = "quadratic"`, one per coefficient.
    pub const KEYS: &[Key] = &[
        Key::number("air_density"),
        Key::number("cd_parallel"),
        Key::number("cd_normal"),
        Key::number("cl_amplitude"),
        Key::number("cop_leading"),
        Key::number("rotational_lift"),
    ];

    /// The coefficients `keys` set, the others at their defaults.
    pub fn from_keys(keys: &AeroKeys) -> QuadraticAero {
        let d = QuadraticAero::default();
        let or = |name: &str, default: f64| keys.number(name).unwrap_or(default);
        QuadraticAero {
            air_density: or("air_density", d.air_density),
            cd_parallel: or("cd_parallel", d.cd_parallel),
            cd_normal: or("cd_normal", d.cd_normal),
            cl_amplitude: or("cl_amplitude", d.cl_amplitude),
            cop_leading: or("cop_leading", d.cop_leading),
            rotational_lift: or("rotational_lift", d.rotational_lift),
        }
    }

    /// Every coefficient finite and in its physical range; errors name the
    /// field as `aero.<name>`.
    pub fn validate(&self) -> Result<(), ModelError> {
        let err = |name: &str, reason: String| ModelError {
            item: format!("aero.{name}"),
            reason,
        };
        let fields = [
            ("air_density", self.air_density),
            ("cd_parallel", self.cd_parallel),
            ("cd_normal", self.cd_normal),
            ("cl_amplitude", self.cl_amplitude),
            ("cop_leading", self.cop_leading),
            ("rotational_lift", self.rotational_lift),
        ];
        for (name, value) in fields {
            if !value.is_finite() {
                return Err(err(name, format!("must be a finite number, got {value}")));
            }
        }
        if self.air_density <= 0.0 {
            return Err(err(
                "air_density",
                format!("must be > 0 kg/m³, got {}", self.air_density),
            ));
        }
        // An edge-on plate without drag would fall freely for ever (and the
        // stability estimate would have no speed bound).
        if self.cd_parallel <= 0.0 {
            return Err(err(
                "cd_parallel",
                format!(
                    "must be > 0 (edge-on drag bounds the fall speed), got {}",
                    self.cd_parallel
                ),
            ));
        }
        if self.cd_normal < self.cd_parallel {
            return Err(err(
                "cd_normal",
                format!(
                    "must be ≥ cd_parallel ({}): a plate is draggier face-on, got {}",
                    self.cd_parallel, self.cd_normal
                ),
            ));
        }
        // In-plane drag C_D∥ + (C_D⊥ − C_D∥ − 2C_L★) sin²α must stay ≥ 0 or
        // the air would push a sliding plate forwards.
        if self.cl_amplitude < 0.0 || 2.0 * self.cl_amplitude > self.cd_normal {
            return Err(err(
                "cl_amplitude",
                format!(
                    "must be in [0, cd_normal/2 = {}] (larger lift makes the in-plane drag negative), got {}",
                    0.5 * self.cd_normal,
                    self.cl_amplitude
                ),
            ));
        }
        if !(0.0..=0.5).contains(&self.cop_leading) {
            return Err(err(
                "cop_leading",
                format!(
                    "must be in [0, 0.5] (fraction of the chord behind the leading edge), got {}",
                    self.cop_leading
                ),
            ));
        }
        Ok(())
    }

    /// C_D(α) and C_L(α), α in radians.
    pub fn coefficients(&self, alpha: f64) -> (f64, f64) {
        let (s, c) = alpha.sin_cos();
        (
            self.cd_parallel * c * c + self.cd_normal * s * s,
            self.cl_amplitude * (2.0 * alpha).sin(),
        )
    }

    /// Bound on ‖∂(wᵢ F)/∂v‖ / (½ ρ A |v|) for the corner share wᵢ of a
    /// triangle's force, where `lever` = r_max/hᵢ (the centroid's largest
    /// distance to a corner over the corner's height).
    ///
    /// F = ½ρA|v|² c(α) in the turning frame (v̂, l̂), so
    /// ‖∂F/∂v‖ ≤ ½ρA|v| (3|c| + |c′|): 2|c| from |v|², |c| from the frame
    /// turning and |c′| from α changing (both at rate ≤ 1/|v| per unit
    /// velocity). The share is wᵢ ≤ 1/3 + (1 − 2α/π) lever, and it moves by
    /// ‖∂wᵢ/∂v‖ ≤ (1 + 2/π) lever/|v| (the centre of pressure shifts by at
    /// most r_max (1 + 2/π)/|v| per unit velocity, since 1 − 2α/π ≤ cos α),
    /// adding |c| (1 + 2/π) lever. Maximised over α on a fine grid: the
    /// share is largest at small α, where the force is smallest.
    pub fn corner_rate_bound(&self, lever: f64) -> f64 {
        let n = 512;
        let step = std::f64::consts::FRAC_PI_2 / n as f64;
        let shift = 1.0 + std::f64::consts::FRAC_2_PI;
        (0..=n)
            .map(|k| {
                let a = k as f64 * step;
                let (cd, cl) = self.coefficients(a);
                let c = cd.hypot(cl);
                // Exact derivatives of the two coefficients.
                let dcd = (self.cd_normal - self.cd_parallel) * (2.0 * a).sin();
                let dcl = 2.0 * self.cl_amplitude * (2.0 * a).cos();
                let share = 1.0 / 3.0 + (1.0 - a * std::f64::consts::FRAC_2_PI) * lever;
                share * (3.0 * c + dcd.hypot(dcl)) + c * shift * lever
            })
            .fold(0.0, f64::max)
    }
}
