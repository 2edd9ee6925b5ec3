//! Accumulating a scene's objects into one set of model parts, with the
//! owner of every particle, spring, triangle, hinge and rigid body so that
//! errors name the object, and the limits checked before an object is built.

use super::compiled::{ObjectKind, PoseFrame, SceneObject};
use super::error::{Ctx, SceneError};
use super::shapes::Part;
use crate::physics::model::RigidGroup;
use crate::physics::model::{ModelParts, Spring, Triangle};
use nalgebra::{UnitQuaternion, Vector3};

type V3 = Vector3<f64>;

/// Most particles a scene may hold (all objects together). Checked from the
/// counts in the file before anything is built, so that a cylinder, rope or
/// sheet of 10⁸ segments (or 10⁸ copies of a leaf) is refused at once, with
/// `--explain` too, instead of allocating gigabytes. The shipped scenes
/// hold at most 273.
pub const MAX_PARTICLES: usize = 1_000_000;
/// Most springs a scene may hold (a sheet has about four per particle).
pub const MAX_SPRINGS: usize = 4_000_000;

/// Accumulates objects into one set of model parts.
#[derive(Default)]
pub(super) struct Builder {
    pub(super) parts: ModelParts,
    pub(super) velocity: Vec<V3>,
    /// Scene path of the object that made each particle, spring, triangle, hinge.
    pub(super) particle_owner: Vec<String>,
    pub(super) spring_owner: Vec<String>,
    pub(super) triangle_owner: Vec<String>,
    pub(super) hinge_owner: Vec<String>,
    pub(super) rigid_owner: Vec<String>,
    pub(super) objects: Vec<SceneObject>,
    pub(super) pruned: Vec<String>,
    /// The first leaf that set the scene's aerodynamic law: a model has one
    /// law, so every leaf must share it.
    pub(super) aero_from: Option<String>,
}

impl Builder {
    /// Appends `part` moved to world = translation + rotation · (local −
    /// pivot), with the rigid velocity field v + ω × (x − c) about the placed
    /// centre of mass c. Fixed particles get no velocity. Returns the new
    /// particle indices.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn add_part(
        &mut self,
        owner: &str,
        part: &Part,
        drag: &[f64],
        alpha: (f64, f64),
        pivot: V3,
        rotation: UnitQuaternion<f64>,
        translation: V3,
        velocity: V3,
        omega: V3,
    ) -> Vec<usize> {
        let start = self.parts.mass.len();
        let world: Vec<V3> = part
            .position
            .iter()
            .map(|x| translation + rotation * (x - pivot))
            .collect();
        let total: f64 = part.mass.iter().sum();
        let com = world
            .iter()
            .zip(&part.mass)
            .fold(V3::zeros(), |s, (x, m)| s + x * *m)
            / total;
        for (k, x) in world.iter().enumerate() {
            self.parts.mass.push(part.mass[k]);
            self.parts.fixed.push(part.fixed[k]);
            self.parts
                .particle_drag
                .push(drag.get(k).copied().unwrap_or(0.0));
            self.parts.rest_position.push(*x);
            self.velocity.push(if part.fixed[k] {
                V3::zeros()
            } else {
                velocity + omega.cross(&(x - com))
            });
            self.particle_owner.push(owner.to_string());
        }
        for s in &part.springs {
            let [i, j] = s.ends;
            self.parts.springs.push(Spring {
                i: start + i,
                j: start + j,
                rest_length: (part.position[i] - part.position[j]).norm(),
                stiffness: s.stiffness,
                damping: s.damping,
                break_strain: s.break_strain,
            });
            self.spring_owner.push(owner.to_string());
        }
        let (alpha_n, alpha_t) = alpha;
        if alpha_n != 0.0 || alpha_t != 0.0 {
            for t in &part.triangles {
                self.parts.triangles.push(Triangle {
                    corners: t.map(|c| start + c),
                    alpha_n,
                    alpha_t,
                });
                self.triangle_owner.push(owner.to_string());
            }
        }
        (start..start + part.mass.len()).collect()
    }

    pub(super) fn push_object(
        &mut self,
        name: String,
        kind: ObjectKind,
        particles: Vec<usize>,
        pose: Option<PoseFrame>,
        rigid: bool,
        owner: &str,
    ) {
        let rigid_body = rigid.then(|| {
            self.parts.rigid.push(RigidGroup {
                members: particles.clone(),
            });
            self.rigid_owner.push(owner.to_string());
            self.parts.rigid.len() - 1
        });
        self.objects.push(SceneObject {
            name,
            kind,
            particles,
            pose,
            rigid_body,
            surface: Vec::new(),
        });
    }

    /// Sets the display surface of the object pushed last (local indices).
    pub(super) fn set_surface(&mut self, triangles: Vec<[usize; 3]>) {
        if let Some(o) = self.objects.last_mut() {
            o.surface = triangles;
        }
    }

    /// Refuses an object that would take the scene past [`MAX_PARTICLES`]
    /// or [`MAX_SPRINGS`], before it is built. Counts arrive as f64 so that
    /// products of counts from the file cannot overflow.
    pub(super) fn reserve(
        &self,
        ctx: &Ctx<'_>,
        field: &str,
        what: &str,
        particles: f64,
        springs: f64,
    ) -> Result<(), SceneError> {
        let have = self.parts.mass.len() as f64;
        let have_springs = self.parts.springs.len() as f64;
        if have + particles > MAX_PARTICLES as f64 {
            return Err(ctx.err(
                field,
                format!(
                    "{what} makes {} particles{}, more than a scene may hold ({MAX_PARTICLES} in all); \
                     use fewer segments, cells or copies",
                    count_text(particles),
                    if have > 0.0 {
                        format!(" beside the {have} already placed")
                    } else {
                        String::new()
                    }
                ),
            ));
        }
        if have_springs + springs > MAX_SPRINGS as f64 {
            return Err(ctx.err(
                field,
                format!(
                    "{what} makes {} springs, more than a scene may hold ({MAX_SPRINGS} in all); \
                     use fewer segments, cells or copies",
                    count_text(springs)
                ),
            ));
        }
        Ok(())
    }

    /// The scene path of a model item named by
    /// [`ModelError`](crate::physics::model::ModelError).
    pub(super) fn owner_of(&self, item: &str) -> Option<String> {
        let index = |prefix: &str| -> Option<usize> {
            item.strip_prefix(prefix)?.split(']').next()?.parse().ok()
        };
        let lists: [(&str, &Vec<String>); 5] = [
            ("particle[", &self.particle_owner),
            ("spring[", &self.spring_owner),
            ("triangle[", &self.triangle_owner),
            ("hinge[", &self.hinge_owner),
            ("rigid[", &self.rigid_owner),
        ];
        lists
            .iter()
            .find_map(|(prefix, owners)| index(prefix).and_then(|i| owners.get(i).cloned()))
    }
}

/// A count for a message: whole below 10⁹, else in scientific notation.
fn count_text(n: f64) -> String {
    if n < 1e9 {
        format!("{n:.0}")
    } else {
        format!("{n:.2e}")
    }
}
