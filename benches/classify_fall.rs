//! `classify_fall`: naming the motion of one 10 s fall recorded at 240 Hz
//! (2401 poses) — a floater (prototype A), a spinner (the fixture spinning
//! about the vertical) and a lilter (prototype B). The falls are simulated
//! once, outside the timing; criterion's time per iteration is one
//! classification.

use criterion::{Criterion, criterion_group, criterion_main};
use leafmagic::leaf::LeafSpec;
use leafmagic::motion::classify::{MotionClass, classify};
use leafmagic::motion::describe::{Descriptors, MotionTarget};
use leafmagic::sim::drop::{DropParams, drop_leaf};
use std::hint::black_box;

fn classify_fall(c: &mut Criterion) {
    let fixture = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/a-spinner.toml");
    let cases = [
        ("a", MotionClass::Floater),
        (fixture, MotionClass::Spinner),
        ("b", MotionClass::Lilter),
    ];
    let mut group = c.benchmark_group("classify_fall");
    for (leaf, class) in cases {
        let model = LeafSpec::load(leaf).unwrap().model().unwrap();
        let fall = drop_leaf(&model, &DropParams::default())
            .unwrap()
            .trajectory;
        assert_eq!(fall.len(), 2401, "10 s at 240 Hz");
        let chord = model.chord();
        assert_eq!(classify(&fall, chord).class, class, "{leaf}");
        group.bench_function(class.as_str(), |b| {
            b.iter(|| black_box(classify(black_box(&fall), chord)))
        });
        // What `breed --like` adds per fall: the descriptors and the
        // distance to an example (here the fall itself).
        let target = MotionTarget::like(
            leaf,
            chord,
            &Descriptors::of(&classify(&fall, chord)).unwrap(),
        );
        group.bench_function(format!("{}_described", class.as_str()), |b| {
            b.iter(|| {
                let d = Descriptors::of(&classify(black_box(&fall), chord)).unwrap();
                black_box(target.distance(&d))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, classify_fall);
criterion_main!(benches);
