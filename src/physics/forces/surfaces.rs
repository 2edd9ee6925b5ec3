//! The triangles that act as surfaces at a given shape, shared by both
//! aerodynamic laws.

use crate::physics::model::{Model, Triangle};
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// The triangles that act as surfaces, with their unnormalised normal
/// N = e₁ × e₂ (e₁ = x_b − x_a, e₂ = x_c − x_a) and |N|² = 4A²: those not torn (`torn[t]`; an empty mask tears
/// none) and not exactly flat. Forces built on N go to zero continuously as
/// |N| → 0; only an exactly flat triangle would divide by zero, so it alone
/// is skipped. Shared by both aerodynamic laws.
#[inline]
pub(crate) fn surfaces<'m>(
    model: &'m Model,
    x: &'m [V3],
    torn: &'m [bool],
) -> impl Iterator<Item = (&'m Triangle, V3, f64)> + 'm {
    model
        .triangles
        .iter()
        .enumerate()
        .filter(|(t, _)| !torn.get(*t).copied().unwrap_or(false))
        .filter_map(|(_, tri)| {
            let [a, b, c] = tri.corners;
            let big_n = (x[b] - x[a]).cross(&(x[c] - x[a]));
            let n2 = big_n.norm_squared();
            (n2 > f64::MIN_POSITIVE).then_some((tri, big_n, n2))
        })
}
