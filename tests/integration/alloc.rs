//! The step loop does not allocate: a counting allocator wraps the system
//! one for this test binary, and counts per thread so other tests running in
//! parallel do not disturb the count.

use leafmagic::leaf::LeafSpec;
use leafmagic::physics::integrate::Simulator;
use leafmagic::physics::params::Integrator;
use leafmagic::physics::state::State;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

/// Counts allocations of the current thread, then defers to [`System`].
pub struct Counting;

// SAFETY: every method forwards its arguments unchanged to `System`, which
// upholds the `GlobalAlloc` contract; the counter is a const-initialised
// thread-local `Cell`, which neither allocates nor re-enters the allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: same layout as given to us, per the trait contract.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System.alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: forwarded unchanged.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> u64 {
    ALLOCATIONS.with(|c| c.get())
}

/// Prototypes A and B under the paper's linear law, and A under the
/// unsteady law with its lagged centre of pressure and its opt-in wake.
#[test]
fn stepping_allocates_nothing() {
    let unsteady = crate::common::with_aero(
        leafmagic::leaf::PROTOTYPE_A,
        "law = \"unsteady\"\nwake_couple = 1.25",
    );
    for p in ["a", "b", "unsteady a"] {
        let model = if p == "unsteady a" {
            LeafSpec::from_toml(&unsteady, "a-unsteady.toml")
        } else {
            LeafSpec::load(p)
        }
        .unwrap()
        .model()
        .unwrap();
        for integrator in Integrator::ALL {
            let mut state = State::released(
                &model,
                leafmagic::sim::drop::release_rotation([10.0, 2.0]),
                Default::default(),
            );
            let mut sim = Simulator::new(&model, integrator);
            // First step outside the count: Verlet fills its carried acceleration.
            sim.step(&model, &mut state, 1e-4).unwrap();
            let before = allocations();
            for _ in 0..500 {
                sim.step(&model, &mut state, 1e-4).unwrap();
            }
            assert_eq!(
                allocations() - before,
                0,
                "{integrator} allocated in the step loop of prototype {p}"
            );
        }
    }
}

/// Scenes with ground contact, rigid bodies, ropes, wind and breaking springs
/// step without allocating once their scratch space has grown (the first
/// steps size the contact lists; the first break sizes the torn mask).
#[test]
fn scene_stepping_allocates_nothing() {
    for name in ["rocking-bin", "inhale", "swings", "tear"] {
        let scene = crate::scenes::load(name);
        let dt = leafmagic::physics::run::resolve_dt(
            &scene.model,
            scene.integrator,
            scene.dt,
            1.0 / scene.frame_rate,
        )
        .unwrap();
        let mut state = scene.initial.clone();
        let mut sim = Simulator::new(&scene.model, scene.integrator);
        // Warm up through the tear scene's first breaks (from t = 1.37 s).
        let warm = (1.7 / dt) as usize;
        for _ in 0..warm {
            sim.step(&scene.model, &mut state, dt).unwrap();
        }
        let before = allocations();
        for _ in 0..500 {
            sim.step(&scene.model, &mut state, dt).unwrap();
        }
        assert_eq!(
            allocations() - before,
            0,
            "{name} allocated in the step loop"
        );
    }
}
