//! Step 4 of the method ([`super`]): the area signals' maxima per second
//! (the turn rate of a plate turning about a horizontal axis) and their
//! periodicity.

use super::features::PathFeatures;
use super::signal::{detrended, periodicity};
use crate::motion::trajectory::Trajectory;

/// Smallest swing of an area signal counted as a maximum, as a fraction of
/// the signal's range over the window: the authors' own rate of tumbling
/// counted maxima of at least 5 % prominence on clean signals; tracked
/// silhouettes flicker by more, 20 % keeps the turns and drops the flicker
/// (calibrated, docs/guide/classification.md).
pub const AREA_MIN_SWING: f64 = 0.2;

/// Smallest swing of an area signal counted as a maximum, as a fraction of
/// the signal's mean level, whatever its range: a plate's projected area
/// changes by a good part of itself as the plate turns (a tumbling plate's
/// from edge-on to face-on), a steady plate's only by the silhouette's
/// flicker, whose range alone would otherwise set the swing (our choice:
/// five times the corpus cameras' 2 % flicker; no verdict at 98 fps
/// changes, docs/guide/classification.md, "Frame rates").
pub const AREA_MIN_SWING_OF_LEVEL: f64 = 0.1;

/// Half-width of the moving average applied to area signals before
/// counting maxima, s (one frame at 98 fps: silhouette flicker).
pub const AREA_SMOOTHING_S: f64 = 0.01;

/// Turning points of `y` with swings of at least `swing`: the number of
/// maxima.
fn maxima(y: &[f64], swing: f64) -> usize {
    let (mut dir, mut count) = (0i8, 0usize);
    let (mut lo, mut hi) = (y[0], y[0]);
    let mut ext = y[0];
    for &v in y {
        match dir {
            0 => {
                lo = lo.min(v);
                hi = hi.max(v);
                if v - lo >= swing {
                    dir = 1;
                    ext = v;
                } else if hi - v >= swing {
                    dir = -1;
                    ext = v;
                }
            }
            1 => {
                if v > ext {
                    ext = v;
                } else if ext - v >= swing {
                    count += 1;
                    dir = -1;
                    ext = v;
                }
            }
            _ => {
                if v < ext {
                    ext = v;
                } else if v - ext >= swing {
                    dir = 1;
                    ext = v;
                }
            }
        }
    }
    count
}

/// The area features of a uniform record.
pub(super) fn measure_areas(g: &Trajectory, dt: f64, f: &mut PathFeatures) {
    let m = g.len();
    let duration = (m - 1) as f64 * dt;
    let h = (AREA_SMOOTHING_S / dt).round() as usize;
    let (mut rate_sum, mut best_period) = (0.0f64, f64::NEG_INFINITY);
    for a in &g.areas {
        // Detrend (the paper nears or leaves the camera), then smooth.
        let detrended = detrended(&a.values);
        let smooth: Vec<f64> = (0..m)
            .map(|k| {
                let (lo, hi) = (k.saturating_sub(h), (k + h).min(m - 1));
                detrended[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64
            })
            .collect();
        let (lo, hi) = smooth
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &v| {
                (l.min(v), u.max(v))
            });
        let range = hi - lo;
        let level = a.values.iter().sum::<f64>() / m as f64;
        let swing = (AREA_MIN_SWING * range).max(AREA_MIN_SWING_OF_LEVEL * level.abs());
        if range > 0.0 {
            rate_sum += maxima(&smooth, swing) as f64 / duration;
        }
        best_period = best_period.max(periodicity(&detrended));
        f.area_signals += 1;
    }
    if f.area_signals > 0 {
        let rate = rate_sum / f.area_signals as f64;
        f.area_maxima_per_s = Some(rate);
        f.area_turn_rate_rad_s = Some(std::f64::consts::PI * rate);
        f.area_periodicity = Some(best_period);
    }
}
