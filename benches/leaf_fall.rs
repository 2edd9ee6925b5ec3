//! `leaf_fall`: prototype A falling 1 simulated second in still air, with
//! the integrator and step that `drop --dt auto` picks. `drop_1s` is the wall
//! time per simulated second (criterion's time for one iteration is exactly
//! that); `stability_estimate` is the one-off cost of choosing the step,
//! which `drop_1s_with_auto_dt` includes.
//! Before timing, checks that this run is within 1e-3 chord of a fine
//! reference, so the speed is that of an accurate run.

use criterion::{Criterion, criterion_group, criterion_main};
use leafmagic::leaf::LeafSpec;
use leafmagic::physics::integrate::Simulator;
use leafmagic::physics::params::Integrator;
use leafmagic::physics::params::TimeStep;
use leafmagic::physics::run;
use leafmagic::physics::state::State;
use leafmagic::sim::drop;
use leafmagic::sim::drop::{DropParams, drop_leaf};
use std::hint::black_box;

fn end_positions(
    model: &leafmagic::physics::model::Model,
    integrator: Integrator,
    dt: TimeStep,
) -> Vec<nalgebra::Vector3<f64>> {
    let params = DropParams {
        integrator,
        dt,
        seconds: 1.0,
        record_particles: true,
        ..Default::default()
    };
    drop_leaf(model, &params)
        .unwrap()
        .particles
        .unwrap()
        .pop()
        .unwrap()
}

fn leaf_fall(c: &mut Criterion) {
    let model = LeafSpec::load("a").unwrap().model().unwrap();
    let defaults = DropParams {
        seconds: 1.0,
        ..Default::default()
    };
    let reference = end_positions(&model, Integrator::Rk4, TimeStep::Fixed(1.0 / 240.0 / 64.0));
    let fast = end_positions(&model, defaults.integrator, TimeStep::Auto);
    let rms = (fast
        .iter()
        .zip(&reference)
        .map(|(a, b)| (a - b).norm_squared())
        .sum::<f64>()
        / fast.len() as f64)
        .sqrt();
    let error = rms / model.chord();
    let dt = run::resolve_step(
        &model,
        defaults.integrator,
        TimeStep::Auto,
        1.0 / drop::FRAME_RATE,
    )
    .unwrap();
    eprintln!(
        "leaf_fall: {} at dt = {dt:.4e} s; end error {error:.2e} chord against RK4 at h/64",
        defaults.integrator
    );
    assert!(
        error < 1e-3,
        "the benchmarked run is not accurate: {error:e} chord"
    );

    let mut group = c.benchmark_group("leaf_fall");
    // The rate: a drop at the step `--dt auto` picks, given as a fixed step
    // so that choosing it (a one-off cost per leaf, timed below) is not
    // charged to the simulated second.
    let at_auto_dt = DropParams {
        dt: TimeStep::Fixed(dt),
        ..defaults
    };
    group.bench_function("drop_1s", |b| {
        b.iter(|| black_box(drop_leaf(&model, &at_auto_dt).unwrap()))
    });
    group.bench_function("drop_1s_with_auto_dt", |b| {
        b.iter(|| black_box(drop_leaf(&model, &defaults).unwrap()))
    });
    group.bench_function("stability_estimate", |b| {
        b.iter(|| {
            black_box(run::resolve_step(
                &model,
                defaults.integrator,
                TimeStep::Auto,
                1.0 / drop::FRAME_RATE,
            ))
        })
    });
    // The stepping alone, without pose extraction and recording.
    group.bench_function("steps_1s", |b| {
        b.iter(|| {
            let mut state = State::released(
                &model,
                drop::release_rotation(defaults.tilt_deg),
                Default::default(),
            );
            let mut simulator = Simulator::new(&model, defaults.integrator);
            let steps = (1.0 / dt).round() as usize;
            for _ in 0..steps {
                simulator.step(&model, &mut state, dt).unwrap();
            }
            black_box(state)
        })
    });
    group.finish();
}

criterion_group!(benches, leaf_fall, lockstep);
criterion_main!(benches);

/// Lockstep batches (issue 20): four mutated leaves of prototype A, each
/// on its own auto step for one simulated second, stepped one after
/// another by `Simulator` (`scalar_4_leaves_1s`) and together in the lanes
/// of a `Batch` (`batch_4_leaves_1s`, with AVX2 where the CPU has it; with
/// the baseline's SSE2 only; and two batches of two). The lanes
/// end bit for bit where the lone leaves end (tests/integration/batch.rs).
fn lockstep(c: &mut Criterion) {
    use leafmagic::leaf::genome::{Genome, mutate};
    use leafmagic::physics::batch::Batch;
    use rand::SeedableRng;
    let spec = LeafSpec::load("a").unwrap();
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(20);
    let g = Genome::of_prototype(&spec);
    let models: Vec<_> = (0..4)
        .map(|_| {
            mutate(&g, &spec.bounds, 1.0, &mut rng)
                .model(&spec)
                .unwrap()
        })
        .collect();
    let dt: Vec<f64> = models
        .iter()
        .map(|m| {
            run::resolve_step(
                m,
                Integrator::Verlet,
                TimeStep::Auto,
                1.0 / drop::FRAME_RATE,
            )
            .unwrap()
        })
        .collect();
    let steps: Vec<u64> = dt.iter().map(|h| (1.0 / h).round() as u64).collect();
    let states: Vec<State> = models
        .iter()
        .map(|m| State::released(m, drop::release_rotation([10.0, 2.0]), Default::default()))
        .collect();
    let mut group = c.benchmark_group("lockstep");
    group.bench_function("scalar_4_leaves_1s", |b| {
        b.iter(|| {
            for k in 0..4 {
                let mut state = states[k].clone();
                let mut sim = Simulator::new(&models[k], Integrator::Verlet);
                for _ in 0..steps[k] {
                    sim.step(&models[k], &mut state, dt[k]).unwrap();
                }
                black_box(&state);
            }
        })
    });
    fn run_batch<const L: usize>(
        models: &[leafmagic::physics::model::Model],
        states: &[State],
        dt: &[f64],
        steps: &[u64],
        kernel: &str,
    ) {
        let mut batch = Batch::<L>::new(
            std::array::from_fn(|k| &models[k]),
            std::array::from_fn(|k| &states[k]),
            std::array::from_fn(|k| dt[k]),
        )
        .unwrap();
        batch = match kernel {
            "generic" => batch.generic_vectors(),
            "baseline" => batch.baseline_vectors(),
            _ => batch,
        };
        loop {
            let active: [bool; L] = std::array::from_fn(|k| batch.steps()[k] < steps[k]);
            if !active.iter().any(|&a| a) {
                break;
            }
            black_box(batch.step(active));
        }
        black_box(batch.lane(0));
    }
    group.bench_function("batch_4_leaves_1s", |b| {
        b.iter(|| run_batch::<4>(&models, &states, &dt, &steps, "intrinsics"))
    });
    group.bench_function("batch_4_leaves_1s_generic_kernel", |b| {
        b.iter(|| run_batch::<4>(&models, &states, &dt, &steps, "generic"))
    });
    group.bench_function("batch_4_leaves_1s_baseline_vectors", |b| {
        b.iter(|| run_batch::<4>(&models, &states, &dt, &steps, "baseline"))
    });
    group.bench_function("batch_2x2_leaves_1s", |b| {
        b.iter(|| {
            run_batch::<2>(&models[..2], &states[..2], &dt[..2], &steps[..2], "");
            run_batch::<2>(&models[2..], &states[2..], &dt[2..], &steps[2..], "");
        })
    });
    group.finish();
}
