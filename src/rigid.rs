//! Rigid bodies made of particles, moved as the paper does after Hahn (1988):
//! the net force F = Σ fᵢ and net torque τ = Σ rᵢ × fᵢ of all a body's
//! particles drive its linear and angular momentum.
//!
//! A body is a set of model particles; it has no state of its own. Its
//! centre of mass c, velocity V and angular momentum L are read from the
//! particles, so everything else in the simulator (forces, springs to other
//! objects, output) keeps working on particles. Two passes make the particles
//! move as one body with every integrator:
//!
//! 1. **Accelerations** ([`accelerations`], inside the force path): each
//!    member gets the exact rigid-body acceleration under the summed load,
//!
//!    aᵢ = F/M + α × rᵢ + ω × (ω × rᵢ),   α = I⁻¹ (τ − ω × L),   ω = I⁻¹ L,
//!
//!    with rᵢ = xᵢ − c and I the world inertia tensor about c (Euler's
//!    equations in the world frame: dL/dt = τ with L = I ω and
//!    dI/dt ω = ω × L). Internal forces (springs between members) cancel in
//!    F and τ, so they change nothing.
//! 2. **Projection** ([`RigidProjector::project`], after each step): the
//!    integrator moved the members along straight lines, which leaves the
//!    rigid shape by O(h^(p+1)) per step for an order-p scheme. The rotation
//!    R that best maps the body-frame offsets onto the members (the same
//!    Newton fit as [`crate::pose`]) puts them back exactly, and velocities are
//!    reset to V + ω × rᵢ with ω = (R I_b Rᵀ)⁻¹ L. This keeps the centre of
//!    mass, the momentum M V and the angular momentum L unchanged, and never
//!    adds energy (for a given L the rigid velocity field has the least
//!    kinetic energy).
//!
//! The orientation is therefore always an exact rotation, and it follows the
//! rigid-body equations to the integrator's order.

use crate::model::ModelError;
use crate::pose;
use crate::state::State;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

type V3 = Vector3<f64>;

/// A set of particles to be moved as one rigid body (a [`crate::model::ModelParts`] item).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RigidGroup {
    /// The member particles.
    pub members: Vec<usize>,
}

/// A validated rigid body: its members and their mass properties, in the
/// body frame, which is the world frame of the model's rest layout.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidBody {
    /// The member particles.
    pub members: Vec<usize>,
    /// Their masses, kg (copied from the model for the hot loops).
    pub member_mass: Vec<f64>,
    /// Total mass M, kg.
    pub mass: f64,
    /// Member offsets from the centre of mass in the body frame, m.
    pub offsets: Vec<V3>,
    /// Inertia tensor about the centre of mass in the body frame, kg·m².
    pub inertia: Matrix3<f64>,
    /// Its inverse.
    pub inertia_inv: Matrix3<f64>,
}

/// Smallest principal moment, relative to the largest, of a valid body: below
/// it the members lie (nearly) on a line and a rotation about that line is
/// undetermined.
pub const MIN_INERTIA_RATIO: f64 = 1e-9;

/// Inertia tensor Σ mᵢ (|rᵢ|² 1 − rᵢ rᵢᵀ) of point masses at offsets rᵢ.
pub fn inertia_tensor<'a>(
    masses: &[f64],
    offsets: impl IntoIterator<Item = &'a V3>,
) -> Matrix3<f64> {
    let mut inertia = Matrix3::zeros();
    for (m, r) in masses.iter().zip(offsets) {
        inertia += (Matrix3::identity() * r.norm_squared() - r * r.transpose()) * *m;
    }
    inertia
}

impl RigidBody {
    /// Validates group `index` against the model's particles and computes its
    /// mass properties from the rest layout.
    pub fn new(
        index: usize,
        group: &RigidGroup,
        mass: &[f64],
        fixed: &[bool],
        rest: &[V3],
    ) -> Result<RigidBody, ModelError> {
        let item = |f: &str| format!("rigid[{index}].{f}");
        let fail = |f: &str, reason: String| ModelError {
            item: item(f),
            reason,
        };
        let n = mass.len();
        if group.members.len() < 3 {
            return Err(fail(
                "members",
                format!(
                    "a rigid body needs at least 3 particles not on one line, got {}",
                    group.members.len()
                ),
            ));
        }
        let mut seen = std::collections::HashSet::new();
        for &i in &group.members {
            if i >= n {
                return Err(fail(
                    "members",
                    format!("particle index {i} out of range (there are {n} particles)"),
                ));
            }
            if !seen.insert(i) {
                return Err(fail("members", format!("particle {i} is listed twice")));
            }
            if fixed[i] {
                return Err(fail(
                    "members",
                    format!("particle {i} is fixed; a rigid body moves as a whole"),
                ));
            }
        }
        let member_mass: Vec<f64> = group.members.iter().map(|&i| mass[i]).collect();
        let total: f64 = member_mass.iter().sum();
        let mut com = V3::zeros();
        for (&i, &m) in group.members.iter().zip(&member_mass) {
            com += rest[i] * m;
        }
        com /= total;
        let offsets: Vec<V3> = group.members.iter().map(|&i| rest[i] - com).collect();
        let inertia = inertia_tensor(&member_mass, &offsets);
        let eig = inertia.symmetric_eigenvalues();
        let (lo, hi) = (eig.min(), eig.max());
        let inertia_inv = inertia
            .try_inverse()
            .filter(|_| lo > MIN_INERTIA_RATIO * hi);
        let Some(inertia_inv) = inertia_inv else {
            return Err(fail(
                "members",
                "the particles lie on one line (or coincide): the rotation about that line is undetermined"
                    .to_string(),
            ));
        };
        Ok(RigidBody {
            members: group.members.clone(),
            member_mass,
            mass: total,
            offsets,
            inertia,
            inertia_inv,
        })
    }

    /// Centre of mass and mean velocity of the members.
    pub fn centre(&self, x: &[V3], v: &[V3]) -> (V3, V3) {
        let (mut c, mut vc) = (V3::zeros(), V3::zeros());
        for (&i, &m) in self.members.iter().zip(&self.member_mass) {
            c += x[i] * m;
            vc += v[i] * m;
        }
        (c / self.mass, vc / self.mass)
    }

    /// Angular momentum of the members about their centre of mass `c`
    /// moving at `vc`, kg·m²/s.
    pub fn angular_momentum(&self, x: &[V3], v: &[V3], c: &V3, vc: &V3) -> V3 {
        let mut l = V3::zeros();
        for (&i, &m) in self.members.iter().zip(&self.member_mass) {
            l += (x[i] - c).cross(&(v[i] - vc)) * m;
        }
        l
    }

    /// World inertia tensor of the members about `c`, from their positions.
    pub fn world_inertia(&self, x: &[V3], c: &V3) -> Matrix3<f64> {
        let mut inertia = Matrix3::zeros();
        for (&i, &m) in self.members.iter().zip(&self.member_mass) {
            let r = x[i] - c;
            inertia += (Matrix3::identity() * r.norm_squared() - r * r.transpose()) * m;
        }
        inertia
    }

    /// Kinetic energy ½ M |V|² + ½ ω·L of the members, J (exact for a rigid
    /// velocity field).
    pub fn kinetic_energy(&self, x: &[V3], v: &[V3]) -> f64 {
        let (c, vc) = self.centre(x, v);
        let l = self.angular_momentum(x, v, &c, &vc);
        let omega = self
            .world_inertia(x, &c)
            .try_inverse()
            .map_or(V3::zeros(), |inv| inv * l);
        0.5 * self.mass * vc.norm_squared() + 0.5 * omega.dot(&l)
    }
}

/// Replaces the force on every member of every body by mᵢ aᵢ, with aᵢ the
/// rigid-body acceleration under the body's summed force and torque (see
/// the module documentation). Called with forces in `force`, before the
/// division by mass, so that the caller's aᵢ = fᵢ/mᵢ gives the rigid value.
pub fn accelerations(bodies: &[RigidBody], x: &[V3], v: &[V3], force: &mut [V3]) {
    for body in bodies {
        let (c, vc) = body.centre(x, v);
        let mut f = V3::zeros();
        let mut tau = V3::zeros();
        let mut l = V3::zeros();
        let mut inertia = Matrix3::zeros();
        for (&i, &m) in body.members.iter().zip(&body.member_mass) {
            let r = x[i] - c;
            f += force[i];
            tau += r.cross(&force[i]);
            l += r.cross(&(v[i] - vc)) * m;
            inertia += (Matrix3::identity() * r.norm_squared() - r * r.transpose()) * m;
        }
        // Members stay within round-off of the rigid shape, whose inertia was
        // checked invertible at validation; a failure here means the state
        // is already non-finite, which the divergence check reports.
        let inv = inertia.try_inverse().unwrap_or_else(Matrix3::zeros);
        let omega = inv * l;
        let alpha = inv * (tau - omega.cross(&l));
        let lin = f / body.mass;
        for (&i, &m) in body.members.iter().zip(&body.member_mass) {
            let r = x[i] - c;
            force[i] = (lin + alpha.cross(&r) + omega.cross(&omega.cross(&r))) * m;
        }
    }
}

/// The after-step pass that puts every body's members back on its rigid
/// shape; holds each body's last rotation to warm-start the fit.
#[derive(Clone, Debug)]
pub struct RigidProjector {
    rotation: Vec<UnitQuaternion<f64>>,
}

impl RigidProjector {
    /// A projector for `bodies`, starting from the rest orientation.
    pub fn new(bodies: &[RigidBody]) -> RigidProjector {
        RigidProjector {
            rotation: vec![UnitQuaternion::identity(); bodies.len()],
        }
    }

    /// The rotation (body frame → world) found for body `b` by the last
    /// projection.
    pub fn rotation(&self, b: usize) -> UnitQuaternion<f64> {
        self.rotation[b]
    }

    /// Makes every body exactly rigid again, keeping its centre of mass,
    /// momentum and angular momentum (see the module documentation).
    pub fn project(&mut self, bodies: &[RigidBody], state: &mut State) {
        for (body, rotation) in bodies.iter().zip(&mut self.rotation) {
            let (x, v) = (&mut state.position, &mut state.velocity);
            let (c, vc) = body.centre(x, v);
            let l = body.angular_momentum(x, v, &c, &vc);
            // A = Σ mᵢ (xᵢ − c) bᵢᵀ; the best rotation maximises tr(Rᵀ A).
            let mut a = Matrix3::zeros();
            for ((&i, &m), b) in body
                .members
                .iter()
                .zip(&body.member_mass)
                .zip(&body.offsets)
            {
                a += (x[i] - c) * (b * m).transpose();
            }
            let q = pose::best_rotation(&a, *rotation);
            *rotation = q;
            let r: Rotation3<f64> = q.to_rotation_matrix();
            let world_inv = r.matrix() * body.inertia_inv * r.matrix().transpose();
            let omega = world_inv * l;
            for (&i, b) in body.members.iter().zip(&body.offsets) {
                let arm = r * b;
                x[i] = c + arm;
                v[i] = vc + omega.cross(&arm);
            }
        }
    }
}
