//! `scene_compile`: what the scene compiler saves. Prototype A falls one
//! simulated second in still air (Verlet, the `--dt auto` step):
//!
//! - `compiled`: the terms the model needs ([`Terms::needed`]): gravity,
//!   springs, hinges, still-air aerodynamics;
//! - `all_terms`: the same drop with every term switched on but
//!   contributing zero: the wind sampled from a zero uniform primitive,
//!   particle drag with α = 0, a ground 1 km below, break strains no spring
//!   reaches, the rigid-body pass (over no bodies);
//! - `all_terms_scene_wind`: as `all_terms`, but the wind is the field of
//!   `scenes/inhale.toml` (uniform, Lamb–Oseen vortex, point sink, bounded
//!   uniform, keyframed) with every strength set to 0, which the compiler
//!   prunes: the cost of evaluating a scene-sized field that contributes
//!   nothing;
//! - `+ <term>`: the compiled terms plus one left-out term alone, to show
//!   what each costs;
//! - `scene <name>`: each shipped scene's first 240 steps with every term on
//!   against compiled: what the compiler saves in real scenes;
//! - `skipping <name>`: the 100-leaf scene and the inhale, shockwave and
//!   ground-blow scenes run whole, compiled, with exact per-object skipping
//!   of wind primitives ([`leafmagic::physics::skip`]) against the same run
//!   with skipping off (checked bit-identical first): the ratios of each
//!   round's pair (run side by side), their median and spread.
//!
//! Before timing, the runs are checked bit-identical, so the difference is
//! pure overhead. The ratio of the times is the compiler's gain. On a shared
//! machine criterion's means drift with the neighbours' load, so the bench
//! first times the variants interleaved, round after round, and prints the
//! ratios of their minimum times (the least disturbed runs).

use criterion::{Criterion, criterion_group, criterion_main};
use leafmagic::leaf::LeafSpec;
use leafmagic::physics::field::{Primitive, WindField};
use leafmagic::physics::integrate::Simulator;
use leafmagic::physics::model::Ground;
use leafmagic::physics::model::Model;
use leafmagic::physics::params::Integrator;
use leafmagic::physics::params::TimeStep;
use leafmagic::physics::run;
use leafmagic::physics::state::State;
use leafmagic::physics::terms::Terms;
use leafmagic::sim::drop;
use nalgebra::Vector3;
use std::hint::black_box;

fn fall(model: &Model, terms: Terms, dt: f64, steps: usize) -> State {
    let mut state = State::released(model, drop::release_rotation([10.0, 2.0]), Vector3::zeros());
    let mut simulator = Simulator::with_terms(model, Integrator::Verlet, terms);
    for _ in 0..steps {
        simulator.step(model, &mut state, dt).unwrap();
    }
    state
}

fn scene_compile(c: &mut Criterion) {
    let plain = LeafSpec::load("a").unwrap().model().unwrap();
    let mut everything = plain.clone();
    everything.wind = WindField::new(vec![Primitive::uniform(Vector3::zeros())]);
    everything.particle_drag = vec![0.0; everything.len()];
    everything.ground = Some(Ground {
        height: -1000.0,
        static_friction: 0.5,
        kinetic_friction: 0.4,
        restitution: 0.0,
    });
    for s in &mut everything.springs {
        s.break_strain = Some(1e9);
    }
    let dt = run::resolve_dt(
        &plain,
        Integrator::Verlet,
        TimeStep::Auto,
        1.0 / drop::FRAME_RATE,
    )
    .unwrap();
    let steps = (1.0 / dt).round() as usize;
    let needed = Terms::needed(&plain);
    assert!(!needed.wind && !needed.contact && !needed.breaking && !needed.rigid);
    let a = fall(&plain, needed, dt, steps);
    let b = fall(&everything, Terms::all(), dt, steps);
    assert_eq!(a, b, "the extra terms must contribute exactly zero");

    let mut scene_wind = everything.clone();
    scene_wind.wind = zero_inhale_wind();
    let c2 = fall(&scene_wind, Terms::all(), dt, steps);
    assert_eq!(
        a, c2,
        "the zero-strength scene wind must contribute exactly zero"
    );

    // Each left-out term alone switched back on, to show where the
    // difference goes.
    let one = |set: fn(&mut Terms)| {
        let mut t = needed;
        set(&mut t);
        t
    };
    let variants: [(&str, &Model, Terms); 8] = [
        ("compiled", &plain, needed),
        ("+ wind (zero uniform)", &everything, one(|t| t.wind = true)),
        (
            "+ particle drag",
            &everything,
            one(|t| t.particle_drag = true),
        ),
        ("+ ground contact", &everything, one(|t| t.contact = true)),
        ("+ spring breaking", &everything, one(|t| t.breaking = true)),
        ("+ rigid-body pass", &everything, one(|t| t.rigid = true)),
        ("all_terms", &everything, Terms::all()),
        ("all_terms_scene_wind", &scene_wind, Terms::all()),
    ];
    for (name, model, terms) in &variants {
        assert_eq!(
            a,
            fall(model, *terms, dt, steps),
            "{name} must add exactly zero"
        );
    }
    let mut best = [f64::INFINITY; 8];
    for _ in 0..300 {
        for (k, (_, model, terms)) in variants.iter().enumerate() {
            let start = std::time::Instant::now();
            black_box(fall(model, *terms, dt, steps));
            best[k] = best[k].min(start.elapsed().as_secs_f64());
        }
    }
    for (k, (name, _, _)) in variants.iter().enumerate() {
        eprintln!(
            "scene_compile: {name:<21} minimum {:7.1} µs per simulated second, {:5.1} ns per step, {:.2}x the compiled run",
            best[k] * 1e6,
            best[k] / steps as f64 * 1e9,
            best[k] / best[0]
        );
    }

    shipped_scenes();
    skipping();

    let mut group = c.benchmark_group("scene_compile");
    group.bench_function("compiled", |bench| {
        bench.iter(|| black_box(fall(&plain, needed, dt, steps)))
    });
    group.bench_function("all_terms", |bench| {
        bench.iter(|| black_box(fall(&everything, Terms::all(), dt, steps)))
    });
    group.bench_function("all_terms_scene_wind", |bench| {
        bench.iter(|| black_box(fall(&scene_wind, Terms::all(), dt, steps)))
    });
    group.finish();
}

/// The compiler's gain in the shipped scenes: each scene's first 240 steps
/// compiled against the same steps with every term on (checked
/// bit-identical first), minimum times of 20 interleaved rounds.
fn shipped_scenes() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for name in [
        "hover",
        "shockwave",
        "ground-blow",
        "inhale",
        "swings",
        "rocking-bin",
        "tear",
    ] {
        let scene = leafmagic::sim::scene::Scene::load(&dir.join(format!("{name}.toml"))).unwrap();
        let model = &scene.model;
        let dt =
            run::resolve_dt(model, scene.integrator, scene.dt, 1.0 / scene.frame_rate).unwrap();
        let run = |terms: Terms| {
            let mut state = scene.initial.clone();
            let mut simulator = Simulator::with_terms(model, scene.integrator, terms);
            for _ in 0..240 {
                simulator.step(model, &mut state, dt).unwrap();
            }
            state
        };
        let needed = Terms::needed(model);
        assert_eq!(
            run(needed),
            run(Terms::all()),
            "{name}: the extra terms must add zero"
        );
        let mut best = [f64::INFINITY; 2];
        for _ in 0..20 {
            for (k, terms) in [needed, Terms::all()].into_iter().enumerate() {
                let start = std::time::Instant::now();
                black_box(run(terms));
                best[k] = best[k].min(start.elapsed().as_secs_f64());
            }
        }
        let left_out: Vec<&str> = needed
            .explain(model, scene.integrator)
            .into_iter()
            // Force terms and passes only, not the integrators' state.
            .filter(|d| !d.kept && !d.reason.starts_with("integrator"))
            .map(|d| d.name)
            .collect();
        eprintln!(
            "scene_compile: scene {name:<12} every term on {:.2}x the compiled run (left out: {})",
            best[1] / best[0],
            if left_out.is_empty() {
                "nothing".to_string()
            } else {
                left_out.join(", ")
            }
        );
    }
}

/// Exact skipping on against off, per scene: each scene run whole (frames
/// every 1/frame_rate, as `scene` does), checked bit-identical, then
/// timed in interleaved pairs.
fn skipping() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for rel in [
        "benches/hundred-leaves.toml",
        "scenes/inhale.toml",
        "scenes/shockwave.toml",
        "scenes/ground-blow.toml",
    ] {
        let scene = leafmagic::sim::scene::Scene::load(&root.join(rel)).unwrap();
        let model = &scene.model;
        let dt =
            run::resolve_dt(model, scene.integrator, scene.dt, 1.0 / scene.frame_rate).unwrap();
        let steps = (scene.duration / dt).round() as usize;
        let run = |skip: bool| {
            let mut state = scene.initial.clone();
            let mut simulator = Simulator::new(model, scene.integrator);
            simulator.set_skipping(model, skip);
            for _ in 0..steps {
                simulator.step(model, &mut state, dt).unwrap();
            }
            (state, simulator.skip_counts())
        };
        let ((on, counts), (off, _)) = (run(true), run(false));
        assert_eq!(on, off, "{rel}: skipping must not change a bit");
        let rounds = 9;
        let mut ratios = Vec::new();
        let mut times = [Vec::new(), Vec::new()];
        for r in 0..rounds {
            let mut pair = [0.0; 2];
            let order = if r % 2 == 0 {
                [true, false]
            } else {
                [false, true]
            };
            for skip in order {
                let start = std::time::Instant::now();
                black_box(run(skip));
                pair[usize::from(!skip)] = start.elapsed().as_secs_f64();
            }
            ratios.push(pair[0] / pair[1]);
            times[0].push(pair[0]);
            times[1].push(pair[1]);
        }
        let median = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let spread = |v: &[f64]| (v[0], v[v.len() - 1]);
        let (m_on, m_off, m_r) = (
            median(&mut times[0]),
            median(&mut times[1]),
            median(&mut ratios),
        );
        let (lo, hi) = spread(&ratios);
        let share = counts.wind_skipped as f64
            / (counts.wind_skipped + counts.wind_evaluated).max(1) as f64;
        eprintln!(
            "scene_compile: skipping {rel:<28} on {m_on:.4} s, off {m_off:.4} s (medians of {rounds}); on/off {m_r:.3} ({lo:.3}–{hi:.3}); {:.1} % of wind primitive evaluations skipped",
            share * 100.0
        );
    }
}

/// The wind of `scenes/inhale.toml` with every strength 0.
fn zero_inhale_wind() -> WindField {
    #[derive(serde::Deserialize)]
    struct Wind {
        wind: WindField,
    }
    let text = r#"
        [[wind]]
        kind = "uniform"
        velocity = [0.0, 0.0, 0.0]
        [[wind]]
        kind = "line_vortex"
        point = [0.0, 0.0, 0.0]
        axis = [0.0, 0.0, 1.0]
        circulation = 0.0
        core_radius = 0.2
        keys = [[0.5, 0.0], [3.0, 1.0]]
        [[wind]]
        kind = "point_sink"
        point = [0.0, 0.0, 0.6]
        flux = 0.0
        core_radius = 0.3
        keys = [[0.5, 0.0], [3.0, 1.0]]
        [[wind]]
        kind = "uniform"
        velocity = [0.0, 0.0, 0.0]
        keys = [[0.5, 0.0], [3.0, 1.0]]
        bounds = { shape = "cylinder", point = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0], radius = 0.12, falloff = 0.1 }
    "#;
    toml::from_str::<Wind>(text).unwrap().wind
}

criterion_group!(benches, scene_compile);
criterion_main!(benches);
