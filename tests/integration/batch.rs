//! Lockstep batches (issue 20): every lane of a batch of mutated leaves ends
//! bit for bit where a lone `Simulator` ends, whatever its neighbours, with
//! each lane on its own auto step.
//!
//! The linear aerodynamic law is written once, over a lane type
//! (`physics::aero::linear::kernel`): a lone drop runs it on `f64`, the
//! batch's generic lanes on `L` of them, and the AVX2 step
//! (`physics::batch`'s `avx2.rs`) is its one hand-vectorised
//! specialisation. These tests are what hold the three to the same bits.

use leafmagic::leaf::LeafSpec;
use leafmagic::leaf::genome::{Genome, mutate};
use leafmagic::physics::batch::{Batch, BatchError};
use leafmagic::physics::integrate::Simulator;
use leafmagic::physics::model::Model;
use leafmagic::physics::params::{Integrator, TimeStep};
use leafmagic::physics::run::resolve_step;
use leafmagic::physics::state::State;
use leafmagic::sim::drop::{FRAME_RATE, release_rotation};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

fn variants(proto: &str, n: usize, seed: u64) -> Vec<Model> {
    let spec = LeafSpec::load(proto).unwrap();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let g = Genome::of_prototype(&spec);
    (0..n)
        .map(|_| {
            mutate(&g, &spec.bounds, 1.0, &mut rng)
                .model(&spec)
                .unwrap()
        })
        .collect()
}

fn auto_dt(model: &Model) -> f64 {
    resolve_step(model, Integrator::Verlet, TimeStep::Auto, 1.0 / FRAME_RATE).unwrap()
}

/// Lanes of different leaves, steps and tilts, each stepped for its own
/// number of steps (the batch keeps a finished lane still), against each
/// leaf dropped alone; with the CPU's widest vectors (the kernel written
/// with intrinsics, and the generic one), and with the baseline's: the
/// linear law's one kernel on `f64` (the lone drops), on four generic
/// lanes, and in its AVX2 form, bit for bit.
#[test]
fn every_lane_is_bit_identical_to_a_lone_drop() {
    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Kernel {
        Intrinsics,
        Generic,
        Baseline,
    }
    use Kernel::*;
    for (proto, kernel) in [
        ("a", Intrinsics),
        ("b", Intrinsics),
        ("a", Generic),
        ("b", Generic),
        ("a", Baseline),
    ] {
        let models = variants(proto, 4, 20);
        let tilts = [[10.0, 2.0], [35.0, -5.0], [0.5, 0.0], [80.0, 30.0]];
        let states: Vec<State> = models
            .iter()
            .zip(tilts)
            .map(|(m, t)| State::released(m, release_rotation(t), Default::default()))
            .collect();
        let dt: [f64; 4] = std::array::from_fn(|k| auto_dt(&models[k]));
        assert!(
            dt.iter().any(|&h| h != dt[0]),
            "the lanes should differ in step"
        );
        let steps: [u64; 4] = std::array::from_fn(|k| (1.5 / dt[k]).round() as u64 + 7 * k as u64);
        let mut batch = Batch::<4>::new(
            std::array::from_fn(|k| &models[k]),
            std::array::from_fn(|k| &states[k]),
            dt,
        )
        .unwrap();
        batch = match kernel {
            Intrinsics => batch,
            Generic => batch.generic_vectors(),
            Baseline => batch.baseline_vectors(),
        };
        loop {
            let active: [bool; 4] = std::array::from_fn(|k| batch.steps()[k] < steps[k]);
            if !active.iter().any(|&a| a) {
                break;
            }
            let live = batch.step(active);
            assert!(
                live.iter().all(|&l| l),
                "{proto} {kernel:?}: a lane diverged"
            );
        }
        for k in 0..4 {
            let mut state = states[k].clone();
            let mut sim = Simulator::new(&models[k], Integrator::Verlet);
            for _ in 0..steps[k] {
                sim.step(&models[k], &mut state, dt[k]).unwrap();
            }
            let (x, v) = batch.lane(k);
            let bits = |p: &[nalgebra::Vector3<f64>]| -> Vec<u64> {
                p.iter()
                    .flat_map(|q| q.iter().map(|c| c.to_bits()))
                    .collect()
            };
            assert_eq!(
                bits(&x),
                bits(&state.position),
                "{proto} {kernel:?} lane {k}: positions"
            );
            assert_eq!(
                bits(&v),
                bits(&state.velocity),
                "{proto} {kernel:?} lane {k}: velocities"
            );
            assert_eq!(batch.steps()[k], steps[k]);
        }
    }
}

/// Leaves of different topologies are refused, naming the lane.
#[test]
fn different_topologies_are_refused() {
    let a = variants("a", 1, 1).pop().unwrap();
    let b = variants("b", 1, 1).pop().unwrap();
    let (sa, sb) = (State::at_rest(&a), State::at_rest(&b));
    let err = Batch::<2>::new([&a, &b], [&sa, &sb], [1e-3; 2]).unwrap_err();
    assert!(matches!(err, BatchError::Topology { lane: 1, .. }), "{err}");
}

/// A breed's evaluation drops an individual's four releases (four tilts,
/// one model, one step) in the lanes of one lockstep batch; it is the
/// evaluation of the four dropped alone, to the bit (compared through the
/// Debug text, which prints every f64 exactly), for 10 mutated children.
#[test]
fn lockstep_evaluations_equal_lone_ones() {
    use leafmagic::breed::evaluate::{LOCKSTEP, evaluate, evaluate_alone};
    use leafmagic::breed::settings::BreedSettings;
    let spec = LeafSpec::load("a").unwrap();
    let settings = BreedSettings {
        seconds: 1.5,
        releases: LOCKSTEP,
        ..BreedSettings::default_run()
    };
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
    let g = Genome::of_prototype(&spec);
    for id in 0..10u64 {
        let child = mutate(&g, &spec.bounds, 1.5, &mut rng);
        let together = evaluate(&spec, id, &child, &settings);
        assert_eq!(together.releases, LOCKSTEP);
        assert_eq!(
            format!("{together:?}"),
            format!("{:?}", evaluate_alone(&spec, id, &child, &settings))
        );
    }
}
