//! `studio`: the latency of one studio generation as the page sees it:
//! 12 candidates × 4 releases × 10 s bred from two picks, on 2 threads,
//! from the picks to the last candidate evaluated with the fall it is
//! shown with (`complete`) and to the first (`first_candidate`). The
//! files written after (a few hundred kilobytes, atomically) are not
//! included: they do not delay what the page draws.
//!
//! Run: `nice cargo bench --bench studio`.

use criterion::{Criterion, criterion_group, criterion_main};
use leafmagic::leaf::LeafSpec;
use leafmagic::motion::classify::MotionClass;
use leafmagic::studio::{Session, StudioSettings};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

fn studio(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("leafmagic-bench-studio-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let settings = StudioSettings::new("a", MotionClass::Floater, 1991);
    assert_eq!(
        (settings.grid, settings.releases, settings.seconds),
        (12, 4, 10.0)
    );
    let proto = LeafSpec::load("a").unwrap();
    let session = Session::create(&dir, settings, proto).unwrap();
    let ids = session.current().0.ids.clone();
    let picks = [ids[1], ids[2]];
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let mut group = c.benchmark_group("studio_generation_12x4x10s");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(20));
    group.bench_function("complete", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let pending = session.plan(&picks, None).unwrap();
                let start = Instant::now();
                let done = pool.install(|| pending.evaluate(|_, _, _| {}));
                total += start.elapsed();
                std::hint::black_box(done);
            }
            total
        })
    });
    group.bench_function("first_candidate", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let pending = session.plan(&picks, None).unwrap();
                let first = OnceLock::new();
                let start = Instant::now();
                let done = pool.install(|| {
                    pending.evaluate(|_, _, _| {
                        first.get_or_init(Instant::now);
                    })
                });
                total += *first.get().unwrap() - start;
                std::hint::black_box(done);
            }
            total
        })
    });
    group.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, studio);
criterion_main!(benches);
