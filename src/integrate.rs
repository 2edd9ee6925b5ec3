//! Time integration of Newton's law for every particle (eq. 1–3), five ways,
//! all sharing one force evaluation path ([`Forces`]), plus spring breaking
//! and divergence detection after every step.

use crate::contact::ContactSolver;
use crate::force::{ForceTerms, Forces};
use crate::model::Model;
use crate::rigid::RigidProjector;
use crate::state::State;
use crate::terms::Terms;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

type V3 = Vector3<f64>;

/// A time-stepping scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Integrator {
    /// Forward Euler exactly as the paper's eq. 1–3: the position update uses
    /// the old velocity v(t). First order; unstable for undamped springs.
    Euler,
    /// Semi-implicit (symplectic) Euler: velocity first, then position with
    /// the new velocity. First order, stable for ωh < 2.
    Symplectic,
    /// Velocity Verlet; velocity-dependent forces are evaluated at the
    /// predicted velocity v + h a, which keeps second order with dashpots and
    /// drag. One force evaluation per step.
    Verlet,
    /// Classical fourth-order Runge–Kutta. Four force evaluations per step.
    Rk4,
    /// Linearised backward Euler (Baraff & Witkin 1998): one Newton step per
    /// time step, solved by preconditioned conjugate gradients. First order,
    /// stable at any step, numerically damped.
    Implicit,
}

impl Integrator {
    /// All integrators, in the order they are reported.
    pub const ALL: [Integrator; 5] = [
        Integrator::Euler,
        Integrator::Symplectic,
        Integrator::Verlet,
        Integrator::Rk4,
        Integrator::Implicit,
    ];

    /// The command-line and file name.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Euler => "euler",
            Integrator::Symplectic => "symplectic",
            Integrator::Verlet => "verlet",
            Integrator::Rk4 => "rk4",
            Integrator::Implicit => "implicit",
        }
    }

    /// How far, in units of dt, the new position moves per unit of velocity
    /// gained from a force constant over the step: x_{n+1} gains c h Δv with
    /// Δv = a h. Forward Euler 0 (its position uses the old velocity),
    /// symplectic and backward Euler 1, Verlet and RK4 ½ (h²/2 a). An
    /// impulse applied after the step (ground contact) moves positions by the
    /// same amount, as if it had acted within the step.
    pub fn impulse_position_factor(self) -> f64 {
        match self {
            Integrator::Euler => 0.0,
            Integrator::Symplectic | Integrator::Implicit => 1.0,
            Integrator::Verlet | Integrator::Rk4 => 0.5,
        }
    }

    /// Order of convergence of the global error.
    pub fn order(self) -> u32 {
        match self {
            Integrator::Euler | Integrator::Symplectic | Integrator::Implicit => 1,
            Integrator::Verlet => 2,
            Integrator::Rk4 => 4,
        }
    }
}

impl fmt::Display for Integrator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Integrator {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Integrator::ALL
            .into_iter()
            .find(|i| i.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown integrator '{s}' (expected euler, symplectic, verlet, rk4 or implicit)"
                )
            })
    }
}

/// Why a run stopped before its end.
#[derive(Clone, Debug, PartialEq)]
pub enum SimError {
    /// The state became non-finite or ran away.
    Diverged(Box<Divergence>),
    /// The implicit solver's conjugate gradients did not converge.
    SolverFailed {
        /// Step index (0-based) at which it failed.
        step: u64,
        /// Simulated time at the start of that step, s.
        time: f64,
        /// Iterations spent.
        iterations: usize,
        /// Relative residual reached.
        residual: f64,
    },
}

/// Where and how a run diverged, with what is needed to fix it.
#[derive(Clone, Debug, PartialEq)]
pub struct Divergence {
    /// Step index (0-based) whose result was bad.
    pub step: u64,
    /// Simulated time at the end of that step, s.
    pub time: f64,
    /// The particle with the bad value.
    pub particle: usize,
    /// "position" or "velocity".
    pub quantity: &'static str,
    /// Its magnitude (m or m/s; NaN or inf when non-finite).
    pub value: f64,
    /// The integrator.
    pub integrator: Integrator,
    /// The time step used, s.
    pub dt: f64,
    /// The estimated largest stable step for this integrator, s (None when
    /// unconditionally stable).
    pub dt_max: Option<f64>,
    /// The largest force term on that particle, with its magnitude in N.
    pub dominant_force: (&'static str, f64),
    /// The spring with the largest k (1/m_i + 1/m_j), if any.
    pub stiffest_spring: Option<usize>,
}

impl fmt::Display for SimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SimError::SolverFailed {
                step,
                time,
                iterations,
                residual,
            } => {
                write!(
                    f,
                    "implicit solver did not converge at step {step} (t = {time:.6} s): "
                )?;
                if residual.is_finite() {
                    write!(f, "relative residual {residual:.2e}")?;
                } else {
                    // pᵀAp ≤ 0 or overflowed: the linearised system is no
                    // longer positive definite; there is no residual to show.
                    write!(f, "the system matrix lost positive definiteness")?;
                }
                write!(
                    f,
                    " after {iterations} CG iterations; \
                     the system is ill-conditioned, try a smaller --dt"
                )
            }
            SimError::Diverged(d) => {
                let kind = if d.value.is_finite() {
                    "ran away"
                } else {
                    "became non-finite"
                };
                // Non-finite magnitudes are said in words: a diagnosis never
                // prints NaN.
                let magnitude = |v: f64, unit: &str| {
                    if v.is_finite() {
                        format!("{v:.3e}{unit}")
                    } else {
                        "non-finite".to_string()
                    }
                };
                write!(
                    f,
                    "simulation diverged at step {} (t = {:.6} s): particle {} {} {}",
                    d.step, d.time, d.particle, d.quantity, kind
                )?;
                if d.value.is_finite() {
                    write!(f, " ({:.3e})", d.value)?;
                }
                write!(
                    f,
                    "; dominant force term: {} ({}); integrator {}, dt = {:.3e} s",
                    d.dominant_force.0,
                    magnitude(d.dominant_force.1, " N"),
                    d.integrator,
                    d.dt
                )?;
                match d.dt_max {
                    Some(m) if d.dt > m => write!(
                        f,
                        ", above the estimated stable limit dt_max = {m:.3e} s: \
                         the time step is too large for the stiffness; use the automatic step (`--dt auto`, or `dt = \"auto\"` in a scene file) or a step below dt_max"
                    )?,
                    Some(m) => write!(
                        f,
                        ", below the estimated stable limit dt_max = {m:.3e} s; \
                         likely cause: forces growing without bound (extreme wind or parameters)"
                    )?,
                    None => write!(f, "; likely cause: extreme forces or parameters")?,
                }
                if let Some(s) = d.stiffest_spring {
                    write!(f, "; stiffest spring: {s}")?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for SimError {}

/// Speeds above this (m/s), or plus ten times the wind's bound, count as a
/// runaway: no falling leaf or scene object gets anywhere near it, while an
/// unstable integration passes it many steps before overflowing to inf.
pub const RUNAWAY_SPEED: f64 = 1e4;
/// Positions farther than this from the origin (m) count as a runaway.
pub const RUNAWAY_DISTANCE: f64 = 1e7;

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
        let speed_limit = RUNAWAY_SPEED + 10.0 * model.wind.speed_bound();
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
        imp.linearise(model, s, h, self.forces.torn());
        // b = h (f0 + h K v0), K = ∂f/∂x = −Σ S_k (see linearise).
        let b = &mut imp.b;
        for (bi, f) in b.iter_mut().zip(&self.acc) {
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
                let rate = crate::force::fold_rate(&blk.ids, &blk.grad, &s.velocity);
                for (&i, g) in blk.ids.iter().zip(&blk.grad) {
                    b[i] -= g * (h * h * blk.stiffness * rate);
                }
            }
        }
        let result = imp.solve(model);
        match result {
            Ok(()) => {
                for ((x, v), dv) in s.position.iter_mut().zip(&mut s.velocity).zip(&imp.dv) {
                    *v += *dv;
                    *x += *v * h;
                }
                Ok(())
            }
            Err((iterations, residual)) => Err(SimError::SolverFailed {
                step: self.steps,
                time: s.time,
                iterations,
                residual,
            }),
        }
    }

    /// Non-finite or runaway values stop the run with a diagnosis. The
    /// common case costs one pass of sums (NaN and inf propagate through
    /// them, and a sum over the limit means some term is large); only a
    /// failing state is scanned particle by particle to name the culprit.
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
        let (quantity, value) = if within(x2, limit_x2) && x2.is_finite() {
            ("velocity", v2.sqrt())
        } else {
            ("position", x2.sqrt())
        };
        Err(self.diagnose(model, s, dt, step, i, quantity, value))
    }

    #[allow(clippy::too_many_arguments)]
    fn diagnose(
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
        let estimate = crate::stability::estimate(model);
        SimError::Diverged(Box::new(Divergence {
            step,
            time: s.time,
            particle,
            quantity,
            value,
            integrator: self.integrator,
            dt,
            dt_max: estimate.dt_max(self.integrator),
            dominant_force: terms.dominant(),
            stiffest_spring: estimate.stiffest_spring,
        }))
    }
}

/// A breakable spring and the squared length past which it breaks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BreakLimit {
    /// Index of the spring in [`Model::springs`].
    pub spring: usize,
    /// ((1 + ε) L)² for break strain ε and rest length L.
    pub length2: f64,
}

/// The [`BreakLimit`] of every breakable spring, in spring order.
pub fn break_limits(model: &Model) -> Vec<BreakLimit> {
    model
        .springs
        .iter()
        .enumerate()
        .filter_map(|(k, s)| {
            let l = (1.0 + s.break_strain?) * s.rest_length;
            Some(BreakLimit {
                spring: k,
                length2: l * l,
            })
        })
        .collect()
}

/// Breaks every intact spring of `limits` whose strain (l − L)/L exceeds its
/// threshold ε, tested as l² > ((1 + ε) L)² (no square root); returns how
/// many broke. A broken spring stays broken.
pub fn break_springs(model: &Model, state: &mut State, limits: &[BreakLimit]) -> usize {
    let mut broken = 0;
    for limit in limits {
        let k = limit.spring;
        if !state.spring_alive[k] {
            continue;
        }
        let spring = &model.springs[k];
        let l2 = (state.position[spring.i] - state.position[spring.j]).norm_squared();
        if l2 > limit.length2 {
            state.spring_alive[k] = false;
            broken += 1;
        }
    }
    broken
}

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
struct ImplicitScratch {
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
    fn new(model: &Model) -> ImplicitScratch {
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

    fn linearise(&mut self, model: &Model, s: &State, h: f64, torn: &crate::force::Tears) {
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
            *blk = match crate::force::dihedral(&s.position, hinge) {
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
