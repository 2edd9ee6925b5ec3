//! The stiff and extreme matrix (docs/design/numerics.md, "Stress matrix"): variants
//! of a model that push the integrators to and past their limits, each run with
//! every integrator. Every run ends either finite, with its energy drift and
//! largest strain, or with a clear error naming the step, the particle, the
//! cause and the stable-step estimate — never a NaN, never a panic.
//!
//! Explicit integrators given a step above their estimated stable step
//! either refuse to run or sub-step, as the user chooses
//! ([`ExplicitPolicy`]). Sub-stepping splits each step into
//! n = clamp(⌈h / (AUTO_SAFETY · dt_max)⌉, 1, cap) equal sub-steps — the
//! rule of `--dt auto` — and warns when the cap clamps n, because the run
//! may then be unstable (docs/design/numerics.md, "Stress matrix").

use crate::physics::field::{Flow, LineVortex, Primitive, VortexCore, WindField};
use crate::physics::forces;
use crate::physics::integrate::{SimError, Simulator};
use crate::physics::model::{Model, ModelError, ModelParts};
use crate::physics::params::Integrator;
use crate::physics::stability::{self, AUTO_SAFETY};
use crate::physics::state::State;
use crate::sim::drop;
use crate::util::setting::Setting;
use nalgebra::Vector3;
use serde::Serialize;
use std::fmt;
use std::str::FromStr;
use std::time::Instant;

type V3 = Vector3<f64>;

/// Simulated duration of each stress run, s (longer when the case's step
/// is longer: one step at least).
pub const STRESS_SECONDS: f64 = 0.25;
/// The most sub-steps one step may be split into.
pub const DEFAULT_SUBSTEP_CAP: u64 = 100_000;

/// |Energy drift| above this share of the turnover is flagged: the run is
/// finite but its energy is not to be trusted.
pub const SUSPECT_DRIFT: f64 = 0.1;
/// Strains above this are flagged (a leaf's springs are meant to stay near
/// their rest length; this is a spring stretched to twice it).
pub const SUSPECT_STRAIN: f64 = 1.0;

/// What an explicit integrator does with a step above its stable estimate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ExplicitPolicy {
    /// Do not run; report the step and the estimate.
    Refuse,
    /// Split each step into sub-steps below the estimate (what `--dt auto`
    /// does for `drop`).
    #[default]
    Substep,
}

impl fmt::Display for ExplicitPolicy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ExplicitPolicy::Refuse => "refuse",
            ExplicitPolicy::Substep => "substep",
        })
    }
}

/// A name that is no [`ExplicitPolicy`]'s.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("expected 'refuse' or 'substep', got '{0}'")]
pub struct UnknownPolicy(pub String);

impl FromStr for ExplicitPolicy {
    type Err = UnknownPolicy;
    fn from_str(s: &str) -> Result<Self, UnknownPolicy> {
        match s {
            "refuse" => Ok(ExplicitPolicy::Refuse),
            "substep" => Ok(ExplicitPolicy::Substep),
            _ => Err(UnknownPolicy(s.to_string())),
        }
    }
}

/// One variant of the model to run.
#[derive(Clone, Debug)]
pub struct StressCase {
    /// Short name (a table key).
    pub name: String,
    /// What was changed.
    pub description: String,
    /// The model variant.
    pub model: Model,
    /// Its initial state.
    pub initial: State,
    /// The step asked for, s.
    pub dt: f64,
    /// Simulated duration, s (a whole number of steps).
    pub seconds: f64,
}

/// Spring and hinge stiffness scaled so that the largest single-element
/// rate (max k (1/mᵢ + 1/mⱼ), or k_b |∇θ|²/m for a hinge) reaches these, s⁻².
pub const STIFF_RATES: [f64; 5] = [1e4, 1e5, 1e6, 1e7, 1e8];
/// Steps of the huge/tiny-step cases, s.
pub const STEPS: [f64; 4] = [1e-5, 1e-3, 1e-1, 10.0];
/// Uniform wind speeds of the huge-wind cases, m/s.
pub const WIND_SPEEDS: [f64; 3] = [1e1, 1e2, 1e3];
/// Lightest mass of the tiny-mass cases, kg.
pub const TINY_MASSES: [f64; 2] = [1e-6, 1e-9];
/// Wind in the tiny-mass cases, m/s (along x).
pub const TINY_MASS_WIND: f64 = 5.0;
/// The light particle's mass over the mean mass of its neighbours.
pub const LIGHT_RATIO: f64 = 1e-4;

/// A validated copy of `model` changed by `change`.
fn variant(model: &Model, change: impl FnOnce(&mut ModelParts)) -> Result<Model, ModelError> {
    let mut parts = model.to_parts();
    change(&mut parts);
    Model::new(parts)
}

fn with_wind(model: &Model, primitive: Primitive) -> Result<Model, ModelError> {
    variant(model, |p| {
        let mut prims = p.wind.primitives().to_vec();
        prims.push(primitive);
        p.wind = WindField::new(prims);
    })
}

/// The particle with the most springs (the lowest index on a tie).
fn best_connected(model: &Model) -> usize {
    let mut degree = vec![0usize; model.len()];
    for s in &model.springs {
        degree[s.i] += 1;
        degree[s.j] += 1;
    }
    (0..model.len())
        .max_by_key(|&i| (degree[i], std::cmp::Reverse(i)))
        .unwrap_or(0)
}

/// The stress cases for `model` started from `initial` (the table in
/// docs/design/numerics.md, "Stress matrix"). Cases that need a spring or a
/// triangle are left out when the model has none.
///
/// # Errors
/// A variant that fails validation (only for unusual models, e.g. one whose
/// masses cannot be rescaled); the error names the item.
pub fn cases(model: &Model, initial: &State) -> Result<Vec<StressCase>, ModelError> {
    let frame = 1.0 / drop::FRAME_RATE;
    let mut out = Vec::new();
    let mut push = |name: String, description: String, model: Model, initial: State, dt: f64| {
        out.push(StressCase {
            name,
            description,
            model,
            initial,
            dt,
            seconds: (STRESS_SECONDS / dt).ceil().max(1.0) * dt,
        });
    };
    let rate = stability::estimate(model).omega_lower.powi(2);
    if rate > 0.0 {
        for target in STIFF_RATES {
            let scale = target / rate;
            let m = variant(model, |p| {
                p.springs.iter_mut().for_each(|s| s.stiffness *= scale);
                p.hinges.iter_mut().for_each(|h| h.stiffness *= scale);
            })?;
            push(
                format!("stiff-{target:.0e}"),
                format!(
                    "all springs and hinges ×{scale:.3e}: max single-element rate = {target:.0e} s^-2"
                ),
                m,
                initial.clone(),
                frame,
            );
        }
    }
    if !model.springs.is_empty() {
        let p = best_connected(model);
        let neighbours: Vec<f64> = model
            .springs
            .iter()
            .filter_map(|s| match (s.i == p, s.j == p) {
                (true, _) => Some(model.mass[s.j]),
                (_, true) => Some(model.mass[s.i]),
                _ => None,
            })
            .collect();
        let mean = neighbours.iter().sum::<f64>() / neighbours.len() as f64;
        let m = variant(model, |parts| parts.mass[p] = LIGHT_RATIO * mean)?;
        push(
            "light-particle".into(),
            format!("particle {p} at {LIGHT_RATIO:.0e} × the mean mass of its neighbours"),
            m,
            initial.clone(),
            frame,
        );
    }
    let lightest = model.mass.iter().copied().fold(f64::INFINITY, f64::min);
    for target in TINY_MASSES {
        let scale = target / lightest;
        let m = variant(model, |p| p.mass.iter_mut().for_each(|m| *m *= scale))?;
        let m = with_wind(&m, Primitive::uniform(V3::new(TINY_MASS_WIND, 0.0, 0.0)))?;
        push(
            format!("tiny-mass-{target:.0e}"),
            format!(
                "masses ×{scale:.3e} (lightest {target:.0e} kg) in a {TINY_MASS_WIND} m/s wind"
            ),
            m,
            initial.clone(),
            frame,
        );
    }
    for dt in STEPS {
        push(
            format!("dt-{dt:.0e}"),
            format!("the model as given, step {dt:.0e} s"),
            model.clone(),
            initial.clone(),
            dt,
        );
    }
    for speed in WIND_SPEEDS {
        let m = with_wind(model, Primitive::uniform(V3::new(speed, 0.0, 0.0)))?;
        push(
            format!("wind-{speed:.0e}"),
            format!("uniform wind {speed:.0e} m/s along x"),
            m,
            initial.clone(),
            frame,
        );
    }
    let core = 1e-3 * model.chord().max(1e-3);
    let vortex = Primitive::new(Flow::LineVortex(LineVortex {
        point: initial.position[0],
        axis: V3::new(1.0, 0.0, 0.0),
        circulation: 0.5,
        core_radius: core,
        core: VortexCore::LambOseen,
    }));
    push(
        "vortex-axis".into(),
        format!(
            "particle 0 on the axis of a line vortex (Γ = 0.5 m²/s, Lamb–Oseen core {core:.1e} m)"
        ),
        with_wind(model, vortex)?,
        initial.clone(),
        frame,
    );
    if let Some(s) = model.springs.first() {
        let mut state = initial.clone();
        state.position[s.j] = state.position[s.i];
        push(
            "coincident".into(),
            format!(
                "particle {} starts on particle {} (spring 0 squeezed to zero length)",
                s.j, s.i
            ),
            model.clone(),
            state,
            frame,
        );
    }
    if let Some(t) = model.triangles.first() {
        let [a, b, c] = t.corners;
        let mut state = initial.clone();
        state.position[c] = 0.5 * (state.position[a] + state.position[b]);
        push(
            "collinear-triangle".into(),
            format!("triangle 0: corner {c} starts midway between {a} and {b} (zero area)"),
            model.clone(),
            state,
            frame,
        );
    }
    if let Some(s) = model.springs.first().copied() {
        let m = variant(model, |p| p.springs[0].rest_length = 0.0)?;
        let mut state = initial.clone();
        state.position[s.j] = state.position[s.i];
        push(
            "zero-length-spring".into(),
            format!(
                "spring 0 ({}–{}) has rest length 0 and starts at zero length",
                s.i, s.j
            ),
            m,
            state,
            frame,
        );
    }
    Ok(out)
}

/// Outcome of one run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Finished with a finite state.
    Ok,
    /// Refused or stopped with a diagnosis.
    Error,
}

/// Where and why a run did not finish.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Failure {
    /// The step (of size dt / substeps, 0-based) whose result was bad; 0 for
    /// a refusal.
    pub step: u64,
    /// Simulated time, s.
    pub time: f64,
    /// The particle concerned, if one is.
    pub particle: Option<usize>,
    /// Short cause.
    pub cause: String,
}

/// One row of the matrix.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StressRow {
    /// The case name.
    pub case: String,
    /// The integrator.
    pub integrator: Integrator,
    /// `ok` or `error`.
    pub outcome: Outcome,
    /// One line saying what happened.
    pub message: String,
    /// Every number of the row and, for `ok`, the whole final state are
    /// finite.
    pub all_finite: bool,
    /// The step asked for, s.
    pub dt: f64,
    /// Sub-steps per step actually used.
    pub substeps: u64,
    /// The estimated stable step of this integrator on this case, s (`None`:
    /// unconditionally stable).
    pub dt_max: Option<f64>,
    /// Steps (of dt / substeps) taken.
    pub steps: u64,
    /// Energy drift: the share of the energy turnover that the integration
    /// created (+) or destroyed (−) beyond the physical work of air and
    /// dashpots, (E(T) − E(0) − W_nc) / S, with E from [`energy`], W_nc the
    /// trapezoid integral over every (sub-)step of [`nonconservative_power`],
    /// and the turnover S = |ΔE_grav| + ∫|P_nc| dt + (E_kin + E_spring) at
    /// the start and at the end. |drift| ≤ 1 by construction; a blow-up
    /// shows as a drift near +1. `None` on error (or if nothing moved).
    pub energy_drift: Option<f64>,
    /// E(T) − E(0), J (physical work included).
    pub energy_change_j: Option<f64>,
    /// W_nc, J: work of air and dashpots over the run.
    pub nonconservative_work_j: Option<f64>,
    /// Largest |l − L|/L over springs of non-zero rest length, sampled after
    /// every step of dt.
    pub max_strain: Option<f64>,
    /// Where and why it failed.
    pub failure: Option<Failure>,
    /// Warnings (e.g. sub-steps clamped).
    pub warnings: Vec<String>,
    /// Wall time of the run, s.
    pub wall_s: f64,
}

/// The mechanical energy of a state split by kind, J.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Energy {
    /// Σ ½ m |v|².
    pub kinetic: f64,
    /// −Σ m g·x (zero at the origin).
    pub gravitational: f64,
    /// Σ ½ k (l − L)² over intact springs.
    pub spring: f64,
    /// Σ k_b (1 − cos(θ − θ₀)) over hinges (the potential of `forces::hinges`).
    pub bending: f64,
}

impl Energy {
    /// The sum of the four.
    pub fn total(&self) -> f64 {
        self.kinetic + self.gravitational + self.spring + self.bending
    }
}

/// The mechanical energy of a state. In air it is not conserved — drag
/// removes energy, wind adds it — which is why [`StressRow::energy_drift`]
/// subtracts the work of those forces.
pub fn energy(model: &Model, state: &State) -> Energy {
    let mut e = Energy::default();
    for (i, (x, v)) in state.position.iter().zip(&state.velocity).enumerate() {
        let m = model.mass[i];
        e.kinetic += 0.5 * m * v.norm_squared();
        e.gravitational -= m * model.gravity.dot(x);
    }
    for (s, spring) in model.springs.iter().enumerate() {
        if state.spring_alive[s] {
            let l = (state.position[spring.i] - state.position[spring.j]).norm();
            e.spring += 0.5 * spring.stiffness * (l - spring.rest_length).powi(2);
        }
    }
    for hinge in &model.hinges {
        if let Some((theta, _)) = forces::dihedral(&state.position, hinge) {
            e.bending += hinge.stiffness * (1.0 - (theta - hinge.rest_angle).cos());
        }
    }
    e
}

/// The power of the non-conservative forces, Σ F·v over particles, W: the
/// paper's aerodynamics (eq. 9–10) and particle drag (eq. 7) in the wind at
/// the state's time, the springs' dashpots and the hinges' dampers. `wind` and `force` are
/// scratch buffers (resized as needed).
pub fn nonconservative_power(
    model: &Model,
    state: &State,
    wind: &mut Vec<V3>,
    force: &mut Vec<V3>,
) -> f64 {
    let (x, v) = (&state.position, &state.velocity);
    force.clear();
    force.resize(model.len(), V3::zeros());
    let still = model.wind.is_still();
    if !still {
        wind.clear();
        wind.extend(x.iter().map(|p| model.wind.velocity(p, state.time)));
    }
    let w = (!still).then_some(wind.as_slice());
    forces::triangle_aero(model, x, v, w, force);
    forces::particle_drag(model, v, w, force);
    let mut power: f64 = force
        .iter()
        .zip(v)
        .zip(&model.inv_mass)
        // Fixed particles (inverse mass 0) do not move under force.
        .filter(|(_, w)| **w > 0.0)
        .map(|((f, v), _)| f.dot(v))
        .sum();
    for (s, sp) in model.springs.iter().enumerate() {
        if !state.spring_alive[s] || sp.damping == 0.0 {
            continue;
        }
        let d = x[sp.i] - x[sp.j];
        let l = d.norm();
        if l == 0.0 {
            continue;
        }
        // F_i = −c (n·v_ij) n, F_j = −F_i: power −c (n·v_ij)².
        let rate = (v[sp.i] - v[sp.j]).dot(&(d / l));
        power -= sp.damping * rate * rate;
    }
    // Hinge dampers: torque −c_b θ̇ against the fold rate, power −c_b θ̇².
    for hinge in model.hinges.iter().filter(|h| h.damping != 0.0) {
        if let Some((_, grad)) = forces::dihedral(x, hinge) {
            let ids = hinge.particles();
            let rate = forces::fold_rate(&ids, &grad, v);
            power -= hinge.damping * rate * rate;
        }
    }
    power
}

/// Largest |l − L|/L over intact springs with L > 0.
pub fn max_strain(model: &Model, state: &State) -> f64 {
    model
        .springs
        .iter()
        .enumerate()
        .filter(|(s, sp)| state.spring_alive[*s] && sp.rest_length > 0.0)
        .map(|(_, sp)| {
            let l = (state.position[sp.i] - state.position[sp.j]).norm();
            (l - sp.rest_length).abs() / sp.rest_length
        })
        .fold(0.0, f64::max)
}

fn fmt_limit(dt_max: Option<f64>) -> String {
    match dt_max {
        None => "unbounded".into(),
        Some(m) if m <= 0.0 => "none (unstable at any step)".into(),
        Some(m) => format!("{m:.3e} s"),
    }
}

/// Runs one case with one integrator.
pub fn run_case(
    case: &StressCase,
    integrator: Integrator,
    policy: ExplicitPolicy,
    substep_cap: u64,
) -> StressRow {
    let model = &case.model;
    let est = stability::estimate(model);
    let dt_max = est.dt_max(integrator);
    let limiting = limiting_particle(model, &est);
    let mut row = StressRow {
        case: case.name.clone(),
        integrator,
        outcome: Outcome::Error,
        message: String::new(),
        all_finite: true,
        dt: case.dt,
        substeps: 1,
        dt_max,
        steps: 0,
        energy_drift: None,
        energy_change_j: None,
        nonconservative_work_j: None,
        max_strain: None,
        failure: None,
        warnings: Vec::new(),
        wall_s: 0.0,
    };
    let step = ExplicitStep {
        policy,
        substep_cap,
        dt_max,
        limiting,
    };
    if refused_before_start(case, integrator, step, &mut row) {
        return row;
    }
    let run = integrate(case, integrator, &mut row);
    match run.failure {
        Some(ref e) => record_failure(case, dt_max, run.h, e, &mut row),
        None => record_finish(case, &run, &mut row),
    }
    row
}

/// The particle a refusal names: the lighter end of the stiffest spring,
/// or the lightest particle when no spring sets the limit.
fn limiting_particle(model: &Model, est: &stability::StabilityEstimate) -> usize {
    est.stiffest_spring
        .map(|s| {
            let sp = &model.springs[s];
            if model.mass[sp.i] <= model.mass[sp.j] {
                sp.i
            } else {
                sp.j
            }
        })
        .unwrap_or(est.lightest_particle)
}

/// What an explicit integrator's step is checked against.
#[derive(Clone, Copy)]
struct ExplicitStep {
    policy: ExplicitPolicy,
    substep_cap: u64,
    dt_max: Option<f64>,
    /// The particle a refusal names ([`limiting_particle`]).
    limiting: usize,
}

/// Refuses (true, said in `row`) an explicit integrator with no stable
/// step, or with a step above its estimate under
/// [`ExplicitPolicy::Refuse`]; under [`ExplicitPolicy::Substep`] sets the
/// sub-steps.
fn refused_before_start(
    case: &StressCase,
    integrator: Integrator,
    step: ExplicitStep,
    row: &mut StressRow,
) -> bool {
    let ExplicitStep {
        policy,
        substep_cap,
        dt_max,
        limiting,
    } = step;
    let refuse = |row: &mut StressRow, cause: &str, message: String| {
        row.failure = Some(Failure {
            step: 0,
            time: case.initial.time,
            particle: Some(limiting),
            cause: cause.into(),
        });
        row.message = message;
    };
    if integrator != Integrator::Implicit {
        match dt_max {
            Some(m) if m <= 0.0 => {
                refuse(
                    row,
                    "no stable step",
                    format!(
                        "refused at step 0: {integrator} has no stable step on this model \
                         (the stiffest spring mode is undamped; particle {limiting}); \
                         dt_max estimate {}; choose another integrator",
                        fmt_limit(dt_max)
                    ),
                );
                return true;
            }
            Some(m) if case.dt > m => match policy {
                ExplicitPolicy::Refuse => {
                    refuse(
                        row,
                        "dt exceeds the stability estimate",
                        format!(
                            "refused at step 0: dt = {:.3e} s exceeds the stability estimate \
                             dt_max = {m:.3e} s of {integrator} (limited at particle {limiting}); \
                             use {}, a smaller dt or the implicit integrator",
                            case.dt,
                            Setting::Explicit.set("substep")
                        ),
                    );
                    return true;
                }
                ExplicitPolicy::Substep => {
                    let wanted = (case.dt / (AUTO_SAFETY * m)).ceil();
                    let cap = substep_cap.max(1);
                    if wanted > cap as f64 {
                        row.substeps = cap;
                        row.warnings.push(format!(
                            "sub-steps clamped to {cap} (wanted {wanted:.0}): \
                             each sub-step exceeds {AUTO_SAFETY} × dt_max, the run may be unstable"
                        ));
                    } else {
                        row.substeps = (wanted as u64).max(1);
                    }
                }
            },
            _ => {}
        }
    }
    false
}

/// A case's run: its end state and what was summed along the way.
struct Integrated {
    /// The time step of each sub-step, s.
    h: f64,
    state: State,
    e0: Energy,
    strain: f64,
    work: f64,
    turnover_work: f64,
    failure: Option<SimError>,
}

/// Integrates `case` with `integrator` at `row`'s sub-steps, setting its
/// wall time and steps.
fn integrate(case: &StressCase, integrator: Integrator, row: &mut StressRow) -> Integrated {
    let model = &case.model;
    let h = case.dt / row.substeps as f64;
    let outer = (case.seconds / case.dt).round().max(1.0) as u64;
    let mut state = case.initial.clone();
    let e0 = energy(model, &state);
    let mut strain = max_strain(model, &state);
    let (mut wind, mut force) = (Vec::new(), Vec::new());
    let mut power = nonconservative_power(model, &state, &mut wind, &mut force);
    let (mut work, mut turnover_work) = (0.0, 0.0);
    let mut sim = Simulator::new(model, integrator);
    let start = Instant::now();
    let mut failure: Option<SimError> = None;
    'run: for k in 0..outer {
        for _ in 0..row.substeps {
            if let Err(e) = sim.step(model, &mut state, h) {
                failure = Some(e);
                break 'run;
            }
            let next = nonconservative_power(model, &state, &mut wind, &mut force);
            work += 0.5 * (power + next) * h;
            turnover_work += 0.5 * (power.abs() + next.abs()) * h;
            power = next;
        }
        // Pin the clock to the step grid (sub-steps accumulate round-off).
        state.time = case.initial.time + (k + 1) as f64 * case.dt;
        strain = strain.max(max_strain(model, &state));
    }
    row.wall_s = start.elapsed().as_secs_f64();
    row.steps = sim.steps();
    Integrated {
        h,
        state,
        e0,
        strain,
        work,
        turnover_work,
        failure,
    }
}

/// Says in `row` where and why the run failed.
fn record_failure(
    case: &StressCase,
    dt_max: Option<f64>,
    h: f64,
    e: &SimError,
    row: &mut StressRow,
) {
    let (step, time, particle, cause) = match &e {
        SimError::Diverged(d) => (
            d.step,
            d.time,
            Some(d.particle),
            format!(
                "{} {}",
                d.quantity,
                if d.value.is_finite() {
                    "ran away"
                } else {
                    "became non-finite"
                }
            ),
        ),
        SimError::SolverFailed { step, time, .. } => (
            *step,
            *time,
            None,
            "implicit solve did not converge".to_string(),
        ),
    };
    row.message = match &e {
        // A divergence message names dt_max itself.
        SimError::Diverged(_) => e.to_string(),
        SimError::SolverFailed { .. } => {
            format!("{e}; dt_max estimate {}", fmt_limit(dt_max))
        }
    };
    if row.substeps > 1 {
        row.message.push_str(&format!(
            "; {} sub-steps of {h:.3e} s per step",
            row.substeps
        ));
    }
    row.failure = Some(Failure {
        step,
        time,
        particle,
        cause,
    });
    row.all_finite = [time, case.dt].iter().all(|v| v.is_finite())
        && dt_max.is_none_or(f64::is_finite)
        && !has_non_finite_text(&row.message);
}

/// Says in `row` what a run that finished shows: energy drift, strain,
/// finiteness.
fn record_finish(case: &StressCase, run: &Integrated, row: &mut StressRow) {
    let model = &case.model;
    let Integrated {
        h,
        ref state,
        ref e0,
        strain,
        work,
        turnover_work,
        ..
    } = *run;
    let e1 = energy(model, state);
    let change = e1.total() - e0.total();
    let turnover = (e1.gravitational - e0.gravitational).abs()
        + turnover_work
        + e0.kinetic
        + e0.spring
        + e0.bending
        + e1.kinetic
        + e1.spring
        + e1.bending;
    row.energy_change_j = Some(change);
    row.nonconservative_work_j = Some(work);
    row.energy_drift = (turnover > 0.0).then(|| (change - work) / turnover);
    row.max_strain = Some(strain);
    let state_finite = state
        .position
        .iter()
        .chain(&state.velocity)
        .all(|v| v.iter().all(|c| c.is_finite()));
    row.all_finite = state_finite
        && change.is_finite()
        && work.is_finite()
        && strain.is_finite()
        && row.energy_drift.is_none_or(f64::is_finite);
    // Finite is not the same as right: say when the numbers show it.
    if let Some(d) = row.energy_drift.filter(|d| d.abs() > SUSPECT_DRIFT) {
        row.warnings.push(format!(
            "energy drift {d:+.2}: the integration {} {:.0} % of the energy turnover",
            if d > 0.0 { "created" } else { "destroyed" },
            100.0 * d.abs()
        ));
    }
    if strain > SUSPECT_STRAIN {
        row.warnings.push(format!(
            "largest strain {strain:.1e}: a spring stretched by more than {SUSPECT_STRAIN} × its rest length"
        ));
    }
    row.outcome = if row.all_finite {
        Outcome::Ok
    } else {
        Outcome::Error
    };
    row.message = if row.all_finite {
        format!(
            "finite after {:.3} s: energy drift {}, largest strain {:.3e}{}",
            case.seconds,
            row.energy_drift
                .map_or(format!("{change:.3e} J"), |d| format!("{d:+.3e}")),
            strain,
            if row.substeps > 1 {
                format!(", {} sub-steps of {h:.3e} s per step", row.substeps)
            } else {
                String::new()
            }
        )
    } else {
        // The simulator checks every step, so this is a bug guard.
        "the run finished with a non-finite state or energy".into()
    };
}

fn has_non_finite_text(s: &str) -> bool {
    s.split(|c: char| !c.is_ascii_alphanumeric())
        .any(|w| w.eq_ignore_ascii_case("nan") || w.eq_ignore_ascii_case("inf"))
}

/// Runs every case with every integrator.
pub fn run_matrix(
    cases: &[StressCase],
    policy: ExplicitPolicy,
    substep_cap: u64,
) -> Vec<StressRow> {
    cases
        .iter()
        .flat_map(|case| {
            Integrator::ALL
                .iter()
                .map(move |&i| run_case(case, i, policy, substep_cap))
        })
        .collect()
}
