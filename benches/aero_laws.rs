//! `aero_laws`: prototype A falling 10 simulated seconds under the paper's
//! linear law and under the unsteady law (`[aero] law = "unsteady"`), each
//! as `drop` runs it: `--dt auto`, so the time includes choosing the step
//! (under the unsteady law that measures the air's rates by some thousand
//! force evaluations, [`leafmagic::physics::aero::unsteady::drag_rate`]).
//! The bound: the unsteady law at most 2× the linear law's cost.
//! `stepping` pairs time the same drops at the step fixed beforehand, and
//! `choose_step` pairs the choice of the step alone (what `drop` adds).
//! Run with `cargo bench --bench aero_laws`; all are timed in the same run.

use criterion::{Criterion, criterion_group, criterion_main};
use leafmagic::leaf::{LeafSpec, PROTOTYPE_A};
use leafmagic::physics::params::TimeStep;
use leafmagic::physics::run;
use leafmagic::sim::drop::{self, DropParams, drop_leaf};
use std::hint::black_box;

fn aero_laws(c: &mut Criterion) {
    let start = PROTOTYPE_A.find("[aero]").unwrap();
    let end = start + PROTOTYPE_A[start..].find("\n[bounds]").unwrap();
    let unsteady = format!(
        "{}[aero]\nlaw = \"unsteady\"\n{}",
        &PROTOTYPE_A[..start],
        &PROTOTYPE_A[end..]
    );
    let mut group = c.benchmark_group("aero_laws");
    group.sample_size(10);
    for (name, text) in [
        ("linear_drop_10s", PROTOTYPE_A.to_string()),
        ("unsteady_drop_10s", unsteady),
    ] {
        let model = LeafSpec::from_toml(&text, name).unwrap().model().unwrap();
        let defaults = DropParams::default();
        let dt = run::resolve_step(
            &model,
            defaults.integrator,
            TimeStep::Auto,
            1.0 / drop::FRAME_RATE,
        )
        .unwrap();
        eprintln!("aero_laws: {name} at dt = {dt:.4e} s");
        let auto = DropParams {
            seconds: 10.0,
            ..defaults
        };
        let fixed = DropParams {
            dt: TimeStep::Fixed(dt),
            ..auto
        };
        group.bench_function(format!("{name}_choose_step"), |b| {
            b.iter(|| {
                black_box(
                    run::resolve_step(
                        &model,
                        defaults.integrator,
                        TimeStep::Auto,
                        1.0 / drop::FRAME_RATE,
                    )
                    .unwrap(),
                )
            })
        });
        group.bench_function(name, |b| {
            b.iter(|| black_box(drop_leaf(&model, &auto).unwrap()))
        });
        group.bench_function(format!("{name}_stepping"), |b| {
            b.iter(|| black_box(drop_leaf(&model, &fixed).unwrap()))
        });
    }
    group.finish();
}

criterion_group!(benches, aero_laws);
criterion_main!(benches);
