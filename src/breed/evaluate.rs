//! One individual's evaluation: its drops (one per release attitude), their
//! classification and scores, and the robust score of the lot.

use super::boundary::class_distance;
use super::population::{Evaluation, Fall, Outcome};
use super::robust::{combine, release_attitudes};
use super::settings::BreedSettings;
use crate::leaf::LeafSpec;
use crate::leaf::genome::Genome;
use crate::motion::classify::{MotionClass, classify};
use crate::motion::describe::{Descriptors, root_mean_square};
use crate::physics::model::Model;
use crate::physics::params::TimeStep;
use crate::physics::run::resolve_step;
use crate::sim::drop::{DropError, DropParams, DropResult, FRAME_RATE, drop_leaf, drop_leaves};

/// Releases of one individual dropped side by side in the lanes of one
/// lockstep batch ([`drop_leaves`]): four, the f64 lanes of one AVX2
/// register. The releases share the model and its step, so the lanes are
/// full; each lane computes what a lone drop computes, to the bit.
pub const LOCKSTEP: usize = 4;

/// Score of a fall outside the class it is bred toward: 1 / (1 + D), with D
/// the distance to that class's boundary in the classifier's scale units
/// ([`super::boundary`]); 0 for a fall whose record the rules never judged.
/// In (0, 1], rising to 1 at the boundary, so it grades a leaf by how
/// close it came to the class and never by how deep it sits in another.
pub fn outside_score(boundary: Option<f64>) -> f64 {
    boundary.map_or(0.0, |d| 1.0 / (1.0 + d))
}

/// Score of a fall bred toward motion descriptors: within the target's
/// class gate 1 + 1/(1 + d), so that the closest falls rank first and every
/// fall that passes the gate outranks every one that does not; outside it
/// [`outside_score`] of the distance to the gate's class; −1 for a diverged
/// drop (`class` `None`).
pub fn like_score(class: Option<MotionClass>, distance: Option<f64>, boundary: Option<f64>) -> f64 {
    match (distance, class) {
        (Some(d), _) if d.is_finite() => 1.0 + 1.0 / (1.0 + d),
        (_, None) => -1.0,
        _ => outside_score(boundary),
    }
}

/// Score of a fall for a target class: diverged (`class` `None`) −1, the
/// worst; another class or undetermined [`outside_score`] of its distance
/// `boundary` to the target class, in (0, 1]; the target 1 + margin, so
/// that among members of the target class those far from every class
/// boundary (robust to small changes) rank first. The score is continuous
/// across the class boundary: 1 on both sides.
pub fn score(
    class: Option<MotionClass>,
    margin: f64,
    boundary: Option<f64>,
    target: MotionClass,
) -> f64 {
    match class {
        None => -1.0,
        Some(c) if c == target => 1.0 + margin,
        Some(_) => outside_score(boundary),
    }
}

/// Drops individual `id` from each of its release attitudes
/// ([`release_attitudes`]), [`LOCKSTEP`] at a time in the lanes of one batch,
/// and scores it on the lower median of their scores ([`combine`]).
pub fn evaluate(
    proto: &LeafSpec,
    id: u64,
    genome: &Genome,
    settings: &BreedSettings,
) -> Evaluation {
    evaluate_in(proto, id, genome, settings, true)
}

/// [`evaluate`] with every release dropped alone, one after another: the
/// same evaluation to the bit (tests/integration/batch.rs), kept to measure
/// what the batches gain (benches/generation.rs).
pub fn evaluate_alone(
    proto: &LeafSpec,
    id: u64,
    genome: &Genome,
    settings: &BreedSettings,
) -> Evaluation {
    evaluate_in(proto, id, genome, settings, false)
}

fn evaluate_in(
    proto: &LeafSpec,
    id: u64,
    genome: &Genome,
    settings: &BreedSettings,
    lockstep: bool,
) -> Evaluation {
    let attitudes = release_attitudes(settings.seed, id, settings.releases);
    let model = match genome.model(proto) {
        Ok(m) => m,
        Err(e) => {
            return Evaluation {
                releases: attitudes.len(),
                ..diverged(format!("invalid model: {e}"), attitudes[0])
            };
        }
    };
    let gate = match &settings.like {
        Some(t) => t.class,
        None => Some(settings.target),
    };
    // The step depends on the model alone, not on its attitude: estimated
    // once (what TimeStep::Auto would choose for every drop), not K times.
    let params = DropParams::default();
    let dt = match resolve_step(&model, params.integrator, TimeStep::Auto, 1.0 / FRAME_RATE) {
        Ok(dt) => TimeStep::Fixed(dt),
        Err(_) => TimeStep::Auto,
    };
    let mut drops: Vec<Evaluation> = Vec::with_capacity(attitudes.len());
    for group in attitudes.chunks(if lockstep { LOCKSTEP } else { 1 }) {
        if group.len() == LOCKSTEP {
            let params: [DropParams; LOCKSTEP] =
                std::array::from_fn(|k| release_params(group[k], dt, settings));
            let results = drop_leaves([&model; LOCKSTEP], std::array::from_fn(|k| &params[k]));
            for (tilt, result) in group.iter().zip(results) {
                drops.push(scored(&model, *tilt, result, settings));
            }
        } else {
            drops.extend(
                group
                    .iter()
                    .map(|&tilt| drop_once(&model, tilt, dt, settings)),
            );
        }
    }
    let kept: Vec<bool> = drops
        .iter()
        .map(|e| match (gate, e.fall()) {
            (Some(c), Some(f)) => f.class == c,
            (None, Some(_)) => e.distance.is_some(),
            (_, None) => false,
        })
        .collect();
    combine(drops, &kept)
}

fn diverged(error: String, tilt: [f64; 2]) -> Evaluation {
    Evaluation {
        outcome: Outcome::Diverged(error),
        score: -1.0,
        distance: None,
        releases: 1,
        kept: 0,
        release_deg: tilt,
        residuals: Vec::new(),
        spread: [0.0; 3],
    }
}

/// One drop of `model` released at `tilt` with step `dt`, classified and
/// scored.
pub fn drop_once(
    model: &Model,
    tilt: [f64; 2],
    dt: TimeStep,
    settings: &BreedSettings,
) -> Evaluation {
    scored(
        model,
        tilt,
        drop_leaf(model, &release_params(tilt, dt, settings)),
        settings,
    )
}

/// The drop settings of one release.
fn release_params(tilt: [f64; 2], dt: TimeStep, settings: &BreedSettings) -> DropParams {
    DropParams {
        seconds: settings.seconds,
        dt,
        tilt_deg: tilt,
        ..Default::default()
    }
}

/// The evaluation of one release's drop: its classification and score.
fn scored(
    model: &Model,
    tilt: [f64; 2],
    drop: Result<DropResult, DropError>,
    settings: &BreedSettings,
) -> Evaluation {
    match drop {
        Err(e) => diverged(e.to_string(), tilt),
        Ok(result) => {
            let c = classify(&result.trajectory, model.chord());
            let f = &c.features;
            // Inside the target's gate: the residuals (kept for the hybrid's
            // Levenberg–Marquardt steps) and the distance, their RMS.
            let (distance, residuals) = settings
                .like
                .as_ref()
                .and_then(|target| target.residuals(&Descriptors::of(&c).ok()?))
                .map(|r| (root_mean_square(&r), r))
                .filter(|(d, _)| d.is_finite())
                .map_or((None, Vec::new()), |(d, r)| (Some(d), r));
            let score = match &settings.like {
                Some(t) => like_score(
                    Some(c.class),
                    distance,
                    t.class.and_then(|g| class_distance(f, g)),
                ),
                None => score(
                    Some(c.class),
                    f.margin,
                    class_distance(f, settings.target),
                    settings.target,
                ),
            };
            Evaluation {
                outcome: Outcome::Fell(Fall {
                    class: c.class,
                    regime: c.regime,
                    margin: f.margin,
                    descent_m_s: f.mean_descent_speed_m_s,
                    drift_ratio: f.drift_ratio,
                    net_turns: f.net_turns,
                    yaw_turns: f.yaw_turns,
                    spin_rad_s: std::f64::consts::TAU * (f.net_turns.abs() + f.yaw_turns.abs())
                        / (f.t_end_s - f.t_start_s).max(f64::MIN_POSITIVE),
                    reversals: f.reversals,
                    flips: f.normal_flips,
                    tilt_deg: f.tilt_mean_deg,
                    dt: result.stats.dt,
                }),
                score,
                distance,
                releases: 1,
                kept: 0,
                release_deg: tilt,
                residuals,
                spread: [0.0; 3],
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn score_orders_diverged_outside_target() {
        let t = MotionClass::Floater;
        let s = |c: Option<MotionClass>, m: f64, d: Option<f64>| score(c, m, d, t);
        let (floater, spinner) = (Some(MotionClass::Floater), Some(MotionClass::Spinner));
        let undetermined = Some(MotionClass::Undetermined);
        assert!(s(None, 0.0, None) < s(undetermined, 0.0, None));
        // Outside the class, nearer the boundary is better, whatever the
        // margin inside the wrong class.
        assert!(s(spinner, 1.0, Some(3.0)) < s(spinner, 0.0, Some(0.5)));
        assert!(s(spinner, 0.0, Some(0.5)) < s(undetermined, 0.0, Some(0.2)));
        assert_eq!(s(spinner, 0.7, Some(1.0)), 0.5);
        // Continuous at the boundary, and the target outranks all else.
        assert_eq!(s(spinner, 0.3, Some(0.0)), s(floater, 0.0, Some(0.0)));
        assert!(s(spinner, 1.0, Some(1e-9)) < s(floater, 1e-6, Some(0.0)));
        assert!(s(floater, 0.2, Some(0.0)) < s(floater, 0.9, Some(0.0)));
    }

    #[test]
    fn like_score_gates_then_grades() {
        let sp = Some(MotionClass::Spinner);
        assert_eq!(like_score(None, None, None), -1.0);
        assert_eq!(like_score(sp, Some(0.0), None), 2.0);
        assert!(like_score(sp, Some(0.5), None) > like_score(sp, Some(0.6), None));
        assert!(like_score(sp, None, Some(0.0)) < like_score(sp, Some(1e6), None));
        assert!(like_score(sp, None, Some(2.0)) < like_score(sp, None, Some(1.0)));
    }
}
