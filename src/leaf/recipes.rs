//! The paper's three recipes (section 4.1) as leaves, and seeded families
//! of variants around them, as leafmagic's predecessor tested them
//! (docs/design/falling-plates.md, "Folded leaves under the linear law"):
//!
//! - **floater**: topology A, flaps 1, 2 and 3 folded up, centre of gravity
//!   near the leaf centre;
//! - **spinner**: topology A, flaps 1 and 3 folded in opposite directions,
//!   centre of gravity off to one side;
//! - **lilter**: topology B, flap 1 folded up, flaps 2 and 3 down.
//!
//! A family member draws its folds, its areal density and a ±15 %
//! variation of every mass from a seeded generator, and a release attitude
//! within ±20° about both body axes.

use crate::leaf::LeafSpec;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// The three recipes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Recipe {
    /// Topology A, all flaps up, mass central.
    Floater,
    /// Topology A, flaps 1 and 3 opposed, mass moved to one side.
    Spinner,
    /// Topology B, flap 1 up, flaps 2 and 3 down.
    Lilter,
}

/// Spread of each particle's mass in a family: e^U(−s, s).
pub const MASS_SPREAD: f64 = 0.15;
/// Largest release tilt about each body axis in a family, degrees.
pub const RELEASE_SPREAD_DEG: f64 = 20.0;
/// The particle of prototype A that the spinner recipe loads: the tip of
/// flap 2, the flap left between the two opposed ones.
pub const SPINNER_LOADED_PARTICLE: usize = 5;

/// Multiplies every mass by e^U(−s, s), then rescales so that the total is
/// `total_factor` times what it was.
pub fn vary_masses(spec: &mut LeafSpec, rng: &mut Xoshiro256PlusPlus, total_factor: f64, s: f64) {
    let before: f64 = spec.particles.iter().map(|p| p.mass).sum();
    for p in &mut spec.particles {
        p.mass *= rng.random_range(-s..=s).exp();
    }
    let after: f64 = spec.particles.iter().map(|p| p.mass).sum();
    for p in &mut spec.particles {
        p.mass *= total_factor * before / after;
    }
}

/// Moves `fraction` of the total mass onto particle `to`, keeping the total.
pub fn move_mass(spec: &mut LeafSpec, to: usize, fraction: f64) {
    let total: f64 = spec.particles.iter().map(|p| p.mass).sum();
    for p in &mut spec.particles {
        p.mass *= 1.0 - fraction;
    }
    spec.particles[to].mass += fraction * total;
}

/// The spinner recipe on prototype A: flap 1 at `flap1`, flap 2 at
/// `flap2`, flap 3 at `flap3` degrees, and `fraction` of the mass moved to
/// [`SPINNER_LOADED_PARTICLE`].
pub fn spinner_leaf(flap1: f64, flap2: f64, flap3: f64, fraction: f64) -> LeafSpec {
    let mut spec = LeafSpec::load("a").expect("prototype A is valid");
    spec.name = "recipe-spinner".to_string();
    for fold in &mut spec.folds {
        fold.angle_deg = match fold.flap {
            Some(1) => flap1,
            Some(2) => flap2,
            Some(3) => flap3,
            _ => fold.angle_deg,
        };
    }
    move_mass(&mut spec, SPINNER_LOADED_PARTICLE, fraction);
    spec
}

impl Recipe {
    /// The recipe's own leaf: prototype A (flaps 20° up, uniform 80 g/m²)
    /// for the floater; A with flap 1 at +30°, flap 3 at −30°, flap 2 flat
    /// and a quarter of the mass on the tip of flap 2 for the spinner;
    /// prototype B for the lilter.
    pub fn leaf(self) -> LeafSpec {
        match self {
            Recipe::Floater => LeafSpec::load("a").expect("prototype A is valid"),
            Recipe::Spinner => spinner_leaf(30.0, 0.0, -30.0, 0.25),
            Recipe::Lilter => LeafSpec::load("b").expect("prototype B is valid"),
        }
    }

    /// Family member `seed` and its release tilt (degrees):
    /// - floater: each flap up 20–45°, σ × 0.5–1.9 (40–150 g/m²);
    /// - spinner: flap 1 up β = 20–45°, flap 3 down (0.8–1.2) β, flap 2
    ///   within ±10°, σ × 0.5–1.9, then 15–35 % of the mass moved to the tip
    ///   of flap 2 (docs/design/falling-plates.md, "Folded leaves under the linear
    ///   law");
    /// - lilter: B's flaps each moved ±8°, σ × 0.7–1.4;
    ///
    /// then every mass ±15 % ([`MASS_SPREAD`]) and a release within ±20°.
    pub fn variant(self, seed: u64) -> (LeafSpec, [f64; 2]) {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let rng = &mut rng;
        let spec = match self {
            Recipe::Floater => {
                let mut spec = self.leaf();
                for fold in &mut spec.folds {
                    fold.angle_deg = rng.random_range(20.0..=45.0);
                }
                let total = rng.random_range(0.5..=1.9);
                vary_masses(&mut spec, rng, total, MASS_SPREAD);
                spec
            }
            Recipe::Spinner => {
                let beta = rng.random_range(20.0..=45.0);
                let flap3 = -beta * rng.random_range(0.8..=1.2);
                let flap2 = rng.random_range(-10.0..=10.0);
                let fraction = rng.random_range(0.15..=0.35);
                let mut spec = spinner_leaf(beta, flap2, flap3, 0.0);
                let total = rng.random_range(0.5..=1.9);
                vary_masses(&mut spec, rng, total, MASS_SPREAD);
                move_mass(&mut spec, SPINNER_LOADED_PARTICLE, fraction);
                spec
            }
            Recipe::Lilter => {
                let mut spec = self.leaf();
                for fold in spec.folds.iter_mut().filter(|f| f.flap.is_some()) {
                    fold.angle_deg += rng.random_range(-8.0..=8.0);
                }
                let total = rng.random_range(0.7..=1.4);
                vary_masses(&mut spec, rng, total, MASS_SPREAD);
                spec
            }
        };
        let s = RELEASE_SPREAD_DEG;
        let tilt = [rng.random_range(-s..=s), rng.random_range(-s..=s)];
        (spec, tilt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recipes_fold_and_load_as_the_paper_says() {
        let flap = |spec: &LeafSpec, k: u8| {
            spec.folds
                .iter()
                .find(|f| f.flap == Some(k))
                .unwrap()
                .angle_deg
        };
        for seed in 1..=16 {
            let (f, _) = Recipe::Floater.variant(seed);
            assert!((1..=3).all(|k| flap(&f, k) >= 20.0));
            let (s, _) = Recipe::Spinner.variant(seed);
            assert!(flap(&s, 1) > 0.0 && flap(&s, 3) < 0.0);
            let model = s.model().unwrap();
            let total = model.total_mass();
            // At least 15 % of the mass sits on the loaded tip, moving the
            // centre of gravity towards it.
            assert!(model.mass[SPINNER_LOADED_PARTICLE] > 0.15 * total);
            let (l, tilt) = Recipe::Lilter.variant(seed);
            assert!(flap(&l, 1) > 0.0 && flap(&l, 2) < 0.0 && flap(&l, 3) < 0.0);
            assert!(tilt.iter().all(|t| t.abs() <= RELEASE_SPREAD_DEG));
        }
        assert_eq!(Recipe::Spinner.variant(3), Recipe::Spinner.variant(3));
    }
}
