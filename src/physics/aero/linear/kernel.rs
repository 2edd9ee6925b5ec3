//! The linear law's arithmetic for one triangle, written once over a lane
//! type: `f64` for a lone drop, the batch's `L`-lane number for leaves
//! stepped in lockstep. Each operation is the IEEE 754 one, in one order,
//! whatever the lane type, so every lane computes bit for bit what the
//! scalar law computes (the batch tests check it).

use std::ops::{Add, Div, Mul, Sub};

/// A number the kernel computes with: one `f64`, or several side by side,
/// each operation applied lane by lane.
pub trait Lane:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// `v` in every lane.
    fn splat(v: f64) -> Self;
    /// The square root of every lane.
    fn sqrt(self) -> Self;
}

impl Lane for f64 {
    #[inline(always)]
    fn splat(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
}

/// The dot product of 3-vectors in nalgebra's order: (a₀b₀ + a₁b₁) + a₂b₂.
#[inline(always)]
pub fn dot<T: Lane>(a: [T; 3], b: [T; 3]) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// One triangle under the linear law (eq. 9–10), ready to give each corner
/// its force: F = αᵗ A v_r + (αⁿ − αᵗ) A (n·v_r) n, with
/// A n (n·v) = N (N·v) / (2|N|) for the unnormalised normal N = e₁ × e₂
/// (|N| = 2A), so a triangle squeezed towards zero area gets a force that
/// goes to zero instead of NaN.
#[derive(Clone, Copy, Debug)]
pub struct LinearTriangle<T> {
    big_n: [T; 3],
    tangential: T,
    normal_excess: T,
}

impl<T: Lane> LinearTriangle<T> {
    /// The triangle of normal N = `big_n`, |N|² = `n2` (> 0), and
    /// coefficients αⁿ, αᵗ.
    #[inline(always)]
    pub fn new(big_n: [T; 3], n2: T, alpha_n: T, alpha_t: T) -> Self {
        let doubled_area = n2.sqrt();
        let area = T::splat(0.5) * doubled_area;
        LinearTriangle {
            big_n,
            tangential: alpha_t * area,
            normal_excess: (alpha_n - alpha_t) / (T::splat(2.0) * doubled_area),
        }
    }

    /// The force on a corner whose air moves at `v_rel` relative to it:
    /// αᵗ A v_r + (αⁿ − αᵗ) A (n·v_r) n.
    #[inline(always)]
    pub fn corner_force(&self, v_rel: [T; 3]) -> [T; 3] {
        let along = self.normal_excess * dot(self.big_n, v_rel);
        std::array::from_fn(|c| self.tangential * v_rel[c] + self.big_n[c] * along)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// Four f64 side by side: a lane type of the kernel's own kind.
    #[derive(Clone, Copy, Debug)]
    struct Four([f64; 4]);

    macro_rules! four_op {
        ($trait:ident, $method:ident, $op:tt) => {
            impl std::ops::$trait for Four {
                type Output = Four;
                fn $method(self, o: Four) -> Four {
                    Four(std::array::from_fn(|k| self.0[k] $op o.0[k]))
                }
            }
        };
    }
    four_op!(Add, add, +);
    four_op!(Sub, sub, -);
    four_op!(Mul, mul, *);
    four_op!(Div, div, /);

    impl Lane for Four {
        fn splat(v: f64) -> Self {
            Four([v; 4])
        }
        fn sqrt(self) -> Self {
            Four(self.0.map(f64::sqrt))
        }
    }

    /// Each lane of a four-lane triangle is, to the bit, the `f64` kernel on
    /// that lane's numbers; and the `f64` kernel is the law as eq. 9–10
    /// state it, αᵗ A vᵗ + αⁿ A vⁿ with the unit normal, to rounding.
    #[test]
    fn lanes_equal_the_scalar_kernel_and_the_equations() {
        let corners = |k: usize| {
            let s = k as f64;
            [
                Vector3::new(0.0, 0.0, 0.1 * s),
                Vector3::new(0.03 + 0.01 * s, 0.002, -0.004),
                Vector3::new(0.005, 0.02 - 0.003 * s, 0.001 * s),
            ]
        };
        let alpha = |k: usize| (0.47 + 0.1 * k as f64, 0.047 * (1.0 + k as f64));
        let v_rel = |k: usize| Vector3::new(0.3 - 0.2 * k as f64, -1.1, 2.0 + k as f64);
        let big_n = |k: usize| {
            let [a, b, c] = corners(k);
            (b - a).cross(&(c - a))
        };
        let lanes = |f: &dyn Fn(usize) -> f64| Four(std::array::from_fn(f));
        let four = LinearTriangle::new(
            std::array::from_fn(|c| lanes(&|k| big_n(k)[c])),
            lanes(&|k| big_n(k).norm_squared()),
            lanes(&|k| alpha(k).0),
            lanes(&|k| alpha(k).1),
        );
        let f4 = four.corner_force(std::array::from_fn(|c| lanes(&|k| v_rel(k)[c])));
        for k in 0..4 {
            let n = big_n(k);
            let (alpha_n, alpha_t) = alpha(k);
            let one = LinearTriangle::new(n.into(), n.norm_squared(), alpha_n, alpha_t);
            let f1 = one.corner_force(v_rel(k).into());
            for c in 0..3 {
                assert_eq!(f4[c].0[k].to_bits(), f1[c].to_bits(), "lane {k}, axis {c}");
            }
            let area = 0.5 * n.norm();
            let unit = n.normalize();
            let normal = unit * unit.dot(&v_rel(k));
            let tangential = v_rel(k) - normal;
            let expected = alpha_n * area * normal + alpha_t * area * tangential;
            let got = Vector3::from(f1);
            assert!(
                (got - expected).norm() <= 1e-14 * expected.norm(),
                "lane {k}: {got:?} against eq. 9–10's {expected:?}"
            );
        }
    }
}
