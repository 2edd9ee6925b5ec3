//! Spring breaking after each step: the paper's "threshold associated with
//! every spring" (section 2.1), tested on squared lengths.

use crate::physics::model::Model;
use crate::physics::state::State;

/// A breakable spring and the squared length past which it breaks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BreakLimit {
    /// Index of the spring in [`Model::springs`].
    pub spring: usize,
    /// ((1 + ε) L)² for break strain ε and rest length L.
    pub length2: f64,
}

/// The [`BreakLimit`] of every breakable spring, in spring order.
pub fn break_limits(model: &Model) -> Vec<BreakLimit> {
    model
        .springs
        .iter()
        .enumerate()
        .filter_map(|(k, s)| {
            let l = (1.0 + s.break_strain?) * s.rest_length;
            Some(BreakLimit {
                spring: k,
                length2: l * l,
            })
        })
        .collect()
}

/// Breaks every intact spring of `limits` whose strain (l − L)/L exceeds its
/// threshold ε, tested as l² > ((1 + ε) L)² (no square root); returns how
/// many broke. A broken spring stays broken.
pub fn break_springs(model: &Model, state: &mut State, limits: &[BreakLimit]) -> usize {
    let mut broken = 0;
    for limit in limits {
        let k = limit.spring;
        if !state.spring_alive[k] {
            continue;
        }
        let spring = &model.springs[k];
        let l2 = (state.position[spring.i] - state.position[spring.j]).norm_squared();
        if l2 > limit.length2 {
            state.spring_alive[k] = false;
            broken += 1;
        }
    }
    broken
}
