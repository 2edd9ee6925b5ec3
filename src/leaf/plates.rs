//! Plates for validation: a flat square card built as a leaf, and the
//! dimensionless numbers the falling-plate literature sorts falls by
//! (docs/falling-plates.md, "Dimensionless groups").

use crate::leaf::{AeroSpec, BendingSpec, LeafSpec, ParticleSpec, SpringSpec, TriangleSpec};
use crate::physics::model::AIR_DENSITY;
use crate::physics::model::{Model, STANDARD_GRAVITY};
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
        name: format!("card-{:.0}mm-{:.0}gsm", side * 1e3, sigma * 1e3),
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
/// (docs/falling-plates.md, "Dimensionless groups") with Ī the mean of the two
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
