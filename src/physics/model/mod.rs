//! The immutable description of what is simulated: particles, springs,
//! triangles, the wind field and gravity (the paper's section 2).
//!
//! A [`Model`] never changes during a run; everything that does (positions,
//! velocities, which springs are still intact, time) lives in
//! [`crate::physics::state::State`]. Construction validates every item, so the
//! simulator can assume finite masses, stiffnesses and in-range indices.

mod elements;
pub(crate) mod error;
mod ground;
mod rigid_body;
mod surface_geometry;

/// The model's aerodynamic law, held as data; the law itself (its
/// coefficients, keys, forces and bounds) is [`crate::physics::aero`].
pub use crate::physics::aero::law::AeroLaw;
pub use elements::{DEGENERATE_TRIANGLE_RATIO, Hinge, Spring, Triangle};
pub use error::ModelError;
pub use ground::Ground;
pub use rigid_body::{MIN_INERTIA_RATIO, RigidBody, RigidGroup, inertia_tensor};
pub use surface_geometry::{
    ADDED_MASS_EXPONENT, ADDED_MASS_PREFACTOR, CHORD_SAMPLES, SurfaceGeometry, plates,
    surface_geometry,
};

use crate::physics::field::WindField;
use nalgebra::Vector3;
use std::collections::HashSet;

/// Standard gravity, m/s², pointing down the z axis (z is up).
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// Everything that stays fixed during a run. Fields are public for reading;
/// build one with [`Model::new`], which validates.
#[derive(Clone, Debug)]
pub struct Model {
    /// Particle masses, kg (all > 0).
    pub mass: Vec<f64>,
    /// 1/m for free particles and 0 for fixed ones, so that fixed particles
    /// never accelerate without a branch in the integrators.
    pub inv_mass: Vec<f64>,
    /// Particles pinned in space (the paper's swing ropes hang from these).
    pub fixed: Vec<bool>,
    /// Linear drag α of eq. 7 for each particle, kg/s; used for particles that
    /// belong to no triangle (0 elsewhere).
    pub particle_drag: Vec<f64>,
    /// Rest shape, m: the reference for pose extraction and rest lengths.
    pub rest_position: Vec<Vector3<f64>>,
    /// Springs; a broken spring keeps its index (see `State::spring_alive`).
    pub springs: Vec<Spring>,
    /// Wind-catching triangles.
    pub triangles: Vec<Triangle>,
    /// Bending hinges between triangles.
    pub hinges: Vec<Hinge>,
    /// The aerodynamic law used on triangles.
    pub aero: AeroLaw,
    /// The wind velocity field G(x, t).
    pub wind: WindField,
    /// Gravitational acceleration, m/s².
    pub gravity: Vector3<f64>,
    /// The ground plane, if any (scenes).
    pub ground: Option<Ground>,
    /// Particle sets moved as rigid bodies (scenes).
    pub rigid: Vec<RigidBody>,
    /// Under the unsteady law, each triangle's share of its plate (added
    /// mass, chords), measured on the rest shape; empty under the others.
    pub surfaces: Vec<SurfaceGeometry>,
}

/// The raw parts of a model, before validation.
#[derive(Clone, Debug, Default)]
pub struct ModelParts {
    /// See [`Model::mass`].
    pub mass: Vec<f64>,
    /// See [`Model::fixed`].
    pub fixed: Vec<bool>,
    /// See [`Model::particle_drag`]; empty means zero for all.
    pub particle_drag: Vec<f64>,
    /// See [`Model::rest_position`].
    pub rest_position: Vec<Vector3<f64>>,
    /// See [`Model::springs`].
    pub springs: Vec<Spring>,
    /// See [`Model::triangles`].
    pub triangles: Vec<Triangle>,
    /// See [`Model::hinges`].
    pub hinges: Vec<Hinge>,
    /// See [`Model::aero`].
    pub aero: AeroLaw,
    /// See [`Model::wind`].
    pub wind: WindField,
    /// See [`Model::gravity`].
    pub gravity: Vector3<f64>,
    /// See [`Model::ground`].
    pub ground: Option<Ground>,
    /// Member lists of the rigid bodies (see [`Model::rigid`]).
    pub rigid: Vec<RigidGroup>,
}

fn err(item: impl Into<String>, reason: impl Into<String>) -> ModelError {
    ModelError {
        item: item.into(),
        reason: reason.into(),
    }
}

fn finite(item: &str, value: f64) -> Result<(), ModelError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(err(item, format!("must be a finite number, got {value}")))
    }
}

impl Model {
    /// Validates the parts and builds the model. Rejects non-finite values,
    /// mass ≤ 0, negative stiffness, damping or rest length, indices out of
    /// range, springs joining a particle to itself, duplicate springs, and
    /// triangles of zero area at rest.
    pub fn new(mut parts: ModelParts) -> Result<Model, ModelError> {
        let n = parts.mass.len();
        if parts.fixed.len() != n || parts.rest_position.len() != n {
            return Err(err(
                "particle",
                "mass, fixed flag and position lists differ in length",
            ));
        }
        if n == 0 {
            return Err(err("particle", "a model needs at least one particle"));
        }
        let particle_drag = if parts.particle_drag.is_empty() {
            vec![0.0; n]
        } else if parts.particle_drag.len() == n {
            std::mem::take(&mut parts.particle_drag)
        } else {
            return Err(err("particle", "drag list length differs from particles"));
        };
        check_particles(&parts, &particle_drag)?;
        check_springs(&parts)?;
        check_triangles(&parts)?;
        check_hinges(&parts)?;
        check_law_and_surroundings(&parts)?;
        let rigid = rigid_bodies(&parts)?;
        let surfaces = if parts.aero.needs_surface_geometry() {
            let corners: Vec<[usize; 3]> = parts.triangles.iter().map(|t| t.corners).collect();
            surface_geometry(&parts.rest_position, &corners)
        } else {
            Vec::new()
        };
        let inv_mass = parts
            .mass
            .iter()
            .zip(&parts.fixed)
            .map(|(&m, &f)| if f { 0.0 } else { 1.0 / m })
            .collect();
        Ok(Model {
            mass: parts.mass,
            inv_mass,
            fixed: parts.fixed,
            particle_drag,
            rest_position: parts.rest_position,
            springs: parts.springs,
            triangles: parts.triangles,
            hinges: parts.hinges,
            aero: parts.aero,
            wind: parts.wind,
            gravity: parts.gravity,
            ground: parts.ground,
            rigid,
            surfaces,
        })
    }

    /// The parts this model was built from (to build a changed copy).
    pub fn to_parts(&self) -> ModelParts {
        ModelParts {
            mass: self.mass.clone(),
            fixed: self.fixed.clone(),
            particle_drag: self.particle_drag.clone(),
            rest_position: self.rest_position.clone(),
            springs: self.springs.clone(),
            triangles: self.triangles.clone(),
            hinges: self.hinges.clone(),
            aero: self.aero,
            wind: self.wind.clone(),
            gravity: self.gravity,
            ground: self.ground,
            rigid: self
                .rigid
                .iter()
                .map(|b| RigidGroup {
                    members: b.members.clone(),
                })
                .collect(),
        }
    }

    /// The rigid body each particle belongs to (its index in
    /// [`Model::rigid`]), `None` for a free particle.
    pub fn body_of(&self) -> Vec<Option<usize>> {
        let mut body_of = vec![None; self.len()];
        for (b, body) in self.rigid.iter().enumerate() {
            for &i in &body.members {
                body_of[i] = Some(b);
            }
        }
        body_of
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.mass.len()
    }

    /// True when the model has no particles (never, for a validated model).
    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// Total mass, kg.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// Mass-weighted centre of a set of positions.
    pub fn centre_of_mass(&self, x: &[Vector3<f64>]) -> Vector3<f64> {
        let mut sum = Vector3::zeros();
        for (m, p) in self.mass.iter().zip(x) {
            sum += *m * p;
        }
        sum / self.total_mass()
    }

    /// Largest distance between two particles of the rest shape (the chord), m.
    pub fn chord(&self) -> f64 {
        let x = &self.rest_position;
        let mut best: f64 = 0.0;
        for a in 0..x.len() {
            for b in a + 1..x.len() {
                best = best.max((x[a] - x[b]).norm());
            }
        }
        best
    }

    /// How many plates (triangles joined through shared edges,
    /// [`plates`]) the model has.
    pub fn plate_count(&self) -> usize {
        self.surfaces.iter().map(|g| g.plate + 1).max().unwrap_or(0)
    }

    /// Total triangle area of the rest shape, m².
    pub fn surface_area(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.corners;
                let x = &self.rest_position;
                0.5 * (x[b] - x[a]).cross(&(x[c] - x[a])).norm()
            })
            .sum()
    }

    /// Which particles belong to at least one triangle.
    pub fn in_surface(&self) -> Vec<bool> {
        let mut flags = vec![false; self.len()];
        for t in &self.triangles {
            for &c in &t.corners {
                flags[c] = true;
            }
        }
        flags
    }
}

/// Every particle's mass (positive, with a finite inverse), position and
/// drag.
fn check_particles(parts: &ModelParts, particle_drag: &[f64]) -> Result<(), ModelError> {
    for (p, &m) in parts.mass.iter().enumerate() {
        finite(&format!("particle[{p}].mass"), m)?;
        if m <= 0.0 {
            return Err(err(
                format!("particle[{p}].mass"),
                format!("must be > 0 kg, got {m}"),
            ));
        }
        // A subnormal mass passes `> 0` but its 1/m overflows to inf.
        if !(1.0 / m).is_finite() {
            return Err(err(
                format!("particle[{p}].mass"),
                format!(
                    "must be at least {:e} kg (1/m must be finite), got {m:e}",
                    f64::MIN_POSITIVE
                ),
            ));
        }
        let x = parts.rest_position[p];
        for (axis, value) in x.iter().enumerate() {
            finite(&format!("particle[{p}].position[{axis}]"), *value)?;
        }
        let drag = particle_drag[p];
        finite(&format!("particle[{p}].drag"), drag)?;
        if drag < 0.0 {
            return Err(err(
                format!("particle[{p}].drag"),
                format!("must be ≥ 0 kg/s, got {drag}"),
            ));
        }
    }
    Ok(())
}

/// Every spring's ends (in range, two particles, no duplicate) and numbers.
fn check_springs(parts: &ModelParts) -> Result<(), ModelError> {
    let n = parts.mass.len();
    let mut seen = HashSet::new();
    for (s, spring) in parts.springs.iter().enumerate() {
        let item = |f: &str| format!("spring[{s}].{f}");
        for (name, idx) in [("ends[0]", spring.i), ("ends[1]", spring.j)] {
            if idx >= n {
                return Err(err(
                    item(name),
                    format!("particle index {idx} out of range (there are {n} particles)"),
                ));
            }
        }
        if spring.i == spring.j {
            return Err(err(
                item("ends"),
                "a spring must join two different particles",
            ));
        }
        let key = (spring.i.min(spring.j), spring.i.max(spring.j));
        if !seen.insert(key) {
            return Err(err(
                item("ends"),
                format!("duplicate spring between particles {} and {}", key.0, key.1),
            ));
        }
        for (name, value) in [
            ("rest_length", spring.rest_length),
            ("stiffness", spring.stiffness),
            ("damping", spring.damping),
        ] {
            finite(&item(name), value)?;
            if value < 0.0 {
                return Err(err(item(name), format!("must be ≥ 0, got {value}")));
            }
        }
        if let Some(b) = spring.break_strain {
            finite(&item("break_strain"), b)?;
            if b <= 0.0 {
                return Err(err(
                    item("break_strain"),
                    format!("must be > 0 (a strain), got {b}"),
                ));
            }
        }
    }
    Ok(())
}

/// Every triangle's corners (in range, three particles, an area at rest)
/// and coefficients.
fn check_triangles(parts: &ModelParts) -> Result<(), ModelError> {
    let n = parts.mass.len();
    for (t, tri) in parts.triangles.iter().enumerate() {
        let item = |f: &str| format!("triangle[{t}].{f}");
        for (c, &idx) in tri.corners.iter().enumerate() {
            if idx >= n {
                return Err(err(
                    item(&format!("corners[{c}]")),
                    format!("particle index {idx} out of range (there are {n} particles)"),
                ));
            }
        }
        let [a, b, c] = tri.corners;
        if a == b || b == c || a == c {
            return Err(err(
                item("corners"),
                "corners must be three different particles",
            ));
        }
        for (name, value) in [("alpha_n", tri.alpha_n), ("alpha_t", tri.alpha_t)] {
            finite(&item(name), value)?;
            if value < 0.0 {
                return Err(err(item(name), format!("must be ≥ 0, got {value}")));
            }
        }
        let x = &parts.rest_position;
        let doubled_area = (x[b] - x[a]).cross(&(x[c] - x[a])).norm();
        let longest = (x[b] - x[a])
            .norm()
            .max((x[c] - x[b]).norm())
            .max((x[a] - x[c]).norm());
        if doubled_area <= DEGENERATE_TRIANGLE_RATIO * longest * longest {
            return Err(err(
                item("corners"),
                "zero area at rest (the corners are coincident or collinear)",
            ));
        }
    }
    Ok(())
}

/// Every hinge's four particles and numbers.
fn check_hinges(parts: &ModelParts) -> Result<(), ModelError> {
    let n = parts.mass.len();
    for (h, hinge) in parts.hinges.iter().enumerate() {
        let item = |f: &str| format!("hinge[{h}].{f}");
        let ids = hinge.particles();
        if let Some(&bad) = ids.iter().find(|&&i| i >= n) {
            return Err(err(
                item("particles"),
                format!("particle index {bad} out of range (there are {n} particles)"),
            ));
        }
        for a in 0..4 {
            for b in a + 1..4 {
                if ids[a] == ids[b] {
                    return Err(err(
                        item("particles"),
                        "edge and apexes must be four different particles",
                    ));
                }
            }
        }
        for (name, value) in [
            ("rest_angle", hinge.rest_angle),
            ("stiffness", hinge.stiffness),
            ("damping", hinge.damping),
        ] {
            finite(&item(name), value)?;
            if name != "rest_angle" && value < 0.0 {
                return Err(err(item(name), format!("must be ≥ 0, got {value}")));
            }
        }
    }
    Ok(())
}

/// Gravity, the aerodynamic law (and no linear α left under another law),
/// the wind and the ground.
fn check_law_and_surroundings(parts: &ModelParts) -> Result<(), ModelError> {
    for (axis, value) in parts.gravity.iter().enumerate() {
        finite(&format!("gravity[{axis}]"), *value)?;
    }
    parts.aero.validate()?;
    if !parts.aero.uses_triangle_alpha() {
        // These laws replace the linear one: leftover α would be ignored
        // by the forces yet damp the implicit step and the stability
        // estimate.
        for (t, tri) in parts.triangles.iter().enumerate() {
            if tri.alpha_n != 0.0 || tri.alpha_t != 0.0 {
                return Err(err(
                    format!("triangle[{t}].alpha_n"),
                    format!(
                        "the {} aerodynamic law uses no αⁿ, αᵗ: they must be 0",
                        parts.aero.name()
                    ),
                ));
            }
        }
    }
    parts
        .wind
        .validate()
        .map_err(|e| err(e.item.clone(), e.reason.clone()))?;
    if let Some(ground) = &parts.ground {
        ground.validate()?;
    }
    Ok(())
}

/// The rigid bodies, each particle in one at most.
fn rigid_bodies(parts: &ModelParts) -> Result<Vec<RigidBody>, ModelError> {
    let n = parts.mass.len();
    let mut owner: Vec<Option<usize>> = vec![None; n];
    let mut rigid = Vec::with_capacity(parts.rigid.len());
    for (b, group) in parts.rigid.iter().enumerate() {
        let body = RigidBody::new(b, group, &parts.mass, &parts.fixed, &parts.rest_position)?;
        for &i in &body.members {
            if let Some(other) = owner[i].replace(b) {
                return Err(err(
                    format!("rigid[{b}].members"),
                    format!("particle {i} already belongs to rigid[{other}]"),
                ));
            }
        }
        rigid.push(body);
    }
    Ok(rigid)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair() -> ModelParts {
        ModelParts {
            mass: vec![1.0, 1.0, 1.0],
            fixed: vec![false; 3],
            rest_position: vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::new(0.0, 1.0, 0.0),
            ],
            springs: vec![Spring {
                i: 0,
                j: 1,
                rest_length: 1.0,
                stiffness: 1.0,
                damping: 0.0,
                break_strain: None,
            }],
            triangles: vec![Triangle {
                corners: [0, 1, 2],
                alpha_n: 1.0,
                alpha_t: 0.1,
            }],
            gravity: Vector3::new(0.0, 0.0, -STANDARD_GRAVITY),
            ..Default::default()
        }
    }

    #[test]
    fn a_valid_model_builds_and_reports_its_size() {
        let m = Model::new(pair()).unwrap();
        assert_eq!(m.len(), 3);
        assert!((m.surface_area() - 0.5).abs() < 1e-15);
        assert!((m.chord() - 2f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn fixed_particles_have_zero_inverse_mass() {
        let mut p = pair();
        p.fixed[1] = true;
        let m = Model::new(p).unwrap();
        assert_eq!(m.inv_mass, vec![1.0, 0.0, 1.0]);
    }
}
