//! Selection and variation: ranking, tournaments, the 1/5 success rule for
//! the variation scale, and the seeded random streams that make every
//! generation the same bytes whatever process derives it.

use super::least_squares;
use super::population::{Checkpoint, Child, GenerationSummary, Individual, OutcomeCounts, Plan};
use super::settings::{BreedSettings, Strategy};
use super::strategy::{cma_children, search_bounds};
use crate::leaf::Bounds;
use crate::leaf::LeafSpec;
use crate::leaf::genome::{Genome, mutate};
use crate::motion::classify::MotionClass;
use rand::RngExt;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// Variation scale rule (Rechenberg's 1/5 success rule): after each
/// generation, if more than a fifth of the children scored at least as well
/// as their parents, widen the variation by 1.22 (e^0.2), else narrow it by
/// 0.82 (e^-0.2); clamped to [`MIN_SCALE`, `MAX_SCALE`]. As the population
/// converges on the target fewer children improve, so the variation shrinks
/// as the paper's second round did by hand.
pub const SUCCESS_TARGET: f64 = 0.2;
/// Smallest variation scale.
pub const MIN_SCALE: f64 = 0.05;
/// Largest variation scale.
pub const MAX_SCALE: f64 = 2.0;

pub(crate) fn next_scale(scale: f64, success_rate: f64) -> f64 {
    let factor = if success_rate > SUCCESS_TARGET {
        0.2f64.exp()
    } else {
        (-0.2f64).exp()
    };
    (scale * factor).clamp(MIN_SCALE, MAX_SCALE)
}

/// A well-mixed 64-bit seed for one random stream (SplitMix64 finaliser).
pub fn stream_seed(seed: u64, generation: u64, id: u64) -> u64 {
    let mut z = seed
        .wrapping_add(generation.wrapping_mul(0x9E37_79B9_7F4A_7C15))
        .wrapping_add(id.wrapping_mul(0xBF58_476D_1CE4_E5B9))
        .wrapping_add(0x94D0_49BB_1331_11EB);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The stream id used for parent selection (never an individual's id).
const SELECTION_STREAM: u64 = u64::MAX;

/// Members best first; ties broken by id so the order is deterministic.
pub fn rank(population: &[Individual]) -> Vec<&Individual> {
    let mut v: Vec<&Individual> = population.iter().collect();
    v.sort_by(|a, b| b.eval.score.total_cmp(&a.eval.score).then(a.id.cmp(&b.id)));
    v
}

/// The summary of a generation; `target`, for a run toward a class, counts
/// its [`super::novelty::distinct`] leaves.
pub(crate) fn summarise(
    generation: usize,
    population: &[Individual],
    scale: f64,
    success_rate: f64,
    target: Option<MotionClass>,
) -> GenerationSummary {
    let mut counts = OutcomeCounts::default();
    for i in population {
        counts[i.eval.kind()] += 1;
    }
    let best = rank(population)[0];
    GenerationSummary {
        generation,
        counts,
        best_score: best.eval.score,
        mean_score: population.iter().map(|i| i.eval.score).sum::<f64>() / population.len() as f64,
        best_id: best.id,
        scale,
        success_rate,
        best_distance: best.eval.distance,
        best_kept: best.eval.kept,
        releases: best.eval.releases,
        distinct: target.map_or(0, |t| {
            super::novelty::distinct(&rank(population), t, usize::MAX).len()
        }),
    }
}

/// Share of generation 0 that are varied copies of the prototype; the rest
/// are uniform draws over its bounds. Around a prototype rare classes are
/// rare indeed (issue 19: 0.13 % lilters around prototype A, 12 % among
/// uniform draws), while its neighbourhood is where its own class lives.
pub const INITIAL_COPY_SHARE: f64 = 0.5;

/// How many of generation 0's children are copies of the prototype (the
/// first ones): [`INITIAL_COPY_SHARE`] of them, none for random search, all
/// for the GA of a run written before uniform draws (see
/// [`BreedSettings::uniform_start`]).
pub fn initial_copies(s: &BreedSettings) -> usize {
    match s.strategy {
        Strategy::Random => 0,
        _ if !s.uniform_start => s.population,
        _ => (s.population as f64 * INITIAL_COPY_SHARE).round() as usize,
    }
}

/// Which of `available` start leaves ([`BreedSettings::start`]) take the
/// first of generation 0's `slots` places of prototype copies (the uniform
/// half is kept whole: measured, benches/start-from.sh, a floater run's
/// archive in place of uniform draws found lilters later, not sooner): all of them in
/// order when they fit, else `slots` of them spread evenly over the list
/// (an archive is in cell order, so every region of descent × spin keeps
/// a representative).
fn start_places(available: usize, slots: usize) -> Vec<usize> {
    if available <= slots {
        (0..available).collect()
    } else {
        (0..slots).map(|k| k * available / slots).collect()
    }
}

/// A genome drawn uniformly over the unit box of `template`'s coordinates
/// ([`Genome::coordinates`]): fold angles uniform in degrees, factors
/// log-uniform.
pub fn uniform<R: rand::Rng + ?Sized>(template: &Genome, bounds: &Bounds, rng: &mut R) -> Genome {
    let n = template.values().len();
    let u: Vec<f64> = (0..n).map(|_| rng.random_range(0.0..=1.0)).collect();
    template.with_coordinates(bounds, &u)
}

/// Generation 0's children: copies of the prototype with the first round's
/// variation, an earlier run's leaves where the run starts from one, and
/// (all of them for random search) uniform draws over `bounds`.
fn first_children(s: &BreedSettings, proto: &LeafSpec, bounds: &Bounds) -> Vec<Child> {
    // Generation 0: copies of the prototype with the first round's
    // variation, and (all of it for random search) uniform draws
    // over the bounds.
    let g0 = Genome::of_prototype(proto);
    let copies = initial_copies(s);
    let start = start_places(s.start.len(), copies);
    (0..s.population as u64)
        .map(|id| {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(s.seed, 0, id));
            let genome = if let Some(k) = start.get(id as usize) {
                // An earlier run's leaf, as it was, moved into
                // this run's bounds where they are narrower
                // (a --like run holds stiffness at 1).
                s.start[*k].clamped(bounds)
            } else if (id as usize) < copies {
                mutate(&g0, bounds, s.initial_scale, &mut rng)
            } else {
                uniform(&g0, bounds, &mut rng)
            };
            Child {
                id,
                parent: None,
                genome,
                parent_score: f64::NAN,
            }
        })
        .collect()
}

/// The next generation before evaluation: its children, derived
/// deterministically from the checkpoint (none: generation 0, copies of
/// the prototype), and the elites it keeps. Every random draw comes from
/// [`stream_seed`] streams, so any process that holds the run directory
/// derives the same plan.
pub fn plan(s: &BreedSettings, proto: &LeafSpec, checkpoint: Option<&Checkpoint>) -> Plan {
    let bounds = search_bounds(s, proto);
    let (generation, scale, next_id, children, model_children, cma_children) = match checkpoint {
        None => {
            let children = first_children(s, proto, &bounds);
            (0, s.initial_scale, s.population as u64, children, 0, 0)
        }
        Some(cp) => {
            let generation = cp.generation + 1;
            let parents = rank(&cp.population);
            let mut sel = Xoshiro256PlusPlus::seed_from_u64(stream_seed(
                s.seed,
                generation as u64,
                SELECTION_STREAM,
            ));
            let mut next_id = cp.next_id;
            let total = s.population - s.elites;
            let cma = cma_children(s, cp, total);
            let mut children = Vec::with_capacity(total);
            // In a hybrid run toward descriptors, once CMA-ES has started,
            // a few of its places go to Levenberg–Marquardt steps from the
            // evaluated population (least_squares): both refine, while the
            // GA's places stay whole to keep other regions reachable.
            let (step_parent, steps) = if s.strategy == Strategy::Hybrid && s.like.is_some() {
                least_squares::steps(&cp.population, &bounds, &Genome::of_prototype(proto))
            } else {
                (None, Vec::new())
            };
            // CMA-ES keeps at least two samples to rank (as cma_children).
            let steps: Vec<Genome> = steps.into_iter().take(cma.saturating_sub(2)).collect();
            let model_children = steps.len();
            let cma = cma - model_children;
            let bred = if s.strategy == Strategy::Random {
                0
            } else {
                total - cma - model_children
            };
            for _ in 0..bred {
                // Tournament: the best of `tournament` uniformly drawn members.
                let pick = (0..s.tournament)
                    .map(|_| sel.random_range(0..parents.len()))
                    .min()
                    .expect("tournament size ≥ 1");
                let parent = parents[pick];
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(
                    s.seed,
                    generation as u64,
                    next_id,
                ));
                let genome = mutate(&parent.genome, &bounds, cp.scale, &mut rng);
                children.push(Child {
                    id: next_id,
                    parent: Some(parent.id),
                    genome,
                    parent_score: parent.eval.score,
                });
                next_id += 1;
            }
            for genome in steps {
                children.push(Child {
                    id: next_id,
                    parent: step_parent.map(|p: &Individual| p.id),
                    genome,
                    parent_score: step_parent.map_or(f64::NAN, |p| p.eval.score),
                });
                next_id += 1;
            }
            if s.strategy == Strategy::Random {
                let template = Genome::of_prototype(proto);
                for _ in 0..total {
                    let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(
                        s.seed,
                        generation as u64,
                        next_id,
                    ));
                    children.push(Child {
                        id: next_id,
                        parent: None,
                        genome: uniform(&template, &bounds, &mut rng),
                        parent_score: f64::NAN,
                    });
                    next_id += 1;
                }
            }
            if let Some(state) = cp.cmaes.as_ref().filter(|_| cma > 0) {
                // CMA-ES samples, each from its own id's stream.
                let template = Genome::of_prototype(proto);
                for _ in 0..cma {
                    let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(
                        s.seed,
                        generation as u64,
                        next_id,
                    ));
                    let u = state.sample(&mut rng);
                    children.push(Child {
                        id: next_id,
                        parent: None,
                        genome: template.with_coordinates(&bounds, &u),
                        parent_score: f64::NAN,
                    });
                    next_id += 1;
                }
            }
            (generation, cp.scale, next_id, children, model_children, cma)
        }
    };
    let elites: Vec<Individual> = match checkpoint {
        None => Vec::new(),
        Some(cp) => rank(&cp.population)
            .into_iter()
            .take(s.elites)
            .map(|i| Individual {
                elite: true,
                ..i.clone()
            })
            .collect(),
    };
    Plan {
        generation,
        scale,
        next_id,
        children,
        elites,
        cma_children,
        model_children,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_fifth_rule_widens_on_success_and_narrows_otherwise() {
        assert!(next_scale(1.0, 0.5) > 1.0);
        assert!(next_scale(1.0, 0.1) < 1.0);
        assert_eq!(next_scale(MIN_SCALE, 0.0), MIN_SCALE);
        assert_eq!(next_scale(MAX_SCALE, 1.0), MAX_SCALE);
    }

    #[test]
    fn streams_differ_by_generation_and_id() {
        let a = stream_seed(1, 0, 0);
        assert_ne!(a, stream_seed(1, 0, 1));
        assert_ne!(a, stream_seed(1, 1, 0));
        assert_ne!(a, stream_seed(2, 0, 0));
        assert_eq!(a, stream_seed(1, 0, 0));
    }
}
