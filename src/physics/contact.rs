//! Ground contact with Coulomb friction, for free particles and rigid bodies.
//!
//! The ground is the plane z = h with normal ẑ. Contact is resolved at the
//! velocity level after every step (the integrators never see it): a point
//! below the plane receives a normal impulse that stops its approach, or
//! reverses it with restitution e for impacts, and a friction impulse:
//!
//! - **static**: if the impulse that stops all sliding is within μ_s times
//!   the normal impulse, the point sticks (tangential velocity 0);
//! - **kinetic**: otherwise it slides on, slowed by μ_k times the normal
//!   impulse (μ_k ≤ μ_s).
//!
//! With gravity g the normal impulse of a resting point is m g h per step,
//! so a sliding point decelerates at exactly μ_k g and a point on a slope of
//! angle θ stays put while tan θ ≤ μ_s: Coulomb's law, discretised. Positions
//! move with the velocity change as if the impulse had acted within
//! the step (for symplectic Euler exactly the scheme with the contact force
//! included; each integrator has its own factor), so nothing creeps; what penetration remains is removed by putting a particle back on
//! the plane, or by a separate position solve for a body that changes no
//! velocity (split impulses), so it is repaired without adding energy.
//!
//! A rigid body's contacts are coupled through its rotation; they are solved
//! together by projected Gauss–Seidel over accumulated impulses (Catto's
//! sequential impulses), first with the static cone μ_s and, if the body
//! still slips, again with μ_k. A free particle's single contact is solved exactly
//! in closed form. Events like these make any integrator first order at the
//! steps where contacts change (docs/design/numerics.md, "Error against work",
//! step 6); the oracles are the first impact at √(2H/g) and bounce heights
//! e^{2k} H (docs/design/numerics.md, "Oracles", O11).

use crate::physics::model::{Ground, Model};
use crate::physics::state::State;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

type V3 = Vector3<f64>;

/// Most velocity iterations of the rigid contact solve.
const VELOCITY_ITERATIONS: usize = 30;
/// The velocity iterations stop when a sweep changes no impulse by more
/// than this fraction of the largest normal impulse.
const CONVERGED: f64 = 1e-10;
/// Position iterations of the rigid contact solve.
const POSITION_ITERATIONS: usize = 10;
/// Fraction of a rigid body's penetration removed per step; below 1 so the
/// coupled contacts of a body do not overshoot each other.
const POSITION_FRACTION: f64 = 0.8;
/// A body whose contact points still slip faster than this fraction of the
/// resting speed after the static solve is sliding.
const STICK_TOLERANCE: f64 = 1e-3;
/// Approach speeds below this many steps' worth of gravity, |g| dt, count as
/// resting contact and do not bounce (a resting point gains |g| dt per step).
const RESTING_STEPS: f64 = 2.0;

/// One rigid member below the ground during a solve.
#[derive(Clone, Copy, Debug)]
struct Contact {
    body: usize,
    particle: usize,
    /// Member position relative to the body's centre of mass, m.
    arm: V3,
    /// Penetration h − z > 0, m.
    depth: f64,
    /// Effective masses along ẑ, x̂, ŷ, kg.
    mass_n: f64,
    mass_t: [f64; 2],
    /// Normal velocity before the solve, m/s.
    approach: f64,
    /// Target normal velocity (restitution), m/s.
    bounce: f64,
    /// Accumulated normal, friction and position impulses.
    p_n: f64,
    p_t: [f64; 2],
    p_pos: f64,
}

/// A rigid body's velocity state during a solve.
#[derive(Clone, Copy, Debug)]
struct Body {
    centre: V3,
    velocity: V3,
    omega: V3,
    /// Velocities before the solve.
    velocity0: V3,
    omega0: V3,
    inv_mass: f64,
    inv_inertia: Matrix3<f64>,
    /// Pseudo-velocities of the position solve.
    push: V3,
    push_omega: V3,
    touched: bool,
    /// The friction coefficient of this solve (μ_s, or μ_k once sliding).
    mu: f64,
    slid: bool,
}

impl Body {
    fn point_velocity(&self, arm: &V3) -> V3 {
        self.velocity + self.omega.cross(arm)
    }
    fn apply(&mut self, impulse: &V3, arm: &V3) {
        self.velocity += impulse * self.inv_mass;
        self.omega += self.inv_inertia * arm.cross(impulse);
    }
    fn apply_push(&mut self, impulse: &V3, arm: &V3) {
        self.push += impulse * self.inv_mass;
        self.push_omega += self.inv_inertia * arm.cross(impulse);
    }
    /// 1 / (effective mass) of the body at `arm` along `dir`.
    fn compliance(&self, arm: &V3, dir: &V3) -> f64 {
        self.inv_mass + dir.dot(&(self.inv_inertia * arm.cross(dir)).cross(arm))
    }
}

/// The contact pass: scratch space sized for one model, so resolving never
/// allocates after the first steps.
#[derive(Clone, Debug)]
pub struct ContactSolver {
    /// For each particle, the rigid body it belongs to, if any.
    body_of: Vec<Option<usize>>,
    contacts: Vec<Contact>,
    bodies: Vec<Body>,
    resolved: u64,
    /// Last step's normal and friction impulses of each rigid member in
    /// contact, to warm-start the next solve (zero otherwise).
    warm: Vec<(f64, [f64; 2])>,
    /// The members with a stored impulse.
    warm_list: Vec<usize>,
}

/// [`ContactSolver::velocity_iterations`] on one body and its contacts:
/// sweeps until every contact meets its conditions to within `tolerance`
/// (m/s): a pushing contact reaches its target normal velocity, a free one
/// does not approach faster than it, a sticking one does not slip.
/// Impulses of redundant contacts (a ring resting on the ground) may still
/// wander; velocities not.
fn solve_body(sb: &mut Body, contacts: &mut [Contact], tolerance: f64) {
    let ez = V3::z();
    for _ in 0..VELOCITY_ITERATIONS {
        for c in contacts.iter_mut() {
            let u = sb.point_velocity(&c.arm);
            let p_n = (c.p_n + c.mass_n * (c.bounce - u.z)).max(0.0);
            sb.apply(&(ez * (p_n - c.p_n)), &c.arm);
            c.p_n = p_n;
            let u = sb.point_velocity(&c.arm);
            let candidate = [c.p_t[0] - c.mass_t[0] * u.x, c.p_t[1] - c.mass_t[1] * u.y];
            let p_t = clamp_disc(candidate, sb.mu, c.p_n);
            sb.apply(&V3::new(p_t[0] - c.p_t[0], p_t[1] - c.p_t[1], 0.0), &c.arm);
            c.p_t = p_t;
        }
        let residual = contacts.iter().fold(0.0f64, |worst, c| {
            let u = sb.point_velocity(&c.arm);
            let normal = if c.p_n > 0.0 {
                (u.z - c.bounce).abs()
            } else {
                (c.bounce - u.z).max(0.0)
            };
            let inside = c.p_t[0] * c.p_t[0] + c.p_t[1] * c.p_t[1]
                < (sb.mu * c.p_n) * (sb.mu * c.p_n) * (1.0 - 1e-9);
            let slip = if inside {
                (u.x * u.x + u.y * u.y).sqrt()
            } else {
                0.0
            };
            worst.max(normal).max(slip)
        });
        if residual <= tolerance {
            break;
        }
    }
}

/// Projects a tangential impulse onto the friction disc of radius μ p_n.
fn clamp_disc(candidate: [f64; 2], mu: f64, p_n: f64) -> [f64; 2] {
    // Impulses are far from overflow: sqrt of the sum, not the slower hypot.
    let mag = (candidate[0] * candidate[0] + candidate[1] * candidate[1]).sqrt();
    let limit = mu * p_n;
    if mag <= limit {
        candidate
    } else {
        [candidate[0] * limit / mag, candidate[1] * limit / mag]
    }
}

/// Coulomb friction on the tangential impulse that would stop a point: keep
/// it if within the static cone μ_s p_n, otherwise slide with μ_k p_n along
/// it (exact for a single contact).
fn coulomb(candidate: [f64; 2], p_n: f64, ground: &Ground) -> [f64; 2] {
    let mag = (candidate[0] * candidate[0] + candidate[1] * candidate[1]).sqrt();
    if mag <= ground.static_friction * p_n {
        candidate
    } else {
        let scale = ground.kinetic_friction * p_n / mag;
        [candidate[0] * scale, candidate[1] * scale]
    }
}

impl ContactSolver {
    /// A solver for `model` (which may have no ground: then it does nothing).
    pub fn new(model: &Model) -> ContactSolver {
        ContactSolver {
            body_of: model.body_of(),
            contacts: Vec::new(),
            bodies: Vec::with_capacity(model.rigid.len()),
            resolved: 0,
            warm: vec![(0.0, [0.0; 2]); model.len()],
            warm_list: Vec::new(),
        }
    }

    /// Point contacts resolved so far (a measure of contact work).
    pub fn resolved(&self) -> u64 {
        self.resolved
    }

    /// Resolves every point below the ground after a step of length `dt`,
    /// moving positions by `shift` (s) times each velocity change, as the
    /// integrator would have moved them had the impulse acted within the step
    /// (see [`crate::physics::params::Integrator::impulse_position_factor`]).
    /// Returns whether any position or velocity changed.
    pub fn resolve(&mut self, model: &Model, state: &mut State, dt: f64, shift: f64) -> bool {
        let Some(ground) = model.ground else {
            return false;
        };
        let h = ground.height;
        let resting = RESTING_STEPS * model.gravity.norm() * dt;
        let mut changed = false;
        let mut any_rigid = false;
        for i in 0..state.position.len() {
            if state.position[i].z >= h || model.fixed[i] {
                continue;
            }
            if self.body_of[i].is_some() {
                any_rigid = true;
                continue;
            }
            changed = true;
            self.resolved += 1;
            let v = &mut state.velocity[i];
            let before = *v;
            if v.z < 0.0 {
                let target = if -v.z > resting {
                    -ground.restitution * v.z
                } else {
                    0.0
                };
                // Normal impulse per unit mass; the friction rule is the same
                // per unit mass, so the particle's mass drops out.
                let p_n = target - v.z;
                v.z = target;
                let slide = coulomb([-v.x, -v.y], p_n, &ground);
                v.x += slide[0];
                v.y += slide[1];
            }
            // The step moved the point with its pre-contact velocity; move it
            // as if the contact impulse had acted within the step (symplectic
            // Euler with the contact force), so a resting point does not creep.
            let x = &mut state.position[i];
            *x += (*v - before) * shift;
            x.z = x.z.max(h);
        }
        if any_rigid {
            self.resolve_rigid(model, state, &ground, dt, shift, resting);
            changed = true;
        } else {
            self.forget_warm();
        }
        changed
    }

    /// Projected Gauss–Seidel on the velocity constraints: normal impulses
    /// ≥ 0 reaching each contact's target normal velocity, friction within
    /// each body's disc μ p_n. Bodies touch only the ground, so each body's
    /// contacts (contiguous: they are listed body by body) are solved on
    /// their own and stop when they have converged: one body still settling
    /// does not keep every other iterating (16 plates resting on the ground
    /// ran all sweeps where each alone needed about a dozen). With
    /// `slid_only`, only the bodies that slid are solved again.
    fn velocity_iterations(&mut self, tolerance: f64, slid_only: bool) {
        let mut start = 0;
        while start < self.contacts.len() {
            let b = self.contacts[start].body;
            let count = self.contacts[start..]
                .iter()
                .take_while(|c| c.body == b)
                .count();
            let body = &mut self.bodies[b];
            if !slid_only || body.slid {
                solve_body(body, &mut self.contacts[start..start + count], tolerance);
            }
            start += count;
        }
    }

    fn forget_warm(&mut self) {
        for &i in &self.warm_list {
            self.warm[i] = (0.0, [0.0; 2]);
        }
        self.warm_list.clear();
    }

    fn resolve_rigid(
        &mut self,
        model: &Model,
        state: &mut State,
        ground: &Ground,
        dt: f64,
        shift: f64,
        resting: f64,
    ) {
        let h = ground.height;
        self.bodies.clear();
        for body in &model.rigid {
            let (centre, velocity) = body.centre(&state.position, &state.velocity);
            let inertia = body.world_inertia(&state.position, &centre);
            let inv_inertia = inertia.try_inverse().unwrap_or_else(Matrix3::zeros);
            let l = body.angular_momentum(&state.position, &state.velocity, &centre, &velocity);
            let omega = inv_inertia * l;
            self.bodies.push(Body {
                centre,
                velocity,
                omega,
                velocity0: velocity,
                omega0: omega,
                inv_mass: 1.0 / body.mass,
                inv_inertia,
                push: V3::zeros(),
                push_omega: V3::zeros(),
                touched: false,
                mu: ground.static_friction,
                slid: false,
            });
        }
        self.contacts.clear();
        let (ez, ex, ey) = (V3::z(), V3::x(), V3::y());
        for (b, body) in model.rigid.iter().enumerate() {
            for &i in &body.members {
                let z = state.position[i].z;
                if z >= h {
                    continue;
                }
                let sb = &mut self.bodies[b];
                sb.touched = true;
                let arm = state.position[i] - sb.centre;
                let approach = sb.point_velocity(&arm).z;
                let bounce = if -approach > resting {
                    -ground.restitution * approach
                } else {
                    0.0
                };
                let (p_n, p_t) = self.warm[i];
                self.contacts.push(Contact {
                    body: b,
                    particle: i,
                    arm,
                    depth: h - z,
                    mass_n: 1.0 / sb.compliance(&arm, &ez),
                    mass_t: [
                        1.0 / sb.compliance(&arm, &ex),
                        1.0 / sb.compliance(&arm, &ey),
                    ],
                    approach,
                    bounce,
                    p_n,
                    p_t,
                    p_pos: 0.0,
                });
            }
        }
        self.resolved += self.contacts.len() as u64;
        // Warm start: a contact that persists begins from last step's
        // impulses, which a resting body needs again almost unchanged, so
        // the iterations start near the solution (projected Gauss-Seidel
        // converges only linearly on the redundant contacts of a resting
        // ring: about 1.6x per sweep).
        self.forget_warm();
        for c in &self.contacts {
            let impulse = V3::new(c.p_t[0], c.p_t[1], c.p_n);
            self.bodies[c.body].apply(&impulse, &c.arm);
        }
        // Coulomb per body: stick if the static cone allows it, else slide.
        // Deciding inside the iterations, contact by contact, would lock the
        // solve into sliding: early on each contact tries to stop the whole
        // body alone and overshoots its share of the cone.
        for b in &mut self.bodies {
            b.mu = ground.static_friction;
        }
        let tolerance = CONVERGED * resting;
        self.velocity_iterations(tolerance, false);
        let stuck = STICK_TOLERANCE * resting.max(f64::MIN_POSITIVE);
        let mut rerun = false;
        for c in &self.contacts {
            let sb = &mut self.bodies[c.body];
            let u = sb.point_velocity(&c.arm);
            if (u.x * u.x + u.y * u.y).sqrt() > stuck && sb.mu != ground.kinetic_friction {
                sb.mu = ground.kinetic_friction;
                sb.slid = true;
                rerun = true;
            }
        }
        if rerun {
            for c in &mut self.contacts {
                if self.bodies[c.body].slid {
                    (c.p_n, c.p_t) = (0.0, [0.0; 2]);
                }
            }
            for b in &mut self.bodies {
                if b.slid {
                    (b.velocity, b.omega) = (b.velocity0, b.omega0);
                }
            }
            self.velocity_iterations(tolerance, true);
        }
        for c in &self.contacts {
            self.warm[c.particle] = (c.p_n, c.p_t);
            self.warm_list.push(c.particle);
        }
        // The velocity change moves the body by `shift` times it; only the
        // penetration left after that is pushed out.
        for c in &mut self.contacts {
            let u = self.bodies[c.body].point_velocity(&c.arm).z;
            c.depth = (c.depth - shift * (u - c.approach)).max(0.0);
        }
        let push_rate = POSITION_FRACTION / dt;
        for _ in 0..POSITION_ITERATIONS {
            for c in &mut self.contacts {
                let sb = &mut self.bodies[c.body];
                let u = sb.push + sb.push_omega.cross(&c.arm);
                let p = (c.p_pos + c.mass_n * (c.depth * push_rate - u.z)).max(0.0);
                sb.apply_push(&(ez * (p - c.p_pos)), &c.arm);
                c.p_pos = p;
            }
        }
        for (body, sb) in model.rigid.iter().zip(&self.bodies) {
            if !sb.touched {
                continue;
            }
            // Move by the velocity change (as for particles) plus the push
            // that repairs what penetration remains.
            let turn = UnitQuaternion::from_scaled_axis(
                (sb.omega - sb.omega0) * shift + sb.push_omega * dt,
            );
            let moved = (sb.velocity - sb.velocity0) * shift + sb.push * dt;
            for &i in &body.members {
                let arm = turn * (state.position[i] - sb.centre);
                state.position[i] = sb.centre + moved + arm;
                state.velocity[i] = sb.velocity + sb.omega.cross(&arm);
            }
        }
    }
}
