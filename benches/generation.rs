//! `generation`: evaluating one generation of the default breed (100 variants
//! of prototype A, 10 s drops, classified) on 1 and on 2 threads. The ratio
//! of the two times is the parallel speed-up (one drop per leaf).
//! `releases4_threads_2` is the generation as the default breed evaluates
//! it, four releases per leaf in one lockstep batch, and
//! `releases4_alone_threads_2` the same four dropped one after another (the
//! same evaluations to the bit). `like_threads_2` evaluates the
//! same 100 genomes scored toward an example fall (`breed --like`, the
//! tumbling fixture) instead of a class: the same drops, so the difference is
//! the cost of describing each fall and measuring its distance.

use criterion::{Criterion, criterion_group, criterion_main};
use leafmagic::breed::evaluate::evaluate_alone;
use leafmagic::breed::selection::stream_seed;
use leafmagic::breed::{BreedSettings, evaluate};
use leafmagic::leaf::LeafSpec;
use leafmagic::leaf::genome::{Genome, mutate};
use leafmagic::motion::classify::classify;
use leafmagic::motion::describe::{Descriptors, MotionTarget};
use leafmagic::sim::drop::{DropParams, drop_leaf};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;
use std::hint::black_box;

fn generation(c: &mut Criterion) {
    // One drop per leaf (`--releases 1`), as this benchmark has always
    // timed: a default generation drops each leaf `releases` times.
    let settings = BreedSettings {
        releases: 1,
        ..BreedSettings::default_run()
    };
    let proto = LeafSpec::load(&settings.prototype).unwrap();
    let g0 = Genome::of_prototype(&proto);
    let genomes: Vec<Genome> = (0..settings.population as u64)
        .map(|id| {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(settings.seed, 0, id));
            mutate(&g0, &proto.bounds, settings.initial_scale, &mut rng)
        })
        .collect();
    let example_leaf = LeafSpec::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/a-tumbler.toml"
    ))
    .unwrap()
    .model()
    .unwrap();
    let example = drop_leaf(&example_leaf, &DropParams::default()).unwrap();
    let described = Descriptors::of(&classify(&example.trajectory, example_leaf.chord())).unwrap();
    let like = BreedSettings {
        like: Some(MotionTarget::like(
            "a-tumbler",
            example_leaf.chord(),
            &described,
        )),
        ..settings.clone()
    };
    let mut group = c.benchmark_group("generation");
    group.sample_size(10);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        group.bench_function(format!("threads_{threads}"), |b| {
            b.iter(|| {
                pool.install(|| {
                    let evals: Vec<_> = genomes
                        .par_iter()
                        .enumerate()
                        .map(|(id, g)| evaluate(&proto, id as u64, g, &settings))
                        .collect();
                    black_box(evals)
                })
            })
        });
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    group.bench_function("like_threads_2", |b| {
        b.iter(|| {
            pool.install(|| {
                let evals: Vec<_> = genomes
                    .par_iter()
                    .enumerate()
                    .map(|(id, g)| evaluate(&proto, id as u64, g, &like))
                    .collect();
                black_box(evals)
            })
        })
    });
    let four = BreedSettings {
        releases: 4,
        ..settings.clone()
    };
    type Eval =
        fn(&LeafSpec, u64, &Genome, &BreedSettings) -> leafmagic::breed::population::Evaluation;
    let ways: [(&str, Eval); 2] = [
        ("releases4_threads_2", evaluate),
        ("releases4_alone_threads_2", evaluate_alone),
    ];
    for (name, eval) in ways {
        group.bench_function(name, |b| {
            b.iter(|| {
                pool.install(|| {
                    let evals: Vec<_> = genomes
                        .par_iter()
                        .enumerate()
                        .map(|(id, g)| eval(&proto, id as u64, g, &four))
                        .collect();
                    black_box(evals)
                })
            })
        });
    }
    group.finish();
}

criterion_group!(benches, generation);
criterion_main!(benches);
