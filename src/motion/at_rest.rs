//! The part of a record in which the leaf is in the air. A filmed fall
//! often begins with the leaf held still before it is let go and ends
//! with it lying on the floor; a simulated one may end on the ground.
//! Those stretches are not the fall: classified with it, a tumbling
//! square that lies on the floor for a second reads as chaotic (its
//! descent "modulated" by 81 %), and a 10 s bake that lands after 4 s
//! loses its whole analysis window to the rest.
//!
//! At rest means that the centre stays within [`REST_RADIUS_CHORDS`]
//! chords (at least [`REST_RADIUS_MIN_M`]) of where the record starts, or
//! of where it ends, for at least [`MIN_REST_S`]. A leaf let go from rest
//! leaves that ball within a few hundredths of a second (free fall takes
//! 0.05 s to fall a quarter of a 5 cm chord), and a leaf still falling at
//! the end leaves it as fast, backwards in time; a leaf carried by wind
//! moves away from it too. Only a leaf that is still is cut.

use crate::motion::trajectory::Trajectory;
use serde::{Deserialize, Serialize};

/// Radius of the ball the centre stays in while at rest, in chords (our
/// choice: a leaf lying on the floor moves by the tracker's noise, a
/// millimetre or so; one falling at 0.3 m/s leaves a quarter chord of a 5
/// cm leaf in 0.04 s).
pub const REST_RADIUS_CHORDS: f64 = 0.25;

/// Least radius of that ball, m (a tracker's noise on a small leaf).
pub const REST_RADIUS_MIN_M: f64 = 0.005;

/// Shortest stretch at rest that is cut, s: the films' flat releases sit
/// still for their first 0.03–0.07 s (an artefact of their first frames,
/// docs/lab/real-falls.md), which is part of the record as filmed.
pub const MIN_REST_S: f64 = 0.2;

/// What was cut from a record as rest, s (0 when nothing).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AtRest {
    /// Still before release: the record's first seconds.
    pub before_s: f64,
    /// Still after landing: its last seconds.
    pub after_s: f64,
}

impl AtRest {
    /// In words, for a classification's reason.
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if self.before_s > 0.0 {
            parts.push(format!("the first {:.2} s, before release", self.before_s));
        }
        if self.after_s > 0.0 {
            parts.push(format!("the last {:.2} s, after landing", self.after_s));
        }
        format!("still for {}: left out", parts.join(" and "))
    }
}

/// The record without its still start and end, and what was cut; `None`
/// when the leaf is never still for [`MIN_REST_S`] at either end (the
/// record is used as it is), or when nothing in the air would be left.
pub fn in_air(trajectory: &Trajectory, size: f64) -> Option<(Trajectory, AtRest)> {
    let n = trajectory.len();
    let finite = trajectory
        .position
        .iter()
        .all(|p| p.iter().all(|x| x.is_finite()));
    let sized = size.is_finite() && size > 0.0;
    if n < 3 || trajectory.position.len() != n || !finite || !sized {
        return None;
    }
    let radius = (REST_RADIUS_CHORDS * size).max(REST_RADIUS_MIN_M);
    let (p, t) = (&trajectory.position, &trajectory.time);
    // The first sample outside the ball about the start, and the last one
    // outside the ball about the end.
    let first = (0..n).find(|&k| (p[k] - p[0]).norm() > radius)?;
    let last = (0..n).rev().find(|&k| (p[k] - p[n - 1]).norm() > radius)?;
    let start = if t[first] - t[0] >= MIN_REST_S {
        first - 1
    } else {
        0
    };
    let end = if t[n - 1] - t[last] >= MIN_REST_S {
        last + 1
    } else {
        n - 1
    };
    if (start == 0 && end == n - 1) || end <= start + 1 {
        return None;
    }
    let cut = AtRest {
        before_s: t[start] - t[0],
        after_s: t[n - 1] - t[end],
    };
    Some((trajectory.slice(start, end), cut))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    const RATE: f64 = 100.0;
    const CHORD: f64 = 0.05;

    /// A record at 100 Hz of `seconds`, the centre at `p(t)`.
    fn record(seconds: f64, p: impl Fn(f64) -> Vector3<f64>) -> Trajectory {
        let mut tr = Trajectory::default();
        for k in 0..=(seconds * RATE).round() as usize {
            let t = k as f64 / RATE;
            tr.push_position(t, p(t));
        }
        tr
    }

    /// Held still for 0.5 s, let go, falling 1 m/s for 1 s, then lying
    /// on the floor with a millimetre of tracking jitter for 1 s: both
    /// stretches are cut, to within a sample of where the leaf leaves
    /// and reaches the ball of a quarter chord.
    #[test]
    fn a_held_start_and_a_landed_end_are_cut() {
        let jitter = |t: f64| 0.001 * (37.0 * t).sin();
        let tr = record(2.5, |t| {
            let z = if t < 0.5 {
                1.0
            } else if t < 1.5 {
                1.0 - (t - 0.5)
            } else {
                0.0
            };
            Vector3::new(jitter(t), 0.0, z + jitter(t))
        });
        let (air, rest) = in_air(&tr, CHORD).unwrap();
        // The ball's radius, 12.5 mm, is left in 0.0125 s at 1 m/s.
        assert!((rest.before_s - 0.5).abs() <= 0.02, "{rest:?}");
        assert!((rest.after_s - 1.0).abs() <= 0.02, "{rest:?}");
        assert!(air.time[0] >= 0.5 - 0.02 && *air.time.last().unwrap() <= 1.5 + 0.02);
        assert_eq!(air.len(), air.position.len());
        let said = rest.describe();
        assert!(
            said.contains(&format!("the first {:.2} s, before release", rest.before_s))
                && said.contains("after landing: left out"),
            "{said}"
        );
    }

    /// A fall from rest (free fall, then 0.3 m/s), one still falling at
    /// the end, one carried sideways by wind at a constant height: nothing
    /// is cut; nor from a leaf that never moves (nothing is in the air).
    #[test]
    fn falls_without_a_still_end_are_kept_whole() {
        let from_rest = record(2.0, |t| {
            Vector3::new(0.0, 0.0, -(0.5 * 9.8 * t * t).min(0.3 * t))
        });
        assert!(in_air(&from_rest, CHORD).is_none());
        let hovering = record(2.0, |t| Vector3::new(0.5 * t, 0.0, 1.0));
        assert!(in_air(&hovering, CHORD).is_none());
        let still = record(2.0, |_| Vector3::new(0.0, 0.0, 1.0));
        assert!(in_air(&still, CHORD).is_none());
        // Slower than radius / MIN_REST_S (6 cm/s for a 5 cm chord) reads
        // as still; faster does not.
        let slow = record(2.0, |t| Vector3::new(0.0, 0.0, -0.05 * t));
        assert!(in_air(&slow, CHORD).is_some());
        let fast = record(2.0, |t| Vector3::new(0.0, 0.0, -0.07 * t));
        assert!(in_air(&fast, CHORD).is_none());
    }
}
