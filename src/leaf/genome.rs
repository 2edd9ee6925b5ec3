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
    /// ln of the aspect-ratio factor (log-normal).
    pub const LOG_ASPECT: f64 = 0.25;
    /// ln of the drag-ratio factor (log-normal).
    pub const LOG_DRAG_RATIO: f64 = 0.3;
    /// Camber, fraction of the extent along y (additive normal).
    pub const CAMBER: f64 = 0.05;
    /// Petiole mass, fraction of the blade's mass (additive normal).
    pub const PETIOLE_MASS: f64 = 0.1;
    /// ln of the size factor (log-normal): a quarter, so that the default
    /// bounds (½–2×, ln 2 = 0.69 away) are under three steps from the
    /// prototype (issue 19: at 0.08 they were 8.7 steps away, and
    /// `--target-features descent=0.6,spin=20` needs them).
    pub const LOG_SIZE: f64 = 0.25;
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
    /// Aspect ratio of the outline relative to the prototype's: x stretched
    /// by √a, y by 1/√a, area (and so mass) kept. 1 in a genome written
    /// before it.
    #[serde(default = "unit")]
    pub aspect_ratio: f64,
    /// Factor on the linear law's tangential/normal drag ratio αᵗ/αⁿ.
    #[serde(default = "unit")]
    pub drag_ratio: f64,
    /// Camber: the flat layout bowed across y, arc height over the extent
    /// along y ([`Bounds::camber`]). 0 in a genome written before it.
    #[serde(default)]
    pub camber: f64,
    /// Petiole mass at the base over the blade's mass
    /// ([`Bounds::petiole_mass`]).
    #[serde(default)]
    pub petiole_mass: f64,
}

fn unit() -> f64 {
    1.0
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
            aspect_ratio: 1.0,
            drag_ratio: 1.0,
            camber: 0.0,
            petiole_mass: 0.0,
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
        let stretch = [
            s * self.aspect_ratio.sqrt(),
            s / self.aspect_ratio.sqrt(),
            s,
        ];
        for (p, f) in leaf.particles.iter_mut().zip(&self.mass_factor) {
            p.mass *= f * norm;
            for (c, k) in p.position.iter_mut().zip(stretch) {
                *c *= k;
            }
        }
        for spring in &mut leaf.springs {
            spring.stiffness *= self.stiffness(&spring.group);
            if let Some(l) = spring.rest_length.as_mut() {
                // An explicit rest length stretches as its ends do.
                let [i, j] = spring.ends;
                let length = |ps: &[crate::leaf::ParticleSpec]| {
                    let (a, b) = (ps[i].position, ps[j].position);
                    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
                };
                let before = length(&proto.particles);
                *l *= if before > 0.0 {
                    length(&leaf.particles) / before
                } else {
                    s
                };
            }
        }
        if let Some(t) = leaf.aero.number("alpha_t") {
            leaf.aero.set_number("alpha_t", t * self.drag_ratio);
        }
        if self.camber != 0.0 || self.petiole_mass != 0.0 {
            let ys: Vec<f64> = proto.particles.iter().map(|p| p.position[1]).collect();
            let (lo, hi) = ys
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
                    (a.min(y), b.max(y))
                });
            let (mid, half) = ((lo + hi) / 2.0, (hi - lo) / 2.0);
            if half > 0.0 && self.camber != 0.0 {
                // z = c · 2h · (1 − ((y − mid)/h)²): height c × extent at
                // the middle, 0 at both ends, before the folds.
                let extent = 2.0 * half * stretch[1];
                for (p, &y) in leaf.particles.iter_mut().zip(&ys) {
                    let u = (y - mid) / half;
                    p.position[2] += self.camber * extent * (1.0 - u * u);
                }
            }
            if self.petiole_mass > 0.0 {
                let base = (0..ys.len())
                    .min_by(|&a, &b| ys[a].total_cmp(&ys[b]).then(a.cmp(&b)))
                    .expect("a leaf has particles");
                let blade: f64 = leaf.particles.iter().map(|p| p.mass).sum();
                leaf.particles[base].mass += self.petiole_mass * blade;
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
        out.push(("aspect_ratio".to_string(), self.aspect_ratio));
        out.push(("drag_ratio".to_string(), self.drag_ratio));
        out.push(("camber".to_string(), self.camber));
        out.push(("petiole_mass".to_string(), self.petiole_mass));
        out
    }
}

/// How one gene maps onto the unit interval the search strategies work in
/// ([`Genome::coordinates`]): fold angles linearly over their bounds,
/// positive factors by their logarithm (so a step doubles or halves them
/// alike).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Axis {
    Linear([f64; 2]),
    Log([f64; 2]),
}

impl Axis {
    fn to_unit(self, v: f64) -> f64 {
        let (x, [lo, hi]) = match self {
            Axis::Linear(r) => (v, r),
            Axis::Log(r) => (v.ln(), [r[0].ln(), r[1].ln()]),
        };
        if hi > lo {
            ((x - lo) / (hi - lo)).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    fn range(self) -> [f64; 2] {
        match self {
            Axis::Linear(r) | Axis::Log(r) => r,
        }
    }

    fn at_unit(self, u: f64) -> f64 {
        let u = u.clamp(0.0, 1.0);
        match self {
            Axis::Linear([lo, hi]) => (lo + u * (hi - lo)).clamp(lo, hi),
            Axis::Log([lo, hi]) => (lo.ln() + u * (hi.ln() - lo.ln())).exp().clamp(lo, hi),
        }
    }

    /// A mutation's standard deviation at scale 1 (`sd` in the gene's own
    /// units, or of its logarithm) as a fraction of the unit interval.
    fn unit_sd(self, sd: f64) -> f64 {
        let width = match self {
            Axis::Linear([lo, hi]) => hi - lo,
            Axis::Log([lo, hi]) => hi.ln() - lo.ln(),
        };
        if width > 0.0 { sd / width } else { 0.0 }
    }
}

impl Genome {
    /// The axis and scale-1 standard deviation of every gene, in
    /// [`Genome::values`] order.
    fn axes(&self, b: &Bounds) -> Vec<(Axis, f64)> {
        let mut out = Vec::new();
        out.extend(
            self.fold_deg
                .iter()
                .map(|_| (Axis::Linear(b.fold_deg), sigma::FOLD_DEG)),
        );
        out.extend(
            self.mass_factor
                .iter()
                .map(|_| (Axis::Log(b.mass_factor), sigma::LOG_MASS)),
        );
        out.push((Axis::Log(b.total_mass_factor), sigma::LOG_TOTAL_MASS));
        out.extend(
            self.stiffness_factor
                .iter()
                .map(|_| (Axis::Log(b.stiffness_factor), sigma::LOG_STIFFNESS)),
        );
        out.push((Axis::Log(b.size_factor), sigma::LOG_SIZE));
        out.push((Axis::Log(b.aspect_ratio), sigma::LOG_ASPECT));
        out.push((Axis::Log(b.drag_ratio), sigma::LOG_DRAG_RATIO));
        out.push((Axis::Linear(b.camber), sigma::CAMBER));
        out.push((Axis::Linear(b.petiole_mass), sigma::PETIOLE_MASS));
        out
    }

    /// The genes as coordinates in the unit box [0, 1]ⁿ spanned by the
    /// prototype's bounds, in [`Genome::values`] order: what CMA-ES
    /// searches. A gene whose bounds are one point is 0.
    pub fn coordinates(&self, b: &Bounds) -> Vec<f64> {
        self.axes(b)
            .iter()
            .zip(self.values())
            .map(|((axis, _), (_, v))| axis.to_unit(v))
            .collect()
    }

    /// The genome of the same prototype at coordinates `u` (each clamped to
    /// [0, 1], so within the bounds).
    ///
    /// # Panics
    /// If `u` has not one coordinate per gene.
    pub fn with_coordinates(&self, b: &Bounds, u: &[f64]) -> Genome {
        let axes = self.axes(b);
        assert_eq!(axes.len(), u.len(), "one coordinate per gene");
        self.with_values(axes.iter().zip(u).map(|((axis, _), &x)| axis.at_unit(x)))
    }

    /// The same genome with every gene clamped into `b`: a gene inside its
    /// range keeps its value to the bit (an earlier run's leaf reused in a
    /// run whose bounds are narrower, `breed --start-from`).
    pub fn clamped(&self, b: &Bounds) -> Genome {
        let axes = self.axes(b);
        self.with_values(axes.iter().zip(self.values()).map(|((axis, _), (_, v))| {
            let [lo, hi] = axis.range();
            v.clamp(lo, hi)
        }))
    }

    /// The genome of the same prototype with its genes taken, in
    /// [`Genome::values`] order, from `v`.
    fn with_values(&self, mut v: impl Iterator<Item = f64>) -> Genome {
        let mut next = || v.next().expect("counted");
        let fold_deg = self.fold_deg.iter().map(|_| next()).collect();
        let mass_factor = self.mass_factor.iter().map(|_| next()).collect();
        let total_mass_factor = next();
        let stiffness_factor = self
            .stiffness_factor
            .iter()
            .map(|(g, _)| (g.clone(), next()))
            .collect();
        let size_factor = next();
        let aspect_ratio = next();
        let drag_ratio = next();
        let camber = next();
        let petiole_mass = next();
        Genome {
            fold_deg,
            mass_factor,
            total_mass_factor,
            stiffness_factor,
            size_factor,
            aspect_ratio,
            drag_ratio,
            camber,
            petiole_mass,
        }
    }

    /// The standard deviation of one scale-1 [`mutate`] step of every gene
    /// as a fraction of its coordinate's unit interval: the per-gene step
    /// sizes CMA-ES starts from.
    pub fn coordinate_sds(&self, b: &Bounds) -> Vec<f64> {
        self.axes(b)
            .iter()
            .map(|(axis, sd)| axis.unit_sd(*sd))
            .collect()
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
        within("size_factor".to_string(), self.size_factor, b.size_factor)?;
        within(
            "aspect_ratio".to_string(),
            self.aspect_ratio,
            b.aspect_ratio,
        )?;
        within("drag_ratio".to_string(), self.drag_ratio, b.drag_ratio)?;
        within("camber".to_string(), self.camber, b.camber)?;
        within(
            "petiole_mass".to_string(),
            self.petiole_mass,
            b.petiole_mass,
        )
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
    // Drawn last, so the earlier genes' draws are what they were before
    // these genes existed.
    let mut factor = |v: f64, sd: f64, range: [f64; 2]| {
        if range[0] == range[1] {
            range[0]
        } else {
            clamp(v * normal(sd * scale).exp(), range)
        }
    };
    let aspect_ratio = factor(genome.aspect_ratio, sigma::LOG_ASPECT, bounds.aspect_ratio);
    let drag_ratio = factor(genome.drag_ratio, sigma::LOG_DRAG_RATIO, bounds.drag_ratio);
    let mut shift = |v: f64, sd: f64, range: [f64; 2]| {
        if range[0] == range[1] {
            range[0]
        } else {
            clamp(v + normal(sd * scale), range)
        }
    };
    let camber = shift(genome.camber, sigma::CAMBER, bounds.camber);
    let petiole_mass = shift(
        genome.petiole_mass,
        sigma::PETIOLE_MASS,
        bounds.petiole_mass,
    );
    Genome {
        fold_deg,
        mass_factor,
        total_mass_factor,
        stiffness_factor,
        size_factor,
        aspect_ratio,
        drag_ratio,
        camber,
        petiole_mass,
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
    fn coordinates_span_the_bounds_and_round_trip() {
        for p in ["a", "b"] {
            let proto = LeafSpec::load(p).unwrap();
            let g = Genome::of_prototype(&proto);
            let b = &proto.bounds;
            for seed in 0..50 {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
                let v = mutate(&g, b, 2.0, &mut rng);
                let u = v.coordinates(b);
                assert!(u.iter().all(|x| (0.0..=1.0).contains(x)), "{u:?}");
                let back = g.with_coordinates(b, &u);
                for ((_, x), (_, y)) in back.values().iter().zip(v.values()) {
                    assert!((x - y).abs() <= 1e-12 * y.abs().max(1.0), "{p}: {x} vs {y}");
                }
            }
            // The corners of the box are the bounds.
            let n = g.values().len();
            let low = g.with_coordinates(b, &vec![0.0; n]);
            let high = g.with_coordinates(b, &vec![1.0; n]);
            assert_eq!(low.size_factor, b.size_factor[0]);
            assert_eq!(high.size_factor, b.size_factor[1]);
            assert_eq!(low.fold_deg[0], b.fold_deg[0]);
            assert_eq!(low.check(&proto), Ok(()));
            assert_eq!(high.check(&proto), Ok(()));
            assert!(g.coordinate_sds(b).iter().all(|&s| s > 0.0 && s < 1.0));
        }
    }

    /// Clamping keeps a gene inside its range to the bit and moves one
    /// outside onto the nearer bound: drawn within wide bounds, then
    /// clamped into the prototype's.
    #[test]
    fn clamped_keeps_what_is_inside_and_moves_what_is_not() {
        let proto = LeafSpec::load("a").unwrap();
        let g = Genome::of_prototype(&proto);
        let b = &proto.bounds;
        let wide = Bounds {
            size_factor: [0.1, 10.0],
            fold_deg: [-90.0, 90.0],
            ..b.clone()
        };
        let mut moved = 0;
        for seed in 0..40 {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
            let v = mutate(&g, &wide, 4.0, &mut rng);
            let c = v.clamped(b);
            assert_eq!(c.check(&proto), Ok(()));
            assert_eq!(v.clamped(&wide), v, "inside its bounds: unchanged");
            let inside = (b.size_factor[0]..=b.size_factor[1]).contains(&v.size_factor);
            if inside {
                assert_eq!(c.size_factor.to_bits(), v.size_factor.to_bits());
            } else {
                moved += 1;
                assert!(c.size_factor == b.size_factor[0] || c.size_factor == b.size_factor[1]);
            }
        }
        assert!(moved > 0, "the draw never left the prototype's bounds");
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
