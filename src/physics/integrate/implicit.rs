//! The implicit integrator's linear algebra: linearised backward Euler
//! (Baraff & Witkin 1998), one Newton step per time step, solved by
//! Jacobi-preconditioned conjugate gradients over 3 × 3 blocks.

use crate::physics::forces::{Tears, dihedral, fold_rate};
use crate::physics::model::Model;
use crate::physics::state::State;
use nalgebra::{Matrix3, Vector3};

type V3 = Vector3<f64>;

/// One spring's linearisation for the implicit step: the block
/// S = α n nᵀ + β I such that −h ∂f/∂v − h² ∂f/∂x contributes S (y_i − y_j).
#[derive(Clone, Copy, Debug, Default)]
struct SpringBlock {
    active: bool,
    n: V3,
    alpha: f64,
    beta: f64,
    // k (n nᵀ (1 − p) + p I) parts, to form ∂f/∂x v₀ for the right-hand side.
    k_nn: f64,
    k_iso: f64,
}

impl SpringBlock {
    fn times(&self, y: &V3) -> V3 {
        self.n * (self.alpha * self.n.dot(y)) + y * self.beta
    }
    /// k J y with J = (1 − p) n nᵀ + p I.
    fn stiffness_times(&self, y: &V3) -> V3 {
        self.n * (self.k_nn * self.n.dot(y)) + y * self.k_iso
    }
}

/// One hinge's linearisation: the rank-one block α g gᵀ with g = ∇θ
/// (Gauss–Newton: the curvature of θ itself is left out, which keeps the
/// block positive semi-definite).
#[derive(Clone, Copy, Debug, Default)]
struct HingeBlock {
    active: bool,
    ids: [usize; 4],
    grad: [V3; 4],
    alpha: f64,
    stiffness: f64,
}

#[derive(Clone, Debug)]
pub(super) struct ImplicitScratch {
    spring_blocks: Vec<SpringBlock>,
    hinge_blocks: Vec<HingeBlock>,
    /// h × (aero + particle drag damping) per particle, plus the mass on the diagonal.
    particle_blocks: Vec<Matrix3<f64>>,
    diag: Vec<V3>,
    b: Vec<V3>,
    dv: Vec<V3>,
    r: Vec<V3>,
    z: Vec<V3>,
    p: Vec<V3>,
    ap: Vec<V3>,
    free: Vec<bool>,
}

/// CG stops when ‖r‖ ≤ this × ‖b‖.
const CG_RELATIVE_TOLERANCE: f64 = 1e-12;

impl ImplicitScratch {
    /// One linearised backward-Euler step from force `f0` at the current
    /// state (see [`super::Simulator`]'s implicit stage): forms
    /// b = h (f0 + h K v0), solves for Δv, then v' = v + Δv, x' = x + h v'.
    /// On failure, the CG iterations spent and the relative residual.
    pub(super) fn step(
        &mut self,
        model: &Model,
        s: &mut State,
        h: f64,
        f0: &[V3],
        torn: &Tears,
        added: &[Matrix3<f64>],
    ) -> Result<(), (usize, f64)> {
        let imp = self;
        imp.linearise(model, s, h, torn, added);
        // b = h (f0 + h K v0), K = ∂f/∂x = −Σ S_k (see linearise).
        let b = &mut imp.b;
        for (bi, f) in b.iter_mut().zip(f0) {
            *bi = *f * h;
        }
        for (k, spring) in model.springs.iter().enumerate() {
            let blk = imp.spring_blocks[k];
            if blk.active {
                let dv = s.velocity[spring.i] - s.velocity[spring.j];
                let kv = blk.stiffness_times(&dv) * (h * h);
                b[spring.i] -= kv;
                b[spring.j] += kv;
            }
        }
        for blk in &imp.hinge_blocks {
            if blk.active {
                let rate = fold_rate(&blk.ids, &blk.grad, &s.velocity);
                for (&i, g) in blk.ids.iter().zip(&blk.grad) {
                    b[i] -= g * (h * h * blk.stiffness * rate);
                }
            }
        }
        imp.solve(model)?;
        for ((x, v), dv) in s.position.iter_mut().zip(&mut s.velocity).zip(&imp.dv) {
            *v += *dv;
            *x += *v * h;
        }
        Ok(())
    }

    pub(super) fn new(model: &Model) -> ImplicitScratch {
        let n = model.len();
        let zeros = || vec![V3::zeros(); n];
        ImplicitScratch {
            spring_blocks: vec![SpringBlock::default(); model.springs.len()],
            hinge_blocks: vec![HingeBlock::default(); model.hinges.len()],
            particle_blocks: vec![Matrix3::zeros(); n],
            diag: zeros(),
            b: zeros(),
            dv: zeros(),
            r: zeros(),
            z: zeros(),
            p: zeros(),
            ap: zeros(),
            free: model.fixed.iter().map(|f| !f).collect(),
        }
    }

    /// `added`: each particle's added-mass tensor (empty: none), which joins
    /// the mass on the diagonal (backward Euler on (M + M_a) v̇ = f).
    fn linearise(
        &mut self,
        model: &Model,
        s: &State,
        h: f64,
        torn: &Tears,
        added: &[Matrix3<f64>],
    ) {
        for (k, spring) in model.springs.iter().enumerate() {
            let d = s.position[spring.i] - s.position[spring.j];
            let l = d.norm();
            self.spring_blocks[k] = if !s.spring_alive[k] || l == 0.0 {
                SpringBlock::default()
            } else {
                let n = d / l;
                // Only tension contributes the geometric term: in compression
                // (1 − L/l) < 0 would make the matrix indefinite (buckling).
                let p = (1.0 - spring.rest_length / l).max(0.0);
                let (k_nn, k_iso) = (spring.stiffness * (1.0 - p), spring.stiffness * p);
                SpringBlock {
                    active: true,
                    n,
                    alpha: h * spring.damping + h * h * k_nn,
                    beta: h * h * k_iso,
                    k_nn,
                    k_iso,
                }
            };
        }
        for (k, (blk, hinge)) in self.hinge_blocks.iter_mut().zip(&model.hinges).enumerate() {
            let torn_wing = torn.hinges.get(k).copied().unwrap_or(false);
            *blk = match dihedral(&s.position, hinge) {
                Some((_, grad)) if !torn_wing => HingeBlock {
                    active: true,
                    ids: hinge.particles(),
                    grad,
                    alpha: h * hinge.damping + h * h * hinge.stiffness,
                    stiffness: hinge.stiffness,
                },
                _ => HingeBlock::default(),
            };
        }
        for (i, blk) in self.particle_blocks.iter_mut().enumerate() {
            *blk = Matrix3::identity() * (model.mass[i] + h * model.particle_drag[i]);
            if let Some(m) = added.get(i) {
                *blk += m;
            }
        }
        for (t, tri) in model.triangles.iter().enumerate() {
            if torn.triangles.get(t).copied().unwrap_or(false) {
                continue;
            }
            let [a, b, c] = tri.corners;
            let x = &s.position;
            let big_n = (x[b] - x[a]).cross(&(x[c] - x[a]));
            let doubled = big_n.norm();
            if doubled == 0.0 {
                continue;
            }
            let n = big_n / doubled;
            let area = 0.5 * doubled;
            let blk = (Matrix3::identity() * tri.alpha_t
                + n * n.transpose() * (tri.alpha_n - tri.alpha_t))
                * (h * area);
            for &i in &tri.corners {
                self.particle_blocks[i] += blk;
            }
        }
        for (i, d) in self.diag.iter_mut().enumerate() {
            let m = &self.particle_blocks[i];
            *d = V3::new(m[(0, 0)], m[(1, 1)], m[(2, 2)]);
        }
        for (k, spring) in model.springs.iter().enumerate() {
            let blk = &self.spring_blocks[k];
            if blk.active {
                let dd = blk.n.component_mul(&blk.n) * blk.alpha + V3::repeat(blk.beta);
                self.diag[spring.i] += dd;
                self.diag[spring.j] += dd;
            }
        }
        for blk in self.hinge_blocks.iter().filter(|b| b.active) {
            for (&i, g) in blk.ids.iter().zip(&blk.grad) {
                self.diag[i] += g.component_mul(g) * blk.alpha;
            }
        }
    }

    fn apply(&self, model: &Model, y: &[V3], out: &mut [V3]) {
        for ((o, blk), yi) in out.iter_mut().zip(&self.particle_blocks).zip(y) {
            *o = blk * yi;
        }
        for (k, spring) in model.springs.iter().enumerate() {
            let blk = &self.spring_blocks[k];
            if blk.active {
                let f = blk.times(&(y[spring.i] - y[spring.j]));
                out[spring.i] += f;
                out[spring.j] -= f;
            }
        }
        for blk in self.hinge_blocks.iter().filter(|b| b.active) {
            let gy: f64 = blk
                .ids
                .iter()
                .zip(&blk.grad)
                .map(|(&i, g)| g.dot(&y[i]))
                .sum();
            for (&i, g) in blk.ids.iter().zip(&blk.grad) {
                out[i] += g * (blk.alpha * gy);
            }
        }
        for (o, &free) in out.iter_mut().zip(&self.free) {
            if !free {
                *o = V3::zeros();
            }
        }
    }

    /// Jacobi-preconditioned CG on the free particles; fixed ones keep Δv = 0.
    fn solve(&mut self, model: &Model) -> Result<(), (usize, f64)> {
        for (bi, &free) in self.b.iter_mut().zip(&self.free) {
            if !free {
                *bi = V3::zeros();
            }
        }
        let b_norm = dot(&self.b, &self.b).sqrt();
        self.dv.fill(V3::zeros());
        if b_norm == 0.0 {
            return Ok(());
        }
        self.r.copy_from_slice(&self.b);
        for ((z, r), d) in self.z.iter_mut().zip(&self.r).zip(&self.diag) {
            *z = r.component_div(d);
        }
        self.p.copy_from_slice(&self.z);
        let mut rz = dot(&self.r, &self.z);
        let max_iterations = 10 * 3 * model.len() + 20;
        for it in 0..max_iterations {
            let mut ap = std::mem::take(&mut self.ap);
            self.apply(model, &self.p, &mut ap);
            self.ap = ap;
            let pap = dot(&self.p, &self.ap);
            if pap <= 0.0 || !pap.is_finite() {
                return Err((it, f64::NAN));
            }
            let alpha = rz / pap;
            for i in 0..self.dv.len() {
                self.dv[i] += self.p[i] * alpha;
                self.r[i] -= self.ap[i] * alpha;
            }
            let r_norm = dot(&self.r, &self.r).sqrt();
            if r_norm <= CG_RELATIVE_TOLERANCE * b_norm {
                return Ok(());
            }
            for ((z, r), d) in self.z.iter_mut().zip(&self.r).zip(&self.diag) {
                *z = r.component_div(d);
            }
            let rz_new = dot(&self.r, &self.z);
            let beta = rz_new / rz;
            rz = rz_new;
            for (p, z) in self.p.iter_mut().zip(&self.z) {
                *p = *z + *p * beta;
            }
        }
        let r_norm = dot(&self.r, &self.r).sqrt();
        // Round-off can stall CG just above a very tight tolerance; accept a
        // residual that is still tiny in absolute terms.
        if r_norm <= 1e-9 * b_norm {
            Ok(())
        } else {
            Err((max_iterations, r_norm / b_norm))
        }
    }
}

fn dot(a: &[V3], b: &[V3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(y)).sum()
}
