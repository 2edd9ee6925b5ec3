//! Accuracy past the horizon: in a long or chaotic fall, small differences
//! grow until two runs are unrelated point by point, so the error at T says
//! nothing. What should not depend on the step is the *kind* of motion and
//! its statistics. For each integrator and step this runs a small ensemble of
//! drops released a hair apart, classifies each (see [`crate::motion::classify`]),
//! and compares the majority class, the mean descent speed and the rotation
//! rate with those at the finest step (docs/design/numerics.md, "Error against
//! work", step 5, with DiffEqDevTools-style 1.96 σ/√N bands).
//!
//! The horizon itself is measured with twin runs at the finest RK4 step,
//! released [`TWIN_SEPARATION`] chords apart: it is the time at which their
//! RMS particle separation first exceeds [`HORIZON_SEPARATION`] chords.

use super::error::AccuracyError;
use crate::motion::classify::{self, MotionClass};
use crate::physics::model::Model;
use crate::physics::params::Integrator;
use crate::physics::params::TimeStep;
use crate::sim::drop::{self, DropParams};
use rayon::prelude::*;
use serde::Serialize;

/// Initial separation of the twin runs, chords (δ₀ = 1e-9 L:
/// docs/design/numerics.md, "Error against work", step 5).
pub const TWIN_SEPARATION: f64 = 1e-9;
/// Separation, chords, at which the twin runs count as unrelated.
pub const HORIZON_SEPARATION: f64 = 1e-3;
/// Statistics agree when they differ by less than the largest of their
/// combined 95 % half-widths, this fraction of the finest value, and the
/// statistic's absolute floor ([`DESCENT_FLOOR`], [`ROTATION_FLOOR`]).
pub const STAT_RELATIVE_TOLERANCE: f64 = 0.01;
/// Descent speeds closer than this agree, m/s.
pub const DESCENT_FLOOR: f64 = 1e-3;
/// Rotation rates closer than this agree, turns/s: one turn in 100 s, far
/// below what tells the classes apart (a spinner makes ≥ 1 turn in its
/// window).
pub const ROTATION_FLOOR: f64 = 1e-2;

/// Settings of the long-horizon comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct LongSettings {
    /// Simulated duration of each drop, s.
    pub seconds: f64,
    /// Drops per (integrator, step).
    pub ensemble: usize,
    /// The releases' tilts about x are spread evenly over this many degrees
    /// around `drop`'s default release.
    pub tilt_spread_deg: f64,
    /// Steps are (1/[`drop::FRAME_RATE`]) / 2^k for k = 0 … `halvings`.
    pub halvings: u32,
    /// The integrators compared.
    pub integrators: Vec<Integrator>,
}

impl Default for LongSettings {
    /// 10 s drops, 5 releases 0.1° apart in all, steps 1/240 s … 1/15360 s,
    /// all integrators.
    fn default() -> Self {
        LongSettings {
            seconds: 10.0,
            ensemble: 5,
            tilt_spread_deg: 0.1,
            halvings: 6,
            integrators: Integrator::ALL.to_vec(),
        }
    }
}

/// Mean and 95 % half-width 1.96 σ/√N of one statistic over an ensemble.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Stat {
    /// Mean.
    pub mean: f64,
    /// 1.96 × standard deviation / √N (0 for a single run).
    pub ci95: f64,
}

impl Stat {
    fn of(values: &[f64]) -> Option<Stat> {
        let n = values.len();
        if n == 0 {
            return None;
        }
        let mean = values.iter().sum::<f64>() / n as f64;
        let ci95 = if n > 1 {
            let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
            1.96 * (var / n as f64).sqrt()
        } else {
            0.0
        };
        Some(Stat { mean, ci95 })
    }

    /// Whether `self` agrees with `finest` (see [`STAT_RELATIVE_TOLERANCE`]);
    /// `floor` is the statistic's absolute tolerance.
    pub fn agrees_with(&self, finest: &Stat, floor: f64) -> bool {
        let band = (self.ci95.powi(2) + finest.ci95.powi(2))
            .sqrt()
            .max(STAT_RELATIVE_TOLERANCE * finest.mean.abs())
            .max(floor);
        (self.mean - finest.mean).abs() <= band
    }
}

/// One (integrator, step) of the comparison.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LongRow {
    /// The integrator.
    pub integrator: Integrator,
    /// The step, s.
    pub dt: f64,
    /// Drops that diverged (and are left out of the statistics).
    pub diverged: usize,
    /// The class of each drop that finished.
    pub classes: Vec<MotionClass>,
    /// The most common class (ties: the first in [`LongRow::classes`]).
    pub majority: Option<MotionClass>,
    /// Share of finished drops in the majority class.
    pub agreement: f64,
    /// Mean descent speed over the classification window, m/s.
    pub descent_speed: Option<Stat>,
    /// Rotation rate: total turns about the dominant horizontal axis per
    /// second of the window (rocking and tumbling alike), turns/s.
    pub rotation_rate: Option<Stat>,
}

/// What one integrator's rows say.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LongSummary {
    /// The integrator.
    pub integrator: Integrator,
    /// The majority class at the finest step.
    pub finest_class: Option<MotionClass>,
    /// The largest step from which every finer step gives that class with no
    /// divergence: the class stops changing here.
    pub class_stable_from: Option<f64>,
    /// The largest step from which every finer step's descent speed and
    /// rotation rate agree with the finest step's.
    pub stats_stable_from: Option<f64>,
}

/// The whole comparison.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LongReport {
    /// Duration of each drop, s.
    pub seconds: f64,
    /// Time at which the twin runs separate by [`HORIZON_SEPARATION`]
    /// chords (`None`: not within the run).
    pub horizon_s: Option<f64>,
    /// The step of the twin runs (RK4), s.
    pub horizon_dt: f64,
    /// All rows, by integrator then from the largest step down.
    pub rows: Vec<LongRow>,
    /// Per-integrator findings.
    pub summaries: Vec<LongSummary>,
}

/// Runs the comparison for `model` dropped as `leafmagic drop` drops it.
///
/// # Errors
/// [`AccuracyError::Settings`] for a non-positive duration or empty
/// ensemble; [`AccuracyError::Reference`] if a twin run diverges.
pub fn long_sweep(model: &Model, settings: &LongSettings) -> Result<LongReport, AccuracyError> {
    if !(settings.seconds > 0.0 && settings.seconds.is_finite()) {
        return Err(AccuracyError::Settings(format!(
            "seconds: must be a positive number, got {}",
            settings.seconds
        )));
    }
    if settings.ensemble == 0 {
        return Err(AccuracyError::Settings(
            "ensemble: at least one drop per step is needed".into(),
        ));
    }
    let frame = 1.0 / drop::FRAME_RATE;
    let chord = model.chord();
    let base = DropParams::default().tilt_deg;
    let n = settings.ensemble;
    let tilts: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let u = if n > 1 {
                k as f64 / (n - 1) as f64 - 0.5
            } else {
                0.0
            };
            [base[0] + settings.tilt_spread_deg * u, base[1]]
        })
        .collect();
    let mut rows = Vec::new();
    for &integrator in &settings.integrators {
        for k in 0..=settings.halvings {
            let dt = frame / f64::from(2u32.pow(k));
            let outcomes: Vec<Option<(MotionClass, f64, f64)>> = tilts
                .par_iter()
                .map(|&tilt_deg| {
                    let params = DropParams {
                        integrator,
                        dt: TimeStep::Fixed(dt),
                        seconds: settings.seconds,
                        tilt_deg,
                        record_particles: false,
                    };
                    let result = drop::drop_leaf(model, &params).ok()?;
                    let c = classify::classify(&result.trajectory, chord);
                    let f = &c.features;
                    let window = (f.t_end_s - f.t_start_s).max(f64::MIN_POSITIVE);
                    Some((c.class, f.mean_descent_speed_m_s, f.total_turns / window))
                })
                .collect();
            let done: Vec<_> = outcomes.iter().flatten().copied().collect();
            let classes: Vec<MotionClass> = done.iter().map(|d| d.0).collect();
            let (majority, agreement) = majority(&classes);
            let speeds: Vec<f64> = done.iter().map(|d| d.1).collect();
            let rates: Vec<f64> = done.iter().map(|d| d.2).collect();
            rows.push(LongRow {
                integrator,
                dt,
                diverged: outcomes.len() - done.len(),
                classes,
                majority,
                agreement,
                descent_speed: Stat::of(&speeds),
                rotation_rate: Stat::of(&rates),
            });
        }
    }
    let summaries = settings
        .integrators
        .iter()
        .map(|&i| summarise(i, &rows))
        .collect();
    let horizon_dt = frame / f64::from(2u32.pow(settings.halvings));
    let horizon_s = horizon(model, base, settings.seconds, horizon_dt)?;
    Ok(LongReport {
        seconds: settings.seconds,
        horizon_s,
        horizon_dt,
        rows,
        summaries,
    })
}

fn majority(classes: &[MotionClass]) -> (Option<MotionClass>, f64) {
    let mut best: Option<(MotionClass, usize)> = None;
    for &c in classes {
        let count = classes.iter().filter(|&&d| d == c).count();
        if best.is_none_or(|b| count > b.1) {
            best = Some((c, count));
        }
    }
    match best {
        Some((c, count)) => (Some(c), count as f64 / classes.len() as f64),
        None => (None, 0.0),
    }
}

fn summarise(integrator: Integrator, rows: &[LongRow]) -> LongSummary {
    // Rows of this integrator, largest step first.
    let mine: Vec<&LongRow> = rows.iter().filter(|r| r.integrator == integrator).collect();
    let finest = mine.last();
    let finest_class = finest.and_then(|r| r.majority);
    let class_ok =
        |r: &LongRow| r.diverged == 0 && r.majority.is_some() && r.majority == finest_class;
    let stats_ok = |r: &LongRow| match (finest, r.descent_speed, r.rotation_rate) {
        (Some(f), Some(s), Some(w)) if r.diverged == 0 => {
            matches!((f.descent_speed, f.rotation_rate), (Some(fs), Some(fw)) if s.agrees_with(&fs, DESCENT_FLOOR) && w.agrees_with(&fw, ROTATION_FLOOR))
        }
        _ => false,
    };
    LongSummary {
        integrator,
        finest_class,
        class_stable_from: stable_from(&mine, class_ok),
        stats_stable_from: stable_from(&mine, stats_ok),
    }
}

/// The largest step from which `ok` holds for it and every finer step.
fn stable_from(rows: &[&LongRow], ok: impl Fn(&LongRow) -> bool) -> Option<f64> {
    let mut from = None;
    for r in rows.iter().rev() {
        if ok(r) {
            from = Some(r.dt);
        } else {
            break;
        }
    }
    from
}

/// Twin RK4 drops released [`TWIN_SEPARATION`] chords apart: when their RMS
/// particle separation first exceeds [`HORIZON_SEPARATION`] chords.
fn horizon(
    model: &Model,
    tilt: [f64; 2],
    seconds: f64,
    dt: f64,
) -> Result<Option<f64>, AccuracyError> {
    // A tilt of δ radians moves the tips by about δ × chord/2.
    let delta_deg = (2.0 * TWIN_SEPARATION).to_degrees();
    let twins: Vec<_> = [tilt, [tilt[0] + delta_deg, tilt[1]]]
        .par_iter()
        .map(|&tilt_deg| {
            drop::drop_leaf(
                model,
                &DropParams {
                    integrator: Integrator::Rk4,
                    dt: TimeStep::Fixed(dt),
                    seconds,
                    tilt_deg,
                    record_particles: true,
                },
            )
        })
        .collect();
    let mut frames = Vec::new();
    for t in twins {
        match t {
            Ok(r) => frames.push((r.trajectory.time.clone(), r.particles.unwrap_or_default())),
            Err(drop::DropError::Sim(e)) => return Err(AccuracyError::Reference(e)),
            Err(drop::DropError::Settings(s)) => return Err(AccuracyError::Step(s)),
        }
    }
    let chord = model.chord();
    let (time, a) = &frames[0];
    let b = &frames[1].1;
    Ok(a.iter()
        .zip(b)
        .zip(time)
        .find(|((x, y), _)| super::run::rms_difference(x, y, chord) > HORIZON_SEPARATION)
        .map(|(_, &t)| t))
}
