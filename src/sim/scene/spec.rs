//! The scene file as written (TOML, every table `deny_unknown_fields`); every
//! field is documented in `scenes/README.md`. [`super::compile`] checks the
//! values and builds the model.

use super::goal_spec::{FreeSpec, GoalSpec};
use crate::physics::field::WindField;
use crate::physics::model::Ground;
use crate::physics::model::STANDARD_GRAVITY;
use crate::physics::params::Integrator;
use serde::de::{self, Deserializer, Visitor};
use serde::{Deserialize, Serialize};
use std::fmt;

/// A whole scene file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// Short name, used for the default output directory.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Simulated duration, s.
    pub duration: f64,
    /// Output frames per simulated second.
    #[serde(default = "default_frame_rate")]
    pub frame_rate: f64,
    /// Time integrator.
    #[serde(default = "default_integrator", deserialize_with = "integrator_name")]
    pub integrator: Integrator,
    /// Time step, s, or `"auto"` (from the stability estimate).
    #[serde(default)]
    pub dt: DtSpec,
    /// Gravitational acceleration, m/s².
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    /// Seed of the random placement of object copies.
    #[serde(default)]
    pub seed: u64,
    /// The ground plane (none when absent).
    #[serde(default)]
    pub ground: Option<Ground>,
    /// Wind primitives, summed (still air when absent).
    #[serde(default)]
    pub wind: WindField,
    /// Leaf objects.
    #[serde(default, rename = "leaf")]
    pub leaves: Vec<LeafObject>,
    /// Rigid objects built from a shape.
    #[serde(default, rename = "rigid")]
    pub rigid: Vec<RigidObject>,
    /// Flexible sheets.
    #[serde(default, rename = "sheet")]
    pub sheets: Vec<SheetObject>,
    /// Fixed particles.
    #[serde(default, rename = "fixed")]
    pub fixed: Vec<FixedPoint>,
    /// Ropes (chains of particles and springs).
    #[serde(default, rename = "rope")]
    pub ropes: Vec<RopeObject>,
    /// Goals for `direct` (a plain run ignores them).
    #[serde(default, rename = "goal")]
    pub goals: Vec<GoalSpec>,
    /// Free parameters for `direct` (a plain run ignores them).
    #[serde(default, rename = "free")]
    pub free: Vec<FreeSpec>,
}

fn default_frame_rate() -> f64 {
    60.0
}

fn default_integrator() -> Integrator {
    Integrator::Verlet
}

fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -STANDARD_GRAVITY]
}

/// An integrator's name: a string, said so when it is anything else (serde's
/// own message for an enum, "wanted string or table", names neither the
/// choices nor what was found).
fn integrator_name<'de, D: Deserializer<'de>>(d: D) -> Result<Integrator, D::Error> {
    struct V;
    impl Visitor<'_> for V {
        type Value = Integrator;
        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str(
                "the name of an integrator in quotes: \"euler\", \"symplectic\", \"verlet\", \"rk4\" or \"implicit\"",
            )
        }
        fn visit_str<E: de::Error>(self, v: &str) -> Result<Integrator, E> {
            v.parse().map_err(E::custom)
        }
    }
    d.deserialize_any(V)
}

fn shape_name<'de, D: Deserializer<'de>>(d: D) -> Result<Shape, D::Error> {
    crate::util::named::by_name(d, &["box", "cylinder"])
}

fn pin_name<'de, D: Deserializer<'de>>(d: D) -> Result<Pin, D::Error> {
    crate::util::named::by_name(d, &["none", "top_edge", "top_corners", "corners", "border"])
}

fn one() -> usize {
    1
}

/// The time step: a number of seconds or `"auto"`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub enum DtSpec {
    /// From the model's stability estimate.
    #[default]
    Auto,
    /// Fixed, s.
    Seconds(f64),
}

impl<'de> Deserialize<'de> for DtSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = DtSpec;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a time step in seconds or \"auto\"")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<DtSpec, E> {
                Ok(DtSpec::Seconds(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<DtSpec, E> {
                Ok(DtSpec::Seconds(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<DtSpec, E> {
                Ok(DtSpec::Seconds(v as f64))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<DtSpec, E> {
                if v == "auto" {
                    Ok(DtSpec::Auto)
                } else {
                    Err(E::invalid_value(de::Unexpected::Str(v), &self))
                }
            }
        }
        d.deserialize_any(V)
    }
}

/// A leaf file placed in the scene, optionally as many seeded random copies.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LeafObject {
    /// Object name; copies are `name-000`, `name-001`, ...
    pub name: String,
    /// `a` / `b` for the embedded prototypes, or a leaf file path relative to
    /// the scene file (exported leaves included).
    pub leaf: String,
    /// Where the leaf's centre of mass goes, m.
    #[serde(default)]
    pub position: [f64; 3],
    /// Rotation about x, then y, then z (fixed axes), degrees.
    #[serde(default)]
    pub rotation_deg: [f64; 3],
    /// Initial velocity of the centre of mass, m/s.
    #[serde(default)]
    pub velocity: [f64; 3],
    /// Initial angular velocity about the centre of mass, rad/s.
    #[serde(default)]
    pub angular_velocity: [f64; 3],
    /// Move the leaf as one rigid body; unset, as the leaf file says (its
    /// `rigid`: a plate from `leafmagic plate` is rigid, with no springs).
    #[serde(default)]
    pub rigid: Option<bool>,
    /// Number of copies.
    #[serde(default = "one")]
    pub count: usize,
    /// Copies: uniform random offset within ±spread along each axis, m.
    #[serde(default)]
    pub spread: [f64; 3],
    /// Copies: extra tilt up to this angle about a random horizontal axis, degrees.
    #[serde(default)]
    pub tilt_deg: f64,
    /// Copies: random heading about the vertical.
    #[serde(default)]
    pub random_yaw: bool,
}

/// Shapes of rigid objects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Shape {
    /// A box of `size`, centred on its origin, with a particle at each corner.
    Box,
    /// An open-topped cylinder (a bin): base centre at the origin, axis +z,
    /// `rings` rings of `segments` particles up its wall and one particle at
    /// the centre of its base.
    Cylinder,
}

/// A rigid object built from a shape.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigidObject {
    /// Object name.
    pub name: String,
    /// The shape.
    #[serde(deserialize_with = "shape_name")]
    pub shape: Shape,
    /// Box: edge lengths along local x, y, z, m.
    #[serde(default)]
    pub size: Option<[f64; 3]>,
    /// Cylinder: radius, m.
    #[serde(default)]
    pub radius: Option<f64>,
    /// Cylinder: height, m.
    #[serde(default)]
    pub height: Option<f64>,
    /// Cylinder: particles around each ring (default 16).
    #[serde(default)]
    pub segments: Option<usize>,
    /// Cylinder: rings up the wall, ≥ 2 (default 2: base and rim).
    #[serde(default)]
    pub rings: Option<usize>,
    /// Mass of the box corners or of the cylinder wall, kg.
    pub mass: f64,
    /// Cylinder: mass of the base, on its centre particle, kg (default 0:
    /// the centre gets a wall particle's mass).
    #[serde(default)]
    pub base_mass: Option<f64>,
    /// αⁿ of the surface triangles, kg/(m²·s) (0 with αᵗ 0: no aerodynamics).
    #[serde(default)]
    pub alpha_n: f64,
    /// αᵗ of the surface triangles, kg/(m²·s).
    #[serde(default)]
    pub alpha_t: f64,
    /// Where the shape's origin goes, m.
    #[serde(default)]
    pub position: [f64; 3],
    /// Rotation about x, then y, then z (fixed axes), degrees.
    #[serde(default)]
    pub rotation_deg: [f64; 3],
    /// Initial velocity of the centre of mass, m/s.
    #[serde(default)]
    pub velocity: [f64; 3],
    /// Initial angular velocity about the centre of mass, rad/s.
    #[serde(default)]
    pub angular_velocity: [f64; 3],
}

/// Which particles of a sheet are fixed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Pin {
    /// None.
    #[default]
    None,
    /// The whole top edge (local +y).
    TopEdge,
    /// The two top corners.
    TopCorners,
    /// All four corners.
    Corners,
    /// Every particle on the sheet's edge.
    Border,
}

/// A flexible rectangular sheet: a grid of particles with structural and
/// shear springs and two triangles per cell.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SheetObject {
    /// Object name.
    pub name: String,
    /// Width (local x) and height (local y), m.
    pub size: [f64; 2],
    /// Grid cells along x and y.
    pub cells: [usize; 2],
    /// Total mass, kg, spread evenly over the particles.
    pub mass: f64,
    /// Stiffness of the springs along the grid lines, N/m.
    pub stiffness: f64,
    /// Stiffness of the diagonal springs, N/m (default: `stiffness`).
    #[serde(default)]
    pub shear_stiffness: Option<f64>,
    /// Dashpot coefficient of every spring, N·s/m.
    #[serde(default)]
    pub damping: f64,
    /// Strain (l − L)/L at which a spring breaks (default: unbreakable).
    #[serde(default)]
    pub break_strain: Option<f64>,
    /// αⁿ of the triangles, kg/(m²·s).
    #[serde(default)]
    pub alpha_n: f64,
    /// αᵗ of the triangles, kg/(m²·s).
    #[serde(default)]
    pub alpha_t: f64,
    /// Fixed particles.
    #[serde(default, deserialize_with = "pin_name")]
    pub pin: Pin,
    /// Where the sheet's centre goes, m.
    #[serde(default)]
    pub position: [f64; 3],
    /// Rotation about x, then y, then z (fixed axes), degrees.
    #[serde(default)]
    pub rotation_deg: [f64; 3],
    /// Initial velocity of the free particles, m/s.
    #[serde(default)]
    pub velocity: [f64; 3],
}

/// A particle fixed in space.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FixedPoint {
    /// Name, for rope ends.
    pub name: String,
    /// Position, m.
    pub position: [f64; 3],
}

/// A chain of `segments` springs between two existing particles.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RopeObject {
    /// Object name.
    pub name: String,
    /// First end: a `[[fixed]]` name, or `OBJECT:K` for particle K of an object.
    pub from: String,
    /// Second end, same form.
    pub to: String,
    /// Number of springs (the rope adds `segments − 1` particles).
    pub segments: usize,
    /// Mass of the added particles, kg (shared evenly).
    pub mass: f64,
    /// Stiffness of each segment, N/m.
    pub stiffness: f64,
    /// Dashpot coefficient of each segment, N·s/m.
    #[serde(default)]
    pub damping: f64,
    /// Linear drag α (eq. 7) of each added particle, kg/s.
    #[serde(default)]
    pub drag: f64,
    /// Rest length = (1 + slack) × initial end distance / segments.
    #[serde(default)]
    pub slack: f64,
    /// Strain at which a segment breaks (default: unbreakable).
    #[serde(default)]
    pub break_strain: Option<f64>,
}
