//! Rigid bodies as data: the member particles and their mass properties in
//! the body frame (the rest layout). How they move is
//! [`crate::physics::rigid`] (after Hahn 1988, as the paper does).

use super::error::ModelError;
use nalgebra::{Matrix3, Vector3};

type V3 = Vector3<f64>;

/// A set of particles to be moved as one rigid body (a [`super::ModelParts`] item).
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
        // Below this a flat body's smallest moment would fall among f64's
        // subnormals, where the ratio test cannot tell a line from a plate.
        if hi < f64::MIN_POSITIVE / MIN_INERTIA_RATIO {
            return Err(fail(
                "members",
                format!(
                    "the body's largest moment of inertia, {hi:.3e} kg m², is too small for \
                     f64 to resolve its rotation (under {:.3e}): its masses or its size are too \
                     small",
                    f64::MIN_POSITIVE / MIN_INERTIA_RATIO
                ),
            ));
        }
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
