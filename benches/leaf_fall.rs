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

criterion_group!(benches, leaf_fall);
criterion_main!(benches);
