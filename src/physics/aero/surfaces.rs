//! The triangles that act as surfaces at a given shape, shared by both
//! aerodynamic laws.

use crate::physics::model::Triangle;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// The unnormalised normal N = e₁ × e₂ (e₁ = x_b − x_a, e₂ = x_c − x_a) of
/// triangle `t` and |N|² = 4A², if it acts as a surface at `x`: not torn
/// (`torn[t]`; an empty mask tears none) and not exactly flat. Forces built
/// on N go to zero continuously as |N| → 0; only an exactly flat triangle
/// would divide by zero, so it alone is skipped. Shared by both aerodynamic
/// laws, which call it in a plain loop over the triangles: an iterator
/// adaptor chain here is not reliably inlined across modules, and the
/// aerodynamics are a fifth of a drop's time.
#[inline(always)]
pub(crate) fn surface(t: usize, tri: &Triangle, x: &[V3], torn: &[bool]) -> Option<(V3, f64)> {
    if torn.get(t).copied().unwrap_or(false) {
        return None;
    }
    let [a, b, c] = tri.corners;
    let big_n = (x[b] - x[a]).cross(&(x[c] - x[a]));
    let n2 = big_n.norm_squared();
    (n2 > f64::MIN_POSITIVE).then_some((big_n, n2))
}
