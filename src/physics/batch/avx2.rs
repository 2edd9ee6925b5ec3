//! [`Batch::step`] of four lanes written with AVX intrinsics: one 256-bit
//! register per quantity, the four lanes of a [`Lanes`] array.
//!
//! The generic kernel (`Batch::step_lanes`) leaves the packing to the
//! compiler, which split much of it into two-wide and scalar operations,
//! packed and unpacked the lane masks, and spilled (perf annotate of a
//! breed). Here every lane operation is written as the one vector
//! instruction it is: the same IEEE 754 operations in the same order as the
//! generic kernel (and so as the scalar `Simulator`), with no FMA and no
//! reassociation, so every lane's bits are unchanged; the tests of
//! tests/integration/batch.rs compare both against lone drops.

use super::{Batch, Lanes, Law, V3Lanes};
use crate::physics::forces::MIN_HINGE_HEIGHT_RATIO;
use core::arch::x86_64::{
    __m256d, _CMP_GT_OQ, _CMP_NEQ_UQ, _CMP_UNORD_Q, _mm256_add_pd, _mm256_and_pd, _mm256_blendv_pd,
    _mm256_castsi256_pd, _mm256_cmp_pd, _mm256_div_pd, _mm256_loadu_pd, _mm256_max_pd,
    _mm256_movemask_pd, _mm256_mul_pd, _mm256_set_epi64x, _mm256_set1_pd, _mm256_sqrt_pd,
    _mm256_storeu_pd, _mm256_sub_pd, _mm256_xor_pd,
};

/// Four lanes of f64.
type W = __m256d;
/// A vector of four lanes.
type VW = [W; 3];

/// The four lanes of `p`.
#[target_feature(enable = "avx2")]
#[inline]
fn load(p: &Lanes<4>) -> W {
    // SAFETY: `p` is a reference to four contiguous f64, valid for reads of
    // the 32 bytes the unaligned load reads.
    unsafe { _mm256_loadu_pd(p.as_ptr()) }
}

/// Writes the four lanes of `v` into `p`.
#[target_feature(enable = "avx2")]
#[inline]
fn store(p: &mut Lanes<4>, v: W) {
    // SAFETY: `p` is an exclusive reference to four contiguous f64, valid
    // for writes of the 32 bytes the unaligned store writes.
    unsafe { _mm256_storeu_pd(p.as_mut_ptr(), v) }
}

#[target_feature(enable = "avx2")]
#[inline]
fn vec(p: &V3Lanes<4>) -> VW {
    [load(&p[0]), load(&p[1]), load(&p[2])]
}

#[target_feature(enable = "avx2")]
#[inline]
fn splat(v: f64) -> W {
    _mm256_set1_pd(v)
}

#[target_feature(enable = "avx2")]
#[inline]
fn add(a: W, b: W) -> W {
    _mm256_add_pd(a, b)
}

#[target_feature(enable = "avx2")]
#[inline]
fn sub(a: W, b: W) -> W {
    _mm256_sub_pd(a, b)
}

#[target_feature(enable = "avx2")]
#[inline]
fn mul(a: W, b: W) -> W {
    _mm256_mul_pd(a, b)
}

#[target_feature(enable = "avx2")]
#[inline]
fn div(a: W, b: W) -> W {
    _mm256_div_pd(a, b)
}

/// −a: the sign bit flipped, as Rust's unary minus.
#[target_feature(enable = "avx2")]
#[inline]
fn neg(a: W) -> W {
    _mm256_xor_pd(a, splat(-0.0))
}

#[target_feature(enable = "avx2")]
#[inline]
fn sqrt(a: W) -> W {
    _mm256_sqrt_pd(a)
}

/// `f64::max` lane by lane: `vmaxpd` returns its second operand where
/// either is NaN, `f64::max` the operand that is not NaN.
#[target_feature(enable = "avx2")]
#[inline]
fn max(a: W, b: W) -> W {
    let m = _mm256_max_pd(a, b);
    _mm256_blendv_pd(m, a, _mm256_cmp_pd::<_CMP_UNORD_Q>(b, b))
}

/// `a` where `mask`, else `b`.
#[target_feature(enable = "avx2")]
#[inline]
fn select(mask: W, a: W, b: W) -> W {
    _mm256_blendv_pd(b, a, mask)
}

/// Whether every lane of `mask` is set: then `select(mask, a, b)` is `a`,
/// and the blend can be left out.
#[target_feature(enable = "avx2")]
#[inline]
fn all(mask: W) -> bool {
    _mm256_movemask_pd(mask) == 0b1111
}

/// The lanes where one element's force acts (a spring of non-zero
/// length, a hinge with both wings, a triangle with an area), and whether
/// that is all four, when a blend would give the new sum itself and is
/// left out (the same bits).
#[derive(Clone, Copy)]
struct Acting {
    mask: W,
    every: bool,
}

impl Acting {
    #[target_feature(enable = "avx2")]
    #[inline]
    fn new(mask: W) -> Acting {
        Acting {
            mask,
            every: all(mask),
        }
    }

    /// Writes `sum` into `p` where the element acts, keeps `old` elsewhere.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn store(self, p: &mut Lanes<4>, sum: W, old: W) {
        store(
            p,
            if self.every {
                sum
            } else {
                select(self.mask, sum, old)
            },
        );
    }
}

/// The mask of lanes where `on`.
#[target_feature(enable = "avx2")]
#[inline]
fn mask(on: [bool; 4]) -> W {
    let m = |k: usize| -i64::from(on[k]);
    _mm256_castsi256_pd(_mm256_set_epi64x(m(3), m(2), m(1), m(0)))
}

#[target_feature(enable = "avx2")]
#[inline]
fn sub3(a: VW, b: VW) -> VW {
    [sub(a[0], b[0]), sub(a[1], b[1]), sub(a[2], b[2])]
}

#[target_feature(enable = "avx2")]
#[inline]
fn scale(v: VW, s: W) -> VW {
    [mul(v[0], s), mul(v[1], s), mul(v[2], s)]
}

/// nalgebra's cross product, component by component in its order.
#[target_feature(enable = "avx2")]
#[inline]
fn cross(a: VW, b: VW) -> VW {
    [
        sub(mul(a[1], b[2]), mul(a[2], b[1])),
        sub(mul(a[2], b[0]), mul(a[0], b[2])),
        sub(mul(a[0], b[1]), mul(a[1], b[0])),
    ]
}

/// nalgebra's dot product of 3-vectors: (a₀b₀ + a₁b₁) + a₂b₂.
#[target_feature(enable = "avx2")]
#[inline]
fn dot(a: VW, b: VW) -> W {
    add(add(mul(a[0], b[0]), mul(a[1], b[1])), mul(a[2], b[2]))
}

impl Batch<4> {
    /// `Batch::step_lanes` for four lanes in AVX registers: the same
    /// operations in the same order.
    #[target_feature(enable = "avx2")]
    pub(super) fn step_avx2_4(&mut self, active: [bool; 4]) -> [bool; 4] {
        let on: [bool; 4] = std::array::from_fn(|k| active[k] && self.live[k]);
        let on_mask = mask(on);
        if !self.acc_valid {
            self.law.acceleration_avx2(&self.x, &self.v, &mut self.acc);
            self.acc_valid = true;
        }
        let h = load(&self.dt);
        let half_h = mul(splat(0.5), h);
        for ((x, v), (a, vp)) in self
            .x
            .iter_mut()
            .zip(&mut self.v)
            .zip(self.acc.iter().zip(&mut self.v_half))
        {
            for c in 0..3 {
                // A lane at rest keeps everything (its v_half is unused).
                let (vk, ak, xk) = (load(&v[c]), load(&a[c]), load(&x[c]));
                store(&mut vp[c], add(vk, mul(ak, h)));
                let half = add(vk, mul(ak, half_h));
                store(&mut v[c], select(on_mask, half, vk));
                store(&mut x[c], select(on_mask, add(xk, mul(half, h)), xk));
            }
        }
        self.law
            .acceleration_avx2(&self.x, &self.v_half, &mut self.acc_new);
        for ((v, a), a_new) in self.v.iter_mut().zip(&mut self.acc).zip(&self.acc_new) {
            for c in 0..3 {
                let (vk, ak, nk) = (load(&v[c]), load(&a[c]), load(&a_new[c]));
                store(&mut v[c], select(on_mask, add(vk, mul(nk, half_h)), vk));
                store(&mut a[c], select(on_mask, nk, ak));
            }
        }
        // The divergence check of `Simulator::check`: one pass of sums.
        let (mut sum_x2, mut sum_v2) = (splat(0.0), splat(0.0));
        for (x, v) in self.x.iter().zip(&self.v) {
            let (x, v) = (vec(x), vec(v));
            sum_x2 = add(sum_x2, add(splat(0.0), dot(x, x)));
            sum_v2 = add(sum_v2, add(splat(0.0), dot(v, v)));
        }
        let (mut sx, mut sv) = ([0.0; 4], [0.0; 4]);
        store(&mut sx, sum_x2);
        store(&mut sv, sum_v2);
        self.judge(on, &sx, &sv)
    }
}

impl Law<4> {
    /// `Law::acceleration` in AVX registers.
    #[target_feature(enable = "avx2")]
    fn acceleration_avx2(&self, x: &[V3Lanes<4>], v: &[V3Lanes<4>], acc: &mut [V3Lanes<4>]) {
        let g = vec(&self.gravity);
        for (f, m) in acc.iter_mut().zip(&self.mass) {
            let m = load(m);
            for c in 0..3 {
                store(&mut f[c], mul(m, g[c]));
            }
        }
        self.springs_avx2(x, v, acc);
        self.hinges_avx2(x, v, acc);
        self.aero_avx2(x, v, acc);
        for (a, w) in acc.iter_mut().zip(&self.inv_mass) {
            let w = load(w);
            for c in a.iter_mut() {
                store(c, mul(load(c), w));
            }
        }
    }

    /// `Law::springs` in AVX registers.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn springs_avx2(&self, x: &[V3Lanes<4>], v: &[V3Lanes<4>], force: &mut [V3Lanes<4>]) {
        let one = splat(1.0);
        for (&[i, j], [rest, stiffness, damping]) in self.springs.iter().zip(&self.spring_law) {
            let d = sub3(vec(&x[i]), vec(&x[j]));
            let l2 = dot(d, d);
            let acts = Acting::new(_mm256_cmp_pd::<_CMP_NEQ_UQ>(l2, splat(0.0)));
            let l = sqrt(l2);
            let inv = div(one, l);
            let n = scale(d, inv);
            let stretch_rate = dot(sub3(vec(&v[i]), vec(&v[j])), n);
            let s = sub(
                mul(neg(load(stiffness)), sub(l, load(rest))),
                mul(load(damping), stretch_rate),
            );
            let f = scale(n, s);
            for c in 0..3 {
                let fi = load(&force[i][c]);
                acts.store(&mut force[i][c], add(fi, f[c]), fi);
                let fj = load(&force[j][c]);
                acts.store(&mut force[j][c], sub(fj, f[c]), fj);
            }
        }
    }

    /// `Law::hinges` in AVX registers.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn hinges_avx2(&self, x: &[V3Lanes<4>], v: &[V3Lanes<4>], force: &mut [V3Lanes<4>]) {
        let ratio = splat(MIN_HINGE_HEIGHT_RATIO);
        let (one, min_positive) = (splat(1.0), splat(f64::MIN_POSITIVE));
        for (ids, [stiffness, damping, rest_sin, rest_cos]) in
            self.hinges.iter().zip(&self.hinge_law)
        {
            let [a, b, p, q] = *ids;
            let xa = vec(&x[a]);
            let e = sub3(vec(&x[b]), xa);
            let (rp, rq) = (sub3(vec(&x[p]), xa), sub3(vec(&x[q]), xa));
            let (np, nq) = (cross(e, rp), cross(e, rq));
            let (np2, nq2, len2) = (dot(np, np), dot(nq, nq), dot(e, e));
            let acts = Acting::new(_mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GT_OQ>(np2, min_positive),
                _mm256_cmp_pd::<_CMP_GT_OQ>(nq2, min_positive),
            ));
            let len = sqrt(len2);
            let inv_norms = div(one, sqrt(mul(np2, nq2)));
            let sin = mul(dot(cross(np, nq), e), div(inv_norms, len));
            let cos = mul(neg(dot(np, nq)), inv_norms);
            let floor = mul(mul(mul(ratio, ratio), len2), len2);
            let gp = scale(np, div(len, max(np2, floor)));
            let gq = scale(nq, div(neg(len), max(nq2, floor)));
            let inv_len2 = div(one, len2);
            let (tp, tq) = (mul(dot(rp, e), inv_len2), mul(dot(rq, e), inv_len2));
            let (one_tp, one_tq) = (sub(one, tp), sub(one, tq));
            let ga: VW = std::array::from_fn(|c| sub(mul(neg(gp[c]), one_tp), mul(gq[c], one_tq)));
            let gb: VW = std::array::from_fn(|c| sub(mul(neg(gp[c]), tp), mul(gq[c], tq)));
            let sin_delta = sub(mul(sin, load(rest_cos)), mul(cos, load(rest_sin)));
            let rate = add(
                add(
                    add(dot(ga, vec(&v[a])), dot(gb, vec(&v[b]))),
                    dot(gp, vec(&v[p])),
                ),
                dot(gq, vec(&v[q])),
            );
            let torque = sub(
                mul(neg(load(stiffness)), sin_delta),
                mul(load(damping), rate),
            );
            for (&i, g) in ids.iter().zip(&[ga, gb, gp, gq]) {
                for c in 0..3 {
                    let f = load(&force[i][c]);
                    acts.store(&mut force[i][c], add(f, mul(g[c], torque)), f);
                }
            }
        }
    }

    /// `Law::aero` in AVX registers: the linear law's kernel
    /// (`aero::linear::kernel::LinearTriangle`) in its one hand-vectorised
    /// form, operation for operation, so it stays bit-identical to it (the
    /// batch tests check it).
    #[target_feature(enable = "avx2")]
    #[inline]
    fn aero_avx2(&self, x: &[V3Lanes<4>], v: &[V3Lanes<4>], force: &mut [V3Lanes<4>]) {
        let (half, two, min_positive) = (splat(0.5), splat(2.0), splat(f64::MIN_POSITIVE));
        for (&[a, b, c3], [alpha_n, alpha_t]) in self.triangles.iter().zip(&self.aero) {
            let xa = vec(&x[a]);
            let big_n = cross(sub3(vec(&x[b]), xa), sub3(vec(&x[c3]), xa));
            let n2 = dot(big_n, big_n);
            let acts = Acting::new(_mm256_cmp_pd::<_CMP_GT_OQ>(n2, min_positive));
            let doubled_area = sqrt(n2);
            let area = mul(half, doubled_area);
            let (alpha_n, alpha_t) = (load(alpha_n), load(alpha_t));
            let tangential = mul(alpha_t, area);
            let normal_excess = div(sub(alpha_n, alpha_t), mul(two, doubled_area));
            for i in [a, b, c3] {
                let vi = vec(&v[i]);
                let along = mul(normal_excess, dot(big_n, vi));
                for c in 0..3 {
                    let f = load(&force[i][c]);
                    let term = add(mul(tangential, vi[c]), mul(big_n[c], along));
                    acts.store(&mut force[i][c], sub(f, term), f);
                }
            }
        }
    }
}
