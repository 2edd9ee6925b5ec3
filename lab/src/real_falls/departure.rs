//! When a real flat release leaves its flat fall, measured past the films'
//! first frames (docs/lab/real-falls.md, "When a flat release departs").
//!
//! The experiment cuts a flat release's start as "steady" until the tracked
//! centre has moved 0.2 r sideways, and those segments last 3–7 frames. But
//! over those frames the two cameras' silhouettes of a plate that is still
//! flat grow 2.6–8.4 times (frame 5 against frame 0, all 50 flat drops),
//! which a tilt of a few degrees cannot do: the plate is still coming into
//! full view (the release holds part of it out of sight, or the tracking's
//! smoothing runs into frames without it), and the centre of what is seen
//! moves while it does. The cut therefore times the artefact, not the fall.
//! Here a drop's centre is taken once its silhouette is whole, and the
//! drop departs when it is 0.2 r sideways from there, the experiment's own
//! threshold: 0.13–0.37 s after the first frame, longer for larger squares.

use super::films::{FPS, Film};
use super::segments::{RealSegment, SQUARE_BINS, bin_of};

/// Frames at the start of a flat drop within which the end of the first
/// frames' artefact is sought: 0.15 s, twice the longest the silhouettes
/// take to grow whole (0.13 s, the 9 cm squares).
pub const ARTEFACT_FRAMES: usize = 15;

/// Share of its largest value within [`ARTEFACT_FRAMES`] at which the two
/// cameras' summed silhouette is taken as whole. 0.8 or a window of 10 or
/// 20 frames moves no bin's median departure by more than 0.06 s.
pub const WHOLE_SHARE: f64 = 0.9;

/// Sideways distance, in half-sides, at which a flat drop departs: the
/// threshold of the experiment's steady cut (classifyBehaviour.m).
pub const DEPARTURE_RADII: f64 = 0.2;

/// One real flat drop, its segments joined.
#[derive(Clone, Debug, PartialEq)]
pub struct FlatDrop {
    /// Half the side, m.
    pub radius: f64,
    /// The segments it was cut into, in order (file names).
    pub segments: Vec<String>,
    /// The whole drop as filmed (frames shared by two segments once).
    pub film: Film,
}

/// The real flat drops of `real`, each with its segments joined: a segment
/// continues the one before it when its first frame is that one's last (the
/// experiment cut drops at a frame that both segments keep).
pub fn flat_drops(real: &[RealSegment]) -> Vec<FlatDrop> {
    let mut drops: Vec<(bool, FlatDrop)> = Vec::new();
    for s in real {
        let film = &s.film;
        let continues = drops.last().is_some_and(|(edge, d)| {
            *edge == s.on_edge
                && d.radius == s.radius
                && d.film.position.last() == film.position.first()
                && d.film.area[0].last() == film.area[0].first()
        });
        if continues {
            let d = &mut drops.last_mut().expect("checked").1;
            d.film.position.extend_from_slice(&film.position[1..]);
            for k in 0..2 {
                d.film.area[k].extend_from_slice(&film.area[k][1..]);
            }
            d.segments.push(s.name.clone());
        } else {
            drops.push((
                s.on_edge,
                FlatDrop {
                    radius: s.radius,
                    segments: vec![s.name.clone()],
                    film: film.clone(),
                },
            ));
        }
    }
    drops
        .into_iter()
        .filter(|(edge, _)| !edge)
        .map(|(_, d)| d)
        .collect()
}

/// How one real flat drop left its flat fall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Departure {
    /// Half the side, m.
    pub radius: f64,
    /// First frame at which the summed silhouette reaches [`WHOLE_SHARE`]
    /// of its largest within [`ARTEFACT_FRAMES`]: where the artefact ends.
    pub whole_from: usize,
    /// The summed silhouette at frame 5 over its first frame's: how much
    /// a still-flat plate seems to grow.
    pub growth: f64,
    /// Seconds from the first frame to the first at which the centre is
    /// [`DEPARTURE_RADII`] half-sides sideways from where it was at
    /// `whole_from`; `None` if it never is.
    pub departs: Option<f64>,
}

/// Measures [`Departure`] on a flat drop's film; `None` for a film shorter
/// than [`ARTEFACT_FRAMES`] or without a finite silhouette in them.
pub fn departure(radius: f64, film: &Film) -> Option<Departure> {
    if film.len() < ARTEFACT_FRAMES {
        return None;
    }
    let seen: Vec<f64> = (0..film.len())
        .map(|k| film.area[0][k] + film.area[1][k])
        .collect();
    // f64::max passes over NaN: a frame the tracking lost is not the largest.
    let largest = seen[..ARTEFACT_FRAMES]
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    if !largest.is_finite() {
        return None;
    }
    let whole_from = seen[..ARTEFACT_FRAMES]
        .iter()
        .position(|&a| a >= WHOLE_SHARE * largest)?;
    let from = film.position[whole_from].xy();
    let departs = (whole_from..film.len())
        .find(|&k| (film.position[k].xy() - from).norm() > DEPARTURE_RADII * radius)
        .map(|k| k as f64 / FPS);
    Some(Departure {
        radius,
        whole_from,
        growth: seen[5] / seen[0],
        departs,
    })
}

/// Every real flat drop's [`Departure`].
pub fn real_departures(real: &[RealSegment]) -> Vec<Departure> {
    flat_drops(real)
        .iter()
        .filter_map(|d| departure(d.radius, &d.film))
        .collect()
}

/// Per bin of [`SQUARE_BINS`], the departures of its real flat drops
/// that depart, s.
pub fn departures_by_bin(real: &[RealSegment]) -> Vec<Vec<f64>> {
    let mut bins = vec![Vec::new(); SQUARE_BINS.len()];
    for d in real_departures(real) {
        if let (Some(b), Some(t)) = (bin_of(d.radius), d.departs) {
            bins[b].push(t);
        }
    }
    bins
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// A film of `n` frames: silhouette `area(k)` in both cameras, centre
    /// `centre(k)`.
    fn film(n: usize, area: impl Fn(usize) -> f64, centre: impl Fn(usize) -> [f64; 2]) -> Film {
        let mut f = Film::default();
        for k in 0..n {
            let [x, y] = centre(k);
            f.position.push(Vector3::new(x, y, 1.0 - 0.008 * k as f64));
            f.area[0].push(area(k));
            f.area[1].push(2.0 * area(k));
        }
        f
    }

    /// A whole silhouette from the first frame and a centre moving
    /// sideways at a constant rate: the drop departs at the first frame
    /// past 0.2 r, ⌊0.2 r / step⌋ + 1.
    #[test]
    fn a_steady_drift_departs_where_it_passes_a_fifth_of_the_half_side() {
        let r = 0.02;
        for step in [1e-4, 3e-4, 7e-4, 1.3e-3] {
            let f = film(
                200,
                |_| 100.0,
                |k| [0.6 * step * k as f64, 0.8 * step * k as f64],
            );
            let d = departure(r, &f).unwrap();
            assert_eq!(d.whole_from, 0);
            assert!((d.growth - 1.0).abs() < 1e-12);
            let frame = (DEPARTURE_RADII * r / step).floor() as usize + 1;
            assert_eq!(d.departs, Some(frame as f64 / FPS), "step {step}");
        }
    }

    /// A silhouette that grows to whole over its first frames while the
    /// centre of what is seen shifts by more than 0.2 r, then a plate that
    /// stays put: the shift is the artefact, and the drop never departs.
    /// Timed from the first frame instead, it would depart at once.
    #[test]
    fn a_shift_while_the_silhouette_grows_is_not_a_departure() {
        let r = 0.02;
        let grow = 6;
        let f = film(
            100,
            |k| 30.0 + 70.0 * (k.min(grow) as f64 / grow as f64),
            |k| {
                let s = 0.3 * r * k.min(grow) as f64 / grow as f64;
                [s, -s]
            },
        );
        let d = departure(r, &f).unwrap();
        assert!((d.growth - (30.0 + 70.0 * 5.0 / 6.0) / 30.0).abs() < 1e-12);
        // 0.9 of the whole (90) is passed at frame 6, not 5 (30 + 70 × 5/6 ≈ 88).
        assert_eq!(d.whole_from, 6);
        assert_eq!(d.departs, None);
        assert!(f.position[2].xy().norm() > 0.0);
        assert!(f.position[grow].xy().norm() > DEPARTURE_RADII * r);
    }

    /// Too short a film, or one whose silhouettes are all lost (NaN) in
    /// the window, gives no measurement rather than a panic.
    #[test]
    fn a_film_shorter_than_the_window_or_without_silhouettes_is_not_measured() {
        let f = film(ARTEFACT_FRAMES - 1, |_| 1.0, |_| [0.0, 0.0]);
        assert_eq!(departure(0.02, &f), None);
        let lost = film(40, |_| f64::NAN, |_| [0.0, 0.0]);
        assert_eq!(departure(0.02, &lost), None);
        // One lost frame among whole ones is passed over.
        let one = film(40, |k| if k == 2 { f64::NAN } else { 1.0 }, |_| [0.0, 0.0]);
        assert_eq!(departure(0.02, &one).unwrap().whole_from, 0);
    }
}
