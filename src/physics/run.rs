//! Running a model for a while: the two frame loops around
//! [`Simulator::step`] (sampled by interpolation for drops, stepped onto
//! every frame for scenes), the choice of the step, and the budget that
//! refuses a run which would never end.

pub use super::stability::StepBound;
use crate::physics::integrate::{SimError, Simulator};
use crate::physics::model::Model;
use crate::physics::params::{Integrator, TimeStep};
use crate::physics::skip::SkipCounts;
use crate::physics::stability;
use crate::physics::state::State;
use crate::util::setting::Setting;
use nalgebra::Vector3;
use serde::Serialize;
use std::fmt::Write as _;
use std::time::Instant;

/// What a run did and what it cost.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunStats {
    /// The integrator used.
    pub integrator: Integrator,
    /// The time step actually used, s.
    pub dt: f64,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time, s.
    pub simulated_s: f64,
    /// Wall-clock time of the stepping loop (set-up and output excluded), s.
    pub wall_s: f64,
    /// Full force evaluations.
    pub force_evals: u64,
    /// Springs broken during the run.
    pub broken_springs: usize,
    /// Point contacts with the ground resolved during the run.
    pub contacts_resolved: u64,
    /// What exact skipping left out (not serialised: outputs stay as
    /// they were without it).
    #[serde(skip)]
    pub skips: SkipCounts,
}

impl RunStats {
    /// The statistics of `sim`'s run since `start` (the wall clock of the
    /// stepping loop alone).
    fn of(sim: &Simulator, dt: f64, simulated_s: f64, start: Instant, broken: usize) -> RunStats {
        RunStats {
            integrator: sim.integrator(),
            dt,
            steps: sim.steps(),
            simulated_s,
            wall_s: start.elapsed().as_secs_f64(),
            force_evals: sim.force_evaluations(),
            broken_springs: broken,
            contacts_resolved: sim.contacts_resolved(),
            skips: sim.skip_counts(),
        }
    }
}

/// Resolves a [`TimeStep`] for `model` to a step that divides `frame_dt`.
/// Errors when `Auto` finds no stable step (forward Euler on undamped
/// springs, a rate that overflows), and at any step when a particle's mass
/// is lost beside its added mass ([`StepError::MassLostToAddedMass`]).
pub fn resolve_dt(
    model: &Model,
    integrator: Integrator,
    dt: TimeStep,
    frame_dt: f64,
) -> Result<f64, StepError> {
    resolve(model, integrator, dt, frame_dt, true)
}

/// Resolves a [`TimeStep`] for a run sampled by [`run_sampled`]: a fixed
/// step is used as given, `Auto` is [`stability::StabilityEstimate::auto_step`]
/// (not snapped to the frame grid). Errors as [`resolve_dt`].
pub fn resolve_step(
    model: &Model,
    integrator: Integrator,
    dt: TimeStep,
    frame_dt: f64,
) -> Result<f64, StepError> {
    resolve(model, integrator, dt, frame_dt, false)
}

fn resolve(
    model: &Model,
    integrator: Integrator,
    dt: TimeStep,
    frame_dt: f64,
    onto_frames: bool,
) -> Result<f64, StepError> {
    match dt {
        TimeStep::Fixed(h) if h > 0.0 && h.is_finite() => {
            // No step is safe for a mass the solve cannot see, fixed or not.
            if let Some((particle, added_mass)) = stability::mass_lost_to_added_mass(model) {
                return Err(StepError::MassLostToAddedMass {
                    particle,
                    added_mass,
                });
            }
            Ok(if onto_frames {
                stability::snap_to_frame(h, frame_dt)
            } else {
                h
            })
        }
        TimeStep::Fixed(h) => Err(StepError::NotPositive(h)),
        TimeStep::Auto => {
            let estimate = stability::estimate(model);
            check_estimate(&estimate)?;
            if onto_frames {
                estimate.auto_dt(integrator, frame_dt)
            } else {
                estimate.auto_step(integrator, frame_dt)
            }
            .ok_or(StepError::NoStableStep(integrator))
        }
    }
}

/// Refuses a stability estimate with a rate that overflows f64 (a stiffness,
/// damping or drag coefficient, gravity or a mass too large, or a mass too
/// small), or a particle whose mass is lost beside its added mass: no step
/// can be chosen from it. What `drop` refuses, `check` refuses with the same
/// message.
///
/// # Errors
/// [`StepError::MassLostToAddedMass`], naming the particle, or
/// [`StepError::Overflow`], naming the rates and the stiffest spring.
pub fn check_estimate(estimate: &stability::StabilityEstimate) -> Result<(), StepError> {
    if estimate.is_finite() {
        return Ok(());
    }
    if let Some((particle, added_mass)) = estimate.mass_lost_to_added_mass {
        return Err(StepError::MassLostToAddedMass {
            particle,
            added_mass,
        });
    }
    let rates = [
        ("ω_max", estimate.omega_max, "rad/s"),
        ("its upper bound", estimate.omega_upper, "rad/s"),
        (
            "the top mode's damping rate",
            estimate.mode_damping_rate,
            "1/s",
        ),
        ("the drag rate", estimate.drag_rate, "1/s"),
        ("the fastest damping rate", estimate.damping_rate_max, "1/s"),
    ];
    let bad: Vec<String> = rates
        .iter()
        .filter(|r| !r.1.is_finite())
        .map(|(name, v, unit)| {
            if v.is_nan() {
                format!("{name} is not a number (inf − inf)")
            } else {
                format!("{name} = {v} {unit}")
            }
        })
        .collect();
    Err(StepError::Overflow {
        rates: bad.join(", "),
        stiffest_spring: estimate
            .stiffest_spring
            .filter(|_| !estimate.omega_lower.is_finite()),
    })
}

/// Most steps, or output frames, one run may take. Far beyond any useful
/// run (a scene of a hundred leaves takes hours for 10⁸ steps): a run that
/// needs more has a step far too small (a very stiff or very light model
/// under `dt = auto`, or a tiny fixed step) or a frame rate far too high, and
/// is refused up front instead of running for ever.
pub const MAX_STEPS: f64 = 1e8;

/// A number for a message: plain when moderate, to four significant
/// figures (`69906`, not `69905.89149035318`), else in scientific notation.
fn quantity(v: f64) -> String {
    let plain = format!("{v}");
    if v != 0.0 && !(1e-3..1e6).contains(&v.abs()) {
        format!("{v:.3e}")
    } else if plain.len() > 8 {
        // |v| in [1e-3, 1e6): 0 to 6 decimals keep four figures.
        let decimals = (3 - v.abs().log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        plain
    }
}

/// Checks that `seconds` of simulation at step `dt`, written at `frame_rate`
/// frames per second, stays within [`MAX_STEPS`] steps and frames, and
/// writes at least one frame ([`check_frames`], [`check_steps`]).
///
/// # Errors
/// The counts and the likely cause.
pub fn check_budget(
    seconds: f64,
    dt: f64,
    frame_rate: f64,
    integrator: Integrator,
) -> Result<(), StepError> {
    check_frames(seconds, frame_rate)?;
    check_steps(seconds, dt, integrator)
}

/// Checks that `seconds` at `frame_rate` is at least one frame and at most
/// [`MAX_STEPS`].
///
/// # Errors
/// The count.
pub fn check_frames(seconds: f64, frame_rate: f64) -> Result<(), StepError> {
    let frames = seconds * frame_rate;
    if frames.is_nan() || frames < 0.5 {
        return Err(StepError::NoFrame {
            seconds,
            frame_rate,
        });
    }
    if frames > MAX_STEPS {
        return Err(StepError::TooManyFrames {
            seconds,
            frame_rate,
        });
    }
    Ok(())
}

/// Checks that `seconds` at step `dt` is at most [`MAX_STEPS`] steps.
///
/// # Errors
/// The count and the likely cause.
pub fn check_steps(seconds: f64, dt: f64, integrator: Integrator) -> Result<(), StepError> {
    let steps = seconds / dt;
    if steps.is_nan() || steps > MAX_STEPS {
        return Err(StepError::TooManySteps {
            seconds,
            dt,
            integrator,
        });
    }
    Ok(())
}

/// Why no step, or no run, can be had: the step chosen or asked for, or the
/// number of steps or frames it would take.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StepError {
    /// A fixed step that is not a positive number of seconds.
    #[error("time step must be a positive number of seconds, got {0}")]
    NotPositive(f64),
    /// A duration that is not a positive number of seconds.
    #[error("duration must be a positive number of seconds, got {0}")]
    Duration(f64),
    /// A rate of the model overflows f64, so the auto step has nothing to go on.
    #[error(
        "no time step can be chosen: {rates} (a stiffness, damping or drag coefficient, \
         gravity or a mass too large, or a mass too small, for f64: k/m, c/m or α/m overflows, \
         or the speeds the unsteady law's rates are read at{})",
        .stiffest_spring.map_or(String::new(), |k| format!("; the stiffest is spring[{k}]"))
    )]
    Overflow {
        /// The rates that are not finite, with their values.
        rates: String,
        /// The stiffest spring, when a spring rate overflows.
        stiffest_spring: Option<usize>,
    },
    /// A particle's added mass under the unsteady law is so far beyond its
    /// own mass that the mass is lost to round-off
    /// ([`stability::MAX_ADDED_MASS_RATIO`]).
    #[error(
        "no time step can be chosen: particle[{particle}]'s added mass is {added_mass:.3e} kg, \
         over {:.0e} times its own mass, which round-off then loses in every step's solve \
         ([aero] added_mass scales the potential flow's, 1 by default; or the particle is \
         far too light)",
        stability::MAX_ADDED_MASS_RATIO
    )]
    MassLostToAddedMass {
        /// The particle, the one of largest ratio of those beyond it.
        particle: usize,
        /// Its added mass (the largest eigenvalue of its tensor), kg.
        added_mass: f64,
    },
    /// Forward Euler on an undamped spring mode: unstable at any step.
    #[error(
        "no stable time step exists for {0} on this model \
         (its stiffest spring mode is undamped); choose another integrator"
    )]
    NoStableStep(Integrator),
    /// Less than one frame.
    #[error(
        "{} s at {} frames per second is no frame at all; raise the frame rate or the duration",
        quantity(*.seconds),
        quantity(*.frame_rate)
    )]
    NoFrame {
        /// Duration, s.
        seconds: f64,
        /// Frames per second.
        frame_rate: f64,
    },
    /// More frames than [`MAX_STEPS`].
    #[error(
        "{} s at {} frames per second is {:.2e} frames, more than the limit of \
         {MAX_STEPS:.0e}; lower the frame rate or the duration",
        quantity(*.seconds),
        quantity(*.frame_rate),
        .seconds * .frame_rate
    )]
    TooManyFrames {
        /// Duration, s.
        seconds: f64,
        /// Frames per second.
        frame_rate: f64,
    },
    /// More work than the limit: the estimate, why, and what to do.
    #[error(transparent)]
    TooMuchWork(Box<WorkError>),
    /// More steps than [`MAX_STEPS`].
    #[error(
        "{} s at dt = {dt:.3e} s needs {} steps of {integrator} (the limit is \
         {MAX_STEPS:.0e}): the step is far too small. With dt = auto this means \
         the model is extremely stiff or light for an explicit integrator (see `leafmagic \
         check`); soften it, make it heavier, or use the implicit integrator, whose step \
         stability does not limit",
        quantity(*.seconds),
        step_count(*.seconds / *.dt)
    )]
    TooManySteps {
        /// Duration, s.
        seconds: f64,
        /// The step, s.
        dt: f64,
        /// The integrator.
        integrator: Integrator,
    },
}

/// Work is counted in particle-steps (particles × steps, times runs): what
/// the step loop costs, whatever the model. Above this a run is long enough
/// that a terminal should show its progress (about 1.3 s of one core for a
/// leaf, which has some 4 elements per particle, at [`REFERENCE_RATE`]).
pub const LONG_WORK: f64 = 3e7;
/// The default limit of one drop or one scene, in particle-steps: about 45 s
/// of one core for a leaf at [`REFERENCE_RATE`] (a scene of dense sheets,
/// with 6 elements per particle, some 70 s). The default breed is 3.7e7 for all its
/// 800 drops; the shipped scenes are at most 1.3e6. The work limit ([`Setting::MaxWork`]) raises it.
pub const MAX_WORK: f64 = 1e9;
/// The default limit of a whole breeding run (every drop of every
/// generation), in particle-steps: about ten minutes of one core. Measured
/// here: the README's quick start (100 leaves × 8 generations, 4 drops of
/// 10 s, prototype A), estimated at 2.95e8, took 17.5 s of CPU on one
/// thread (1.7e7 per second, set-up and classification included), so it
/// stays a thirtieth of the limit. [`REFERENCE_RATE`] quotes the limit at
/// about 7 minutes for leaves (machines differ by 2×). Was 1e11 (75
/// minutes), which let a run start unasked that a slip of a flag made long.
/// A breeding run's work limit ([`Setting::MaxWork`]) raises it.
pub const MAX_BREED_WORK: f64 = 1e10;
/// Element-steps per second of one core (elements: particles, springs,
/// triangles and hinges; what a step touches), for the time a message
/// quotes. Measured here: a drop of prototype A with every spring at 1e8
/// N/m, 3.96e7 Verlet steps of 28 elements, took 12.2 s (9.1e7/s); the tear
/// scene with 1e9 N/m springs, 1.13e7 steps of 1745 elements, is predicted
/// at 3.6 minutes by this rate, and the issue measured 7 on a machine 2.3×
/// slower on the drop. Machines differ by 2×: a guide, not a promise.
pub const REFERENCE_RATE: f64 = 9e7;

/// What one member of a rigid body resting on the ground costs a step, in
/// elements of [`REFERENCE_RATE`]: a contact of the body's projected
/// Gauss–Seidel solve, about a dozen sweeps (crate::physics::contact).
/// Measured on `ground-blow` with its leaves swapped for 16 rigid 5 cm
/// plates under the unsteady law (145 members each): 3.21e6 contacts
/// resolved in 2.9 s of the run's 5.8 (perf), 0.9 µs each, 81 elements.
const RESTING_CONTACT_COST: usize = 80;

/// Elements a step adds, at most, when a model's objects rest on its
/// ground: every rigid member a contact of its body's solve
/// ([`RESTING_CONTACT_COST`]), and under Verlet a second force evaluation
/// (a contact changes the velocities the carried acceleration was
/// evaluated at: `ground-blow` with plates, 3,565 evaluations in 1,800
/// steps). None without a ground.
fn resting_elements(model: &Model, integrator: Integrator, elements: usize) -> usize {
    if model.ground.is_none() {
        return 0;
    }
    let members: usize = model.rigid.iter().map(|b| b.members.len()).sum();
    let second_evaluation = if integrator == Integrator::Verlet {
        elements
    } else {
        0
    };
    members * RESTING_CONTACT_COST + second_evaluation
}

/// What a run will cost before it starts: particles × steps (× runs), the
/// step and why it is that small.
#[derive(Clone, Debug, PartialEq)]
pub struct Work {
    /// Particles stepped.
    pub particles: usize,
    /// Particles, springs, triangles and hinges: what a step touches, for
    /// the time estimate (a triangle under the quadratic or unsteady law
    /// counts as several, [`crate::physics::aero::triangle_cost`]).
    pub elements: usize,
    /// Steps of one run.
    pub steps: f64,
    /// Output frames of one run.
    pub frames: f64,
    /// Runs of this size (1 but for a breed: population × generations).
    pub runs: f64,
    /// Elements a step adds, at most, while the objects rest on the ground
    /// (contacts, and Verlet's second force evaluation): 0 without one.
    pub resting_elements: usize,
    /// For a breed, how many times the prototype's steps its variants take
    /// on average (their masses, stiffnesses and sizes move the auto step;
    /// measured on the first generation); 1 otherwise.
    pub variant_steps: f64,
    /// The integrator.
    pub integrator: Integrator,
    /// The step, s.
    pub dt: f64,
    /// Why the step is what it is.
    pub reason: StepReason,
    /// Steps one run would take with the implicit integrator, when that is
    /// fewer (its step is not bounded by stiffness or lightness).
    pub implicit_steps: Option<f64>,
}

/// What sets a run's step.
#[derive(Clone, Debug, PartialEq)]
pub enum StepReason {
    /// A fixed step, as given.
    Fixed,
    /// The output frame (nothing stiff bounds the step below it).
    Frame,
    /// The auto step, bounded by stability: the stiffest spring and the
    /// lightest particle, and which limit of
    /// [`stability::StabilityEstimate::dt_max`] bounds it.
    Stability {
        /// The stiffest spring: index, its two particles, k (N/m).
        spring: Option<(usize, usize, usize, f64)>,
        /// ω_max, rad/s.
        omega_max: f64,
        /// The lightest free particle and its mass, kg.
        lightest: (usize, f64),
        /// The fastest drag rate γ, 1/s.
        drag_rate: f64,
        /// The network's fastest damping rate, 1/s
        /// ([`stability::StabilityEstimate::damping_rate_max`]).
        damping_rate: f64,
        /// The tumbling-rate bound Ω, 1/s (0 but under the unsteady law).
        tumbling_rate: f64,
        /// Which limit bounds the step.
        bound: StepBound,
    },
}

impl Work {
    /// The work of `seconds` of `model` at step `dt` (`auto`: chosen by
    /// stability) with output frames of `frame_dt`. Cheap: why the step is
    /// what it is is found only when asked ([`Work::explained`]).
    pub fn of(
        model: &Model,
        integrator: Integrator,
        dt: f64,
        auto: bool,
        seconds: f64,
        frame_dt: f64,
    ) -> Work {
        let elements = model.len()
            + model.springs.len()
            + model.triangles.len() * crate::physics::aero::triangle_cost(&model.aero)
            + model.hinges.len();
        Work {
            particles: model.len(),
            elements,
            resting_elements: resting_elements(model, integrator, elements),
            steps: seconds / dt,
            frames: (seconds / frame_dt).round(),
            runs: 1.0,
            variant_steps: 1.0,
            integrator,
            dt,
            reason: if auto {
                StepReason::Frame
            } else {
                StepReason::Fixed
            },
            implicit_steps: None,
        }
    }

    /// The same estimate with the reason filled in: for an auto step below
    /// the frame, the stiffest spring, the lightest particle and which limit
    /// bounds the step ([`stability::StabilityEstimate::bound`]; one
    /// stability estimate of `model`); and the implicit integrator's step
    /// count.
    pub fn explained(mut self, model: &Model, frame_dt: f64) -> Work {
        let estimate = stability::estimate(model);
        let seconds = self.steps * self.dt;
        if self.reason == StepReason::Frame && self.dt < frame_dt * (1.0 - 1e-12) {
            let integrator = self.integrator;
            let spring = estimate.stiffest_spring.map(|k| {
                let s = &model.springs[k];
                (k, s.i, s.j, s.stiffness)
            });
            let lightest = (
                estimate.lightest_particle,
                model
                    .mass
                    .get(estimate.lightest_particle)
                    .copied()
                    .unwrap_or(0.0),
            );
            let bound = estimate.bound(integrator).unwrap_or(StepBound::Spring);
            self.reason = StepReason::Stability {
                spring,
                omega_max: estimate.omega_max,
                lightest,
                drag_rate: estimate.drag_rate,
                damping_rate: estimate.damping_rate_max,
                tumbling_rate: estimate.tumbling_rate,
                bound,
            };
        }
        self.implicit_steps = estimate
            .auto_step(Integrator::Implicit, frame_dt)
            .map(|h| (seconds / h).ceil())
            .filter(|&n| self.integrator != Integrator::Implicit && n < self.steps);
        self
    }

    /// Particle-steps in all.
    pub fn particle_steps(&self) -> f64 {
        self.particles as f64 * self.steps * self.runs * self.variant_steps
    }

    /// Whether the run is long enough to show its progress ([`LONG_WORK`]).
    pub fn is_long(&self) -> bool {
        self.particle_steps() > LONG_WORK
    }

    /// The estimate as a phrase: "2.8e8 particle-steps (7 particles × 3.96e7
    /// steps of verlet at dt = 2.527e-7 s), about 12 s of one core".
    pub fn describe(&self) -> String {
        let mut runs = if self.runs > 1.0 {
            format!(" × {} runs", quantity(self.runs))
        } else {
            String::new()
        };
        if self.variant_steps != 1.0 {
            let _ = write!(runs, " × {:.2} for the variants' steps", self.variant_steps);
        }
        let base = approximate_duration(self.core_seconds());
        let mut phrase = format!("{base} of one core");
        let resting = approximate_duration(self.core_seconds_resting());
        if resting != base {
            let _ = write!(
                phrase,
                ", up to {resting} while its objects rest on the ground"
            );
        }
        format!(
            "{:.2e} particle-steps ({} particles × {} steps of {} at dt = {:.3e} s{runs}), {phrase}",
            self.particle_steps(),
            self.particles,
            step_count(self.steps),
            self.integrator,
            self.dt,
        )
    }

    /// Seconds of one core the run should take at [`REFERENCE_RATE`] (a
    /// guide: machines differ by 2×).
    pub fn core_seconds(&self) -> f64 {
        self.seconds_of(self.elements)
    }

    /// [`Work::core_seconds`] with every object resting on the ground
    /// ([`Work::resting_elements`]): what the run costs at most.
    pub fn core_seconds_resting(&self) -> f64 {
        self.seconds_of(self.elements + self.resting_elements)
    }

    /// Seconds of one core for `elements` per step over every step of
    /// every run.
    fn seconds_of(&self, elements: usize) -> f64 {
        elements as f64 * self.steps * self.runs * self.variant_steps / REFERENCE_RATE
    }

    /// Why the step is that small, as a phrase (empty for a fixed step or
    /// the frame).
    pub fn why(&self) -> String {
        match &self.reason {
            StepReason::Fixed => "the step is the fixed one asked for".to_string(),
            StepReason::Frame => String::new(),
            StepReason::Stability {
                spring,
                omega_max,
                lightest,
                drag_rate,
                damping_rate,
                tumbling_rate,
                bound,
            } => {
                let spring = spring.map_or(String::new(), |(k, i, j, stiffness)| {
                    format!(
                        "the stiffest spring is spring {k} (particles {i}–{j}, k = {} N/m)",
                        quantity(stiffness)
                    )
                });
                let light = format!(
                    "the lightest particle is particle {} ({} kg)",
                    lightest.0,
                    quantity(lightest.1)
                );
                let bound = match bound {
                    StepBound::Drag => format!("the drag rate γ = {} 1/s", quantity(*drag_rate)),
                    StepBound::Damping => format!(
                        "the damping's fastest rate λ_max(M⁻¹C) = {} 1/s (dashpots and air)",
                        quantity(*damping_rate)
                    ),
                    StepBound::Spring => {
                        format!("the stiffest mode ω_max = {} rad/s", quantity(*omega_max))
                    }
                    StepBound::Tumbling => format!(
                        "the tumbling bound Ω = {} rad/s ({} rad per step)",
                        quantity(*tumbling_rate),
                        stability::MAX_TURN_PER_STEP
                    ),
                };
                let parts: Vec<String> = [spring, light]
                    .into_iter()
                    .filter(|p| !p.is_empty())
                    .collect();
                format!(
                    "the {} stability limit is set by {bound}: {}",
                    self.integrator,
                    parts.join(", ")
                )
            }
        }
    }

    /// Refuses the run when it exceeds `limit` particle-steps; the error
    /// explains the step from `model` ([`Work::explained`]).
    ///
    /// # Errors
    /// [`StepError::TooMuchWork`]: the estimate, the reason and the remedy
    /// for `run`.
    pub fn check(
        &self,
        model: &Model,
        frame_dt: f64,
        limit: f64,
        run: RunKind,
    ) -> Result<(), StepError> {
        if self.particle_steps() <= limit {
            return Ok(());
        }
        Err(StepError::TooMuchWork(Box::new(WorkError {
            work: self.clone().explained(model, frame_dt),
            limit,
            run,
        })))
    }
}

/// A duration in words: "under a second", "about 40 s", "about 12
/// minutes", "about 3 hours", "about 5 days".
pub fn approximate_duration(seconds: f64) -> String {
    if !seconds.is_finite() {
        "longer than the age of the universe".to_string()
    } else if seconds < 1.0 {
        "under a second".to_string()
    } else if seconds < 120.0 {
        format!("about {seconds:.0} s")
    } else if seconds < 7200.0 {
        format!("about {:.0} minutes", seconds / 60.0)
    } else if seconds < 3.0 * 86400.0 {
        format!("about {:.0} hours", seconds / 3600.0)
    } else {
        format!("about {} days", quantity((seconds / 86400.0).round()))
    }
}

/// What a [`WorkError`] refuses: which remedies apply to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunKind {
    /// One leaf's drop.
    Drop,
    /// A scene (its integrator is set in its file).
    Scene,
    /// A breeding run (its drops always use the default integrator).
    Breed,
}

/// One way to make a refused run fit its work limit.
#[derive(Clone, Debug, PartialEq)]
pub enum Remedy {
    /// Integrate implicitly, stable at any step: `steps` of them.
    Implicit {
        /// Steps the implicit integrator takes.
        steps: f64,
        /// Set in the scene file rather than as a setting.
        in_scene_file: bool,
    },
    /// Let the model take a longer step, or simulate less time.
    SoftenOrShorten {
        /// The springs' damping sets the step, not their stiffness.
        damping: bool,
        /// The duration is the scene file's (settings may override it).
        in_scene_file: bool,
    },
    /// A breeding run: a softer or heavier prototype, or fewer drops.
    SmallerBreed,
    /// Raise the work limit to `needed` particle-steps.
    RaiseWorkLimit {
        /// The work limit that admits the run.
        needed: f64,
    },
}

impl std::fmt::Display for Remedy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Remedy::Implicit {
                steps,
                in_scene_file: false,
            } => write!(
                f,
                "use `{}` (stable at any step: {} steps)",
                Setting::Integrator.set("implicit"),
                step_count(steps)
            ),
            Remedy::Implicit {
                steps,
                in_scene_file: true,
            } => write!(
                f,
                "set `integrator = \"implicit\"` in the scene file (stable at any step: {} steps)",
                step_count(steps)
            ),
            Remedy::SoftenOrShorten {
                damping,
                in_scene_file,
            } => {
                // What to change in the model: the springs' stiffness, or,
                // where the damping's fastest rate sets the step, their
                // damping.
                let soften = if damping {
                    "lower the springs' and hinges' damping"
                } else {
                    "soften the stiffest springs"
                };
                let duration = Setting::Duration;
                if in_scene_file {
                    write!(
                        f,
                        "{soften} or make the lightest particles heavier, or shorten `duration` (or {duration})"
                    )
                } else {
                    write!(
                        f,
                        "{soften} or make the lightest particles heavier, or shorten {duration}"
                    )
                }
            }
            Remedy::SmallerBreed => write!(
                f,
                "breeding drops every leaf with verlet at its auto step: soften or weight the prototype, or lower {}, {} or {}",
                Setting::Duration,
                Setting::Population,
                Setting::Generations
            ),
            Remedy::RaiseWorkLimit { needed } => write!(
                f,
                "raise the limit with `{}`",
                Setting::MaxWork.set(format_args!("{needed:.1e}"))
            ),
        }
    }
}

/// A run refused before it starts because its estimated work exceeds the
/// limit: the estimate, why the step is so small, and what to do.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}", self.message())]
pub struct WorkError {
    /// The estimate.
    pub work: Work,
    /// The limit it exceeds, particle-steps.
    pub limit: f64,
    /// What is refused.
    pub run: RunKind,
}

impl WorkError {
    /// What would make the run fit, most direct first.
    pub fn remedies(&self) -> Vec<Remedy> {
        let w = &self.work;
        let mut remedies = Vec::new();
        if let Some(steps) = w.implicit_steps {
            match self.run {
                RunKind::Drop | RunKind::Scene => remedies.push(Remedy::Implicit {
                    steps,
                    in_scene_file: self.run == RunKind::Scene,
                }),
                RunKind::Breed => {}
            }
        }
        let damping = matches!(
            w.reason,
            StepReason::Stability {
                bound: StepBound::Damping,
                ..
            }
        );
        remedies.push(match self.run {
            RunKind::Drop | RunKind::Scene => Remedy::SoftenOrShorten {
                damping,
                in_scene_file: self.run == RunKind::Scene,
            },
            RunKind::Breed => Remedy::SmallerBreed,
        });
        remedies.push(Remedy::RaiseWorkLimit {
            needed: w.particle_steps() * 1.01,
        });
        remedies
    }

    fn message(&self) -> String {
        let w = &self.work;
        let what = match self.run {
            RunKind::Drop => "this drop",
            RunKind::Scene => "this scene",
            RunKind::Breed => "this breeding run",
        };
        let why = w.why();
        let why = if why.is_empty() {
            String::new()
        } else {
            format!("; {why}")
        };
        let remedies: Vec<String> = self.remedies().iter().map(Remedy::to_string).collect();
        // The limit in the estimate's own time, so both read alike.
        let per_step = w.core_seconds() / w.particle_steps();
        let limit_time = if per_step.is_finite() && per_step > 0.0 {
            format!(
                " ({} of one core for this model)",
                approximate_duration(self.limit * per_step)
            )
        } else {
            String::new()
        };
        format!(
            "{what} needs about {} — more than the limit of {:.1e} particle-steps{limit_time}{why}. To run it: {}",
            w.describe(),
            self.limit,
            remedies.join("; ")
        )
    }
}

/// A step count for a message: whole below a million, then scientific;
/// "over 1e308" when it overflows.
fn step_count(steps: f64) -> String {
    if steps.is_finite() && steps < 1e6 {
        format!("{:.0}", steps.ceil())
    } else if steps.is_finite() {
        format!("{steps:.2e}")
    } else {
        "over 1e308".to_string()
    }
}

/// Steps `state` with step `dt`, which need not divide `frame_dt`, until
/// `frames` frames have passed, calling `on_frame(k, positions)` at frame 0
/// and at every frame time k·`frame_dt`. A frame that falls inside a step
/// gets the cubic Hermite interpolant through the positions and velocities
/// at both ends of that step: its error, O(dt⁴) for smooth motion, stays
/// below the integrators' own O(dt²) or better, and it lets the step be as
/// long as stability allows instead of a divisor of the frame.
///
/// On return `state` is at the end of the last step, at or just past the
/// last frame.
pub fn run_sampled(
    model: &Model,
    state: &mut State,
    integrator: Integrator,
    dt: f64,
    frame_dt: f64,
    frames: u64,
    mut on_frame: impl FnMut(u64, &[Vector3<f64>]),
) -> Result<RunStats, SimError> {
    run_sampled_until(model, state, integrator, dt, frame_dt, frames, |k, x| {
        on_frame(k, x);
        Ok(())
    })
}

/// A frame that a caller of [`run_sampled_until`] or [`run_frames_until`]
/// found bad: a pose fit that is not finite though the particles are.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseFault {
    /// The particle that dominates the mass-weighted sums.
    pub particle: usize,
    /// Its mass-weighted offset m·|x − c|, kg·m (may be non-finite).
    pub value: f64,
}

impl PoseFault {
    /// The fault of a pose that is not finite: the particle with the
    /// largest mass-weighted offset from the centre `c` (from the origin if
    /// `c` is not finite), among `members` of the model (all if `None`).
    pub fn of(model: &Model, x: &[Vector3<f64>], c: &Vector3<f64>, members: &[usize]) -> PoseFault {
        let centre = if c.iter().all(|v| v.is_finite()) {
            *c
        } else {
            Vector3::zeros()
        };
        let (particle, value) = x
            .iter()
            .zip(members)
            .map(|(p, &i)| (i, model.mass[i] * (p - centre).norm()))
            .fold(
                (members.first().copied().unwrap_or(0), -1.0f64),
                |best, cur| {
                    if (!cur.1.is_finite() && best.1.is_finite()) || cur.1 > best.1 {
                        cur
                    } else {
                        best
                    }
                },
            );
        PoseFault { particle, value }
    }
}

/// [`run_sampled`] with an `on_frame` that may stop the run: a
/// [`PoseFault`] it returns becomes the simulator's diagnosis of the step
/// that reached that frame ([`SimError::Diverged`], quantity `pose`).
pub fn run_sampled_until(
    model: &Model,
    state: &mut State,
    integrator: Integrator,
    dt: f64,
    frame_dt: f64,
    frames: u64,
    mut on_frame: impl FnMut(u64, &[Vector3<f64>]) -> Result<(), PoseFault>,
) -> Result<RunStats, SimError> {
    let t0 = state.time;
    let mut sim = Simulator::new(model, integrator);
    let fault = |sim: &mut Simulator, state: &State, f: PoseFault| {
        let step = sim.steps().saturating_sub(1);
        sim.diagnose(model, state, dt, step, f.particle, "pose", f.value)
    };
    if let Err(f) = on_frame(0, &state.position) {
        return Err(fault(&mut sim, state, f));
    }
    let start = Instant::now();
    let broken_before = state.broken_springs();
    let n = state.position.len();
    let mut x0 = state.position.clone();
    let mut v0 = state.velocity.clone();
    let mut sample = vec![Vector3::zeros(); n];
    let mut k = 1;
    while k <= frames {
        // Step ends counted from t0, so the clock carries no summed round-off.
        let begin = sim.steps() as f64 * dt;
        let end = (sim.steps() + 1) as f64 * dt;
        // The start of the step is needed only if a frame falls inside it
        // (the same test as below, for the earliest frame not yet sampled).
        if within(k as f64 * frame_dt, begin, dt) < 1.0 - 1e-12 {
            x0.copy_from_slice(&state.position);
            v0.copy_from_slice(&state.velocity);
        }
        sim.step(model, state, dt)?;
        while k <= frames && k as f64 * frame_dt <= end * (1.0 + 1e-12) {
            let s = within(k as f64 * frame_dt, begin, dt);
            let sampled = if s >= 1.0 - 1e-12 {
                on_frame(k, &state.position)
            } else {
                hermite(
                    &x0,
                    &v0,
                    &state.position,
                    &state.velocity,
                    dt,
                    s,
                    &mut sample,
                );
                on_frame(k, &sample)
            };
            if let Err(f) = sampled {
                return Err(fault(&mut sim, state, f));
            }
            k += 1;
        }
        state.time = t0 + end;
    }
    Ok(RunStats::of(
        &sim,
        dt,
        frames as f64 * frame_dt,
        start,
        state.broken_springs() - broken_before,
    ))
}

/// Where time `t` falls in the step [begin, begin + dt], as s ∈ [0, 1]
/// (the sampling of [`run_sampled_until`], shared with lockstep drops).
#[inline]
pub fn within(t: f64, begin: f64, dt: f64) -> f64 {
    ((t - begin) / dt).clamp(0.0, 1.0)
}

/// The cubic Hermite interpolant at s ∈ [0, 1] of a step of length `h`
/// from (x0, v0) to (x1, v1).
pub fn hermite(
    x0: &[Vector3<f64>],
    v0: &[Vector3<f64>],
    x1: &[Vector3<f64>],
    v1: &[Vector3<f64>],
    h: f64,
    s: f64,
    out: &mut [Vector3<f64>],
) {
    let s2 = s * s;
    let s3 = s2 * s;
    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    let h10 = (s3 - 2.0 * s2 + s) * h;
    let h01 = 3.0 * s2 - 2.0 * s3;
    let h11 = (s3 - s2) * h;
    for i in 0..out.len() {
        out[i] = h00 * x0[i] + h10 * v0[i] + h01 * x1[i] + h11 * v1[i];
    }
}

/// The frame loop of scenes: steps `state` through `frames` frames of
/// length `frame_dt` with step `dt`
/// (which must divide `frame_dt`), calling `on_frame(k, state)` at frame 0
/// and after each frame.
pub fn run_frames(
    model: &Model,
    state: &mut State,
    integrator: Integrator,
    dt: f64,
    frame_dt: f64,
    frames: u64,
    mut on_frame: impl FnMut(u64, &State),
) -> Result<RunStats, SimError> {
    run_frames_until(model, state, integrator, dt, frame_dt, frames, |k, s| {
        on_frame(k, s);
        Ok(())
    })
}

/// [`run_frames`] with an `on_frame` that may stop the run, as
/// [`run_sampled_until`].
pub fn run_frames_until(
    model: &Model,
    state: &mut State,
    integrator: Integrator,
    dt: f64,
    frame_dt: f64,
    frames: u64,
    mut on_frame: impl FnMut(u64, &State) -> Result<(), PoseFault>,
) -> Result<RunStats, SimError> {
    let steps_per_frame = (frame_dt / dt).round().max(1.0) as u64;
    let t0 = state.time;
    let mut sim = Simulator::new(model, integrator);
    let fault = |sim: &mut Simulator, state: &State, f: PoseFault| {
        let step = sim.steps().saturating_sub(1);
        sim.diagnose(model, state, dt, step, f.particle, "pose", f.value)
    };
    if let Err(f) = on_frame(0, state) {
        return Err(fault(&mut sim, state, f));
    }
    let start = Instant::now();
    let broken_before = state.broken_springs();
    for k in 1..=frames {
        for _ in 0..steps_per_frame {
            sim.step(model, state, dt)?;
        }
        // Pin the clock to the frame grid so output times carry no round-off drift.
        state.time = t0 + k as f64 * frame_dt;
        if let Err(f) = on_frame(k, state) {
            return Err(fault(&mut sim, state, f));
        }
    }
    Ok(RunStats::of(
        &sim,
        dt,
        frames as f64 * frame_dt,
        start,
        state.broken_springs() - broken_before,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leaf::LeafSpec;
    use crate::physics::integrate::Divergence;

    /// The estimate's "up to" counts what objects resting on the ground
    /// cost: every rigid member a contact of its body's solve, and under
    /// Verlet a second force evaluation; without a ground there is none, and
    /// the phrase says it only where it changes the duration.
    #[test]
    fn resting_on_the_ground_is_counted_only_with_a_ground() {
        use crate::physics::model::{Ground, RigidGroup};
        let leaf = LeafSpec::load("a").unwrap().model().unwrap();
        let mut parts = crate::physics::model::ModelParts {
            mass: leaf.mass.clone(),
            fixed: leaf.fixed.clone(),
            rest_position: leaf.rest_position.clone(),
            triangles: leaf.triangles.clone(),
            aero: leaf.aero,
            gravity: leaf.gravity,
            rigid: vec![RigidGroup {
                members: (0..leaf.len()).collect(),
            }],
            ..Default::default()
        };
        let airborne = Model::new(parts.clone()).unwrap();
        parts.ground = Some(Ground {
            height: -1.0,
            static_friction: 0.5,
            kinetic_friction: 0.4,
            restitution: 0.0,
        });
        let grounded = Model::new(parts).unwrap();
        let of = |m: &Model, i| Work::of(m, i, 1e-3, true, 1e4, 1.0 / 60.0);
        assert_eq!(of(&airborne, Integrator::Verlet).resting_elements, 0);
        let verlet = of(&grounded, Integrator::Verlet);
        let symplectic = of(&grounded, Integrator::Symplectic);
        let members = grounded.len() * RESTING_CONTACT_COST;
        assert_eq!(symplectic.resting_elements, members);
        assert_eq!(verlet.resting_elements, members + verlet.elements);
        assert!(verlet.core_seconds_resting() > verlet.core_seconds());
        assert!(
            verlet
                .describe()
                .contains("while its objects rest on the ground")
        );
        assert!(
            !of(&airborne, Integrator::Verlet)
                .describe()
                .contains("up to")
        );
        // A run too short for the difference to show says one duration.
        let short = Work::of(&grounded, Integrator::Verlet, 1e-3, true, 0.01, 1.0 / 60.0);
        assert!(!short.describe().contains("up to"), "{}", short.describe());
    }

    /// A frame whose pose the caller finds not finite stops the run with the
    /// simulator's diagnosis of the step that reached it.
    #[test]
    fn a_pose_fault_stops_the_run_with_the_diagnosis_of_its_step() {
        let model = LeafSpec::load("a").unwrap().model().unwrap();
        let mut state = State::at_rest(&model);
        let (dt, frame_dt) = (1e-3, 1.0 / 240.0);
        let err = run_sampled_until(
            &model,
            &mut state,
            Integrator::Verlet,
            dt,
            frame_dt,
            10,
            |k, _| {
                if k == 3 {
                    Err(PoseFault {
                        particle: 4,
                        value: f64::INFINITY,
                    })
                } else {
                    Ok(())
                }
            },
        )
        .unwrap_err();
        let SimError::Diverged(d) = &err else {
            panic!("{err}");
        };
        let d: &Divergence = d;
        // Frame 3 at 12.5 ms is reached by step 12 (0-based) of 1 ms.
        assert_eq!((d.step, d.particle, d.quantity), (12, 4, "pose"));
        let text = err.to_string();
        assert!(
            text.contains("pose") && text.contains("step 12") && text.contains("particle 4"),
            "{text}"
        );
        assert!(
            text.contains("dominant force term") && text.contains("likely cause"),
            "{text}"
        );
        assert!(!text.contains("NaN") && !text.contains("inf "), "{text}");
    }

    #[test]
    fn quantities_in_messages_are_short() {
        assert_eq!(quantity(69905.89149035318), "69906");
        assert_eq!(quantity(4.0 / 3.0), "1.333");
        assert_eq!(quantity(0.0013333333333), "0.001333");
        assert_eq!(quantity(2400.0), "2400");
        assert_eq!(quantity(1e8), "1.000e8");
        assert_eq!(quantity(7.217e-6), "7.217e-6");
    }

    /// A narrow heavy strip under the unsteady law steps at its tumbling
    /// bound, and its work says so (not the drag rate or a spring).
    #[test]
    fn a_tumbling_strips_step_is_explained_by_the_tumbling_bound() {
        use crate::leaf::AeroSpec;
        use crate::leaf::plates::{PlateShape, plate};
        let model = plate(
            PlateShape::Rectangle,
            0.005,
            5.0,
            0.28,
            AeroSpec::unsteady(),
        )
        .unwrap()
        .model()
        .unwrap();
        let frame_dt = 1.0 / 240.0;
        let dt = resolve_step(&model, Integrator::Verlet, TimeStep::Auto, frame_dt).unwrap();
        let work = Work::of(&model, Integrator::Verlet, dt, true, 10.0, frame_dt)
            .explained(&model, frame_dt);
        match &work.reason {
            StepReason::Stability { bound, .. } => assert_eq!(*bound, StepBound::Tumbling),
            other => panic!("{other:?}"),
        }
        assert!(work.why().contains("tumbling bound"), "{}", work.why());
    }

    /// The work of a stiff leaf is explained by its stiffest spring, and the
    /// refusal names the remedies.
    #[test]
    fn a_refusal_names_the_stiffest_spring_and_the_remedies() {
        let mut spec = LeafSpec::load("a").unwrap();
        for s in &mut spec.springs {
            s.stiffness = 1e8;
        }
        let model = spec.model().unwrap();
        let frame_dt = 1.0 / 240.0;
        let dt = resolve_step(&model, Integrator::Verlet, TimeStep::Auto, frame_dt).unwrap();
        let work = Work::of(&model, Integrator::Verlet, dt, true, 10.0, frame_dt);
        // 10 s at the auto step: about 4e7 steps of 7 particles.
        assert!(
            (2e8..4e8).contains(&work.particle_steps()),
            "{}",
            work.describe()
        );
        let err = work
            .check(&model, frame_dt, MAX_WORK / 10.0, RunKind::Drop)
            .unwrap_err();
        let StepError::TooMuchWork(refused) = &err else {
            panic!("not refused for its work: {err}");
        };
        // The remedies as data: the implicit step, then the limit that
        // admits the run, above its estimate.
        let remedies = refused.remedies();
        assert!(matches!(remedies[0], Remedy::Implicit { steps, .. } if steps == 2400.0));
        assert!(
            matches!(remedies.last(), Some(&Remedy::RaiseWorkLimit { needed })
            if needed > work.particle_steps())
        );
        let text = err.to_string();
        // Unspelled by a front end, the settings read as their keys.
        for w in [
            "spring 0",
            "k = 1.000e8 N/m",
            "`integrator = implicit` (stable at any step: 2400 steps)",
            "`max_work = ",
        ] {
            assert!(text.contains(w), "no {w:?} in {text}");
        }
        assert!(
            work.check(&model, frame_dt, MAX_WORK, RunKind::Drop)
                .is_ok()
        );
    }
}
