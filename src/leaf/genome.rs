//! The genome of a leaf: what section 4.1 of the paper varied by hand when it
//! copied a prototype "with small random variations in geometry, and
//! physical properties such as mass distribution and stiffness". A genome is
//! a set of factors and angles applied to a prototype; it turns into a leaf
//! (and a [`Model`]) deterministically, and [`mutate`] draws a variant from
//! `rand_distr` distributions, clamped to the prototype's [`Bounds`] so that
//! every variant is a valid model.

use crate::leaf::{Bounds, LeafSpec};
use crate::physics::model::{Model, ModelError};
use crate::util::number::shown;
use rand::Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

/// Standard deviations of one mutation at scale 1 (the paper's first round
/// of "small random variations"; later rounds use a smaller scale).
pub mod sigma {
    /// Fold angle, degrees (additive normal).
    pub const FOLD_DEG: f64 = 12.0;
    /// ln of each particle's mass factor (log-normal).
    pub const LOG_MASS: f64 = 0.35;
    /// ln of the total mass factor (log-normal).
    pub const LOG_TOTAL_MASS: f64 = 0.15;
    /// ln of each stiffness group's factor (log-normal).
    pub const LOG_STIFFNESS: f64 = 0.3;
    /// ln of the size factor (log-normal).
    pub const LOG_SIZE: f64 = 0.08;
}

/// The name of the stiffness group that scales the bending hinges.
pub const BENDING_GROUP: &str = "bending";

/// A variant of a prototype leaf.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Genome {
    /// Fold angle of each of the prototype's folds, in its order, degrees
    /// (+ up). Signed, so a flap can move from up to down.
    pub fold_deg: Vec<f64>,
    /// Each particle's share of the mass relative to the prototype (the mass
    /// distribution); renormalised so that it alone never changes the total.
    pub mass_factor: Vec<f64>,
    /// Total mass relative to the prototype (areal density at equal size).
    pub total_mass_factor: f64,
    /// Stiffness factor of each spring group, and of the bending hinges
    /// (group `bending`), sorted by group name.
    pub stiffness_factor: Vec<(String, f64)>,
    /// Linear size relative to the prototype (mass scales with area).
    pub size_factor: f64,
}

impl Genome {
    /// The prototype itself: its folds, unit factors.
    pub fn of_prototype(proto: &LeafSpec) -> Genome {
        let mut groups: Vec<String> = proto.springs.iter().map(|s| s.group.clone()).collect();
        if proto.bending.is_some() {
            groups.push(BENDING_GROUP.to_string());
        }
        groups.sort();
        groups.dedup();
        Genome {
            fold_deg: proto.folds.iter().map(|f| f.angle_deg).collect(),
            mass_factor: vec![1.0; proto.particles.len()],
            total_mass_factor: 1.0,
            stiffness_factor: groups.into_iter().map(|g| (g, 1.0)).collect(),
            size_factor: 1.0,
        }
    }

    /// The leaf this genome describes: the prototype with folds, masses,
    /// stiffnesses and size replaced. Deterministic.
    pub fn to_leaf(&self, proto: &LeafSpec) -> LeafSpec {
        let mut leaf = proto.clone();
        for (fold, &angle) in leaf.folds.iter_mut().zip(&self.fold_deg) {
            fold.angle_deg = angle;
        }
        let s = self.size_factor;
        // Distribution factors are normalised so that the prototype's total
        // mass times `total_mass_factor` (times the area ratio s²) results.
        let proto_total: f64 = proto.particles.iter().map(|p| p.mass).sum();
        let weighted: f64 = proto
            .particles
            .iter()
            .zip(&self.mass_factor)
            .map(|(p, f)| p.mass * f)
            .sum();
        let norm = proto_total / weighted * self.total_mass_factor * s * s;
        for (p, f) in leaf.particles.iter_mut().zip(&self.mass_factor) {
            p.mass *= f * norm;
            p.position = p.position.map(|c| c * s);
        }
        for spring in &mut leaf.springs {
            spring.stiffness *= self.stiffness(&spring.group);
            if let Some(l) = spring.rest_length.as_mut() {
                *l *= s;
            }
        }
        if let Some(b) = leaf.bending.as_mut() {
            b.stiffness *= self.stiffness(BENDING_GROUP);
        }
        leaf
    }

    /// The model of [`Genome::to_leaf`].
    pub fn model(&self, proto: &LeafSpec) -> Result<Model, ModelError> {
        self.to_leaf(proto).model()
    }

    fn stiffness(&self, group: &str) -> f64 {
        self.stiffness_factor
            .iter()
            .find(|(g, _)| g == group)
            .map_or(1.0, |(_, f)| *f)
    }

    /// The genome as named numbers, in a fixed order (CSV columns).
    pub fn values(&self) -> Vec<(String, f64)> {
        let mut out = Vec::new();
        for (i, f) in self.fold_deg.iter().enumerate() {
            out.push((format!("fold{i}_deg"), *f));
        }
        for (i, m) in self.mass_factor.iter().enumerate() {
            out.push((format!("mass{i}"), *m));
        }
        out.push(("total_mass".to_string(), self.total_mass_factor));
        for (g, k) in &self.stiffness_factor {
            out.push((format!("stiffness_{g}"), *k));
        }
        out.push(("size".to_string(), self.size_factor));
        out
    }
}

/// A gene outside what the prototype allows: which gene, and why.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {reason}")]
pub struct GenomeError {
    /// The gene, as the genome's fields name it (`mass_factor[3]`).
    pub field: String,
    /// What is wrong with it.
    pub reason: String,
}

impl Genome {
    /// Checks the genome against its prototype: one gene per fold, per
    /// particle and per stiffness group (the prototype's groups, sorted),
    /// every gene finite and within the prototype's [`Bounds`] — what every
    /// genome [`mutate`] draws satisfies, so a genome read back from disk
    /// that does not was damaged or edited, and would make an invalid leaf
    /// (a mass factor of −1, a size of 1e300).
    ///
    /// # Errors
    /// The first gene that fails, with the reason.
    pub fn check(&self, proto: &LeafSpec) -> Result<(), GenomeError> {
        let b = &proto.bounds;
        let fail = |field: String, reason: String| Err(GenomeError { field, reason });
        let count = |field: &str, got: usize, want: usize, what: &str| {
            if got == want {
                Ok(())
            } else {
                fail(
                    field.to_string(),
                    format!("{got} genes, but the prototype has {want} {what}"),
                )
            }
        };
        let within = |field: String, v: f64, range: [f64; 2]| {
            if v.is_finite() && range[0] <= v && v <= range[1] {
                Ok(())
            } else {
                fail(
                    field,
                    format!(
                        "{} is outside the prototype's bounds [{}, {}]",
                        shown(v),
                        shown(range[0]),
                        shown(range[1])
                    ),
                )
            }
        };
        count("fold_deg", self.fold_deg.len(), proto.folds.len(), "folds")?;
        for (k, &v) in self.fold_deg.iter().enumerate() {
            within(format!("fold_deg[{k}]"), v, b.fold_deg)?;
        }
        count(
            "mass_factor",
            self.mass_factor.len(),
            proto.particles.len(),
            "particles",
        )?;
        for (k, &v) in self.mass_factor.iter().enumerate() {
            within(format!("mass_factor[{k}]"), v, b.mass_factor)?;
        }
        within(
            "total_mass_factor".to_string(),
            self.total_mass_factor,
            b.total_mass_factor,
        )?;
        let groups: Vec<String> = Genome::of_prototype(proto)
            .stiffness_factor
            .into_iter()
            .map(|(g, _)| g)
            .collect();
        let have: Vec<&String> = self.stiffness_factor.iter().map(|(g, _)| g).collect();
        if have.iter().copied().ne(groups.iter()) {
            return fail(
                "stiffness_factor".to_string(),
                format!("groups {have:?}, but the prototype's are {groups:?}"),
            );
        }
        for (g, v) in &self.stiffness_factor {
            within(format!("stiffness_factor.{g}"), *v, b.stiffness_factor)?;
        }
        within("size_factor".to_string(), self.size_factor, b.size_factor)
    }
}

/// A variant of `genome`: every gene perturbed with spread proportional to
/// `scale` (1 for the paper's first round), clamped to `bounds`. Fold angles
/// are normal, positive factors log-normal (so they stay positive and
/// multiply symmetrically). The draws happen in a fixed order, so the same
/// rng state gives the same variant.
pub fn mutate<R: Rng + ?Sized>(
    genome: &Genome,
    bounds: &Bounds,
    scale: f64,
    rng: &mut R,
) -> Genome {
    let scale = scale.max(0.0);
    let mut normal = |sd: f64| -> f64 {
        if sd == 0.0 {
            return 0.0;
        }
        Normal::new(0.0, sd)
            .expect("finite, positive sd")
            .sample(rng)
    };
    let clamp = |v: f64, range: [f64; 2]| v.clamp(range[0], range[1]);
    let fold_deg = genome
        .fold_deg
        .iter()
        .map(|a| clamp(a + normal(sigma::FOLD_DEG * scale), bounds.fold_deg))
        .collect();
    let mass_factor = genome
        .mass_factor
        .iter()
        .map(|m| {
            clamp(
                m * normal(sigma::LOG_MASS * scale).exp(),
                bounds.mass_factor,
            )
        })
        .collect();
    let total_mass_factor = clamp(
        genome.total_mass_factor * normal(sigma::LOG_TOTAL_MASS * scale).exp(),
        bounds.total_mass_factor,
    );
    let stiffness_factor = genome
        .stiffness_factor
        .iter()
        .map(|(g, k)| {
            (
                g.clone(),
                clamp(
                    k * normal(sigma::LOG_STIFFNESS * scale).exp(),
                    bounds.stiffness_factor,
                ),
            )
        })
        .collect();
    let size_factor = clamp(
        genome.size_factor * normal(sigma::LOG_SIZE * scale).exp(),
        bounds.size_factor,
    );
    Genome {
        fold_deg,
        mass_factor,
        total_mass_factor,
        stiffness_factor,
        size_factor,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    #[test]
    fn the_prototype_genome_reproduces_the_prototype() {
        for p in ["a", "b"] {
            let proto = LeafSpec::load(p).unwrap();
            let g = Genome::of_prototype(&proto);
            let leaf = g.to_leaf(&proto);
            for (a, b) in leaf.particles.iter().zip(&proto.particles) {
                assert!((a.mass - b.mass).abs() <= 1e-15 * b.mass);
                assert_eq!(a.position, b.position);
            }
            assert_eq!(leaf.springs, proto.springs);
            assert_eq!(leaf.folds, proto.folds);
        }
    }

    #[test]
    fn mass_distribution_keeps_the_total_unless_asked() {
        let proto = LeafSpec::load("a").unwrap();
        let total = |l: &LeafSpec| l.particles.iter().map(|p| p.mass).sum::<f64>();
        let mut g = Genome::of_prototype(&proto);
        g.mass_factor[4] = 3.0;
        g.mass_factor[0] = 0.5;
        let leaf = g.to_leaf(&proto);
        assert!((total(&leaf) - total(&proto)).abs() < 1e-15);
        assert!(leaf.particles[4].mass > 2.0 * proto.particles[4].mass);
        g.total_mass_factor = 1.5;
        g.size_factor = 2.0;
        let leaf = g.to_leaf(&proto);
        assert!((total(&leaf) - 6.0 * total(&proto)).abs() < 1e-15 * 6.0);
    }

    #[test]
    fn drawn_genomes_pass_their_check_and_damaged_ones_name_the_gene() {
        for p in ["a", "b"] {
            let proto = LeafSpec::load(p).unwrap();
            let g = Genome::of_prototype(&proto);
            for seed in 0..200 {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
                let v = mutate(&g, &proto.bounds, 2.0, &mut rng);
                assert_eq!(v.check(&proto), Ok(()), "{p} seed {seed}");
            }
            let mut bad = g.clone();
            bad.size_factor = 1e300;
            assert_eq!(bad.check(&proto).unwrap_err().field, "size_factor");
            let mut bad = g.clone();
            bad.mass_factor[3] = -1.0;
            assert_eq!(bad.check(&proto).unwrap_err().field, "mass_factor[3]");
            let mut bad = g.clone();
            bad.fold_deg.pop();
            assert!(bad.check(&proto).unwrap_err().reason.contains("folds"));
            let mut bad = g.clone();
            bad.stiffness_factor[0].1 = f64::NAN;
            assert!(bad.check(&proto).is_err());
        }
    }

    #[test]
    fn same_seed_same_variant() {
        let proto = LeafSpec::load("b").unwrap();
        let g = Genome::of_prototype(&proto);
        let draw = |seed| {
            mutate(
                &g,
                &proto.bounds,
                1.0,
                &mut Xoshiro256PlusPlus::seed_from_u64(seed),
            )
        };
        assert_eq!(draw(7), draw(7));
        assert_ne!(draw(7), draw(8));
        let none = mutate(
            &g,
            &proto.bounds,
            0.0,
            &mut Xoshiro256PlusPlus::seed_from_u64(7),
        );
        assert_eq!(none, g);
    }
}
