//! What broken springs tear: the triangles and hinges whose edges they were.

use crate::physics::model::Model;

/// The spring (if any) joining each pair of particles, in either order.
fn spring_between(model: &Model) -> impl Fn(usize, usize) -> Option<usize> {
    let mut by_pair = std::collections::HashMap::new();
    for (k, s) in model.springs.iter().enumerate() {
        by_pair.insert((s.i.min(s.j), s.i.max(s.j)), k);
    }
    move |i, j| by_pair.get(&(i.min(j), i.max(j))).copied()
}

/// For each triangle, the spring (if any) along each of its three edges.
pub fn edge_springs(model: &Model) -> Vec<[Option<usize>; 3]> {
    let between = spring_between(model);
    model
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.corners;
            [(a, b), (b, c), (c, a)].map(|(i, j)| between(i, j))
        })
        .collect()
}

/// For each hinge, the spring (if any) along each edge of its two wings:
/// the shared edge a–b, then a–p, b–p, a–q, b–q.
pub fn hinge_springs(model: &Model) -> Vec<[Option<usize>; 5]> {
    let between = spring_between(model);
    model
        .hinges
        .iter()
        .map(|h| {
            let ([a, b], [p, q]) = (h.edge, h.apexes);
            [(a, b), (a, p), (b, p), (a, q), (b, q)].map(|(i, j)| between(i, j))
        })
        .collect()
}

/// What broken springs have torn: triangles that are no longer surfaces
/// (an edge spring broke; they feel no air) and hinges with a torn wing (a
/// spring along either wing broke; they bend no more). Both masks are empty
/// until the first spring breaks, and an empty mask tears nothing.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Tears {
    /// `triangles[t]`: triangle t is torn.
    pub triangles: Vec<bool>,
    /// `hinges[h]`: hinge h has a torn wing.
    pub hinges: Vec<bool>,
}

/// Sets `mask[e]` for every element e with a broken spring among
/// `springs[e]`; leaves the mask empty while none is broken (sized at the
/// first tear only, refilled in place afterwards).
pub(super) fn tear_mask<const N: usize>(
    mask: &mut Vec<bool>,
    springs: &[[Option<usize>; N]],
    alive: &[bool],
) {
    if !springs.iter().flatten().flatten().any(|&s| !alive[s]) {
        mask.clear();
        return;
    }
    mask.resize(springs.len(), false);
    for (torn, edges) in mask.iter_mut().zip(springs) {
        *torn = edges.iter().flatten().any(|&s| !alive[s]);
    }
}
