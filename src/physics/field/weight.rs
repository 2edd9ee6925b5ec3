//! The smooth falloff shared by [`Bounds`](super::Bounds) and
//! [`Front`](super::Front).

/// Weight 1 for d ≤ 0, quintic smoothstep down to 0 at d = width, 0 beyond.
///
/// w = 1 − (6s⁵ − 15s⁴ + 10s³), s = d/width: w and its first two derivatives
/// are continuous at both ends (Perlin's "smootherstep"), so a bounded field
/// has no kink for a leaf to feel. `width = 0` is a hard edge.
#[inline]
pub(super) fn falloff_weight(d: f64, width: f64) -> f64 {
    if d <= 0.0 {
        1.0
    } else if d >= width {
        0.0
    } else {
        let s = d / width;
        1.0 - s * s * s * (10.0 + s * (6.0 * s - 15.0))
    }
}
