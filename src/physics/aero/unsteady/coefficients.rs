//! The unsteady law's coefficients, their sources, defaults and leaf-file
//! keys, and its one validation (the equations and where each coefficient
//! comes from: [`crate::physics::aero::unsteady`]). Adding a coefficient is
//! a field, its default, its key, its line in [`UnsteadyAero::from_keys`]
//! and, if numeric, in [`UnsteadyAero::coefficients`], all here.

use crate::physics::aero::keys::{AeroKeys, Key};
use crate::physics::model::error::ModelError;
use serde::{Deserialize, Serialize};

/// Density of dry air at 20 °C and 101.325 kPa, kg/m³: the unsteady law's
/// default (the quadratic law keeps its rounded [`AIR_DENSITY`](crate::physics::aero::quadratic::AIR_DENSITY)).
pub const AIR_DENSITY_20C: f64 = 1.204;
/// Kinematic viscosity of dry air at 20 °C, m²/s.
pub const AIR_VISCOSITY_20C: f64 = 1.516e-5;

/// The unsteady law's coefficients. Every one has a source in
/// [`crate::physics::aero::unsteady`]'s module docs; one set serves every
/// shape and size (the lengths the law needs come from the leaf's own
/// geometry, [`crate::physics::model::SurfaceGeometry`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UnsteadyAero {
    /// Fluid density ρ, kg/m³.
    pub air_density: f64,
    /// Kinematic viscosity ν of the fluid, m²/s (0: inviscid, no skin friction).
    pub kinematic_viscosity: f64,
    /// Factor on the potential-flow added mass of the plate (1 = the
    /// potential-flow value; 0 switches added mass off).
    pub added_mass: f64,
    /// C_D face-on (α = π/2).
    pub cd_normal: f64,
    /// Pressure (form) drag coefficient edge-on (α = 0), on top of skin
    /// friction.
    pub cd_parallel: f64,
    /// Factor on laminar (Blasius) skin friction, 1.328/√Re on each face.
    pub skin_friction: f64,
    /// C_T of the translational circulation: C_L = C_T sin 2α.
    pub translational_lift: f64,
    /// C_R of the rotational circulation Γ = ½ C_R c² ω.
    pub rotational_lift: f64,
    /// μ₁ of the rotational damping torque (μ₁ |v| + μ₂ a |ω|) ω per unit
    /// (π/2) ρ a² A.
    pub rotational_damping: f64,
    /// μ₂ of the rotational damping torque.
    pub rotational_damping_quadratic: f64,
    /// Share of the velocity a triangle gets from its plate's rotation that
    /// drag and translational lift see: 0 (the default) evaluates them on
    /// the plate's translation, as APW's model does, so rotation acts only
    /// through the rotational lift and damping calibrated for it; 1 is strip
    /// theory (each triangle's own velocity), which damps a turning plate
    /// 2–3 times more than APW's μ₁ term (docs/lab/real-falls.md).
    pub rotation_drag: f64,
    /// Buoyancy: an upward force ρ (m/ρ_s) g on every particle.
    pub buoyancy: bool,
    /// Density of the leaf's material ρ_s for buoyancy, kg/m³.
    pub solid_density: f64,
    /// G, the gain on the lagged centre of pressure: the normal force acts
    /// G c∥ (f(α_L) − f(α)) cos α upstream of where it acts in steady flow, α_L
    /// the angle of attack lagged by [`Self::pressure_lag`] (default
    /// [`UNSTEADY_PRESSURE_LAG_GAIN`]; 0 leaves the term out;
    /// [`crate::physics::aero::unsteady`]).
    pub pressure_lag_gain: f64,
    /// k, the lag's time constant in chord transits: τ = k c∥/|u|.
    pub pressure_lag: f64,
    /// C_W, the wake's rocking couple on a plate falling face-on (default
    /// 0: off; [`crate::physics::aero::unsteady`], "Wake").
    #[serde(default)]
    pub wake_couple: f64,
    /// St, the Strouhal number of the wake's shedding on the plate's
    /// largest chord (default [`UNSTEADY_WAKE_STROUHAL`]).
    #[serde(default = "default_wake_strouhal")]
    pub wake_strouhal: f64,
    /// β, the share of the Munk couple relieved at broadside: the couple
    /// times 1 − β sin⁶α (default 0: the whole potential-flow couple;
    /// [`crate::physics::aero::unsteady`], "Munk relief").
    #[serde(default)]
    pub munk_relief: f64,
}

/// Default Strouhal number of the wake: 0.15, about what flat plates held
/// normal to a stream shed at on their width (bluff plates 0.13–0.15;
/// Roshko 1954, NACA TN 3169).
pub const UNSTEADY_WAKE_STROUHAL: f64 = 0.15;

fn default_wake_strouhal() -> f64 {
    UNSTEADY_WAKE_STROUHAL
}

/// Default C_D face-on: 2.6, near APW 2005's 2-D A + B = 2.4. One set with
/// [`UNSTEADY_CD_PARALLEL`], [`UNSTEADY_TRANSLATIONAL_LIFT`],
/// [`UNSTEADY_ROTATIONAL_LIFT`], [`UNSTEADY_ROTATIONAL_DAMPING`] and the
/// lagged centre of pressure ([`UNSTEADY_PRESSURE_LAG_GAIN`],
/// [`UNSTEADY_PRESSURE_LAG`]), fitted to the real paper squares and the
/// strips' scaling law (how, and its checks: docs/lab/real-falls.md, "The
/// defaults").
pub const UNSTEADY_CD_NORMAL: f64 = 2.6;
/// Default form drag edge-on beyond skin friction: 0.65 (APW 2005's C_D(0)
/// is 0.4). A paper sheet is far thinner than APW's plates, so this is not
/// edge thickness: it stands for what the 2-D law leaves out at the
/// Reynolds numbers of falling paper (10³–10⁴), the separated flow round
/// the edges of a plate of finite span; set to 0 it lets squares glide up
/// to 6 times too far (docs/lab/real-falls.md).
pub const UNSTEADY_CD_PARALLEL: f64 = 0.65;
/// Default C_T: APW 2005's 1.2, under the law's bound C_D⊥/2 = 1.3.
pub const UNSTEADY_TRANSLATIONAL_LIFT: f64 = 1.2;
/// Default C_R: 1.5, under APW 2005's π (thin-aerofoil theory), before
/// the finite span's lifting-line factor.
pub const UNSTEADY_ROTATIONAL_LIFT: f64 = 1.5;
/// Default μ₁: 0.1, half APW 2005's 0.2.
pub const UNSTEADY_ROTATIONAL_DAMPING: f64 = 0.1;
/// Default μ₂: none (APW's 0.2 stops the real squares' tumbling glide; see
/// [`crate::physics::aero::unsteady`] and docs/lab/real-falls.md).
pub const UNSTEADY_ROTATIONAL_DAMPING_QUADRATIC: f64 = 0.0;
/// Default share of the plate's rotation in drag and translational lift:
/// none, as in APW 2005, whose drag and circulation act on the plate's
/// centre velocity and whose μ₁ is the whole rotational damping.
pub const UNSTEADY_ROTATION_DRAG: f64 = 0.0;
/// Density of paper, kg/m³ (70 g/m² paper is 69 µm thick:
/// docs/design/falling-plates.md, "Measured regimes").
pub const PAPER_DENSITY: f64 = 1008.0;
/// Default gain G on the lagged centre of pressure: 0.6, fitted with the
/// coefficients above and [`UNSTEADY_PRESSURE_LAG`]. With it the strips
/// tumble at Ω ∝ σ^0.42 w^−0.92 over equal scaled times (Mahadevan, Ryu &
/// Samuel 1999: 1/2 and −1; 0.50 and −0.97 as fitted, before the couple
/// was made continuous) and the 3 cm disks fall chaotically inside Field
/// et al.'s band; with a gain of 0 and the other defaults 0.35 and −0.83,
/// and no chaotic disks
/// (docs/lab/real-falls.md, "The defaults").
pub const UNSTEADY_PRESSURE_LAG_GAIN: f64 = 0.6;
/// Default lag of the centre of pressure, in chord transits c∥/|u|: 3,
/// fitted with [`UNSTEADY_PRESSURE_LAG_GAIN`]; the lag's form is Leishman
/// & Beddoes', its value is not theirs.
pub const UNSTEADY_PRESSURE_LAG: f64 = 3.0;

impl Default for UnsteadyAero {
    fn default() -> Self {
        UnsteadyAero {
            air_density: AIR_DENSITY_20C,
            kinematic_viscosity: AIR_VISCOSITY_20C,
            added_mass: 1.0,
            cd_normal: UNSTEADY_CD_NORMAL,
            cd_parallel: UNSTEADY_CD_PARALLEL,
            skin_friction: 1.0,
            translational_lift: UNSTEADY_TRANSLATIONAL_LIFT,
            rotational_lift: UNSTEADY_ROTATIONAL_LIFT,
            rotational_damping: UNSTEADY_ROTATIONAL_DAMPING,
            rotational_damping_quadratic: UNSTEADY_ROTATIONAL_DAMPING_QUADRATIC,
            rotation_drag: UNSTEADY_ROTATION_DRAG,
            buoyancy: false,
            solid_density: PAPER_DENSITY,
            pressure_lag_gain: UNSTEADY_PRESSURE_LAG_GAIN,
            pressure_lag: UNSTEADY_PRESSURE_LAG,
            wake_couple: 0.0,
            wake_strouhal: UNSTEADY_WAKE_STROUHAL,
            munk_relief: 0.0,
        }
    }
}

impl UnsteadyAero {
    /// The `[aero]` keys of `law = "unsteady"`, one per coefficient.
    pub const KEYS: &[Key] = &[
        Key::number("air_density"),
        Key::number("cd_parallel"),
        Key::number("cd_normal"),
        Key::number("rotational_lift"),
        Key::number("kinematic_viscosity"),
        Key::number("added_mass"),
        Key::number("skin_friction"),
        Key::number("translational_lift"),
        Key::number("rotational_damping"),
        Key::number("rotational_damping_quadratic"),
        Key::number("rotation_drag"),
        Key::flag("buoyancy"),
        Key::number("solid_density"),
        Key::number("pressure_lag_gain"),
        Key::number("pressure_lag"),
        Key::number("wake_couple"),
        Key::number("wake_strouhal"),
        Key::number("munk_relief"),
    ];

    /// The coefficients `keys` set, the others at their defaults.
    pub fn from_keys(keys: &AeroKeys) -> UnsteadyAero {
        let d = UnsteadyAero::default();
        let or = |name: &str, default: f64| keys.number(name).unwrap_or(default);
        UnsteadyAero {
            air_density: or("air_density", d.air_density),
            kinematic_viscosity: or("kinematic_viscosity", d.kinematic_viscosity),
            added_mass: or("added_mass", d.added_mass),
            cd_normal: or("cd_normal", d.cd_normal),
            cd_parallel: or("cd_parallel", d.cd_parallel),
            skin_friction: or("skin_friction", d.skin_friction),
            translational_lift: or("translational_lift", d.translational_lift),
            rotational_lift: or("rotational_lift", d.rotational_lift),
            rotational_damping: or("rotational_damping", d.rotational_damping),
            rotational_damping_quadratic: or(
                "rotational_damping_quadratic",
                d.rotational_damping_quadratic,
            ),
            rotation_drag: or("rotation_drag", d.rotation_drag),
            buoyancy: keys.flag("buoyancy").unwrap_or(d.buoyancy),
            solid_density: or("solid_density", d.solid_density),
            pressure_lag_gain: or("pressure_lag_gain", d.pressure_lag_gain),
            pressure_lag: or("pressure_lag", d.pressure_lag),
            wake_couple: or("wake_couple", d.wake_couple),
            wake_strouhal: or("wake_strouhal", d.wake_strouhal),
            munk_relief: or("munk_relief", d.munk_relief),
        }
    }

    /// The coefficients by name, as leaf files spell them.
    pub fn coefficients(&self) -> [(&'static str, f64); 17] {
        [
            ("air_density", self.air_density),
            ("kinematic_viscosity", self.kinematic_viscosity),
            ("added_mass", self.added_mass),
            ("cd_normal", self.cd_normal),
            ("cd_parallel", self.cd_parallel),
            ("skin_friction", self.skin_friction),
            ("translational_lift", self.translational_lift),
            ("rotational_lift", self.rotational_lift),
            ("rotational_damping", self.rotational_damping),
            (
                "rotational_damping_quadratic",
                self.rotational_damping_quadratic,
            ),
            ("rotation_drag", self.rotation_drag),
            ("solid_density", self.solid_density),
            ("pressure_lag_gain", self.pressure_lag_gain),
            ("pressure_lag", self.pressure_lag),
            ("wake_couple", self.wake_couple),
            ("wake_strouhal", self.wake_strouhal),
            ("munk_relief", self.munk_relief),
        ]
    }

    /// Every coefficient finite and in its physical range; errors name the
    /// field as `aero.<name>`.
    pub fn validate(&self) -> Result<(), ModelError> {
        let err = |name: &str, reason: String| ModelError {
            item: format!("aero.{name}"),
            reason,
        };
        for (name, value) in self.coefficients() {
            if !value.is_finite() {
                return Err(err(name, format!("must be a finite number, got {value}")));
            }
        }
        // The strictly positive ones first, so that a negative density is
        // told the rule it must meet (> 0), not the looser one (≥ 0).
        for (name, value, unit) in [
            ("air_density", self.air_density, " kg/m³"),
            ("solid_density", self.solid_density, " kg/m³"),
            ("cd_normal", self.cd_normal, ""),
        ] {
            if value <= 0.0 {
                return Err(err(name, format!("must be > 0{unit}, got {value}")));
            }
        }
        for (name, value) in self.coefficients() {
            if value < 0.0 {
                return Err(err(name, format!("must be ≥ 0, got {value}")));
            }
        }
        if self.rotation_drag > 1.0 {
            return Err(err(
                "rotation_drag",
                format!(
                    "must be in [0, 1] (0: drag on the plate's translation, 1: on each triangle's own velocity), got {}",
                    self.rotation_drag
                ),
            ));
        }
        // In-plane drag C_D∥ + (C_D⊥ − C_D∥ − 2C_T) sin²α must stay ≥ 0 or
        // the air would push a sliding plate forwards.
        if 2.0 * self.translational_lift > self.cd_normal {
            return Err(err(
                "translational_lift",
                format!(
                    "must be at most cd_normal/2 = {} (larger lift makes the in-plane drag negative), got {}",
                    0.5 * self.cd_normal,
                    self.translational_lift
                ),
            ));
        }
        if self.munk_relief > 1.0 {
            return Err(err(
                "munk_relief",
                format!(
                    "must be in [0, 1] (the share of the Munk couple relieved at broadside), got {}",
                    self.munk_relief
                ),
            ));
        }
        if self.wake_couple > 0.0 && self.wake_strouhal <= 0.0 {
            return Err(err(
                "wake_strouhal",
                format!(
                    "must be > 0 when wake_couple > 0 (the wake sheds at St |u| / c), got {}",
                    self.wake_strouhal
                ),
            ));
        }
        // Something must resist an edge-on fall, or it would never end (and
        // the stability estimate would have no speed bound).
        if self.cd_parallel == 0.0 && (self.skin_friction == 0.0 || self.kinematic_viscosity == 0.0)
        {
            return Err(err(
                "cd_parallel",
                "must be > 0 when there is no skin friction (kinematic_viscosity or skin_friction is 0): nothing would resist an edge-on fall".to_string(),
            ));
        }
        Ok(())
    }
}
