//! Plates for validation: a flat square card built as a leaf, and the
//! dimensionless numbers the falling-plate literature sorts falls by
//! (docs/design/falling-plates.md, "Dimensionless groups").

use crate::leaf::{AeroSpec, BendingSpec, LeafSpec, ParticleSpec, SpringSpec, TriangleSpec};
use crate::physics::aero::quadratic::AIR_DENSITY;
use crate::physics::model::{Model, STANDARD_GRAVITY};
use crate::util::setting::Setting;
use nalgebra::{Matrix3, Vector3};

/// Natural frequency the card's springs and hinges are scaled to, rad/s.
/// Twenty times the fastest rotation of a tumbling 5 cm card (~20 rad/s):
/// the card behaves as a rigid plate, and the stable step does not depend
/// on its density (stiffness scales with mass).
pub const CARD_FREQUENCY: f64 = 400.0;

/// Damping ratio of the card's springs and hinges (our choice: flexural
/// ringing decays in a few periods without touching the rigid motion).
pub const CARD_DAMPING_RATIO: f64 = 0.2;

/// Share of the card's mass lumped on each corner: the project's rule for
/// leaves (a third of each triangle's mass on each of its corners) applied
/// to the four triangles; the centre takes the remaining third.
pub const CORNER_SHARE: f64 = 1.0 / 6.0;

/// Release attitudes (tilt about the body x and y axes, degrees) a card is
/// dropped at to name its class by majority: near-flat, steep, one-sided and
/// diagonal releases.
pub const RELEASE_ATTITUDES: [[f64; 2]; 8] = [
    [10.0, 2.0],
    [60.0, 0.0],
    [3.0, 30.0],
    [20.0, 20.0],
    [45.0, 10.0],
    [15.0, -5.0],
    [2.0, 8.0],
    [30.0, 10.0],
];

/// A flat square card of side `side` (m) and areal density `sigma` (kg/m²)
/// in the x-y plane, centred on the origin: four triangles fanned around the
/// centre (symmetric about both centre lines and both diagonals), mass
/// lumped on the corners as every leaf's is ([`CORNER_SHARE`]), springs on
/// the eight edges and bending hinges on the four shared ones, both scaled
/// to [`CARD_FREQUENCY`].
///
/// Why so coarse: the quadratic law places each triangle's centre of
/// pressure at *its own* quarter chord, so the card's centre of pressure
/// moves by a quarter of a triangle's chord. Four triangles make that about
/// a quarter of the card's half-width, like the paper's six-triangle
/// leaves; a 4 × 4 grid of 32 triangles moves it four times less, and such
/// a card falls steadily face-down at every density tried (5–6000 g/m²).
///
/// Mass lumped at the corners gives the card twice a uniform plate's moment
/// of inertia (I = M L²/6 about a centre line); [`i_star`] measures the
/// model's own. With the exact inertia (corner share 1/12) the card also
/// falls steadily at every density tried (5–1500 g/m²): the extra
/// rotational inertia is what lets its rocking overshoot into flips and
/// tumbles.
pub fn square_card(side: f64, sigma: f64, aero: AeroSpec) -> LeafSpec {
    let h = 0.5 * side;
    let area = side * side;
    let corner = |position| ParticleSpec {
        position,
        mass: sigma * area * CORNER_SHARE,
        fixed: false,
        drag: 0.0,
    };
    let mut particles: Vec<ParticleSpec> = [[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]]
        .into_iter()
        .map(corner)
        .collect();
    particles.push(ParticleSpec {
        position: [0.0, 0.0, 0.0],
        mass: sigma * area * (1.0 - 4.0 * CORNER_SHARE),
        fixed: false,
        drag: 0.0,
    });
    // k = m ω² for the mean particle mass; dashpot 2ζ√(k m).
    let m_mean = sigma * area / particles.len() as f64;
    let k = m_mean * CARD_FREQUENCY * CARD_FREQUENCY;
    let c = 2.0 * CARD_DAMPING_RATIO * (k * m_mean).sqrt();
    let spring = |p: usize, q: usize| SpringSpec {
        ends: [p, q],
        stiffness: k,
        damping: c,
        group: "edge".to_string(),
        rest_length: None,
        break_strain: None,
    };
    let springs = (0..4)
        .flat_map(|i| [spring(i, (i + 1) % 4), spring(i, 4)])
        .collect();
    let triangles = (0..4)
        .map(|i| TriangleSpec {
            corners: [4, i, (i + 1) % 4],
            flap: None,
            alpha_n: None,
            alpha_t: None,
        })
        .collect();
    // A hinge's rate is k_b |∇θ|²/m with |∇θ| ~ 1/h at the apex.
    let k_b = m_mean * (CARD_FREQUENCY * h).powi(2);
    LeafSpec {
        name: format!("card-{:.0}mm-{}", side * 1e3, density_tag(sigma)),
        aero,
        bounds: Default::default(),
        bending: Some(BendingSpec {
            stiffness: k_b,
            damping: 2.0 * CARD_DAMPING_RATIO * k_b / CARD_FREQUENCY,
        }),
        gravity: [0.0, 0.0, -STANDARD_GRAVITY],
        particles,
        springs,
        triangles,
        folds: Vec::new(),
        wind: Default::default(),
        rigid: false,
    }
}

/// Areal density of a model: total mass over total triangle area, kg/m².
pub fn areal_density(model: &Model) -> f64 {
    model.total_mass() / model.surface_area()
}

/// The principal moments of inertia of the rest shape about its centre of
/// mass, ascending, kg·m².
pub fn principal_moments(model: &Model) -> [f64; 3] {
    let com = model.centre_of_mass(&model.rest_position);
    let mut inertia = Matrix3::zeros();
    for (x, &m) in model.rest_position.iter().zip(&model.mass) {
        let r: Vector3<f64> = x - com;
        inertia += (Matrix3::identity() * r.norm_squared() - r * r.transpose()) * m;
    }
    let mut eig: Vec<f64> = inertia.symmetric_eigenvalues().iter().copied().collect();
    eig.sort_by(f64::total_cmp);
    [eig[0], eig[1], eig[2]]
}

/// Dimensionless moment of inertia I* = Ī / (ρ_f L⁵): Howison & Iida's I*_shape
/// (docs/design/falling-plates.md, "Dimensionless groups") with Ī the mean of the two
/// smaller principal moments (the in-plane axes of a flat leaf) and L the
/// plate's size — the side of a square (then I* = σ/(12 ρ_f L), as there), the
/// chord of a leaf. I*_APW = 12 I* and I*_disk ≈ 0.59 I* for a square at equal
/// σ, L.
pub fn i_star(model: &Model, length: f64, fluid_density: f64) -> f64 {
    let [a, b, _] = principal_moments(model);
    0.5 * (a + b) / (fluid_density * length.powi(5))
}

/// [`i_star`] in air ([`AIR_DENSITY`]) with the chord as the length.
pub fn i_star_air(model: &Model) -> f64 {
    i_star(model, model.chord(), AIR_DENSITY)
}

/// Kinematic viscosity of air at 20 °C, m²/s.
pub const AIR_VISCOSITY: f64 = 1.5e-5;

/// Reynolds number U L / ν of a fall at mean descent speed `speed` (m/s) of
/// a leaf of chord `chord` (m) in air.
pub fn reynolds(speed: f64, chord: f64) -> f64 {
    speed * chord / AIR_VISCOSITY
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lumped mass gives a uniform plate's moments of inertia within
    /// 2 % for every shape; every triangle faces +z; the areal density is
    /// the one asked for.
    #[test]
    fn plates_have_a_uniform_plates_inertia_within_two_percent() {
        for (shape, aspect) in [
            (PlateShape::Square, 1.0),
            (PlateShape::Rectangle, 4.0),
            (PlateShape::Rectangle, 1.5),
            (PlateShape::Hexagon, 1.0),
            (PlateShape::Circle, 1.0),
            (PlateShape::Cross, 3.0),
            (PlateShape::Cross, 1.25),
            (PlateShape::Cross, 7.0),
        ] {
            let size = 0.05;
            let spec = plate(shape, size, aspect, 0.07, AeroSpec::unsteady()).unwrap();
            let model = spec.model().unwrap();
            assert!((areal_density(&model) - 0.07).abs() < 1e-12);
            let x = &model.rest_position;
            for t in &model.triangles {
                let [a, b, c] = t.corners;
                assert!((x[b] - x[a]).cross(&(x[c] - x[a])).z > 0.0, "{shape:?}");
            }
            let m = model.total_mass();
            let ix: f64 = x
                .iter()
                .zip(&model.mass)
                .map(|(p, w)| w * p.y * p.y)
                .sum::<f64>()
                / m;
            let iy: f64 = x
                .iter()
                .zip(&model.mass)
                .map(|(p, w)| w * p.x * p.x)
                .sum::<f64>()
                / m;
            let [ex, ey] = uniform_plate_moments(shape, size, aspect);
            println!(
                "{shape:?} x{aspect}: I_x {:.4}, I_y {:.4} of uniform",
                ix / ex,
                iy / ey
            );
            assert!(
                (ix / ex - 1.0).abs() < 0.02 && (iy / ey - 1.0).abs() < 0.02,
                "{shape:?}"
            );
        }
    }

    #[test]
    fn bad_plates_name_the_argument() {
        let bad = |s, size, aspect, sigma| {
            plate(s, size, aspect, sigma, AeroSpec::unsteady())
                .unwrap_err()
                .field
        };
        assert_eq!(bad(PlateShape::Square, -0.05, 1.0, 0.07), PlateField::Size);
        assert_eq!(
            bad(PlateShape::Square, f64::NAN, 1.0, 0.07),
            PlateField::Size
        );
        assert_eq!(
            bad(PlateShape::Square, 0.05, 1.0, 0.0),
            PlateField::ArealDensity
        );
        assert_eq!(
            bad(PlateShape::Square, 0.05, 1.0, f64::INFINITY),
            PlateField::ArealDensity
        );
        assert_eq!(bad(PlateShape::Square, 0.05, 2.0, 0.07), PlateField::Aspect);
        assert_eq!(
            bad(PlateShape::Rectangle, 0.05, 0.5, 0.07),
            PlateField::Aspect
        );
        assert_eq!(
            bad(PlateShape::Cross, 0.05, 1.0, 0.07),
            PlateField::ArmWidth
        );
        assert_eq!(
            bad(PlateShape::Cross, 0.05, 0.5, 0.07),
            PlateField::ArmWidth
        );
        assert_eq!(
            bad(PlateShape::Cross, 0.05, f64::INFINITY, 0.07),
            PlateField::ArmWidth
        );
        assert_eq!(
            bad(PlateShape::Cross, 0.05, f64::NAN, 0.07),
            PlateField::ArmWidth
        );
    }

    #[test]
    fn card_has_the_asked_density_and_the_square_i_star() {
        let spec = square_card(0.05, 0.08, AeroSpec::quadratic());
        let model = spec.model().unwrap();
        assert_eq!(model.len(), 5);
        assert_eq!(model.triangles.len(), 4);
        assert_eq!(model.hinges.len(), 4);
        assert!((areal_density(&model) - 0.08).abs() < 1e-12);
        // Corner lumping doubles a uniform plate's σ/(12 ρ L).
        let uniform = 0.08 / (12.0 * AIR_DENSITY * 0.05);
        let lumped = i_star(&model, 0.05, AIR_DENSITY);
        assert!(
            (lumped / uniform - 2.0).abs() < 1e-9,
            "{lumped} vs {uniform}"
        );
    }
}

/// The outline of a flat plate written by [`plate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlateShape {
    /// A square; size = its side.
    Square,
    /// A circle; size = its diameter.
    Circle,
    /// A regular hexagon with a corner on +x; size = its flat-to-flat width.
    Hexagon,
    /// A rectangle, long side along x; size = its width (the short side),
    /// length = aspect × width.
    Rectangle,
    /// A plus of two equal arms along x and y; size = its span, tip to tip;
    /// aspect = span over arm width (each arm's length over its width,
    /// above 1), so an arm is size / aspect wide.
    Cross,
}

impl PlateShape {
    /// The name on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            PlateShape::Square => "square",
            PlateShape::Circle => "circle",
            PlateShape::Hexagon => "hexagon",
            PlateShape::Rectangle => "rectangle",
            PlateShape::Cross => "cross",
        }
    }
}

impl std::str::FromStr for PlateShape {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "square" => Ok(PlateShape::Square),
            "circle" => Ok(PlateShape::Circle),
            "hexagon" => Ok(PlateShape::Hexagon),
            "rectangle" => Ok(PlateShape::Rectangle),
            "cross" => Ok(PlateShape::Cross),
            other => Err(format!(
                "unknown plate shape '{other}': expected square, circle, hexagon, rectangle or cross"
            )),
        }
    }
}

/// Areal density of 70 g/m² paper, the real falls' (docs/lab/real-falls.md), kg/m².
pub const PAPER_AREAL_DENSITY: f64 = 0.070;

/// Cells across the short side of a square or rectangular plate: its mass,
/// lumped a third of each triangle's on each corner, then gives a uniform
/// plate's moment of inertia to 1/n² (1.6 %; a test holds ≤ 2 %).
pub const PLATE_CELLS: usize = 8;

/// Most particles `plate` meshes a plate into (a rectangle's grow with its
/// aspect): the most a scene may hold, `sim::scene::MAX_PARTICLES`, beyond
/// which a plate is no use to any run here (a rectangle takes about 68
/// per unit of aspect, so up to an aspect of about 14 700).
pub const MAX_PLATE_PARTICLES: usize = 1_000_000;

/// Rings of a hexagonal or circular plate's triangular mesh (the same
/// bound: a test holds ≤ 2 %).
pub const PLATE_RINGS: usize = 8;

/// A bad plate request, naming the argument.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{field}: {reason}")]
pub struct PlateError {
    /// The argument.
    pub field: PlateField,
    /// Why it is refused.
    pub reason: String,
}

/// The argument of a plate request that is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlateField {
    /// The size.
    Size,
    /// The aspect ratio.
    Aspect,
    /// A cross's arm width.
    ArmWidth,
    /// The areal density.
    ArealDensity,
    /// Size and areal density together (the particles' masses).
    SizeAndDensity,
    /// A flexible plate's bending stiffness.
    BendingStiffness,
    /// The mesh's refinement ([`plate_meshed`]).
    Refine,
}

impl std::fmt::Display for PlateField {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PlateField::Size => write!(f, "{}", Setting::Size),
            PlateField::Aspect => write!(f, "{}", Setting::Aspect),
            PlateField::ArmWidth => write!(f, "{}", Setting::ArmWidth),
            PlateField::ArealDensity => write!(f, "{}", Setting::ArealDensity),
            PlateField::SizeAndDensity => {
                write!(f, "{} and {}", Setting::Size, Setting::ArealDensity)
            }
            PlateField::BendingStiffness => write!(f, "{}", Setting::BendingStiffness),
            PlateField::Refine => f.write_str("refine"),
        }
    }
}

/// The areal density `sigma` (kg/m²) as a name's tag: grams per square
/// metre ("70gsm", paper's unit), or kilograms per square metre in
/// scientific notation past a tonne per square metre, where grams would
/// print as digits without end or overflow to "inf".
fn density_tag(sigma: f64) -> String {
    if sigma * 1e3 < 1e6 {
        format!("{:.0}gsm", sigma * 1e3)
    } else {
        format!("{sigma:.2e}kgm2")
    }
}

/// A flat plate of `shape`, `size` (m; see [`PlateShape`]), `aspect`
/// (length over width; rectangles only) and areal density `sigma` (kg/m²)
/// in the x-y plane, centred on the origin, normal +z: a fine triangle mesh
/// (mass lumped from the triangles, a third on each corner) moved as one
/// rigid body, the uniform rigid plate of the falling-plate literature.
/// Squares and rectangles: [`PLATE_CELLS`] cells across, each cut into four
/// triangles about its centre (symmetric about both centre lines and, for
/// a square, both diagonals); crosses: the same cells, about a square's
/// across the span ([`PLATE_CELLS`] of them), at least two across an arm
/// and as nearly square along it; hexagons: a triangular
/// lattice of [`PLATE_RINGS`] rings; circles: the same rings laid on
/// circles.
///
/// # Errors
/// A size, aspect or density that is not finite and positive (an aspect
/// other than 1 on a shape that has none; a cross's arm not narrower than
/// its span), naming the flag.
pub fn plate(
    shape: PlateShape,
    size: f64,
    aspect: f64,
    sigma: f64,
    aero: AeroSpec,
) -> Result<LeafSpec, PlateError> {
    plate_meshed(shape, size, aspect, sigma, aero, 1)
}

/// [`plate`] with `refine` times as many cells or rings across (1 is
/// [`plate`]'s mesh): for convergence studies.
///
/// # Errors
/// As [`plate`]; `refine` 0 is refused.
pub fn plate_meshed(
    shape: PlateShape,
    size: f64,
    aspect: f64,
    sigma: f64,
    aero: AeroSpec,
    refine: usize,
) -> Result<LeafSpec, PlateError> {
    check_arguments(shape, size, aspect, sigma, refine)?;
    let (points, triangles) = mesh(shape, size, aspect, refine)?;
    let mass = lumped_masses(&points, &triangles, shape, size, sigma)?;
    let particles = points
        .iter()
        .zip(&mass)
        .map(|(p, &m)| ParticleSpec {
            position: [p[0], p[1], 0.0],
            mass: m,
            fixed: false,
            drag: 0.0,
        })
        .collect();
    let triangles = triangles
        .into_iter()
        .map(|corners| TriangleSpec {
            corners,
            flap: None,
            alpha_n: None,
            alpha_t: None,
        })
        .collect();
    let aspect_tag = match shape {
        PlateShape::Rectangle => format!("-x{aspect}"),
        PlateShape::Cross => format!("-arm{:.1}mm", size / aspect * 1e3),
        _ => String::new(),
    };
    Ok(LeafSpec {
        name: format!(
            "plate-{}-{:.1}mm{aspect_tag}-{}",
            shape.as_str(),
            size * 1e3,
            density_tag(sigma)
        ),
        aero,
        bounds: Default::default(),
        bending: None,
        gravity: [0.0, 0.0, -STANDARD_GRAVITY],
        particles,
        springs: Vec::new(),
        triangles,
        folds: Vec::new(),
        wind: Default::default(),
        rigid: true,
    })
}

/// The plate's arguments checked before anything is meshed.
fn check_arguments(
    shape: PlateShape,
    size: f64,
    aspect: f64,
    sigma: f64,
    refine: usize,
) -> Result<(), PlateError> {
    if refine == 0 {
        return Err(PlateError {
            field: PlateField::Refine,
            reason: "must be at least 1".to_string(),
        });
    }
    let positive = |field: PlateField, value: f64, unit: &str| {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(PlateError {
                field,
                reason: format!("must be a finite number > 0 {unit}, got {value}"),
            })
        }
    };
    positive(PlateField::Size, size, "m")?;
    positive(PlateField::ArealDensity, sigma, "kg/m²")?;
    if shape == PlateShape::Cross {
        // A span over arm width of 1 or less is a square or nothing.
        if !(aspect.is_finite() && aspect > 1.0) {
            return Err(PlateError {
                field: PlateField::ArmWidth,
                reason: format!(
                    "a cross's arms must be wider than 0 and narrower than its span ({size} m), got {} m",
                    size / aspect
                ),
            });
        }
    } else {
        positive(PlateField::Aspect, aspect, "")?;
    }
    if !matches!(shape, PlateShape::Rectangle | PlateShape::Cross) && aspect != 1.0 {
        return Err(PlateError {
            field: PlateField::Aspect,
            reason: format!(
                "only a rectangle has an aspect ratio (a {} has 1), got {aspect}",
                shape.as_str()
            ),
        });
    }
    if shape == PlateShape::Rectangle && aspect < 1.0 {
        return Err(PlateError {
            field: PlateField::Aspect,
            reason: format!(
                "is length over width, at least 1 (size is the short side), got {aspect}"
            ),
        });
    }
    Ok(())
}

/// Points in the plate's plane and counter-clockwise triangles of them.
type PlaneMesh = (Vec<[f64; 2]>, Vec<[usize; 3]>);

/// The plate's points (in its plane) and counter-clockwise triangles,
/// counted before anything is allocated.
fn mesh(shape: PlateShape, size: f64, aspect: f64, refine: usize) -> Result<PlaneMesh, PlateError> {
    let (cells, rings) = (PLATE_CELLS * refine, PLATE_RINGS * refine);
    // Counted before anything is allocated: a long rectangle's cells grow
    // with its aspect (grid_mesh: (nx + 1)(ny + 1) corners and nx ny centres).
    let along = (cells as f64 * aspect / 2.0).ceil().max(cells as f64);
    // A cross's cells are about a square's across its span (the long arm
    // carries most of its moment of inertia), at least two across an arm,
    // and about as long as wide along the arm beyond the centre square.
    let arm_across = (cells as f64 / aspect).ceil().max(2.0);
    let arm_cells = (arm_across * 0.5 * (aspect - 1.0)).ceil().max(1.0);
    let particles = match shape {
        PlateShape::Square | PlateShape::Rectangle => {
            let (nx, ny) = (along, cells as f64);
            (nx + 1.0) * (ny + 1.0) + nx * ny
        }
        // cross_mesh: the centre square's cells and four arms' (a corner and
        // a centre per cell, at most, plus the rims).
        PlateShape::Cross => {
            let n = arm_across;
            let cross_cells = n * n + 4.0 * n * arm_cells;
            2.0 * cross_cells + 4.0 * (n + 1.0) + 2.0 * (2.0 * arm_cells + n + 1.0)
        }
        // ring_mesh: the centre and 6k points on ring k.
        PlateShape::Hexagon | PlateShape::Circle => 1.0 + 3.0 * rings as f64 * (rings as f64 + 1.0),
    };
    if particles > MAX_PLATE_PARTICLES as f64 {
        return Err(PlateError {
            field: if refine > 1 {
                PlateField::Refine
            } else {
                PlateField::Aspect
            },
            reason: format!(
                "the plate would be meshed into {particles:.3e} particles, more than the \
                 {MAX_PLATE_PARTICLES} a plate may hold"
            ),
        });
    }
    let (points, triangles) = match shape {
        PlateShape::Square => grid_mesh(size, size, cells, cells),
        // Cells at most twice as long as wide along the plate.
        PlateShape::Rectangle => grid_mesh(aspect * size, size, along as usize, cells),
        PlateShape::Hexagon => ring_mesh(size / 3f64.sqrt(), rings, false),
        PlateShape::Circle => ring_mesh(0.5 * size, rings, true),
        PlateShape::Cross => {
            cross_mesh(size, size / aspect, arm_across as usize, arm_cells as usize)
        }
    };
    Ok((points, triangles))
}

/// Each particle's mass: a third of each triangle it is a corner of, at
/// areal density `sigma`; refused where f64 cannot hold them.
fn lumped_masses(
    points: &[[f64; 2]],
    triangles: &[[usize; 3]],
    shape: PlateShape,
    size: f64,
    sigma: f64,
) -> Result<Vec<f64>, PlateError> {
    let mut mass = vec![0.0; points.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| Vector3::new(points[i][0], points[i][1], 0.0));
        let share = sigma * 0.5 * (b - a).cross(&(c - a)).norm() / 3.0;
        for &i in t {
            mass[i] += share;
        }
    }
    let (lightest, heaviest) = mass.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &m| {
        (lo.min(m), hi.max(m))
    });
    // 1/m must be finite too: no subnormal mass.
    if !(heaviest.is_finite() && lightest >= f64::MIN_POSITIVE) {
        return Err(PlateError {
            field: PlateField::SizeAndDensity,
            reason: format!(
                "a {} of {size:e} m at {sigma:e} kg/m² has particles of {lightest:.3e} to \
                 {heaviest:.3e} kg, which f64 cannot hold (from {:.3e} kg to finite)",
                shape.as_str(),
                f64::MIN_POSITIVE
            ),
        });
    }
    Ok(mass)
}

/// A `length` (x) × `width` (y) rectangle of nx × ny cells, each cut into
/// four counter-clockwise triangles about its centre.
fn grid_mesh(length: f64, width: f64, nx: usize, ny: usize) -> (Vec<[f64; 2]>, Vec<[usize; 3]>) {
    let mut points = Vec::with_capacity((nx + 1) * (ny + 1) + nx * ny);
    for j in 0..=ny {
        for i in 0..=nx {
            points.push([
                length * (i as f64 / nx as f64 - 0.5),
                width * (j as f64 / ny as f64 - 0.5),
            ]);
        }
    }
    let node = |i: usize, j: usize| j * (nx + 1) + i;
    let mut triangles = Vec::with_capacity(4 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let centre = points.len();
            points.push([
                length * ((i as f64 + 0.5) / nx as f64 - 0.5),
                width * ((j as f64 + 0.5) / ny as f64 - 0.5),
            ]);
            let ring = [
                node(i, j),
                node(i + 1, j),
                node(i + 1, j + 1),
                node(i, j + 1),
            ];
            for k in 0..4 {
                triangles.push([centre, ring[k], ring[(k + 1) % 4]]);
            }
        }
    }
    (points, triangles)
}

/// A plus of span `span` (tip to tip) whose two arms, along x and y, are
/// `width` wide: the centre square in `across` × `across` cells and each
/// arm beyond it in `across` × `along` cells, each cell cut into four
/// counter-clockwise triangles about its centre as in [`grid_mesh`], so
/// the mesh is symmetric about both centre lines and both diagonals.
fn cross_mesh(
    span: f64,
    width: f64,
    across: usize,
    along: usize,
) -> (Vec<[f64; 2]>, Vec<[usize; 3]>) {
    let (h, w) = (0.5 * span, 0.5 * width);
    // The grid lines, the same along x and y: tip to root, across the
    // centre square, root to tip (the ends exact, so the span is).
    let mut lines: Vec<f64> = (0..along)
        .map(|i| -h + (h - w) * i as f64 / along as f64)
        .collect();
    lines.extend((0..across).map(|i| -w + width * i as f64 / across as f64));
    lines.extend((0..along).map(|i| w + (h - w) * i as f64 / along as f64));
    lines.push(h);
    let k = lines.len() - 1;
    let in_band = |i: usize| (along..along + across).contains(&i);
    let mut index = vec![usize::MAX; (k + 1) * (k + 1)];
    let mut points = Vec::new();
    let mut triangles = Vec::new();
    for j in 0..k {
        for i in 0..k {
            if !(in_band(i) || in_band(j)) {
                continue;
            }
            let mut node = |a: usize, b: usize| {
                let slot = &mut index[b * (k + 1) + a];
                if *slot == usize::MAX {
                    *slot = points.len();
                    points.push([lines[a], lines[b]]);
                }
                *slot
            };
            let ring = [
                node(i, j),
                node(i + 1, j),
                node(i + 1, j + 1),
                node(i, j + 1),
            ];
            let centre = points.len();
            points.push([
                0.5 * (lines[i] + lines[i + 1]),
                0.5 * (lines[j] + lines[j + 1]),
            ]);
            for q in 0..4 {
                triangles.push([centre, ring[q], ring[(q + 1) % 4]]);
            }
        }
    }
    (points, triangles)
}

/// A hexagon of circumradius `radius` (corner on +x) as a triangular
/// lattice of `rings` rings (6 rings² triangles), or with `circle` the same
/// rings laid evenly on circles of radius k/rings × `radius`.
fn ring_mesh(radius: f64, rings: usize, circle: bool) -> (Vec<[f64; 2]>, Vec<[usize; 3]>) {
    let corner = |j: usize| {
        let a = std::f64::consts::FRAC_PI_3 * (j % 6) as f64;
        [radius * a.cos(), radius * a.sin()]
    };
    let mut points = vec![[0.0, 0.0]];
    // ring_start[k]: index of ring k's first point; ring k has 6k points.
    let mut ring_start = vec![0usize];
    for k in 1..=rings {
        ring_start.push(points.len());
        let scale = k as f64 / rings as f64;
        for m in 0..6 * k {
            let p = if circle {
                let a = 2.0 * std::f64::consts::PI * m as f64 / (6 * k) as f64;
                [scale * radius * a.cos(), scale * radius * a.sin()]
            } else {
                let (j, s) = (m / k, m % k);
                let (p0, p1) = (corner(j), corner(j + 1));
                let f = s as f64 / k as f64;
                [
                    scale * (p0[0] + (p1[0] - p0[0]) * f),
                    scale * (p0[1] + (p1[1] - p0[1]) * f),
                ]
            };
            points.push(p);
        }
    }
    let at = |k: usize, m: usize| {
        if k == 0 {
            0
        } else {
            ring_start[k] + m % (6 * k)
        }
    };
    let mut triangles = Vec::with_capacity(6 * rings * rings);
    for k in 1..=rings {
        for j in 0..6 {
            // Side j of ring k: outer points o_0..o_k, inner i_0..i_{k−1}.
            let outer = |s: usize| at(k, j * k + s);
            let inner = |s: usize| at(k - 1, j * (k - 1) + s);
            for s in 0..k {
                triangles.push([outer(s), outer(s + 1), inner(s)]);
                if s + 1 < k {
                    triangles.push([inner(s), outer(s + 1), inner(s + 1)]);
                }
            }
        }
    }
    (points, triangles)
}

/// A uniform plate's principal moments of inertia per unit mass about its
/// two in-plane symmetry axes (x, y), m²: what [`plate`]'s lumped mass
/// approximates.
pub fn uniform_plate_moments(shape: PlateShape, size: f64, aspect: f64) -> [f64; 2] {
    match shape {
        PlateShape::Square => [size * size / 12.0; 2],
        PlateShape::Rectangle => [size * size / 12.0, (aspect * size).powi(2) / 12.0],
        // Regular hexagon of side s: I = (5/24) M s² about any in-plane axis.
        PlateShape::Hexagon => [5.0 / 24.0 * size * size / 3.0; 2],
        PlateShape::Circle => [size * size / 16.0; 2],
        PlateShape::Cross => {
            let [area, second] = cross_area_and_second_moment(size, size / aspect);
            [second / area; 2]
        }
    }
}

/// A plus of span `span` and arm width `width` (m): its area 2 S W − W², m²,
/// and its second moment of area about either arm's axis, m⁴: the union of
/// the two arms (S × W and W × S) less the centre square they share,
/// (S W³ + W S³ − W⁴) / 12. By the plus's fourfold symmetry every in-plane
/// axis through its centre has that moment.
pub fn cross_area_and_second_moment(span: f64, width: f64) -> [f64; 2] {
    let (s, w) = (span, width);
    [
        2.0 * s * w - w * w,
        (s * w.powi(3) + w * s.powi(3) - w.powi(4)) / 12.0,
    ]
}

/// Bending stiffness (flexural rigidity D = E t³ / 12(1 − ν²)) of 70 g/m²
/// paper, N·m: a middle value. Paper of that grammage is about 90 µm thick
/// with Young's moduli of 3–6.5 GPa across and along the machine direction
/// (Niskanen, *Paper Physics*, 2nd ed. 2008, ch. 5, as recalled), so D lies
/// between about 1.5e-4 and 4e-4 N·m (docs/lab/real-falls.md, "Paper that
/// bends").
pub const PAPER_BENDING_STIFFNESS: f64 = 2.5e-4;

/// Largest ratio of a mesh's bending stiffness along one direction to
/// another that [`flexible`] accepts: [`plate`]'s square cells bend 1.11 ×
/// as stiffly along their diagonals as along their sides, its ring meshes
/// the same every way; a rectangle's cells, twice as long as wide, 6 ×.
pub const MAX_BENDING_ANISOTROPY: f64 = 1.25;

/// Curvatures imposed on a flat mesh to measure its discrete bending
/// energy ([`flexible`]): cylindrical bending along these directions of its
/// plane, degrees.
pub const CALIBRATION_DIRECTIONS_DEG: [f64; 4] = [0.0, 45.0, 90.0, 135.0];

/// The plate `spec` of [`plate`] (flat, in the x-y plane) made to bend as a
/// thin sheet of bending stiffness `stiffness` (D, N·m) instead of moving
/// as one rigid body: a hinge on every shared edge and a spring on every
/// edge, the leaf's usual springs and hinges.
///
/// - **Hinges.** A hinge of stiffness k_b stores ½ k_b θ², θ its fold
///   angle. Bent to a uniform curvature κ, the sheet stores ½ D κ² A; so
///   k_b = D κ² A / Σθ², with Σθ² summed over the mesh's hinges at that
///   curvature. That sum is measured on the mesh itself, averaged over
///   cylindrical bending along four directions ([`bending_energy_ratio`]),
///   so any of [`plate`]'s meshes gets the sheet's D: the ring meshes of
///   hexagons and circles every way, the square cells within 5 % (stiffer
///   along their diagonals). A rectangle's cells, twice as long as wide,
///   would bend 6 × as stiffly along it as across: refused
///   ([`MAX_BENDING_ANISOTROPY`]).
/// - **Springs.** Real paper stretches far less than it bends (E t ≈ 3e5
///   N/m), which explicit steps cannot afford; the springs are made as
///   stiff as the hinges' fastest mode, so stretching never limits the
///   step that bending sets; a 9 cm sheet of paper stretches by 1.1e-3 at
///   most in a steep fall (a test holds it below 2e-3; springs three times
///   stiffer would cut that to 4e-4 and halve the step).
/// - **Damping.** Springs and hinges at [`CARD_DAMPING_RATIO`] of critical
///   at that fastest mode: the mesh's own ringing decays, the slow bending
///   modes the air drives are hardly touched.
///
/// # Errors
/// A stiffness that is not finite and positive, a
/// plate that is not flat in the x-y plane or has no shared edge, or a
/// mesh that bends much more stiffly one way than another.
pub fn flexible(mut spec: LeafSpec, stiffness: f64) -> Result<LeafSpec, PlateError> {
    let refuse = |reason: String| PlateError {
        field: PlateField::BendingStiffness,
        reason,
    };
    if !(stiffness.is_finite() && stiffness > 0.0) {
        return Err(refuse(format!(
            "must be a finite number > 0 N·m, got {stiffness}"
        )));
    }
    if spec.particles.iter().any(|p| p.position[2] != 0.0) || !spec.folds.is_empty() {
        return Err(refuse(format!(
            "{} is not a flat plate in the x-y plane",
            spec.name
        )));
    }
    spec.rigid = false;
    spec.springs.clear();
    spec.bending = Some(BendingSpec {
        stiffness: 1.0,
        damping: 0.0,
    });
    let unit = spec
        .model()
        .map_err(|e| refuse(format!("{} cannot be meshed: {e}", spec.name)))?;
    if unit.hinges.is_empty() {
        return Err(refuse(format!("{} has no shared edge to bend", spec.name)));
    }
    let along: Vec<f64> = CALIBRATION_DIRECTIONS_DEG
        .iter()
        .map(|&deg| bending_energy_ratio_along(&unit, deg))
        .collect();
    let (lo, hi) = along
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), &r| (l.min(r), h.max(r)));
    if !(lo > 0.0 && hi <= MAX_BENDING_ANISOTROPY * lo) {
        return Err(refuse(format!(
            "{}'s mesh bends {:.1} times as stiffly one way as another (cells longer than wide): \
             it would not bend as a sheet",
            spec.name,
            hi / lo
        )));
    }
    let k_b = stiffness * CALIBRATION_DIRECTIONS_DEG.len() as f64 / along.iter().sum::<f64>();
    // Fastest hinge mode: k_b Σ_h |∇_i θ_h|² / m_i over the particles.
    let mut grad2 = vec![0.0; unit.len()];
    for h in &unit.hinges {
        if let Some((_, grad)) = crate::physics::forces::dihedral(&unit.rest_position, h) {
            let ids = [h.edge[0], h.edge[1], h.apexes[0], h.apexes[1]];
            for (&i, g) in ids.iter().zip(&grad) {
                grad2[i] += g.norm_squared();
            }
        }
    }
    let omega2 = grad2
        .iter()
        .zip(&unit.mass)
        .map(|(g, m)| k_b * g / m)
        .fold(0.0, f64::max);
    let omega = omega2.sqrt();
    // A spring's mode on its lighter end, shared among the about six
    // springs at a particle: k = m ω² / 6 keeps Σk/m at ω².
    let mut edges = std::collections::BTreeSet::new();
    for t in &spec.triangles {
        for k in 0..3 {
            let (a, b) = (t.corners[k], t.corners[(k + 1) % 3]);
            edges.insert((a.min(b), a.max(b)));
        }
    }
    spec.springs = edges
        .into_iter()
        .map(|(a, b)| {
            let m = unit.mass[a].min(unit.mass[b]);
            let k = m * omega2 / 6.0;
            SpringSpec {
                ends: [a, b],
                stiffness: k,
                damping: 2.0 * CARD_DAMPING_RATIO * (k * m).sqrt(),
                group: "sheet".to_string(),
                rest_length: None,
                break_strain: None,
            }
        })
        .collect();
    spec.bending = Some(BendingSpec {
        stiffness: k_b,
        damping: 2.0 * CARD_DAMPING_RATIO * k_b / omega,
    });
    spec.name = format!("{}-bending-{stiffness:.1e}Nm", spec.name);
    Ok(spec)
}

/// D / k_b of `model`'s mesh (flat at rest in the x-y plane): the mean of
/// [`bending_energy_ratio_along`] over [`CALIBRATION_DIRECTIONS_DEG`].
pub fn bending_energy_ratio(model: &Model) -> f64 {
    CALIBRATION_DIRECTIONS_DEG
        .iter()
        .map(|&deg| bending_energy_ratio_along(model, deg))
        .sum::<f64>()
        / CALIBRATION_DIRECTIONS_DEG.len() as f64
}

/// Σθ² / (κ² A) of `model`'s hinges (flat at rest in the x-y plane) bent
/// to a small uniform curvature κ along the direction `direction_deg` of
/// its plane (cylindrical bending): the sheet's bending stiffness per unit
/// hinge stiffness in that direction (on a continuum, ½ D κ² A = ½ k_b Σθ²).
///
/// The mesh's lattice nodes are put on the bent surface; its sub-lattice
/// nodes (the centres of [`plate`]'s four-triangle cells: interior nodes
/// of four triangles) are left where the hinges put them, by least squares
/// on the linearised fold angles. Held on the surface, they make Σθ² a
/// third too large (1.35 × on the square cells), so the hinges come out a
/// quarter too soft: a clamped strip calibrated that way sagged 1.29 × as
/// far as its D says.
pub fn bending_energy_ratio_along(model: &Model, direction_deg: f64) -> f64 {
    let rest = &model.rest_position;
    let extent = rest
        .iter()
        .map(|x| x.xy().norm())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    // Small enough that θ ≈ κ × spacing stays linear (1e-3 rad over the plate).
    let kappa = 1e-3 / extent;
    let area = model.surface_area();
    let relaxed = cell_centres(model);
    let column: Vec<Option<usize>> = {
        let mut c = vec![None; model.len()];
        for (k, &i) in relaxed.iter().enumerate() {
            c[i] = Some(k);
        }
        c
    };
    let d = Vector3::new(
        direction_deg.to_radians().cos(),
        direction_deg.to_radians().sin(),
        0.0,
    );
    let bent: Vec<Vector3<f64>> = rest
        .iter()
        .map(|x| {
            let s = x.dot(&d);
            Vector3::new(x.x, x.y, 0.5 * kappa * s * s)
        })
        .collect();
    // θ = θ₀ + J δz over the relaxed nodes' heights; minimise |θ|².
    let rows: Vec<(f64, [(usize, f64); 4])> = model
        .hinges
        .iter()
        .filter_map(|h| {
            let (theta, grad) = crate::physics::forces::dihedral(&bent, h)?;
            let ids = [h.edge[0], h.edge[1], h.apexes[0], h.apexes[1]];
            Some((theta, std::array::from_fn(|k| (ids[k], grad[k].z))))
        })
        .collect();
    let m = relaxed.len();
    let shift = if m == 0 {
        nalgebra::DVector::zeros(0)
    } else {
        let mut normal = nalgebra::DMatrix::<f64>::zeros(m, m);
        let mut rhs = nalgebra::DVector::<f64>::zeros(m);
        for (theta, entries) in &rows {
            for &(i, gi) in entries {
                let Some(a) = column[i] else { continue };
                rhs[a] -= gi * theta;
                for &(j, gj) in entries {
                    if let Some(b) = column[j] {
                        normal[(a, b)] += gi * gj;
                    }
                }
            }
        }
        normal
            .cholesky()
            .map_or_else(|| nalgebra::DVector::zeros(m), |c| c.solve(&rhs))
    };
    let sum: f64 = rows
        .iter()
        .map(|(theta, entries)| {
            let moved: f64 = entries
                .iter()
                .filter_map(|&(i, g)| column[i].map(|a| g * shift[a]))
                .sum();
            (theta + moved).powi(2)
        })
        .sum();
    sum / (kappa * kappa * area)
}

/// The interior nodes that four triangles share: the centres of
/// [`plate`]'s square cells (its lattice nodes are shared by eight, a ring
/// mesh's by six).
fn cell_centres(model: &Model) -> Vec<usize> {
    let n = model.len();
    let mut valence = vec![0usize; n];
    let mut edge_use = std::collections::HashMap::new();
    for t in &model.triangles {
        for k in 0..3 {
            valence[t.corners[k]] += 1;
            let (a, b) = (t.corners[k], t.corners[(k + 1) % 3]);
            *edge_use.entry((a.min(b), a.max(b))).or_insert(0usize) += 1;
        }
    }
    let mut on_rim = vec![false; n];
    for (&(a, b), &uses) in &edge_use {
        if uses == 1 {
            on_rim[a] = true;
            on_rim[b] = true;
        }
    }
    (0..n).filter(|&i| valence[i] == 4 && !on_rim[i]).collect()
}
