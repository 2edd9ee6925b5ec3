//! One individual's evaluation: its drop, its classification and its score.

use super::population::{Evaluation, Fall, Outcome};
use super::settings::BreedSettings;
use crate::leaf::LeafSpec;
use crate::leaf::genome::Genome;
use crate::motion::classify::{MotionClass, classify};
use crate::motion::describe::Descriptors;
use crate::physics::params::TimeStep;
use crate::sim::drop::{DropParams, drop_leaf};

/// Score of a fall bred toward motion descriptors: as [`score`] for the
/// gate's class, but within it 1 + 1/(1 + d), so that the closest falls
/// rank first and every fall that passes the class gate outranks every one
/// that does not. `class` is `None` for a diverged drop.
pub fn like_score(class: Option<MotionClass>, margin: f64, distance: Option<f64>) -> f64 {
    match (distance, class) {
        (Some(d), _) if d.is_finite() => 1.0 + 1.0 / (1.0 + d),
        (_, None) => -1.0,
        (_, Some(MotionClass::Undetermined)) => 0.0,
        _ => 0.1 * margin,
    }
}

/// Score of a fall for a target class: diverged (`class` `None`) −1, the
/// worst; undetermined 0; another class 0.1 × its margin (a clear motion is
/// a better parent than none, but never as good as the target); the target
/// 1 + margin, so that among members of the target class those far from
/// every class boundary (robust to small changes) rank first.
pub fn score(class: Option<MotionClass>, margin: f64, target: MotionClass) -> f64 {
    match class {
        None => -1.0,
        Some(c) if c == target => 1.0 + margin,
        Some(MotionClass::Undetermined) => 0.0,
        Some(_) => 0.1 * margin,
    }
}

/// Drops one variant and scores its fall.
pub fn evaluate(proto: &LeafSpec, genome: &Genome, settings: &BreedSettings) -> Evaluation {
    let diverged = |error: String| Evaluation {
        outcome: Outcome::Diverged(error),
        score: score(None, 0.0, settings.target),
        distance: None,
    };
    let model = match genome.model(proto) {
        Ok(m) => m,
        Err(e) => return diverged(format!("invalid model: {e}")),
    };
    let params = DropParams {
        seconds: settings.seconds,
        dt: TimeStep::Auto,
        ..Default::default()
    };
    match drop_leaf(&model, &params) {
        Err(e) => diverged(e.to_string()),
        Ok(result) => {
            let c = classify(&result.trajectory, model.chord());
            let f = &c.features;
            let distance = settings.like.as_ref().and_then(|target| {
                let d = target.distance(&Descriptors::of(&c).ok()?);
                d.is_finite().then_some(d)
            });
            let score = match &settings.like {
                Some(_) => like_score(Some(c.class), f.margin, distance),
                None => score(Some(c.class), f.margin, settings.target),
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
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn score_orders_diverged_undetermined_other_target() {
        let t = MotionClass::Floater;
        let s = |c: Option<MotionClass>, m: f64| score(c, m, t);
        let (floater, spinner) = (Some(MotionClass::Floater), Some(MotionClass::Spinner));
        assert!(s(None, 0.0) < s(Some(MotionClass::Undetermined), 0.0));
        assert!(s(Some(MotionClass::Undetermined), 0.0) <= s(spinner, 0.0));
        assert!(s(spinner, 1.0) < s(floater, 0.0));
        assert!(s(floater, 0.2) < s(floater, 0.9));
    }
}
