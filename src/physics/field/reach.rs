//! Where primitives can act together, and the bound on |G| that follows.
//!
//! A bounded primitive is zero beyond its region's falloff band, so two
//! primitives whose bands do not meet never add at one point. The field's
//! speed bound ([`super::WindField::speed_bound`]) is then the largest
//! speed of any group of primitives that pairwise can meet (a clique of the
//! overlap graph; every set of primitives acting at one point is one), not
//! the sum over all of them. Within a group, uniform primitives without
//! keys add as vectors: each is its velocity V_i times a weight in [0, 1]
//! (bounds and front), and |Σ w_i V_i| is convex in the weights, so its
//! largest value is at a vertex, max over subsets T of |Σ_T V_i|. Every other
//! primitive adds its peak speed (triangle inequality).
//!
//! Every test here errs towards "may meet", so the bound stays a bound.

use nalgebra::Vector3;

use super::bounds::Region;
use super::flows::Flow;
use super::primitive::Primitive;

/// Beyond this many primitives the overlap graph is not searched and the
/// bound is the plain sum of peak speeds: a graph of n vertices has up to
/// 3^(n/3) maximal cliques (Moon & Moser 1965), about 1,600 at 20.
const MAX_SEARCHED: usize = 20;

/// Beyond this many uniform primitives in one group their vertex search
/// (2ⁿ subsets) gives way to the sum of their speeds; with
/// [`MAX_SEARCHED`], at most some 10⁷ vector additions per bound, which is
/// taken once per simulator.
const MAX_VERTEX_SEARCH: usize = 10;

/// The closed set outside which a primitive is exactly zero at all times.
#[derive(Clone, Debug)]
enum Support {
    /// No bounds: anywhere (a front sweeps all of space over time).
    Everywhere,
    /// Ball of `radius` around `center` (the region's radius plus its
    /// falloff band).
    Ball { center: Vector3<f64>, radius: f64 },
    /// Axis-aligned box, grown by the falloff band on every side.
    Slab {
        min: Vector3<f64>,
        max: Vector3<f64>,
    },
    /// Infinite tube of `radius` around the line through `point` along the
    /// unit `axis`.
    Tube {
        point: Vector3<f64>,
        axis: Vector3<f64>,
        radius: f64,
    },
}

impl Support {
    fn of(p: &Primitive) -> Support {
        let Some(b) = p.bounds() else {
            return Support::Everywhere;
        };
        let f = b.falloff;
        match &b.region {
            Region::Sphere { center, radius } => Support::Ball {
                center: *center,
                radius: radius + f,
            },
            Region::Box { min, max } => Support::Slab {
                min: min.add_scalar(-f),
                max: max.add_scalar(f),
            },
            Region::Cylinder {
                point,
                axis,
                radius,
            } => Support::Tube {
                point: *point,
                axis: axis.normalize(),
                radius: radius + f,
            },
        }
    }

    /// A ball holding all of the support, or `None` when it is unbounded.
    fn enclosing_ball(&self) -> Option<(Vector3<f64>, f64)> {
        match self {
            Support::Ball { center, radius } => Some((*center, *radius)),
            Support::Slab { min, max } => Some(((min + max) * 0.5, (max - min).norm() * 0.5)),
            Support::Everywhere | Support::Tube { .. } => None,
        }
    }

    /// Whether the two supports may share a point: false only when they
    /// provably do not (a margin of 1e-9 of the scale covers rounding).
    fn may_meet(&self, other: &Support) -> bool {
        use Support::*;
        let within = |gap: f64, reach: f64, scale: f64| gap <= reach + 1e-9 * (scale + 1.0);
        match (self, other) {
            (Everywhere, _) | (_, Everywhere) => true,
            (
                Ball {
                    center: a,
                    radius: r,
                },
                Ball {
                    center: b,
                    radius: s,
                },
            ) => within((a - b).norm(), r + s, a.norm() + b.norm() + r + s),
            (Slab { min: a0, max: a1 }, Slab { min: b0, max: b1 }) => (0..3).all(|i| {
                let scale = a0[i].abs() + a1[i].abs() + b0[i].abs() + b1[i].abs();
                within(a0[i] - b1[i], 0.0, scale) && within(b0[i] - a1[i], 0.0, scale)
            }),
            (Ball { center, radius }, Slab { min, max })
            | (Slab { min, max }, Ball { center, radius }) => {
                let outside = (min - center).sup(&(center - max)).sup(&Vector3::zeros());
                within(
                    outside.norm(),
                    *radius,
                    center.norm() + min.norm() + max.norm(),
                )
            }
            (
                Tube {
                    point,
                    axis,
                    radius,
                },
                other,
            )
            | (
                other,
                Tube {
                    point,
                    axis,
                    radius,
                },
            ) => match other {
                Tube {
                    point: q,
                    axis: b,
                    radius: s,
                } => {
                    let d = q - point;
                    let n = axis.cross(b);
                    let gap = if n.norm() > 1e-9 {
                        d.dot(&n).abs() / n.norm()
                    } else {
                        axis.cross(&d).norm()
                    };
                    within(gap, radius + s, point.norm() + q.norm() + radius + s)
                }
                _ => {
                    let (c, r) = other.enclosing_ball().expect("bounded");
                    let gap = axis.cross(&(c - point)).norm();
                    within(gap, radius + r, point.norm() + c.norm() + radius + r)
                }
            },
        }
    }
}

/// What a primitive adds to the speed of a group it acts in: a velocity
/// that its weights scale within [0, 1], or a peak speed.
enum Contribution {
    Vector(Vector3<f64>),
    Speed(f64),
}

fn contribution(p: &Primitive) -> Contribution {
    match (p.flow(), p.keys()) {
        (Flow::Uniform(u), None) => Contribution::Vector(u.velocity),
        _ => Contribution::Speed(p.speed_bound()),
    }
}

/// Upper bound of |Σ G_i| over all space and time for `primitives`: the
/// largest speed of a group that pairwise may meet (module docs), never
/// more than the sum of their peak speeds.
pub(super) fn speed_bound(primitives: &[Primitive]) -> f64 {
    let sum: f64 = primitives.iter().map(Primitive::speed_bound).sum();
    let n = primitives.len();
    if n <= 1 || n > MAX_SEARCHED {
        return sum;
    }
    let supports: Vec<Support> = primitives.iter().map(Support::of).collect();
    let mut neighbours = vec![0u32; n];
    for i in 0..n {
        for j in i + 1..n {
            if supports[i].may_meet(&supports[j]) {
                neighbours[i] |= 1 << j;
                neighbours[j] |= 1 << i;
            }
        }
    }
    let contributions: Vec<Contribution> = primitives.iter().map(contribution).collect();
    let mut best: f64 = 0.0;
    maximal_cliques(&neighbours, 0, (1u32 << n) - 1, 0, &mut |clique| {
        best = best.max(group_speed(&contributions, clique));
    });
    best.min(sum)
}

/// The largest speed of the primitives in the bit set `group`.
fn group_speed(contributions: &[Contribution], group: u32) -> f64 {
    let mut vectors = Vec::new();
    let mut speeds = 0.0;
    for (i, c) in contributions.iter().enumerate() {
        if group & (1 << i) != 0 {
            match c {
                Contribution::Vector(v) => vectors.push(*v),
                Contribution::Speed(s) => speeds += s,
            }
        }
    }
    let vertex = if vectors.len() > MAX_VERTEX_SEARCH {
        vectors.iter().map(|v| v.norm()).sum()
    } else {
        (0u32..1 << vectors.len())
            .map(|subset| {
                vectors
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| subset & (1 << k) != 0)
                    .map(|(_, v)| v)
                    .sum::<Vector3<f64>>()
                    .norm()
            })
            .fold(0.0, f64::max)
    };
    vertex + speeds
}

/// Calls `found` with every maximal clique of the graph `neighbours` (bit
/// sets), by Bron and Kerbosch's recursion (Commun. ACM 16(9), 1973) with a
/// pivot from P ∪ X, whose neighbours need not be tried: `r` the clique so
/// far, `p` the vertices that extend it, `x` those already tried.
fn maximal_cliques(neighbours: &[u32], r: u32, p: u32, x: u32, found: &mut impl FnMut(u32)) {
    if p == 0 {
        if x == 0 {
            found(r);
        }
        return;
    }
    let pivot = (p | x).trailing_zeros() as usize;
    let (mut p, mut x) = (p, x);
    let mut candidates = p & !neighbours[pivot];
    while candidates != 0 {
        let v = candidates.trailing_zeros() as usize;
        let bit = 1u32 << v;
        candidates &= !bit;
        maximal_cliques(
            neighbours,
            r | bit,
            p & neighbours[v],
            x & neighbours[v],
            found,
        );
        p &= !bit;
        x |= bit;
    }
}
