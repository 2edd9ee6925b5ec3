//! `classify_fall`: naming the motion of one 10 s fall sampled at 240 Hz
//! (2401 poses), for a floater (prototype A) and a spinner (prototype B).

use criterion::{Criterion, criterion_group, criterion_main};
use leafmagic::classify::classify;
use leafmagic::leaf::LeafSpec;
use leafmagic::sim::{DropParams, drop_leaf};
use std::hint::black_box;

fn classify_fall(c: &mut Criterion) {
    let mut group = c.benchmark_group("classify_fall");
    for p in ["a", "b"] {
        let model = LeafSpec::load(p).unwrap().model().unwrap();
        let fall = drop_leaf(&model, &DropParams::default())
            .unwrap()
            .trajectory;
        assert_eq!(fall.len(), 2401);
        let chord = model.chord();
        let class = classify(&fall, chord).class;
        group.bench_function(format!("prototype_{p}_{class}"), |b| {
            b.iter(|| black_box(classify(&fall, chord)))
        });
    }
    group.finish();
}

criterion_group!(benches, classify_fall);
criterion_main!(benches);
