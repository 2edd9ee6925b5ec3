//! `classify_fall`: naming the motion of one 10 s fall recorded at 240 Hz
//! (2401 poses) — a floater (prototype A), a spinner (the fixture spinning
//! about the vertical) and a lilter (prototype B). The falls are simulated
//! once, outside the timing; criterion's time per iteration is one
//! classification. And `video_1.5s`: what video of the tumbler fixture
//! gives, 1.5 s of positions at 98 fps (148 samples, no orientation),
//! classified from its path (`video_1.5s_areas`: with two area signals).

use criterion::{Criterion, criterion_group, criterion_main};
use leafmagic::leaf::LeafSpec;
use leafmagic::motion::classify::{MotionClass, classify};
use leafmagic::motion::describe::{Descriptors, MotionTarget};
use leafmagic::motion::trajectory::AreaSignal;
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
    let model = LeafSpec::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/a-tumbler.toml"
    ))
    .unwrap()
    .model()
    .unwrap();
    let fall = drop_leaf(&model, &DropParams::default())
        .unwrap()
        .trajectory;
    let times: Vec<f64> = (0..148).map(|k| 5.0 + k as f64 / 98.0).collect();
    let posed = fall.sampled_at(&times);
    let mut video = posed.without_orientation();
    let chord = model.chord();
    assert!(classify(&video, chord).path.is_some());
    group.bench_function("video_1.5s", |b| {
        b.iter(|| black_box(classify(black_box(&video), chord)))
    });
    for (k, d) in [[0.77, 0.0, -0.64], [0.40, 0.49, -0.77]].iter().enumerate() {
        video.areas.push(AreaSignal {
            name: format!("area{}", k + 1),
            values: posed
                .orientation
                .iter()
                .map(|q| {
                    (q * nalgebra::Vector3::z())
                        .dot(&nalgebra::Vector3::from(*d))
                        .abs()
                })
                .collect(),
        });
    }
    group.bench_function("video_1.5s_areas", |b| {
        b.iter(|| black_box(classify(black_box(&video), chord)))
    });
    group.finish();
}

criterion_group!(benches, classify_fall);
criterion_main!(benches);
