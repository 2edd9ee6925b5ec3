//! Lockstep stepping of several leaves of one topology (issue 20): the
//! members of a generation share their particles, springs, hinges and
//! triangles and differ only in numbers (masses, stiffnesses, folds, the
//! step), so `L` of them can be stepped together with the leaf index
//! innermost (structure of arrays), one vector instruction doing the same
//! operation for every lane.
//!
//! Each lane's arithmetic is exactly that of [`Simulator::step`] on its own
//! leaf, operation for operation and in the same order (IEEE 754 makes each
//! operation correctly rounded, whatever the vector width), so a lane ends
//! bit for bit where a lone drop ends; the tests check it. What this first
//! version covers is what the default breed steps: velocity Verlet in still
//! air, gravity, springs, hinges and the linear aerodynamic law, no
//! breaking, contact or rigid bodies ([`BatchError::Unsupported`] names what
//! is not covered). A lane that fails the divergence check stops; the caller
//! replays it with [`Simulator`] for the diagnosis.
//!
//! [`Simulator::step`]: crate::physics::integrate::Simulator::step
//! [`Simulator`]: crate::physics::integrate::Simulator

use crate::physics::aero::linear::kernel::{Lane, LinearTriangle};
use crate::physics::forces::hinge_rest;
use crate::physics::integrate::{RUNAWAY_DISTANCE, runaway_speed};
use crate::physics::model::Model;
use crate::physics::state::State;
use crate::physics::terms::Terms;
use nalgebra::Vector3;

#[cfg(target_arch = "x86_64")]
mod avx2;

type V3 = Vector3<f64>;

/// One number per lane.
type Lanes<const L: usize> = [f64; L];
/// A vector per lane: components x, y, z, each with the lane innermost.
type V3Lanes<const L: usize> = [Lanes<L>; 3];

/// Why models cannot be stepped together.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BatchError {
    /// Lanes whose particles, springs, hinges or triangles differ.
    #[error("lane {lane} has another topology than lane 0 ({what} differ)")]
    Topology {
        /// The first lane that differs.
        lane: usize,
        /// What differs.
        what: &'static str,
    },
    /// A model needs a term or integrator this batch does not step.
    #[error("lane {lane} needs {what}, which lockstep batches do not step")]
    Unsupported {
        /// The lane.
        lane: usize,
        /// What is not covered.
        what: &'static str,
    },
}

/// `L` leaves of one topology stepped in lockstep by velocity Verlet, each
/// with its own numbers and step.
#[derive(Clone, Debug)]
pub struct Batch<const L: usize> {
    law: Law<L>,
    dt: Lanes<L>,
    speed_limit2: Lanes<L>,
    x: Vec<V3Lanes<L>>,
    v: Vec<V3Lanes<L>>,
    acc: Vec<V3Lanes<L>>,
    v_half: Vec<V3Lanes<L>>,
    acc_new: Vec<V3Lanes<L>>,
    acc_valid: bool,
    /// Lanes still stepping (false once a lane fails the divergence check).
    live: [bool; L],
    steps: [u64; L],
    /// Whether this CPU has AVX2 ([`Batch::step`] then uses it).
    #[cfg(target_arch = "x86_64")]
    avx2: bool,
    /// Whether four lanes with AVX2 take the kernel written with
    /// intrinsics (else the generic one, compiled for AVX2).
    #[cfg(target_arch = "x86_64")]
    intrinsics: bool,
}

/// What the lanes' forces are made of: the shared topology and each lane's
/// numbers.
#[derive(Clone, Debug)]
struct Law<const L: usize> {
    springs: Vec<[usize; 2]>,
    hinges: Vec<[usize; 4]>,
    triangles: Vec<[usize; 3]>,
    mass: Vec<Lanes<L>>,
    inv_mass: Vec<Lanes<L>>,
    gravity: V3Lanes<L>,
    /// Per spring: rest length, stiffness, damping.
    spring_law: Vec<[Lanes<L>; 3]>,
    /// Per hinge: stiffness, damping, sin θ₀, cos θ₀.
    hinge_law: Vec<[Lanes<L>; 4]>,
    /// Per triangle: αⁿ, αᵗ.
    aero: Vec<[Lanes<L>; 2]>,
}

/// Gathers one number of every lane.
fn lanes<const L: usize>(f: impl Fn(usize) -> f64) -> Lanes<L> {
    std::array::from_fn(f)
}

impl<const L: usize> Batch<L> {
    /// A batch of `models[k]` released in `states[k]`, stepped by `dt[k]`.
    ///
    /// # Errors
    /// [`BatchError`]: lanes of different topologies, or a model that needs
    /// more than this batch steps.
    pub fn new(models: [&Model; L], states: [&State; L], dt: Lanes<L>) -> Result<Self, BatchError> {
        let first = models[0];
        let supported = Terms {
            gravity: true,
            springs: true,
            hinges: true,
            aero: true,
            wind: false,
            particle_drag: false,
            rigid: false,
            contact: false,
            breaking: false,
        };
        for (lane, (m, s)) in models.iter().zip(&states).enumerate() {
            let same = |what, ok: bool| ok.then_some(()).ok_or(BatchError::Topology { lane, what });
            same("particle counts", m.len() == first.len())?;
            same(
                "springs",
                m.springs.len() == first.springs.len()
                    && m.springs
                        .iter()
                        .zip(&first.springs)
                        .all(|(a, b)| (a.i, a.j) == (b.i, b.j)),
            )?;
            same(
                "hinges",
                m.hinges.len() == first.hinges.len()
                    && m.hinges
                        .iter()
                        .zip(&first.hinges)
                        .all(|(a, b)| a.particles() == b.particles()),
            )?;
            same(
                "triangles",
                m.triangles.len() == first.triangles.len()
                    && m.triangles
                        .iter()
                        .zip(&first.triangles)
                        .all(|(a, b)| a.corners == b.corners),
            )?;
            let unsupported = |what| Err(BatchError::Unsupported { lane, what });
            // The lanes step the linear law's kernel: the law whose force
            // is each triangle's α.
            if !m.aero.uses_triangle_alpha() {
                return unsupported("an aerodynamic law other than the linear one");
            }
            if Terms::needed(m) != supported {
                return unsupported("terms other than gravity, springs, hinges and aerodynamics");
            }
            if s.position.len() != m.len() || s.spring_alive.iter().any(|&a| !a) {
                return unsupported("a state with broken springs or of another size");
            }
        }
        let n = first.len();
        let vectors = |pick: &dyn Fn(usize, usize) -> V3| -> Vec<V3Lanes<L>> {
            (0..n)
                .map(|i| std::array::from_fn(|c| lanes(|k| pick(k, i)[c])))
                .collect()
        };
        let rest: Vec<Vec<(f64, f64)>> = models.iter().map(|m| hinge_rest(m)).collect();
        let law = Law {
            springs: first.springs.iter().map(|s| [s.i, s.j]).collect(),
            hinges: first.hinges.iter().map(|h| h.particles()).collect(),
            triangles: first.triangles.iter().map(|t| t.corners).collect(),
            mass: (0..n).map(|i| lanes(|k| models[k].mass[i])).collect(),
            inv_mass: (0..n).map(|i| lanes(|k| models[k].inv_mass[i])).collect(),
            gravity: std::array::from_fn(|c| lanes(|k| models[k].gravity[c])),
            spring_law: (0..first.springs.len())
                .map(|s| {
                    [
                        lanes(|k| models[k].springs[s].rest_length),
                        lanes(|k| models[k].springs[s].stiffness),
                        lanes(|k| models[k].springs[s].damping),
                    ]
                })
                .collect(),
            hinge_law: (0..first.hinges.len())
                .map(|h| {
                    [
                        lanes(|k| models[k].hinges[h].stiffness),
                        lanes(|k| models[k].hinges[h].damping),
                        lanes(|k| rest[k][h].0),
                        lanes(|k| rest[k][h].1),
                    ]
                })
                .collect(),
            aero: (0..first.triangles.len())
                .map(|t| {
                    [
                        lanes(|k| models[k].triangles[t].alpha_n),
                        lanes(|k| models[k].triangles[t].alpha_t),
                    ]
                })
                .collect(),
        };
        Ok(Batch {
            law,
            dt,
            speed_limit2: lanes(|k| {
                let limit = runaway_speed(models[k]);
                limit * limit
            }),
            x: vectors(&|k, i| states[k].position[i]),
            v: vectors(&|k, i| states[k].velocity[i]),
            acc: vec![[[0.0; L]; 3]; n],
            v_half: vec![[[0.0; L]; 3]; n],
            acc_new: vec![[[0.0; L]; 3]; n],
            acc_valid: false,
            live: [true; L],
            steps: [0; L],
            #[cfg(target_arch = "x86_64")]
            avx2: std::arch::is_x86_feature_detected!("avx2"),
            #[cfg(target_arch = "x86_64")]
            intrinsics: true,
        })
    }

    /// The same batch stepped with baseline x86-64 vectors only (SSE2),
    /// even where the CPU has AVX2: for tests and benchmarks of the two
    /// paths, which give the same bits.
    pub fn baseline_vectors(mut self) -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            self.avx2 = false;
        }
        self
    }

    /// The same batch stepped by the generic kernel, compiled for AVX2
    /// where the CPU has it, instead of the one written with intrinsics for
    /// four lanes: for tests and benchmarks of the two, which give the same
    /// bits.
    pub fn generic_vectors(mut self) -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            self.intrinsics = false;
        }
        self
    }

    /// Lanes still stepping.
    pub fn live(&self) -> [bool; L] {
        self.live
    }

    /// Steps each lane has taken.
    pub fn steps(&self) -> [u64; L] {
        self.steps
    }

    /// Copies the positions and velocities of `lane` into `x` and `v`.
    pub fn lane_into(&self, lane: usize, x: &mut [V3], v: &mut [V3]) {
        for ((p, u), (xo, vo)) in self.x.iter().zip(&self.v).zip(x.iter_mut().zip(v)) {
            *xo = V3::new(p[0][lane], p[1][lane], p[2][lane]);
            *vo = V3::new(u[0][lane], u[1][lane], u[2][lane]);
        }
    }

    /// The positions and velocities of `lane`.
    pub fn lane(&self, lane: usize) -> (Vec<V3>, Vec<V3>) {
        let pick = |v: &Vec<V3Lanes<L>>| {
            v.iter()
                .map(|p| V3::new(p[0][lane], p[1][lane], p[2][lane]))
                .collect()
        };
        (pick(&self.x), pick(&self.v))
    }

    /// One Verlet step of every lane in `active` that is still live (a lane
    /// left out keeps its state): [`Simulator::step`]'s arithmetic for
    /// [`Integrator::Verlet`], lane by lane. Returns the lanes live after
    /// the divergence check.
    ///
    /// [`Integrator::Verlet`]: crate::physics::params::Integrator::Verlet
    ///
    /// [`Simulator::step`]: crate::physics::integrate::Simulator::step
    pub fn step(&mut self, active: [bool; L]) -> [bool; L] {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // Four lanes, the breed's batches: the kernel written with AVX
            // intrinsics (`avx2.rs`), the same operations in the same order.
            if self.intrinsics
                && let Some(four) = (self as &mut dyn std::any::Any).downcast_mut::<Batch<4>>()
            {
                // SAFETY: `step_avx2_4` needs AVX2, and `Batch::new` found
                // it on this CPU (`is_x86_feature_detected!`).
                let live = unsafe { four.step_avx2_4(std::array::from_fn(|k| active[k])) };
                return std::array::from_fn(|k| live[k]);
            }
            // SAFETY: `step_avx2` needs AVX2, and `Batch::new` found it on
            // this CPU (`is_x86_feature_detected!`). The code is the same;
            // only the vector width differs, and without FMA (not enabled)
            // every lane operation is the same IEEE 754 operation.
            return unsafe { self.step_avx2(active) };
        }
        self.step_lanes(active)
    }

    /// [`Batch::step`] compiled for AVX2: four lanes per instruction
    /// instead of two (the baseline x86-64 has SSE2 only); measured with
    /// criterion, `lockstep` in benches/leaf_fall.rs.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn step_avx2(&mut self, active: [bool; L]) -> [bool; L] {
        self.step_lanes(active)
    }

    #[inline(always)]
    fn step_lanes(&mut self, active: [bool; L]) -> [bool; L] {
        let on: [bool; L] = std::array::from_fn(|k| active[k] && self.live[k]);
        if !self.acc_valid {
            self.law.acceleration(&self.x, &self.v, &mut self.acc);
            self.acc_valid = true;
        }
        let h = self.dt;
        for ((x, v), (a, vp)) in self
            .x
            .iter_mut()
            .zip(&mut self.v)
            .zip(self.acc.iter().zip(&mut self.v_half))
        {
            for c in 0..3 {
                for k in 0..L {
                    // A lane at rest keeps everything (its v_half is unused).
                    let (vk, ak) = (v[c][k], a[c][k]);
                    vp[c][k] = vk + ak * h[k];
                    let half = vk + ak * (0.5 * h[k]);
                    v[c][k] = if on[k] { half } else { vk };
                    x[c][k] = if on[k] {
                        x[c][k] + half * h[k]
                    } else {
                        x[c][k]
                    };
                }
            }
        }
        self.law
            .acceleration(&self.x, &self.v_half, &mut self.acc_new);
        for ((v, a), a_new) in self.v.iter_mut().zip(&mut self.acc).zip(&self.acc_new) {
            for c in 0..3 {
                for k in 0..L {
                    if on[k] {
                        v[c][k] += a_new[c][k] * (0.5 * h[k]);
                        a[c][k] = a_new[c][k];
                    }
                }
            }
        }
        // The divergence check of `Simulator::check`: one pass of sums.
        let (mut sum_x2, mut sum_v2) = ([0.0; L], [0.0; L]);
        for (x, v) in self.x.iter().zip(&self.v) {
            for k in 0..L {
                sum_x2[k] += 0.0 + ((x[0][k] * x[0][k] + x[1][k] * x[1][k]) + x[2][k] * x[2][k]);
                sum_v2[k] += 0.0 + ((v[0][k] * v[0][k] + v[1][k] * v[1][k]) + v[2][k] * v[2][k]);
            }
        }
        self.judge(on, &sum_x2, &sum_v2)
    }

    /// The divergence check's verdict once a step is taken, from each lane's
    /// sums of |x|² and |v|² over its particles (`Simulator::check`): a
    /// stepped lane counts its step, and a lane beyond the runaway distance
    /// or its speed limit, or whose sums are NaN, is live no more. Returns
    /// which lanes are still live.
    fn judge(&mut self, on: [bool; L], sum_x2: &Lanes<L>, sum_v2: &Lanes<L>) -> [bool; L] {
        let limit_x2 = RUNAWAY_DISTANCE * RUNAWAY_DISTANCE;
        let within = |value: f64, limit: f64| value.partial_cmp(&limit).is_some_and(|o| o.is_le());
        for k in 0..L {
            if on[k] {
                self.steps[k] += 1;
                if !(within(sum_x2[k], limit_x2) && within(sum_v2[k], self.speed_limit2[k])) {
                    self.live[k] = false;
                }
            }
        }
        self.live
    }
}

impl<const L: usize> Law<L> {
    /// a = F/m for every lane at (x, v): gravity, springs, hinges and the
    /// linear law in still air, summed in the order of `Forces::total`.
    #[inline(always)]
    fn acceleration(&self, x: &[V3Lanes<L>], v: &[V3Lanes<L>], acc: &mut [V3Lanes<L>]) {
        for (f, m) in acc.iter_mut().zip(&self.mass) {
            for (f, g) in f.iter_mut().zip(&self.gravity) {
                *f = (F(*m) * F(*g)).0;
            }
        }
        self.springs(x, v, acc);
        self.hinges(x, v, acc);
        self.aero(x, v, acc);
        for (a, w) in acc.iter_mut().zip(&self.inv_mass) {
            for c in a.iter_mut() {
                *c = (F(*c) * F(*w)).0;
            }
        }
    }

    /// `forces::springs`, lane by lane.
    #[inline(always)]
    fn springs(&self, x: &[V3Lanes<L>], v: &[V3Lanes<L>], force: &mut [V3Lanes<L>]) {
        for (&[i, j], [rest, stiffness, damping]) in self.springs.iter().zip(&self.spring_law) {
            let d = sub(vec(&x[i]), vec(&x[j]));
            let l2 = dot(d, d);
            let acts = l2.ne_zero();
            let l = l2.sqrt();
            let inv = F::splat(1.0) / l;
            let n = scale(d, inv);
            let stretch_rate = dot(sub(vec(&v[i]), vec(&v[j])), n);
            let s = -F(*stiffness) * (l - F(*rest)) - F(*damping) * stretch_rate;
            let f = scale(n, s);
            for c in 0..3 {
                force[i][c] = (F(force[i][c]) + f[c]).select(acts, F(force[i][c])).0;
                force[j][c] = (F(force[j][c]) - f[c]).select(acts, F(force[j][c])).0;
            }
        }
    }

    /// `forces::hinges`, lane by lane.
    #[inline(always)]
    fn hinges(&self, x: &[V3Lanes<L>], v: &[V3Lanes<L>], force: &mut [V3Lanes<L>]) {
        let ratio = crate::physics::forces::MIN_HINGE_HEIGHT_RATIO;
        for (ids, [stiffness, damping, rest_sin, rest_cos]) in
            self.hinges.iter().zip(&self.hinge_law)
        {
            let [a, b, p, q] = *ids;
            let xa = vec(&x[a]);
            let e = sub(vec(&x[b]), xa);
            let (rp, rq) = (sub(vec(&x[p]), xa), sub(vec(&x[q]), xa));
            let (np, nq) = (cross(e, rp), cross(e, rq));
            let (np2, nq2, len2) = (dot(np, np), dot(nq, nq), dot(e, e));
            let acts = np2.gt_min_positive() & nq2.gt_min_positive();
            let len = len2.sqrt();
            let inv_norms = F::splat(1.0) / (np2 * nq2).sqrt();
            let sin = dot(cross(np, nq), e) * (inv_norms / len);
            let cos = -dot(np, nq) * inv_norms;
            let floor = F::splat(ratio) * F::splat(ratio) * len2 * len2;
            let gp = scale(np, len / np2.max(floor));
            let gq = scale(nq, -len / nq2.max(floor));
            let inv_len2 = F::splat(1.0) / len2;
            let (tp, tq) = (dot(rp, e) * inv_len2, dot(rq, e) * inv_len2);
            let one = F::splat(1.0);
            let ga = std::array::from_fn(|c| -gp[c] * (one - tp) - gq[c] * (one - tq));
            let gb = std::array::from_fn(|c| -gp[c] * tp - gq[c] * tq);
            let grad = [ga, gb, gp, gq];
            let sin_delta = sin * F(*rest_cos) - cos * F(*rest_sin);
            let rate = ((dot(ga, vec(&v[a])) + dot(gb, vec(&v[b]))) + dot(gp, vec(&v[p])))
                + dot(gq, vec(&v[q]));
            let torque = -F(*stiffness) * sin_delta - F(*damping) * rate;
            for (&i, g) in ids.iter().zip(&grad) {
                for c in 0..3 {
                    let f = F(force[i][c]);
                    force[i][c] = (f + g[c] * torque).select(acts, f).0;
                }
            }
        }
    }

    /// The linear law in still air, lane by lane: the kernel a lone drop
    /// runs ([`LinearTriangle`], `aero::linear::linear_forces`) over `F<L>`.
    #[inline(always)]
    fn aero(&self, x: &[V3Lanes<L>], v: &[V3Lanes<L>], force: &mut [V3Lanes<L>]) {
        for (&[a, b, c3], [alpha_n, alpha_t]) in self.triangles.iter().zip(&self.aero) {
            let xa = vec(&x[a]);
            let big_n = cross(sub(vec(&x[b]), xa), sub(vec(&x[c3]), xa));
            let n2 = dot(big_n, big_n);
            let acts = n2.gt_min_positive();
            let law = LinearTriangle::new(big_n, n2, F(*alpha_n), F(*alpha_t));
            for i in [a, b, c3] {
                // Still air: v_r = −v, the force subtracted.
                let term = law.corner_force(vec(&v[i]));
                for c in 0..3 {
                    let f = F(force[i][c]);
                    force[i][c] = (f - term[c]).select(acts, f).0;
                }
            }
        }
    }
}

/// One f64 per lane, with the operations of the kernels applied lane by
/// lane: each is the IEEE 754 operation of the scalar code, and a loop of
/// L independent ones is what the compiler packs into vector instructions.
#[derive(Clone, Copy, Debug)]
struct F<const L: usize>(Lanes<L>);

impl<const L: usize> Lane for F<L> {
    #[inline(always)]
    fn splat(v: f64) -> Self {
        F([v; L])
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        self.map(f64::sqrt)
    }
}

impl<const L: usize> F<L> {
    #[inline(always)]
    fn map(self, f: impl Fn(f64) -> f64) -> Self {
        F(self.0.map(f))
    }
    #[inline(always)]
    fn zip(self, o: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        F(std::array::from_fn(|k| f(self.0[k], o.0[k])))
    }
    /// `f64::max` lane by lane.
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        self.zip(o, f64::max)
    }
    #[inline(always)]
    fn ne_zero(self) -> Mask<L> {
        Mask(self.0.map(|v| v != 0.0))
    }
    #[inline(always)]
    fn gt_min_positive(self) -> Mask<L> {
        Mask(self.0.map(|v| v > f64::MIN_POSITIVE))
    }
    /// `self` where `mask`, else `other`: a term a lone drop skips leaves
    /// the sum as it was (adding a zero would turn −0 into +0).
    #[inline(always)]
    fn select(self, mask: Mask<L>, other: Self) -> Self {
        F(std::array::from_fn(|k| {
            if mask.0[k] { self.0[k] } else { other.0[k] }
        }))
    }
}

/// One flag per lane.
#[derive(Clone, Copy, Debug)]
struct Mask<const L: usize>([bool; L]);

impl<const L: usize> std::ops::BitAnd for Mask<L> {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        Mask(std::array::from_fn(|k| self.0[k] && o.0[k]))
    }
}

macro_rules! lane_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl<const L: usize> std::ops::$trait for F<L> {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                self.zip(o, |a, b| a $op b)
            }
        }
    };
}
lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl<const L: usize> std::ops::Neg for F<L> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        self.map(|v| -v)
    }
}

/// A vector of lanes.
type VF<const L: usize> = [F<L>; 3];

#[inline(always)]
fn vec<const L: usize>(p: &V3Lanes<L>) -> VF<L> {
    [F(p[0]), F(p[1]), F(p[2])]
}

#[inline(always)]
fn sub<const L: usize>(a: VF<L>, b: VF<L>) -> VF<L> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// v s, component by component (nalgebra's vector times scalar).
#[inline(always)]
fn scale<const L: usize>(v: VF<L>, s: F<L>) -> VF<L> {
    [v[0] * s, v[1] * s, v[2] * s]
}

/// nalgebra's cross product, component by component in its order.
#[inline(always)]
fn cross<const L: usize>(a: VF<L>, b: VF<L>) -> VF<L> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// nalgebra's dot product of 3-vectors: (a₀b₀ + a₁b₁) + a₂b₂.
#[inline(always)]
fn dot<const L: usize>(a: VF<L>, b: VF<L>) -> F<L> {
    (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]
}
