//! Time integration of Newton's law for every particle (eq. 1–3), five ways,
//! all sharing one force evaluation path ([`Forces`]), plus spring breaking
//! and divergence detection after every step.

mod breaking;
mod divergence;
mod implicit;

pub use breaking::{BreakLimit, break_limits, break_springs};
pub use divergence::{
    Divergence, RUNAWAY_DISTANCE, RUNAWAY_SPEED, SimError, WIND_NOT_FINITE, runaway_speed,
};

use crate::physics::contact::ContactSolver;
use crate::physics::forces::{ForceTerms, Forces};
use crate::physics::model::Model;
use crate::physics::params::Integrator;
use crate::physics::rigid::RigidProjector;
use crate::physics::skip::SkipCounts;
use crate::physics::stability;
use crate::physics::state::State;
use crate::physics::terms::Terms;
use implicit::ImplicitScratch;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// Advances a [`State`] of one [`Model`] step by step. Holds all scratch
/// buffers, so stepping never allocates.
#[derive(Clone, Debug)]
pub struct Simulator {
    integrator: Integrator,
    forces: Forces,
    steps: u64,
    breakable: Vec<BreakLimit>,
    speed_limit2: f64,
    // Scratch, sized to the model at construction.
    acc: Vec<V3>,
    acc_valid: bool,
    /// Whether `forces` knows what the state's broken springs have torn
    /// (a state may arrive with springs already broken).
    tears_known: bool,
    x_tmp: Vec<V3>,
    v_tmp: Vec<V3>,
    k_acc: [Vec<V3>; 4],
    k_vel: [Vec<V3>; 3],
    implicit: Option<ImplicitScratch>,
    rigid: Option<RigidProjector>,
    contact: Option<ContactSolver>,
}

impl Simulator {
    /// A simulator for `model` with the chosen integrator, evaluating the
    /// terms the model needs ([`Terms::needed`]).
    pub fn new(model: &Model, integrator: Integrator) -> Simulator {
        Simulator::with_terms(model, integrator, Terms::needed(model))
    }

    /// A simulator that evaluates exactly `terms`, holding scratch space only
    /// for them and for the chosen integrator.
    pub fn with_terms(model: &Model, integrator: Integrator, terms: Terms) -> Simulator {
        let n = model.len();
        let zeros_if = |used: bool| {
            if used {
                vec![V3::zeros(); n]
            } else {
                Vec::new()
            }
        };
        let rk4 = integrator == Integrator::Rk4;
        let breakable = if terms.breaking {
            break_limits(model)
        } else {
            Vec::new()
        };
        let speed_limit = runaway_speed(model);
        Simulator {
            integrator,
            forces: Forces::with_terms(model, terms),
            steps: 0,
            breakable,
            speed_limit2: speed_limit * speed_limit,
            acc: zeros_if(true),
            acc_valid: false,
            tears_known: false,
            x_tmp: zeros_if(rk4),
            v_tmp: zeros_if(integrator == Integrator::Verlet),
            k_acc: std::array::from_fn(|_| zeros_if(rk4)),
            k_vel: std::array::from_fn(|_| zeros_if(rk4)),
            implicit: (integrator == Integrator::Implicit).then(|| ImplicitScratch::new(model)),
            rigid: terms.rigid.then(|| RigidProjector::new(&model.rigid)),
            contact: terms.contact.then(|| ContactSolver::new(model)),
        }
    }

    /// The terms this simulator evaluates.
    pub fn terms(&self) -> Terms {
        self.forces.terms()
    }

    /// The rigid-body projector (its last fitted rotations), if rigid bodies
    /// are simulated.
    pub fn rigid(&self) -> Option<&RigidProjector> {
        self.rigid.as_ref()
    }

    /// Point contacts with the ground resolved so far.
    pub fn contacts_resolved(&self) -> u64 {
        self.contact.as_ref().map_or(0, ContactSolver::resolved)
    }

    /// Turns exact skipping ([`crate::physics::skip`]) on (the default) or
    /// off; off is the baseline it is checked bit-identical against.
    pub fn set_skipping(&mut self, model: &Model, on: bool) {
        self.forces.set_skipping(model, on);
    }

    /// What exact skipping has saved so far.
    pub fn skip_counts(&self) -> SkipCounts {
        self.forces.skip_counts()
    }

    /// Per object ([`crate::physics::skip::groups`]), the wind primitive
    /// evaluations skipped so far.
    pub fn skipped_per_group(&self) -> &[u64] {
        self.forces.skipped_per_group()
    }

    /// The integrator in use.
    pub fn integrator(&self) -> Integrator {
        self.integrator
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Force evaluations so far.
    pub fn force_evaluations(&self) -> u64 {
        self.forces.evaluations()
    }

    /// Forgets what is cached from the state (the acceleration carried
    /// between Verlet steps, what broken springs have torn); call it after
    /// changing the state by hand between steps.
    pub fn invalidate(&mut self) {
        self.acc_valid = false;
        self.tears_known = false;
    }

    /// Advances `state` by `dt`. The stages, each present only if its term
    /// is kept: integrate (forces, with rigid-body accelerations); put rigid
    /// bodies back on their shape; resolve ground contact; break
    /// over-stretched springs; then check the new state. On divergence the
    /// state holds the bad values and the error names the step, particle and
    /// likely cause.
    pub fn step(&mut self, model: &Model, state: &mut State, dt: f64) -> Result<(), SimError> {
        if !self.tears_known {
            if !self.breakable.is_empty() {
                self.forces.tear(&state.spring_alive);
            }
            self.tears_known = true;
        }
        match self.integrator {
            Integrator::Euler => self.step_euler(model, state, dt),
            Integrator::Symplectic => self.step_symplectic(model, state, dt),
            Integrator::Verlet => self.step_verlet(model, state, dt),
            Integrator::Rk4 => self.step_rk4(model, state, dt),
            Integrator::Implicit => self.step_implicit(model, state, dt)?,
        }
        state.time += dt;
        // The lagged centre of pressure commits the step's last force
        // evaluation: at the step's end for Verlet and RK4 (whose forces read
        // the lag at their own times), carried over the step for the others.
        self.forces.advance_pressure_lag(dt);
        if let Some(rigid) = &mut self.rigid {
            rigid.project(&model.rigid, state);
        }
        // Contact impulses change velocities: Verlet's carried acceleration
        // (which depends on them through drag and dashpots) is then stale.
        if let Some(contact) = &mut self.contact {
            let shift = dt * self.integrator.impulse_position_factor();
            if contact.resolve(model, state, dt, shift) {
                self.acc_valid = false;
            }
        }
        if !self.breakable.is_empty() && break_springs(model, state, &self.breakable) > 0 {
            self.forces.tear(&state.spring_alive);
            self.acc_valid = false;
        }
        let step = self.steps;
        self.steps += 1;
        self.check(model, state, dt, step)
    }

    /// Eq. 1–3 as written: a = F/m; v(t+h) = v + a h; r(t+h) = r + v(t) h.
    fn step_euler(&mut self, model: &Model, s: &mut State, h: f64) {
        self.forces.acceleration(
            model,
            &s.position,
            &s.velocity,
            &s.spring_alive,
            s.time,
            &mut self.acc,
        );
        for ((x, v), a) in s.position.iter_mut().zip(&mut s.velocity).zip(&self.acc) {
            *x += *v * h;
            *v += *a * h;
        }
    }

    /// v(t+h) = v + a h; r(t+h) = r + v(t+h) h.
    fn step_symplectic(&mut self, model: &Model, s: &mut State, h: f64) {
        self.forces.acceleration(
            model,
            &s.position,
            &s.velocity,
            &s.spring_alive,
            s.time,
            &mut self.acc,
        );
        for ((x, v), a) in s.position.iter_mut().zip(&mut s.velocity).zip(&self.acc) {
            *v += *a * h;
            *x += *v * h;
        }
    }

    /// v½ = v + a h/2; x' = x + v½ h; a' = a(x', v + a h); v' = v½ + a' h/2.
    /// a' is kept for the next step (one force evaluation per step).
    fn step_verlet(&mut self, model: &Model, s: &mut State, h: f64) {
        if !self.acc_valid {
            self.forces.acceleration(
                model,
                &s.position,
                &s.velocity,
                &s.spring_alive,
                s.time,
                &mut self.acc,
            );
        }
        for (((x, v), a), vp) in s
            .position
            .iter_mut()
            .zip(&mut s.velocity)
            .zip(&self.acc)
            .zip(&mut self.v_tmp)
        {
            *vp = *v + *a * h;
            *v += *a * (0.5 * h);
            *x += *v * h;
        }
        self.forces.acceleration(
            model,
            &s.position,
            &self.v_tmp,
            &s.spring_alive,
            s.time + h,
            &mut self.acc,
        );
        for (v, a) in s.velocity.iter_mut().zip(&self.acc) {
            *v += *a * (0.5 * h);
        }
        self.acc_valid = true;
    }

    /// Classical RK4 on (x, v).
    fn step_rk4(&mut self, model: &Model, s: &mut State, h: f64) {
        let t = s.time;
        let alive = &s.spring_alive;
        let [a1, a2, a3, a4] = &mut self.k_acc;
        let [v2, v3, v4] = &mut self.k_vel;
        let (x0, v0) = (&s.position, &s.velocity);
        self.forces.acceleration(model, x0, v0, alive, t, a1);
        for i in 0..x0.len() {
            self.x_tmp[i] = x0[i] + v0[i] * (0.5 * h);
            v2[i] = v0[i] + a1[i] * (0.5 * h);
        }
        self.forces
            .acceleration(model, &self.x_tmp, v2, alive, t + 0.5 * h, a2);
        for i in 0..x0.len() {
            self.x_tmp[i] = x0[i] + v2[i] * (0.5 * h);
            v3[i] = v0[i] + a2[i] * (0.5 * h);
        }
        self.forces
            .acceleration(model, &self.x_tmp, v3, alive, t + 0.5 * h, a3);
        for i in 0..x0.len() {
            self.x_tmp[i] = x0[i] + v3[i] * h;
            v4[i] = v0[i] + a3[i] * h;
        }
        self.forces
            .acceleration(model, &self.x_tmp, v4, alive, t + h, a4);
        let w = h / 6.0;
        for i in 0..s.position.len() {
            s.position[i] += (s.velocity[i] + (v2[i] + v3[i]) * 2.0 + v4[i]) * w;
            s.velocity[i] += (a1[i] + (a2[i] + a3[i]) * 2.0 + a4[i]) * w;
        }
    }

    /// One Newton step of backward Euler, linearised at the current state:
    /// (M − h ∂f/∂v − h² ∂f/∂x) Δv = h (f₀ + h ∂f/∂x v₀), then
    /// v' = v + Δv, x' = x + h v'. Spring stiffness blocks use only the
    /// tension part of the geometric term so the matrix stays positive
    /// definite; wind gradients and the turning of triangle normals are
    /// treated explicitly (as ARCSim does).
    fn step_implicit(&mut self, model: &Model, s: &mut State, h: f64) -> Result<(), SimError> {
        let imp = self
            .implicit
            .get_or_insert_with(|| ImplicitScratch::new(model));
        // f0 into acc (as force, not acceleration).
        self.forces.total(
            model,
            &s.position,
            &s.velocity,
            &s.spring_alive,
            s.time,
            &mut self.acc,
        );
        imp.step(
            model,
            s,
            h,
            &self.acc,
            self.forces.torn(),
            self.forces.added_mass(),
        )
        .map_err(|(iterations, residual)| SimError::SolverFailed {
            step: self.steps,
            time: s.time,
            iterations,
            residual,
        })
    }

    /// Non-finite or runaway values stop the run with a diagnosis. The
    /// common case costs one pass of sums (NaN and inf propagate through
    /// them, and no term can be over a limit the sum is under); only a
    /// state whose sums are over is scanned particle by particle, to find
    /// the culprit or to find there is none.
    fn check(&mut self, model: &Model, s: &State, dt: f64, step: u64) -> Result<(), SimError> {
        let limit_x2 = RUNAWAY_DISTANCE * RUNAWAY_DISTANCE;
        let (mut sum_x2, mut sum_v2) = (0.0, 0.0);
        for (x, v) in s.position.iter().zip(&s.velocity) {
            sum_x2 += x.norm_squared();
            sum_v2 += v.norm_squared();
        }
        let within = |value: f64, limit: f64| value.partial_cmp(&limit).is_some_and(|o| o.is_le());
        if within(sum_x2, limit_x2) && within(sum_v2, self.speed_limit2) {
            return Ok(());
        }
        // The worst particle: non-finite first, then the largest value.
        let badness = |x2: f64, v2: f64| {
            if !(x2.is_finite() && v2.is_finite()) {
                f64::INFINITY
            } else {
                (x2 / limit_x2).max(v2 / self.speed_limit2)
            }
        };
        let (i, x2, v2) = s
            .position
            .iter()
            .zip(&s.velocity)
            .enumerate()
            .map(|(i, (x, v))| (i, x.norm_squared(), v.norm_squared()))
            .fold((0, 0.0, 0.0), |best, cur| {
                if badness(cur.1, cur.2) > badness(best.1, best.2) {
                    cur
                } else {
                    best
                }
            });
        // The sums over-count a large model whose every particle is well
        // within both limits (a million particles at 10 m/s sum to the
        // speed limit's square): only a particle past a limit is a runaway.
        if within(x2, limit_x2) && within(v2, self.speed_limit2) {
            return Ok(());
        }
        let (quantity, value) = if within(x2, limit_x2) && x2.is_finite() {
            ("velocity", v2.sqrt())
        } else {
            ("position", x2.sqrt())
        };
        Err(self.diagnose(model, s, dt, step, i, quantity, value))
    }

    /// The diagnosis of a bad value of `quantity` ("position", "velocity",
    /// or "pose" for a pose fit that overflowed while the particles are
    /// finite) at `particle` after step `step`: the force terms on it, the
    /// stable step, the stiffest spring. A force term that is not finite
    /// is named before any finite one (NaN compares false with everything,
    /// so a plain maximum would name gravity); a wind that is not finite at
    /// the particle is named as the cause.
    #[allow(clippy::too_many_arguments)]
    pub fn diagnose(
        &mut self,
        model: &Model,
        s: &State,
        dt: f64,
        step: u64,
        particle: usize,
        quantity: &'static str,
        value: f64,
    ) -> SimError {
        let terms: ForceTerms = self.forces.terms_on(
            model,
            &s.position,
            &s.velocity,
            &s.spring_alive,
            s.time,
            particle,
        );
        let estimate = stability::estimate(model);
        let named = [
            ("gravity", terms.gravity),
            ("spring", terms.spring),
            ("bending", terms.bending),
            ("aero", terms.aero),
            ("drag", terms.drag),
        ];
        let x = s.position[particle];
        let wind_bad = x.iter().all(|c| c.is_finite())
            && !model.wind.is_still()
            && [s.time - dt, s.time]
                .iter()
                .any(|&t| !model.wind.velocity(&x, t).iter().all(|c| c.is_finite()));
        // |F| without overflow (nalgebra's norm squares first: 1e200 N
        // would read as inf); NaN when a component is not finite.
        let magnitude = |f: &V3| {
            if !f.iter().all(|c| c.is_finite()) {
                return f64::NAN;
            }
            let m = f.amax();
            if m > 0.0 { m * (f / m).norm() } else { 0.0 }
        };
        let dominant = if wind_bad {
            (WIND_NOT_FINITE, f64::NAN)
        } else {
            named
                .iter()
                .map(|(name, f)| (*name, magnitude(f)))
                .fold(("none", 0.0f64), |best, t| {
                    let worse = (t.1.is_nan() && !best.1.is_nan()) || t.1 > best.1;
                    if worse { t } else { best }
                })
        };
        SimError::Diverged(Box::new(Divergence {
            step,
            time: s.time,
            particle,
            quantity,
            value,
            integrator: self.integrator,
            dt,
            dt_max: estimate.dt_max(self.integrator),
            dominant_force: dominant,
            stiffest_spring: estimate.stiffest_spring,
        }))
    }
}
