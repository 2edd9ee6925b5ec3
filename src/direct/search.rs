//! The search: CMA-ES ([`crate::breed::cmaes`]) over the free parameters,
//! each scaled to [0, 1] of its bounds, a generation's scene runs spread
//! over the threads; and random search with the same budget as the
//! baseline it must beat. Every sample comes from its own seeded stream and
//! results are gathered in sample order, so the same seed gives the same
//! history on any number of threads. After each whole batch the search
//! hands its [`State`] out to be saved, and a saved state goes on to the
//! same history as a search never stopped: each batch's draws derive from
//! the seed and the batch's place, never from an RNG carried along.

use super::problem::{Evaluation, Problem};
use crate::breed::cmaes::CmaState;
use crate::breed::selection::stream_seed;
use crate::util::bad_input::BadInput;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rand_distr::{Distribution, Uniform};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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

/// Where a search stands after a whole batch: all it needs to go on.
/// Random search has begun once `history` holds the budget's CMA-ES runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// CMA-ES's distribution after its last generation.
    pub cma: CmaState,
    /// CMA-ES's generations made.
    pub generation: usize,
    /// Every run so far, in the order sampled.
    pub history: Vec<Record>,
}

/// CMA-ES's samples per generation for `n` parameters: the usual
/// 4 + ⌊3 ln n⌋, at least 6 so a generation keeps a few cores busy.
pub fn lambda(n: usize) -> usize {
    (4 + (3.0 * (n.max(1) as f64).ln()).floor() as usize).max(6)
}

/// Searches `problem`'s free parameters for its goals: CMA-ES with
/// `settings.budget` runs, then random search with as many, going on from
/// `resumed` if given (a state this search, same problem and settings,
/// handed out); `after_batch(state, best so far)` after each batch, the
/// best being CMA-ES's while it runs, then random search's.
///
/// # Errors
/// A budget of 0, a thread pool that cannot start, a resumed state that
/// does not fit the problem, or `after_batch`'s error.
pub fn search<E: From<BadInput>>(
    problem: &Problem,
    settings: &Settings,
    resumed: Option<State>,
    mut after_batch: impl FnMut(&State, &Record) -> Result<(), E>,
) -> Result<Outcome, E> {
    let pool = thread_pool(problem, settings)?;
    let n = problem.free.len();
    let total = 2 * settings.budget;
    if let Some(state) = &resumed {
        check_resumed(problem, settings, state)?;
    }
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
    let mut state = resumed.unwrap_or_else(|| State {
        cma: CmaState::start(vec![0.5; n], &vec![1.0; n], START_SIGMA, lambda(n)),
        generation: 0,
        history: Vec::with_capacity(total),
    });
    let (mut best, mut baseline) = bests(&state.history, settings.budget);
    let State {
        cma,
        generation,
        history,
    } = &mut state;
    while history.len() < settings.budget {
        let size = cma.lambda.min(settings.budget - history.len());
        let units = cma_samples(cma, settings.seed, *generation, size);
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
                generation: *generation,
                values,
                evaluation,
            });
            let k = history.len() - 1;
            if best.is_none_or(|b| better(&history[k], &history[b])) {
                best = Some(k);
            }
        }
        *generation += 1;
        let b = best.expect("a run was made");
        let snapshot = State {
            cma: cma.clone(),
            generation: *generation,
            history: history.clone(),
        };
        after_batch(&snapshot, &history[b])?;
    }
    let best = best.expect("a budget of at least 1 makes a run");

    let batch = lambda(n);
    let mut done = history.len() - settings.budget;
    while done < settings.budget {
        let size = batch.min(settings.budget - done);
        let units = uniform_samples(settings.seed, n, done, size);
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
        let b = baseline.expect("a run was made");
        let snapshot = State {
            cma: cma.clone(),
            generation: *generation,
            history: history.clone(),
        };
        after_batch(&snapshot, &history[b])?;
    }
    Ok(Outcome {
        history: state.history,
        best,
        baseline: baseline.expect("a budget of at least 1 makes a run"),
        generations: state.generation,
    })
}

/// The pool a search runs on; a budget of 0 refused first.
fn thread_pool(problem: &Problem, settings: &Settings) -> Result<rayon::ThreadPool, BadInput> {
    if settings.budget == 0 {
        return Err(BadInput {
            file: problem.file.clone(),
            line: None,
            field: "budget".into(),
            reason: "a budget of 0 scene runs: give at least 1".into(),
        });
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()
        .map_err(|e| BadInput {
            file: problem.file.clone(),
            line: None,
            field: "threads".into(),
            reason: format!("cannot start the threads: {e}"),
        })
}

/// The best of CMA-ES's runs (the first `budget`) and of random search's
/// (the rest) in `history`, as they were found when the runs were made:
/// the first of equal objectives.
fn bests(history: &[Record], budget: usize) -> (Option<usize>, Option<usize>) {
    let better = |a: &Record, b: &Record| a.evaluation.objective < b.evaluation.objective;
    let (mut best, mut baseline): (Option<usize>, Option<usize>) = (None, None);
    for k in 0..history.len() {
        let slot = if k < budget { &mut best } else { &mut baseline };
        if slot.is_none_or(|b| better(&history[k], &history[b])) {
            *slot = Some(k);
        }
    }
    (best, baseline)
}

/// CMA-ES's `size` samples of `generation`, each from its own stream of
/// the seed: the same points whatever the threads and after a resume.
fn cma_samples(cma: &CmaState, seed: u64, generation: usize, size: usize) -> Vec<Vec<f64>> {
    (0..size)
        .map(|i| {
            cma.sample(&mut Xoshiro256PlusPlus::seed_from_u64(stream_seed(
                seed,
                generation as u64,
                i as u64,
            )))
        })
        .collect()
}

/// Random search's runs `done..done + size`, uniform in the unit box, run
/// `e` from stream `e` of the seed's random-search streams.
fn uniform_samples(seed: u64, n: usize, done: usize, size: usize) -> Vec<Vec<f64>> {
    let uniform = Uniform::new(0.0, 1.0).expect("a valid range");
    (done..done + size)
        .map(|e| {
            let mut rng =
                Xoshiro256PlusPlus::seed_from_u64(stream_seed(seed, RANDOM_STREAM, e as u64));
            (0..n).map(|_| uniform.sample(&mut rng)).collect()
        })
        .collect()
}

/// A resumed state must be one this problem and these settings could have
/// reached: a distribution and runs over the free parameters, no more runs
/// than both searches make, CMA-ES's generations covering its runs.
fn check_resumed(problem: &Problem, settings: &Settings, state: &State) -> Result<(), BadInput> {
    let n = problem.free.len();
    let refuse = |field: &str, reason: String| BadInput {
        file: problem.file.clone(),
        line: None,
        field: field.into(),
        reason,
    };
    state
        .cma
        .check(n)
        .map_err(|e| refuse(&format!("checkpoint cma.{}", e.field), e.reason))?;
    if state.history.len() > 2 * settings.budget {
        return Err(refuse(
            "checkpoint history",
            format!(
                "{} runs, more than the {} of a budget of {}",
                state.history.len(),
                2 * settings.budget,
                settings.budget
            ),
        ));
    }
    let cma_runs = state.history.len().min(settings.budget);
    if state.generation * state.cma.lambda < cma_runs
        || state.generation > cma_runs.div_ceil(state.cma.lambda.max(1))
    {
        return Err(refuse(
            "checkpoint generation",
            format!(
                "{} generations of {} do not make the {cma_runs} CMA-ES runs recorded",
                state.generation, state.cma.lambda
            ),
        ));
    }
    if let Some((k, r)) = state.history.iter().enumerate().find(|(k, r)| {
        r.values.len() != n
            || r.evaluation.goals.len() != problem.goals.len()
            || (r.method == Method::Cma) != (*k < settings.budget)
    }) {
        return Err(refuse(
            &format!("checkpoint history[{k}]"),
            format!(
                "a {} run with {} values and {} goals, not one of this search's ({} free parameters, {} goals, the first {} runs CMA-ES's)",
                r.method.name(),
                r.values.len(),
                r.evaluation.goals.len(),
                n,
                problem.goals.len(),
                settings.budget
            ),
        ));
    }
    Ok(())
}
