//! Force terms, each a function that adds its contribution into a force
//! accumulator (one entry per particle). The paper's equations are quoted in
//! each doc comment; [`Forces`] sums them in a fixed order so results are
//! reproducible bit for bit. The triangles' aerodynamics belong to the
//! aerodynamic law, one module per law in [`crate::physics::aero`]; this
//! module calls it like any other term.

mod drag;
mod gravity;
mod hinges;
mod springs;
mod tears;

/// The triangles' aerodynamics, which each law owns
/// ([`crate::physics::aero`]).
pub use crate::physics::aero::{triangle_aero, triangle_aero_intact, triangle_aero_solved};
pub use drag::particle_drag;
pub use gravity::gravity;
pub use hinges::{MIN_HINGE_HEIGHT_RATIO, dihedral, fold_rate, hinge_rest, hinges};
pub use springs::springs;
pub use tears::{Tears, edge_springs, hinge_springs};

use crate::physics::aero::unsteady;
use crate::physics::model::Model;
use crate::physics::rigid;
use crate::physics::skip::{SkipCounts, WindSkip};
use crate::physics::terms::Terms;
use nalgebra::{Matrix3, Vector3};
use tears::tear_mask;

type V3 = Vector3<f64>;

/// The force on one particle split by source, for diagnostics and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ForceTerms {
    /// m g.
    pub gravity: V3,
    /// Springs and dashpots.
    pub spring: V3,
    /// Bending hinges.
    pub bending: V3,
    /// Triangle aerodynamics (eq. 9–10).
    pub aero: V3,
    /// Particle drag (eq. 7).
    pub drag: V3,
}

impl ForceTerms {
    /// The name and magnitude of the largest term.
    pub fn dominant(&self) -> (&'static str, f64) {
        let terms = [
            ("gravity", self.gravity.norm()),
            ("spring", self.spring.norm()),
            ("bending", self.bending.norm()),
            ("aero", self.aero.norm()),
            ("drag", self.drag.norm()),
        ];
        terms
            .into_iter()
            .fold(("none", 0.0), |best, t| if t.1 > best.1 { t } else { best })
    }
}

/// Sums the force terms of a model that its [`Terms`] keep, with
/// preallocated scratch space, so that evaluating forces inside the step
/// loop never allocates.
#[derive(Clone, Debug)]
pub struct Forces {
    wind: Vec<V3>,
    scratch: Vec<V3>,
    evaluations: u64,
    terms: Terms,
    hinge_rest: Vec<(f64, f64)>,
    /// For each triangle, the springs along its edges (with breaking on).
    edge_springs: Vec<[Option<usize>; 3]>,
    /// For each hinge, the springs along its wings (with breaking on).
    hinge_springs: Vec<[Option<usize>; 5]>,
    /// What broken springs have torn (empty until one breaks).
    torn: Tears,
    /// Each particle's added-mass tensor M_i of the last evaluation, under
    /// the unsteady law (empty otherwise).
    added: Vec<Matrix3<f64>>,
    /// Per object, the wind primitives that cannot reach it are skipped.
    skip: WindSkip,
    /// The unsteady law's lagged centre of pressure, where the model's law
    /// has one ([`unsteady::PressureLag`]): state carried from step to step.
    lag: Option<unsteady::PressureLag>,
}

impl Forces {
    /// The terms `model` needs ([`Terms::needed`]), scratch space sized for it.
    pub fn new(model: &Model) -> Forces {
        Forces::with_terms(model, Terms::needed(model))
    }

    /// Evaluates exactly `terms` (a term the model gives nothing to do adds
    /// zeros; a term left out is not evaluated).
    pub fn with_terms(model: &Model, terms: Terms) -> Forces {
        Forces {
            wind: if terms.wind {
                vec![V3::zeros(); model.len()]
            } else {
                Vec::new()
            },
            scratch: vec![V3::zeros(); model.len()],
            evaluations: 0,
            terms,
            hinge_rest: hinge_rest(model),
            edge_springs: if terms.breaking {
                edge_springs(model)
            } else {
                Vec::new()
            },
            hinge_springs: if terms.breaking {
                hinge_springs(model)
            } else {
                Vec::new()
            },
            torn: Tears::default(),
            added: if terms.aero && model.aero.adds_mass() {
                vec![Matrix3::zeros(); model.len()]
            } else {
                Vec::new()
            },
            skip: WindSkip::new(model, terms.wind),
            lag: if terms.aero {
                unsteady::PressureLag::for_model(model)
            } else {
                None
            },
        }
    }

    /// Turns the exact per-object skipping of wind primitives on (the
    /// default) or off; off evaluates every primitive at every particle,
    /// the baseline the skipping is checked bit-identical against.
    pub fn set_skipping(&mut self, model: &Model, on: bool) {
        self.skip = WindSkip::new(model, on && self.terms.wind);
    }

    /// What the skipping has saved so far.
    pub fn skip_counts(&self) -> SkipCounts {
        self.skip.counts()
    }

    /// Per object ([`crate::physics::skip::groups`]), the wind primitive
    /// evaluations skipped so far (empty when skipping is off or cannot
    /// apply).
    pub fn skipped_per_group(&self) -> &[u64] {
        self.skip.skipped_per_group()
    }

    /// Each particle's added-mass tensor M_i at the last force evaluation
    /// (empty unless the model's law has added mass): Newton's law is then
    /// (m_i I + M_i) a_i = f_i.
    pub fn added_mass(&self) -> &[Matrix3<f64>] {
        &self.added
    }

    /// Marks as torn the triangles with a broken edge spring (`alive[s]`
    /// false), which feel no more wind, and the hinges with a broken spring
    /// along a wing, which bend no more. Call after springs break.
    pub fn tear(&mut self, alive: &[bool]) {
        tear_mask(&mut self.torn.triangles, &self.edge_springs, alive);
        tear_mask(&mut self.torn.hinges, &self.hinge_springs, alive);
    }

    /// What is torn (empty masks: nothing).
    pub fn torn(&self) -> &Tears {
        &self.torn
    }

    /// The terms evaluated.
    pub fn terms(&self) -> Terms {
        self.terms
    }

    /// Number of full force evaluations so far (a machine-independent
    /// measure of work).
    pub fn evaluations(&self) -> u64 {
        self.evaluations
    }

    fn sample_wind(&mut self, model: &Model, x: &[V3], t: f64) -> Option<&[V3]> {
        if !self.terms.wind {
            return None;
        }
        if self.skip.is_on() {
            self.skip.sample(model, x, t, &mut self.wind);
        } else {
            for (g, p) in self.wind.iter_mut().zip(x) {
                *g = model.wind.velocity(p, t);
            }
        }
        Some(&self.wind)
    }

    /// Total force on every particle at (x, v, t), written into `force`.
    pub fn total(
        &mut self,
        model: &Model,
        x: &[V3],
        v: &[V3],
        alive: &[bool],
        t: f64,
        force: &mut [V3],
    ) {
        self.evaluations += 1;
        let terms = self.terms;
        // Start from gravity rather than zero: one pass fewer than
        // `fill(0)` followed by `gravity`, same sums in the same order.
        if terms.gravity {
            for (f, &m) in force.iter_mut().zip(&model.mass) {
                *f = m * model.gravity;
            }
        } else {
            force.fill(V3::zeros());
        }
        if terms.springs {
            springs(model, x, v, alive, force);
        }
        if terms.hinges {
            hinges(model, &self.hinge_rest, x, v, &self.torn.hinges, force);
        }
        // Moved out for the call (no allocation): the wind borrows self.
        let torn = std::mem::take(&mut self.torn.triangles);
        let mut added = std::mem::take(&mut self.added);
        let mut lag = self.lag.take();
        if let Some(lag) = &mut lag {
            lag.evaluate_at(t);
        }
        let wind = self.sample_wind(model, x, t);
        if terms.aero {
            added.fill(Matrix3::zeros());
            triangle_aero_solved(model, x, v, wind, &torn, force, &mut added, lag.as_mut());
        }
        if terms.particle_drag {
            particle_drag(model, v, wind, force);
        }
        self.torn.triangles = torn;
        self.added = added;
        self.lag = lag;
    }

    /// Commits the lagged centre of pressure over a step of `h` s from the
    /// step's last evaluation ([`unsteady::PressureLag::advance`]); nothing
    /// without one.
    pub fn advance_pressure_lag(&mut self, h: f64) {
        if let Some(lag) = &mut self.lag {
            lag.advance(h);
        }
    }

    /// Acceleration a_i = F_i / m_i (eq. 1); zero for fixed particles.
    /// Under the unsteady law, (m_i I + M_i) a_i = F_i with each particle's
    /// added-mass tensor M_i, solved per particle (a 3 × 3 system) or per
    /// rigid body (6 × 6), never lagged: lagged, added mass heavier than
    /// the body would make every explicit step unstable.
    pub fn acceleration(
        &mut self,
        model: &Model,
        x: &[V3],
        v: &[V3],
        alive: &[bool],
        t: f64,
        acc: &mut [V3],
    ) {
        self.total(model, x, v, alive, t, acc);
        if self.terms.rigid {
            rigid::accelerations(&model.rigid, x, v, acc, &self.added);
        }
        if self.added.is_empty() {
            for (a, &w) in acc.iter_mut().zip(&model.inv_mass) {
                *a *= w;
            }
            return;
        }
        self.solve_added_mass(model, acc);
        // A triangle with no flow yet: its flow starts along what the
        // accelerations give it (still air only; `seed_flow_start`).
        if let Some(lag) = self.lag.as_mut().filter(|l| l.wants_start())
            && !self.terms.wind
        {
            unsteady::seed_flow_start(model, x, acc, &self.torn.triangles, lag);
        }
    }

    /// Turns the forces in `acc` into accelerations under each particle's
    /// added-mass tensor (rigid bodies are solved already).
    fn solve_added_mass(&self, model: &Model, acc: &mut [V3]) {
        for (((a, &w), &m), added) in acc
            .iter_mut()
            .zip(&model.inv_mass)
            .zip(&model.mass)
            .zip(&self.added)
        {
            if w == 0.0 {
                *a = V3::zeros();
            } else if added.trace() > 0.0 {
                *a = solve_mass(m, added, a);
            } else {
                *a *= w;
            }
        }
    }

    /// Each force term on particle `p` separately (the unsteady law's
    /// velocity-dependent forces as its aero term).
    pub fn terms_on(
        &mut self,
        model: &Model,
        x: &[V3],
        v: &[V3],
        alive: &[bool],
        t: f64,
        p: usize,
    ) -> ForceTerms {
        let mut scratch = std::mem::take(&mut self.scratch);
        let mut term = |f: &mut dyn FnMut(&mut Forces, &mut [V3])| {
            scratch.fill(V3::zeros());
            f(self, &mut scratch);
            scratch[p]
        };
        let terms = ForceTerms {
            gravity: term(&mut |_, s| gravity(model, s)),
            spring: term(&mut |_, s| springs(model, x, v, alive, s)),
            bending: term(&mut |me, s| hinges(model, &me.hinge_rest, x, v, &me.torn.hinges, s)),
            aero: term(&mut |me, s| {
                let wind = me.sample_wind(model, x, t).map(|w| w.to_vec());
                triangle_aero_intact(model, x, v, wind.as_deref(), &me.torn.triangles, s)
            }),
            drag: term(&mut |me, s| {
                let wind = me.sample_wind(model, x, t).map(|w| w.to_vec());
                particle_drag(model, v, wind.as_deref(), s)
            }),
        };
        self.scratch = scratch;
        terms
    }
}

/// Solves (m I + M) a = f for a symmetric positive semi-definite added-mass
/// tensor M (m > 0, so the matrix is positive definite): by the symmetric
/// adjugate and one division by the determinant (a general inverse divides
/// each of its nine entries by it: 8 % of an unsteady-law drop, perf).
#[inline]
pub fn solve_mass(m: f64, added: &Matrix3<f64>, f: &V3) -> V3 {
    // M is exactly symmetric (sums of n nᵀ, whose (i, j) and (j, i)
    // products are the same), so its upper triangle is all of it.
    let (a, b, c) = (added[(0, 0)] + m, added[(1, 1)] + m, added[(2, 2)] + m);
    let (d, e, g) = (added[(0, 1)], added[(0, 2)], added[(1, 2)]);
    let c00 = b * c - g * g;
    let c01 = e * g - d * c;
    let c02 = d * g - e * b;
    let c11 = a * c - e * e;
    let c12 = d * e - a * g;
    let c22 = a * b - d * d;
    let det = a * c00 + d * c01 + e * c02;
    if det == 0.0 {
        // K is positive definite, so det > 0 unless m³ underflows (masses
        // below about 1e-100 kg): then the particle's own mass answers. A
        // NaN determinant (a non-finite M) goes on, and the divergence check
        // reports it.
        return f / m;
    }
    let inv = 1.0 / det;
    V3::new(
        (c00 * f.x + c01 * f.y + c02 * f.z) * inv,
        (c01 * f.x + c11 * f.y + c12 * f.z) * inv,
        (c02 * f.x + c12 * f.y + c22 * f.z) * inv,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};

    /// For any body mass and any sum of added-mass terms m_k n nᵀ, the
    /// solved acceleration satisfies (m I + M) a = f to round-off, as the
    /// general inverse's does.
    #[test]
    fn the_added_mass_solve_satisfies_newtons_law() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        let mut same_bits = 0;
        for _ in 0..2000 {
            let m = 10f64.powf(rng.random_range(-7.0..-3.0));
            let mut added = Matrix3::zeros();
            for _ in 0..rng.random_range(1..7) {
                let n = V3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
                .normalize();
                added += n * n.transpose() * (m * 10f64.powf(rng.random_range(-2.0..1.5)));
            }
            let f = V3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ) * 1e-4;
            let k = Matrix3::identity() * m + added;
            let a = solve_mass(m, &added, &f);
            let residual = (k * a - f).norm() / f.norm();
            assert!(residual < 1e-12, "residual {residual:e}");
            let general = k.try_inverse().unwrap() * f;
            assert!((a - general).norm() <= 1e-12 * general.norm());
            same_bits += usize::from(a == general);
        }
        println!("{same_bits} of 2000 solves equal the general inverse's to the bit");
    }
}
