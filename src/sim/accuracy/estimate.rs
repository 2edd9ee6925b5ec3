//! The error estimate a run records about itself: how far, after T seconds,
//! a run with this integrator and step is from the converged motion of its
//! model, in chords. Breeding records it in each `run.toml`; since every
//! child of a prototype shares the prototype's numerics, the estimate is
//! computed once per prototype and settings and then served from a cache.
//!
//! The estimate is one run at `dt` against an RK4 reference on the same
//! model, both from the same initial state and with spring breaking switched
//! off (see [`super::smooth_model`]). The reference starts at
//! h_ref ≤ min(dt/16, RK4's stable step / 2) and is halved until its
//! self-difference (h_ref against h_ref/2) is below
//! [`super::REFERENCE_FACTOR`] × the estimated error, or until
//! 2^[`MAX_REFERENCE_LOG2`] steps; [`ErrorEstimate::reference_valid`] says
//! whether that succeeded. For a chaotic fall (a T beyond the horizon, see
//! [`super::long`]) the number is still correct but describes one
//! realisation: pointwise error there means nothing.

use super::error::AccuracyError;
use super::run::{default_release, rms_difference, run_steps, smooth_model};
use crate::physics::model::Model;
use crate::physics::params::Integrator;
use crate::physics::stability;
use crate::physics::state::State;
use crate::util::hash::fnv1a64_hex;
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, VecDeque};
use std::sync::{LazyLock, Mutex};

/// Changes whenever the estimator's method changes, so cached or recorded
/// keys from another method never match.
pub const ESTIMATOR_VERSION: u32 = 1;
/// The reference never takes more than 2^this steps.
pub const MAX_REFERENCE_LOG2: u32 = 22;
/// A reference self-difference below this many chords (50 pm for a 5 cm
/// leaf) is the round-off of f64 summed over a reference run: the reference
/// is as converged as it can be shown to be.
pub const ROUND_OFF_CHORDS: f64 = 1e-9;
/// Entries kept by the process-wide cache of [`error_estimate`].
pub const GLOBAL_CACHE_CAPACITY: usize = 64;

/// How accurate a run of a model is, and how well that is known.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorEstimate {
    /// The integrator of the run.
    pub integrator: Integrator,
    /// Its time step, s.
    pub dt: f64,
    /// The simulated duration the error refers to, s.
    pub seconds: f64,
    /// RMS over particles of the position error at `seconds`, in chords.
    pub error: f64,
    /// The chord (the error's length scale), m.
    pub chord: f64,
    /// The finer reference step, s.
    pub reference_dt: f64,
    /// RMS difference of the reference at 2 × `reference_dt` and at
    /// `reference_dt`, in chords (bounds the reference's own error).
    pub reference_self_difference: f64,
    /// Whether the self-difference is below [`super::REFERENCE_FACTOR`] ×
    /// `error`; when false, `error` is only an upper bound of about that size.
    pub reference_valid: bool,
    /// Springs whose breaking was switched off for the estimate.
    pub breaking_disabled: usize,
    /// 16 hex digits (FNV-1a, 64 bits) of the model, the initial state, the
    /// settings and [`ESTIMATOR_VERSION`]: what the cache is keyed by, and
    /// what ties a recorded estimate to its prototype.
    pub key: String,
}

/// Computes the estimate for a run of `model` from `initial` with
/// `integrator` and step `dt` over `seconds`, without any cache.
///
/// # Errors
/// [`AccuracyError::Settings`] if `dt` or `seconds` is not positive and
/// finite or `dt` does not divide `seconds`; [`AccuracyError::Run`] if the
/// run diverges at `dt`; [`AccuracyError::Reference`] if the reference does.
pub fn compute(
    model: &Model,
    initial: &State,
    integrator: Integrator,
    dt: f64,
    seconds: f64,
) -> Result<ErrorEstimate, AccuracyError> {
    let steps = steps_for(dt, seconds)?;
    let (smooth, breaking_disabled) = smooth_model(model);
    let chord = smooth.chord();
    let run = run_steps(&smooth, initial, integrator, dt, steps);
    if let Some(e) = run.error {
        return Err(AccuracyError::Run(e));
    }
    // The reference's first step: well below dt and safely inside RK4's
    // stable range.
    let rk4_limit = stability::estimate(&smooth)
        .dt_max(Integrator::Rk4)
        .unwrap_or(f64::INFINITY);
    let target = (dt / 16.0).min(0.5 * rk4_limit);
    let mut j = (seconds / target).log2().ceil().max(0.0) as u32;
    j = j.min(MAX_REFERENCE_LOG2 - 1);
    let mut coarse = reference_run(&smooth, initial, seconds, j)?;
    loop {
        let fine = reference_run(&smooth, initial, seconds, j + 1)?;
        let self_difference = rms_difference(&coarse, &fine, chord);
        let error = rms_difference(&run.state.position, &fine, chord);
        let valid = self_difference < super::run::REFERENCE_FACTOR * error;
        // Once the reference agrees with itself to round-off, halving again
        // only adds round-off (a fall the run itself gets exact, such as a
        // leaf without air, never validates): stop rather than run on to
        // 2^MAX_REFERENCE_LOG2 steps (9.5 s for a drop of 2 ms).
        let at_round_off = self_difference < ROUND_OFF_CHORDS;
        if valid || at_round_off || j + 1 >= MAX_REFERENCE_LOG2 {
            return Ok(ErrorEstimate {
                integrator,
                dt,
                seconds,
                error,
                chord,
                reference_dt: seconds / f64::from(2u32.pow(j + 1)),
                reference_self_difference: self_difference,
                reference_valid: valid,
                breaking_disabled,
                key: fnv1a64_hex(&key_bytes(model, initial, integrator, dt, seconds)),
            });
        }
        coarse = fine;
        j += 1;
    }
}

fn reference_run(
    model: &Model,
    initial: &State,
    seconds: f64,
    j: u32,
) -> Result<Vec<nalgebra::Vector3<f64>>, AccuracyError> {
    let n = 1u64 << j;
    let run = run_steps(model, initial, Integrator::Rk4, seconds / n as f64, n);
    match run.error {
        Some(e) => Err(AccuracyError::Reference(e)),
        None => Ok(run.state.position),
    }
}

/// The number of steps of `dt` in `seconds`, if it is whole.
fn steps_for(dt: f64, seconds: f64) -> Result<u64, AccuracyError> {
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(AccuracyError::Settings(format!(
            "dt: must be a positive number of seconds, got {dt}"
        )));
    }
    if !(seconds > 0.0 && seconds.is_finite()) {
        return Err(AccuracyError::Settings(format!(
            "seconds: must be a positive number, got {seconds}"
        )));
    }
    let n = (seconds / dt).round();
    if n > crate::physics::run::MAX_STEPS {
        return Err(AccuracyError::Settings(format!(
            "dt: {dt:.3e} s is {n:.2e} steps over {seconds} s, more than the limit of {:.0e}",
            crate::physics::run::MAX_STEPS
        )));
    }
    if n < 1.0 || (n * dt - seconds).abs() > 1e-9 * seconds {
        return Err(AccuracyError::Settings(format!(
            "dt: {dt} s does not divide the duration {seconds} s into a whole number of steps"
        )));
    }
    Ok(n as u64)
}

/// A bounded cache of estimates, keyed by the exact bytes of the model, the
/// initial state and the settings (so two keys never collide), evicting the
/// oldest entry when full. It counts what it computes, so callers and tests
/// can see it does not recompute.
#[derive(Clone, Debug)]
pub struct ErrorCache {
    capacity: usize,
    entries: HashMap<Vec<u8>, ErrorEstimate>,
    order: VecDeque<Vec<u8>>,
    computations: u64,
    hits: u64,
}

impl ErrorCache {
    /// An empty cache holding at most `capacity` (≥ 1) estimates.
    pub fn new(capacity: usize) -> ErrorCache {
        ErrorCache {
            capacity: capacity.max(1),
            entries: HashMap::new(),
            order: VecDeque::new(),
            computations: 0,
            hits: 0,
        }
    }

    /// The estimate for these settings: from the cache if it is there, else
    /// computed with [`compute`] and stored. Failures are not cached.
    pub fn estimate(
        &mut self,
        model: &Model,
        initial: &State,
        integrator: Integrator,
        dt: f64,
        seconds: f64,
    ) -> Result<ErrorEstimate, AccuracyError> {
        let key = key_bytes(model, initial, integrator, dt, seconds);
        if let Some(e) = self.lookup(&key) {
            return Ok(e);
        }
        let estimate = compute(model, initial, integrator, dt, seconds)?;
        self.insert(key, estimate.clone());
        Ok(estimate)
    }

    fn lookup(&mut self, key: &[u8]) -> Option<ErrorEstimate> {
        let hit = self.entries.get(key).cloned();
        if hit.is_some() {
            self.hits += 1;
        }
        hit
    }

    fn insert(&mut self, key: Vec<u8>, estimate: ErrorEstimate) {
        self.computations += 1;
        if self.entries.contains_key(&key) {
            return;
        }
        if self.entries.len() >= self.capacity {
            if let Some(old) = self.order.pop_front() {
                self.entries.remove(&old);
            }
        }
        self.order.push_back(key.clone());
        self.entries.insert(key, estimate);
    }

    /// Estimates computed (cache misses that succeeded).
    pub fn computations(&self) -> u64 {
        self.computations
    }

    /// Estimates served from the cache.
    pub fn hits(&self) -> u64 {
        self.hits
    }

    /// Estimates held.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when nothing is cached.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

static GLOBAL: LazyLock<Mutex<ErrorCache>> =
    LazyLock::new(|| Mutex::new(ErrorCache::new(GLOBAL_CACHE_CAPACITY)));

/// The error estimate of a drop of `model` (released as `leafmagic drop`
/// releases it, see [`default_release`]) with `integrator` and step `dt`
/// over `seconds`, from a process-wide cache.
///
/// ```no_run
/// use leafmagic::{leaf::LeafSpec, physics::params::Integrator, sim::accuracy};
/// let model = LeafSpec::load("a")?.model()?;
/// let e = accuracy::error_estimate(&model, Integrator::Verlet, 1.0 / 1200.0, 1.0)?;
/// println!("error after 1 s: {:.1e} chords (valid reference: {})", e.error, e.reference_valid);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// As [`compute`].
pub fn error_estimate(
    model: &Model,
    integrator: Integrator,
    dt: f64,
    seconds: f64,
) -> Result<ErrorEstimate, AccuracyError> {
    error_estimate_from(model, &default_release(model), integrator, dt, seconds)
}

/// [`error_estimate`] from any initial state (a scene's).
///
/// # Errors
/// As [`compute`].
pub fn error_estimate_from(
    model: &Model,
    initial: &State,
    integrator: Integrator,
    dt: f64,
    seconds: f64,
) -> Result<ErrorEstimate, AccuracyError> {
    let key = key_bytes(model, initial, integrator, dt, seconds);
    // The lock is not held while computing, so threads estimating different
    // prototypes do not wait for each other (two threads asking for the same
    // new key may both compute it; the result is the same).
    let cached = GLOBAL
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .lookup(&key);
    if let Some(e) = cached {
        return Ok(e);
    }
    let estimate = compute(model, initial, integrator, dt, seconds)?;
    GLOBAL
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .insert(key, estimate.clone());
    Ok(estimate)
}

/// The exact bytes of everything the estimate depends on.
pub fn key_bytes(
    model: &Model,
    initial: &State,
    integrator: Integrator,
    dt: f64,
    seconds: f64,
) -> Vec<u8> {
    let mut k = Vec::with_capacity(64 * model.len() + 64 * model.springs.len());
    let mut f = |x: f64| k.extend_from_slice(&x.to_bits().to_le_bytes());
    f(f64::from(ESTIMATOR_VERSION));
    f(dt);
    f(seconds);
    for (i, m) in model.mass.iter().enumerate() {
        f(*m);
        f(if model.fixed[i] { 1.0 } else { 0.0 });
        f(model.particle_drag[i]);
        model.rest_position[i].iter().for_each(|&x| f(x));
    }
    for s in &model.springs {
        f(s.i as f64);
        f(s.j as f64);
        f(s.rest_length);
        f(s.stiffness);
        f(s.damping);
        f(s.break_strain.unwrap_or(-1.0));
    }
    for t in &model.triangles {
        t.corners.iter().for_each(|&c| f(c as f64));
        f(t.alpha_n);
        f(t.alpha_t);
    }
    model.gravity.iter().for_each(|&x| f(x));
    for (x, v) in initial.position.iter().zip(&initial.velocity) {
        x.iter().chain(v.iter()).for_each(|&c| f(c));
    }
    initial
        .spring_alive
        .iter()
        .for_each(|&a| f(if a { 1.0 } else { 0.0 }));
    f(initial.time);
    k.extend_from_slice(integrator.name().as_bytes());
    k.push(0);
    k.extend_from_slice(format!("{:?}", model.aero).as_bytes());
    k.push(0);
    // The wind's serialised form is its full description.
    k.extend_from_slice(
        serde_json::to_string(&model.wind)
            .unwrap_or_default()
            .as_bytes(),
    );
    k
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_must_divide_the_duration() {
        assert_eq!(steps_for(0.25, 1.0).unwrap(), 4);
        assert!(steps_for(0.3, 1.0).is_err());
        assert!(steps_for(0.0, 1.0).is_err());
        assert!(steps_for(0.1, f64::NAN).is_err());
    }
}
