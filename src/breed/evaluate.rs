//! One individual's evaluation: its drop, its classification and its score.

use super::population::{Evaluation, Fall, Outcome};
use super::settings::BreedSettings;
use crate::leaf::LeafSpec;
use crate::leaf::genome::Genome;
use crate::motion::classify::{MotionClass, classify};
use crate::motion::describe::Descriptors;
use crate::physics::model::Model;
use crate::physics::params::TimeStep;
use crate::sim::drop::{DropError, DropParams, DropResult, drop_leaf, drop_leaves, drop_work};
use rayon::prelude::*;

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

/// Children a breed drops side by side in the lanes of one lockstep batch
/// ([`evaluate_lockstep`]): four, the f64 lanes of one AVX2 register.
pub const LOCKSTEP: usize = 4;

/// The drop settings of a breed's evaluations.
fn drop_params(settings: &BreedSettings) -> DropParams {
    DropParams {
        seconds: settings.seconds,
        dt: TimeStep::Auto,
        ..Default::default()
    }
}

fn diverged(error: String, settings: &BreedSettings) -> Evaluation {
    Evaluation {
        outcome: Outcome::Diverged(error),
        score: score(None, 0.0, settings.target),
        distance: None,
    }
}

/// Drops one variant and scores its fall.
pub fn evaluate(proto: &LeafSpec, genome: &Genome, settings: &BreedSettings) -> Evaluation {
    let model = match genome.model(proto) {
        Ok(m) => m,
        Err(e) => return diverged(format!("invalid model: {e}"), settings),
    };
    let drop = drop_leaf(&model, &drop_params(settings));
    scored(&model, drop, settings)
}

/// [`evaluate`] of each of `genomes` (in their order), on the current rayon
/// pool, [`LOCKSTEP`] at a time in the lanes of one batch
/// ([`drop_leaves`]), calling `done` after each. Lanes of a batch step
/// together until the last is done, so children are grouped by their auto
/// step (a batch of similar steps wastes few lane-steps); a remainder, or a
/// child whose model is invalid, is evaluated alone. Every evaluation is the
/// one [`evaluate`] gives, to the bit, however the children are grouped
/// (a lane computes what a lone drop computes), so a breed's results
/// depend neither on the grouping nor on the threads.
pub fn evaluate_lockstep(
    proto: &LeafSpec,
    genomes: &[&Genome],
    settings: &BreedSettings,
    done: &(dyn Fn(&Evaluation) + Sync),
) -> Vec<Evaluation> {
    let params = drop_params(settings);
    // (step, index) of every child that can share a batch.
    let models: Vec<Option<(Model, f64)>> = genomes
        .par_iter()
        .map(|g| {
            let model = g.model(proto).ok()?;
            let dt = drop_work(&model, &params).ok()?.dt;
            Some((model, dt))
        })
        .collect();
    let mut order: Vec<(f64, usize)> = models
        .iter()
        .enumerate()
        .filter_map(|(i, m)| m.as_ref().map(|(_, dt)| (*dt, i)))
        .collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let groups: Vec<&[(f64, usize)]> = order.chunks(LOCKSTEP).collect();
    let batched: Vec<(usize, Evaluation)> = groups
        .par_iter()
        .flat_map_iter(|group| {
            let evals: Vec<Evaluation> = if group.len() == LOCKSTEP {
                let model = |k: usize| &models[group[k].1].as_ref().expect("batchable").0;
                let drops = drop_leaves::<LOCKSTEP>(std::array::from_fn(model), &params);
                drops
                    .into_iter()
                    .enumerate()
                    .map(|(k, d)| scored(model(k), d, settings))
                    .collect()
            } else {
                group
                    .iter()
                    .map(|&(_, i)| evaluate(proto, genomes[i], settings))
                    .collect()
            };
            evals.iter().for_each(done);
            group.iter().map(|&(_, i)| i).zip(evals).collect::<Vec<_>>()
        })
        .collect();
    let alone: Vec<(usize, Evaluation)> = models
        .par_iter()
        .enumerate()
        .filter(|(_, m)| m.is_none())
        .map(|(i, _)| {
            let eval = evaluate(proto, genomes[i], settings);
            done(&eval);
            (i, eval)
        })
        .collect();
    let mut out: Vec<Option<Evaluation>> = vec![None; genomes.len()];
    for (i, eval) in batched.into_iter().chain(alone) {
        out[i] = Some(eval);
    }
    out.into_iter()
        .map(|e| e.expect("every child evaluated once"))
        .collect()
}

/// The evaluation of `model`'s drop: its classification and score.
fn scored(
    model: &Model,
    drop: Result<DropResult, DropError>,
    settings: &BreedSettings,
) -> Evaluation {
    match drop {
        Err(e) => diverged(e.to_string(), settings),
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
