//! The search: CMA-ES ([`crate::breed::cmaes`]) over the free parameters,
//! each scaled to [0, 1] of its bounds, a generation's scene runs spread
//! over the threads; and random search with the same budget as the
//! baseline it must beat. Every sample comes from its own seeded stream and
//! results are gathered in sample order, so the same seed gives the same
//! history on any number of threads.

use super::problem::{Evaluation, Problem};
use crate::breed::cmaes::CmaState;
use crate::breed::selection::stream_seed;
use crate::util::bad_input::BadInput;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rand_distr::{Distribution, Uniform};
use rayon::prelude::*;

/// The random baseline's stream (never a generation number).
const RANDOM_STREAM: u64 = u64::MAX - 1;
/// CMA-ES's starting step in the unit box: a third of each bound's range.
const START_SIGMA: f64 = 0.3;

/// How to search.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Settings {
    /// Scene runs CMA-ES may make (random search makes as many more).
    pub budget: usize,
    /// Seed of every sample.
    pub seed: u64,
    /// Worker threads (0: every core).
    pub threads: usize,
}

/// Which search made an evaluation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// CMA-ES.
    Cma,
    /// Random search, the baseline.
    Random,
}

impl Method {
    /// The name in the history.
    pub fn name(self) -> &'static str {
        match self {
            Method::Cma => "cma-es",
            Method::Random => "random",
        }
    }
}

/// One scene run of the search.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// Which search.
    pub method: Method,
    /// CMA-ES's generation (0 for random search).
    pub generation: usize,
    /// The free values.
    pub values: Vec<f64>,
    /// Its judgement.
    pub evaluation: Evaluation,
}

/// What a search found.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// Every run, CMA-ES's first, in the order sampled.
    pub history: Vec<Record>,
    /// CMA-ES's best run (its index in `history`).
    pub best: usize,
    /// Random search's best run (its index in `history`).
    pub baseline: usize,
    /// CMA-ES's generations.
    pub generations: usize,
}

impl Outcome {
    /// CMA-ES's best record.
    pub fn best(&self) -> &Record {
        &self.history[self.best]
    }

    /// Random search's best record.
    pub fn baseline(&self) -> &Record {
        &self.history[self.baseline]
    }
}

/// CMA-ES's samples per generation for `n` parameters: the usual
/// 4 + ⌊3 ln n⌋, at least 6 so a generation keeps a few cores busy.
pub fn lambda(n: usize) -> usize {
    (4 + (3.0 * (n.max(1) as f64).ln()).floor() as usize).max(6)
}

/// Searches `problem`'s free parameters for its goals: CMA-ES with
/// `settings.budget` runs, then random search with as many;
/// `progress(done, total, best so far)` after each batch.
///
/// # Errors
/// A budget of 0, or a thread pool that cannot start.
pub fn search(
    problem: &Problem,
    settings: &Settings,
    mut progress: impl FnMut(usize, usize, &Record),
) -> Result<Outcome, BadInput> {
    if settings.budget == 0 {
        return Err(BadInput {
            file: problem.file.clone(),
            line: None,
            field: "budget".into(),
            reason: "a budget of 0 scene runs: give at least 1".into(),
        });
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()
        .map_err(|e| BadInput {
            file: problem.file.clone(),
            line: None,
            field: "threads".into(),
            reason: format!("cannot start the threads: {e}"),
        })?;
    let n = problem.free.len();
    let total = 2 * settings.budget;
    let run_all = |units: &[Vec<f64>]| -> Vec<(Vec<f64>, Evaluation)> {
        pool.install(|| {
            units
                .par_iter()
                .map(|u| {
                    let values = problem.values(u);
                    let e = problem.evaluate(&values);
                    (values, e)
                })
                .collect()
        })
    };
    let better = |a: &Record, b: &Record| a.evaluation.objective < b.evaluation.objective;
    let mut history: Vec<Record> = Vec::with_capacity(total);
    let mut best: Option<usize> = None;

    let mut cma = CmaState::start(vec![0.5; n], &vec![1.0; n], START_SIGMA, lambda(n));
    let mut generation = 0;
    while history.len() < settings.budget {
        let size = cma.lambda.min(settings.budget - history.len());
        let units: Vec<Vec<f64>> = (0..size)
            .map(|i| {
                cma.sample(&mut Xoshiro256PlusPlus::seed_from_u64(stream_seed(
                    settings.seed,
                    generation as u64,
                    i as u64,
                )))
            })
            .collect();
        let results = run_all(&units);
        // Ranked best first, ties by sample order: the update learns from
        // the points in the unit box.
        let mut order: Vec<usize> = (0..size).collect();
        order.sort_by(|&a, &b| {
            results[a]
                .1
                .objective
                .total_cmp(&results[b].1.objective)
                .then(a.cmp(&b))
        });
        if size >= 2 {
            let ranked: Vec<Vec<f64>> = order.iter().map(|&k| units[k].clone()).collect();
            cma.update(&ranked);
        }
        for (values, evaluation) in results {
            history.push(Record {
                method: Method::Cma,
                generation,
                values,
                evaluation,
            });
            let k = history.len() - 1;
            if best.is_none_or(|b| better(&history[k], &history[b])) {
                best = Some(k);
            }
        }
        generation += 1;
        progress(
            history.len(),
            total,
            &history[best.expect("a run was made")],
        );
    }
    let best = best.expect("a budget of at least 1 makes a run");

    let uniform = Uniform::new(0.0, 1.0).expect("a valid range");
    let mut baseline: Option<usize> = None;
    let batch = lambda(n);
    let mut done = 0;
    while done < settings.budget {
        let size = batch.min(settings.budget - done);
        let units: Vec<Vec<f64>> = (done..done + size)
            .map(|e| {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(
                    settings.seed,
                    RANDOM_STREAM,
                    e as u64,
                ));
                (0..n).map(|_| uniform.sample(&mut rng)).collect()
            })
            .collect();
        for (values, evaluation) in run_all(&units) {
            history.push(Record {
                method: Method::Random,
                generation: 0,
                values,
                evaluation,
            });
            let k = history.len() - 1;
            if baseline.is_none_or(|b| better(&history[k], &history[b])) {
                baseline = Some(k);
            }
        }
        done += size;
        progress(
            history.len(),
            total,
            &history[baseline.expect("a run was made")],
        );
    }
    Ok(Outcome {
        history,
        best,
        baseline: baseline.expect("a budget of at least 1 makes a run"),
        generations: generation,
    })
}
