//! Exact skipping (`physics::skip`): per object and per force evaluation,
//! the terms that provably contribute exact zeros are left out. Each kind of
//! skip is checked on the shipped scenes by stepping the same scene with
//! skipping on and off: the states must be bit-identical at every frame, and
//! the skip must actually happen (its counts are positive).

use leafmagic::physics::integrate::Simulator;
use leafmagic::physics::run;
use leafmagic::physics::skip::SkipCounts;
use leafmagic::physics::state::State;
use leafmagic::sim::scene::Scene;
use std::path::Path;

fn load(rel: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// The scene stepped for `seconds` with skipping on or off: the state at
/// every frame, and the skip counts.
fn frames(scene: &Scene, seconds: f64, skipping: bool) -> (Vec<State>, SkipCounts) {
    let model = &scene.model;
    let frame_dt = 1.0 / scene.frame_rate;
    let dt = run::resolve_dt(model, scene.integrator, scene.dt, frame_dt).unwrap();
    let per_frame = (frame_dt / dt).round().max(1.0) as usize;
    let mut sim = Simulator::new(model, scene.integrator);
    sim.set_skipping(model, skipping);
    let mut state = scene.initial.clone();
    let mut out = vec![state.clone()];
    for _ in 0..(seconds * scene.frame_rate).round() as usize {
        for _ in 0..per_frame {
            sim.step(model, &mut state, dt).unwrap();
        }
        out.push(state.clone());
    }
    (out, sim.skip_counts())
}

/// Skipping on against off: every frame bit-identical; returns the counts
/// with skipping on (off must count nothing).
fn same_with_and_without(rel: &str, seconds: f64) -> SkipCounts {
    let scene = load(rel);
    let (on, counts) = frames(&scene, seconds, true);
    let (off, none) = frames(&scene, seconds, false);
    assert_eq!(
        none,
        SkipCounts::default(),
        "{rel}: skipping off skips nothing"
    );
    for (k, (a, b)) in on.iter().zip(&off).enumerate() {
        // Compare bits, so that a −0 against +0 or a NaN would show.
        let bits = |s: &State| -> Vec<u64> {
            s.position
                .iter()
                .chain(&s.velocity)
                .flat_map(|p| p.iter().map(|c| c.to_bits()).collect::<Vec<_>>())
                .collect()
        };
        assert!(bits(a) == bits(b) && a == b, "{rel}: frame {k} differs");
    }
    counts
}

/// (1) Wind primitives that cannot reach an object: the shockwave's fronts
/// and bounded columns skip most (object, primitive) pairs, yet every frame
/// is bit-identical to evaluating them all.
#[test]
fn wind_skipping_is_exact_and_happens_in_the_shockwave() {
    let c = same_with_and_without("scenes/shockwave.toml", 6.0);
    assert!(c.wind_skipped > c.wind_evaluated, "{c:?}");
}

/// (1) The inhale scene's keyframed vortex, sink and bounded updraft: the
/// keys are 0 for the first 0.5 s and the bin column's band reaches few
/// leaves.
#[test]
fn wind_skipping_is_exact_and_happens_in_the_inhale() {
    let c = same_with_and_without("scenes/inhale.toml", 10.0);
    assert!(c.wind_skipped > 0, "{c:?}");
}

/// (1) The ground-blow wind is keyed to 0 for the first second: skipped
/// then, evaluated after.
#[test]
fn wind_skipping_is_exact_and_happens_in_the_ground_blow() {
    let c = same_with_and_without("scenes/ground-blow.toml", 6.0);
    assert!(c.wind_skipped > 0 && c.wind_evaluated > 0, "{c:?}");
}

/// (1) An unlimited uniform breeze reaches everything: nothing is skipped,
/// and the result is still the same.
#[test]
fn an_unlimited_breeze_skips_nothing() {
    let c = same_with_and_without("benches/hundred-leaves.toml", 1.0);
    assert_eq!(c.wind_skipped, 0, "{c:?}");
}

/// (1) An object that reads no wind (the inhale scene's rigid bin: the
/// compiler dropped its zero-coefficient surfaces) skips every primitive at
/// every force evaluation, and the run is still bit-identical (above).
#[test]
fn the_inhale_bin_reads_no_wind_and_skips_every_primitive() {
    let scene = load("scenes/inhale.toml");
    let model = &scene.model;
    let bin = scene.object("bin").expect("the inhale scene has a bin");
    let groups = leafmagic::physics::skip::groups(model);
    let g = groups
        .iter()
        .position(|m| m.contains(&bin.particles[0]))
        .unwrap();
    let dt = run::resolve_dt(model, scene.integrator, scene.dt, 1.0 / scene.frame_rate).unwrap();
    let mut sim = Simulator::new(model, scene.integrator);
    let mut state = scene.initial.clone();
    for _ in 0..100 {
        sim.step(model, &mut state, dt).unwrap();
    }
    let per_evaluation = model.wind.primitives().len() as u64;
    assert_eq!(
        sim.skipped_per_group()[g],
        per_evaluation * sim.force_evaluations()
    );
}
