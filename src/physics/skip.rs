//! Exact skipping, one level below [`crate::physics::terms`]: per object
//! (a connected group of particles) and per force evaluation, the wind
//! primitives that cannot reach the object are not evaluated for its
//! particles.
//!
//! A primitive is skipped for a group only when
//! [`Primitive::reaches_box`](crate::physics::field::Primitive::reaches_box)
//! proves it gives exact zeros on the group's bounding box at that time (its
//! keys are 0, or the box lies beyond its bounds' falloff band or ahead of its
//! moving front's band), so the summed wind is bit for bit the full sum
//! ([`WindField::velocity_of`](crate::physics::field::WindField::velocity_of)).
//! The box is taken from the positions being evaluated, so no speed bound is
//! needed; a group with a non-finite coordinate skips nothing.
//!
//! A group that feels no wind (none of its particles is a triangle corner or
//! has particle drag, such as a rigid bin whose surfaces the compiler
//! dropped) skips every primitive: the wind at its particles is never read.

use crate::physics::model::Model;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// The objects of a model: its particles grouped into connected components
/// of springs, triangles, hinges and rigid bodies, each group's members in
/// increasing order, groups ordered by their first member.
pub fn groups(model: &Model) -> Vec<Vec<usize>> {
    let n = model.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut join = |a: usize, b: usize| {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        if ra != rb {
            parent[ra.max(rb)] = ra.min(rb);
        }
    };
    for s in &model.springs {
        join(s.i, s.j);
    }
    for t in &model.triangles {
        join(t.corners[0], t.corners[1]);
        join(t.corners[0], t.corners[2]);
    }
    for h in &model.hinges {
        for &k in h.edge.iter().chain(&h.apexes) {
            join(h.edge[0], k);
        }
    }
    for b in &model.rigid {
        for &m in &b.members {
            join(b.members[0], m);
        }
    }
    let mut index = vec![usize::MAX; n];
    let mut out: Vec<Vec<usize>> = Vec::new();
    for i in 0..n {
        let r = root(&mut parent, i);
        if index[r] == usize::MAX {
            index[r] = out.len();
            out.push(Vec::new());
        }
        out[index[r]].push(i);
    }
    out
}

/// Whether any of `members` reads the wind: a corner of a triangle of the
/// model, or a particle with drag (the only readers of the sampled wind).
pub fn feels_wind(model: &Model, members: &[usize]) -> bool {
    members.iter().any(|&i| model.particle_drag[i] != 0.0)
        || model
            .triangles
            .iter()
            .any(|t| t.corners.iter().any(|c| members.binary_search(c).is_ok()))
}

/// The bounding box [lo, hi] of `x[i]` over `members`, or `None` when a
/// coordinate is not finite (then nothing may be skipped).
#[inline]
pub fn bounding_box(x: &[V3], members: &[usize]) -> Option<(V3, V3)> {
    let first = x[*members.first()?];
    let (mut lo, mut hi) = (first, first);
    let mut sum = 0.0;
    for &i in members {
        let p = &x[i];
        lo = lo.inf(p);
        hi = hi.sup(p);
        sum += p.x + p.y + p.z;
    }
    // NaN does not survive inf/sup; a non-finite sum catches NaN and ±∞.
    sum.is_finite().then_some((lo, hi))
}

/// What the skipping saved so far, for `scene --explain` and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SkipCounts {
    /// (group, primitive) pairs of force evaluations whose primitive was
    /// evaluated at the group's particles.
    pub wind_evaluated: u64,
    /// (group, primitive) pairs skipped: the primitive could not reach the
    /// group.
    pub wind_skipped: u64,
}

/// Per-group wind skipping state of one force path.
#[derive(Clone, Debug, Default)]
pub struct WindSkip {
    /// The groups, or empty when no primitive can ever be skipped.
    groups: Vec<Vec<usize>>,
    /// Per group, whether it reads the wind ([`feels_wind`]).
    feels: Vec<bool>,
    /// Which primitives reach the group being sampled.
    active: Vec<bool>,
    /// Which primitives' keys are nonzero at the time being sampled.
    keyed_on: Vec<bool>,
    /// Per group, evaluations left before its box is tested again.
    hold: Vec<u8>,
    /// Per group, how many primitive evaluations it skipped.
    skipped: Vec<u64>,
    counts: SkipCounts,
}

impl WindSkip {
    /// Skipping for `model`: on only where some primitive has bounds, a
    /// front or keys (an unlimited primitive reaches everything), or some
    /// group feels no wind.
    pub fn new(model: &Model, on: bool) -> WindSkip {
        if !on || model.wind.is_still() {
            return WindSkip::default();
        }
        let limited = model.wind.primitives().iter().any(|p| p.is_limited());
        let groups = groups(model);
        let feels: Vec<bool> = groups.iter().map(|g| feels_wind(model, g)).collect();
        if !limited && feels.iter().all(|&f| f) {
            return WindSkip::default();
        }
        WindSkip {
            skipped: vec![0; groups.len()],
            hold: vec![0; groups.len()],
            feels,
            groups,
            active: vec![true; model.wind.primitives().len()],
            keyed_on: vec![true; model.wind.primitives().len()],
            counts: SkipCounts::default(),
        }
    }

    /// Whether skipping is in use.
    pub fn is_on(&self) -> bool {
        !self.groups.is_empty()
    }

    /// The counts so far.
    pub fn counts(&self) -> SkipCounts {
        self.counts
    }

    /// Per group (as [`groups`]), the primitive evaluations skipped.
    pub fn skipped_per_group(&self) -> &[u64] {
        &self.skipped
    }

    /// Writes G(x_i, t) into `wind[i]` for every particle that reads it,
    /// summing for each group only the primitives that can reach it. Keys
    /// are looked at once per evaluation. The box tests (only for
    /// primitives with bounds or a front) decide each skip afresh; a group
    /// whose test skipped nothing evaluates every keyed primitive for the
    /// next [`HOLD`] evaluations without testing (evaluating more is always
    /// exact), so that groups inside the fields pay the test rarely.
    pub fn sample(&mut self, model: &Model, x: &[V3], t: f64, wind: &mut [V3]) {
        let prims = model.wind.primitives();
        let n = prims.len() as u64;
        let mut keyed_off = 0;
        let mut bounded = false;
        // A bounded primitive keyed to 0 gives 0 · w(x) = NaN at a
        // non-finite x: skipping it needs the positions checked.
        let mut off_bounded = false;
        for (k, p) in self.keyed_on.iter_mut().zip(prims) {
            *k = !p.zero_at(t);
            keyed_off += u64::from(!*k);
            bounded |= *k && p.is_bounded();
            off_bounded |= !*k && p.is_bounded();
        }
        for (g, members) in self.groups.iter().enumerate() {
            if !self.feels[g] {
                // Never read: left as it was.
                self.skipped[g] += n;
                self.counts.wind_skipped += n;
                continue;
            }
            let test = bounded && self.hold[g] == 0;
            self.hold[g] = self.hold[g].saturating_sub(1);
            let bbox = if test || off_bounded {
                match bounding_box(x, members) {
                    Some(b) => Some(b),
                    None => {
                        // Not finite: skip nothing.
                        self.counts.wind_evaluated += n;
                        for &i in members {
                            wind[i] = model.wind.velocity(&x[i], t);
                        }
                        continue;
                    }
                }
            } else {
                None
            };
            let mut off = keyed_off;
            self.active.copy_from_slice(&self.keyed_on);
            if let (true, Some((lo, hi))) = (test, &bbox) {
                for (a, p) in self.active.iter_mut().zip(prims) {
                    if *a && p.is_bounded() && p.zero_on_box(lo, hi, t) {
                        *a = false;
                        off += 1;
                    }
                }
                if off == keyed_off {
                    self.hold[g] = HOLD;
                }
            }
            self.skipped[g] += off;
            self.counts.wind_skipped += off;
            self.counts.wind_evaluated += n - off;
            if off == 0 {
                for &i in members {
                    wind[i] = model.wind.velocity(&x[i], t);
                }
            } else {
                for &i in members {
                    wind[i] = model.wind.velocity_of(&x[i], t, &self.active);
                }
            }
        }
    }
}

/// Evaluations a group that the box tests found inside every keyed field
/// goes untested (evaluating every keyed primitive meanwhile).
pub const HOLD: u8 = 7;
