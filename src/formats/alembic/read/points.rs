//! Alembic `Points` (particles, as Blender and Houdini bake them): each
//! particle becomes a marker ([`ClipObject::marker`], kind [`POINT_KIND`])
//! over its own life, so that `classify` reads its path and `preview`
//! plays it.
//!
//! - **Identity**: a point's `.pointIds` entry, which Alembic means to stay
//!   with the point (Houdini writes its `id` attribute there). Blender's
//!   exporter instead numbers the living particles 0, 1, … at every sample,
//!   so once one dies every later one takes the next lower number. Such a
//!   file (ids counting from 0 in every sample, and the count dropping at
//!   some sample) is followed by motion instead ([`follow`]): between two
//!   samples the survivors keep their order and the newborn come last
//!   (Blender walks its particles in index order and emits them in that
//!   order), so the survivors are the old points, in order, whose
//!   predicted places best fit the first of the new ones.
//! - **Place**: `P` under the transforms above, as a mesh's, turned from
//!   y up to z up.
//! - **Width**: the point's `.widths` entry when it is born (Blender writes
//!   a particle's size; an indexed geometry parameter is read through its
//!   indices), else [`DEFAULT_POINT_WIDTH_M`]. `classify` sizes the path
//!   by it, as it sizes a record by `--size`.
//! - **Life**: from the first frame whose nearest sample holds the point to
//!   the last; where it is missing between (a cache with a dropped
//!   sample), it moves along the line between.

use super::archive::{Archive, MAX_OBJECTS, Sample, nearest, nearest_index};
use super::xform::{Xform, placed, world_matrix};
use crate::formats::clip::{ClipObject, POINT_KIND};
use crate::formats::sampling::MAX_SAMPLED_POINTS;
use nalgebra::{Matrix4, Vector3};
use std::collections::BTreeMap;

type V3 = Vector3<f64>;
type M4 = Matrix4<f64>;

/// Width a particle is drawn and classified at when its cloud has no
/// `.widths`, m: the chord `classify` takes for a record that does not say
/// (`leafmagic classify --size` sets another).
pub const DEFAULT_POINT_WIDTH_M: f64 = crate::motion::classify::DEFAULT_CHORD_M;

/// Most particles that may be gone between two samples of a renumbered
/// cloud: following them costs up to this many steps per point (module
/// docs).
pub const MAX_DEATHS_PER_SAMPLE: usize = 256;

/// A point cloud found in the archive (an `AbcGeom_Points`): its full
/// name, `P` per sample, each point's identity per sample (`.pointIds`, or
/// as [`follow`] tracks a renumbered cloud; `None`: the index, in a cloud
/// whose count never changes), its widths, and the transforms above it
/// (the root first).
pub(super) struct Cloud {
    pub(super) name: String,
    pub(super) points: Vec<Sample>,
    ids: Option<Vec<Vec<u64>>>,
    widths: Option<Widths>,
    pub(super) xforms: Vec<Xform>,
}

/// A cloud's widths: values per sample, and indices into them where the
/// geometry parameter is indexed.
struct Widths {
    values: Vec<Sample>,
    indices: Option<Vec<Sample>>,
}

impl Widths {
    /// Point `j`'s width at time `t` (one value for all, or one each), if
    /// the file gives a positive, finite one.
    fn at(&self, t: f64, j: usize) -> Option<f64> {
        let values = nearest(&self.values, t);
        let k = match &self.indices {
            Some(ix) => *nearest(ix, t).get(j)? as usize,
            None if values.len() == 1 => 0,
            None => j,
        };
        values.get(k).copied().filter(|w| w.is_finite() && *w > 0.0)
    }
}

/// A Points object's `.geom` compound at `pos`, named `name`, under the
/// transforms `above`.
pub(super) fn read_cloud(
    a: &Archive<'_>,
    pos: u64,
    name: &str,
    above: &[Xform],
) -> Result<Cloud, String> {
    let props = a.compound(pos)?;
    let array = |n: &str| {
        props
            .iter()
            .find(|p| p.header.name == n && p.header.kind != 0)
    };
    let points = a.samples(array("P").ok_or("no `P`")?)?;
    let ids = array(".pointIds").map(|p| a.samples(p)).transpose()?;
    let widths = match props.iter().find(|p| p.header.name == ".widths") {
        None => None,
        Some(p) if p.header.kind != 0 => Some(Widths {
            values: a.samples(p)?,
            indices: None,
        }),
        // An indexed geometry parameter: a compound of `.vals` and `.indices`.
        Some(p) => {
            let inner = a.compound(p.group)?;
            let find = |n: &str| {
                inner
                    .iter()
                    .find(|q| q.header.name == n && q.header.kind != 0)
            };
            match find(".vals") {
                Some(v) => Some(Widths {
                    values: a.samples(v)?,
                    indices: find(".indices").map(|i| a.samples(i)).transpose()?,
                }),
                None => None,
            }
        }
    };
    for (t, p) in &points {
        if p.len() % 3 != 0 {
            return Err(format!(
                "its `P` at {t} s holds {} numbers, not whole points",
                p.len()
            ));
        }
    }
    let ids = match ids {
        Some(ids) => Some(identities(&points, &ids, widths.as_ref())?),
        None if points.windows(2).any(|w| w[0].1.len() != w[1].1.len()) => {
            return Err(
                "its points change in number and carry no `.pointIds`: which point is which cannot be told"
                    .into(),
            );
        }
        None => None,
    };
    Ok(Cloud {
        name: name.to_string(),
        points,
        ids,
        widths,
        xforms: above.to_vec(),
    })
}

/// Each sample's point identities: the file's `.pointIds` (at the sample
/// nearest each `P` sample), or, where they only count the points of each
/// sample and the count drops (Blender), those [`follow`] finds.
fn identities(
    points: &[Sample],
    ids: &[Sample],
    widths: Option<&Widths>,
) -> Result<Vec<Vec<u64>>, String> {
    let mut given = Vec::with_capacity(points.len());
    for (t, p) in points {
        let v = nearest(ids, *t);
        if v.len() != p.len() / 3 {
            return Err(format!(
                "at {t} s it has {} points and {} ids",
                p.len() / 3,
                v.len()
            ));
        }
        let mut row = Vec::with_capacity(v.len());
        for &id in v.iter() {
            // Exact in f64 up to 2^53, far beyond any particle count.
            if !(id >= 0.0 && id < 2f64.powi(53) && id.fract() == 0.0) {
                return Err(format!(
                    "point id {id} at {t} s is not one this reader keeps apart"
                ));
            }
            row.push(id as u64);
        }
        given.push(row);
    }
    let counting = given
        .iter()
        .all(|row| row.iter().enumerate().all(|(j, &id)| id == j as u64));
    let drops = points.windows(2).any(|w| w[1].1.len() < w[0].1.len());
    if counting && drops {
        follow(points, widths)
    } else {
        Ok(given)
    }
}

/// Identities for a cloud whose ids are each point's place in its sample
/// (module docs): the first sample's points are 0, 1, …; between samples
/// the survivors are those [`align`] finds, and the new points past them
/// are born, numbered on from the highest so far. Each point is predicted
/// at its last place plus its last displacement.
fn follow(points: &[Sample], widths: Option<&Widths>) -> Result<Vec<Vec<u64>>, String> {
    // Each sample's points and widths, taken once: a sample's widths are
    // the price of its points born, then of its points gone.
    let places = |p: &[f64]| -> Vec<V3> {
        p.chunks_exact(3)
            .map(|c| V3::new(c[0], c[1], c[2]))
            .collect()
    };
    let sized = |t: f64, n: usize| -> Vec<f64> {
        (0..n)
            .map(|j| {
                widths
                    .and_then(|w| w.at(t, j))
                    .unwrap_or(DEFAULT_POINT_WIDTH_M)
            })
            .collect()
    };
    let mut old = places(&points[0].1);
    let mut old_widths = sized(points[0].0, old.len());
    let mut out: Vec<Vec<u64>> = Vec::with_capacity(points.len());
    out.push((0..old.len() as u64).collect());
    let mut next = old.len() as u64;
    // Each old point's last displacement (file units per sample).
    let mut moved = vec![V3::zeros(); old.len()];
    for s in 1..points.len() {
        let (t0, t1) = (points[s - 1].0, points[s].0);
        let fresh = places(&points[s].1);
        let fresh_widths = sized(t1, fresh.len());
        let predicted: Vec<V3> = old.iter().zip(&moved).map(|(x, v)| x + v).collect();
        let survived = align(&predicted, &fresh, &old_widths, &fresh_widths).ok_or_else(|| {
            format!(
                "its points are renumbered at every sample (as Blender's exporter writes particles), and between {t0} s and {t1} s over {MAX_DEATHS_PER_SAMPLE} of them are gone: too many to tell which"
            )
        })?;
        let mut row = Vec::with_capacity(fresh.len());
        let mut now = vec![V3::zeros(); fresh.len()];
        for (j, &i) in survived.iter().enumerate() {
            row.push(out[s - 1][i]);
            now[j] = fresh[j] - old[i];
        }
        for _ in survived.len()..fresh.len() {
            row.push(next);
            next += 1;
        }
        (old, old_widths, moved) = (fresh, fresh_widths, now);
        out.push(row);
    }
    Ok(out)
}

/// Which of the old points (predicted at `predicted`) survive into the new
/// ones (at `fresh`), as their indices in order: the survivors, in their
/// old order, are the first new points, and the rest of the new points
/// are born. Chosen at least cost by a dynamic programme over the old
/// points in order (each survives, matched to the next new point, or is
/// gone): the distance from each survivor's prediction to its new place,
/// plus `gone[i]` for old point i gone and `born[j]` for new point j born
/// (their widths: a point is taken for another only where it strays more
/// than about a width from where it was heading). The programme keeps a
/// band of deaths, widened while the best path runs along its edge;
/// `None` if more than [`MAX_DEATHS_PER_SAMPLE`] would have to go.
fn align(predicted: &[V3], fresh: &[V3], gone: &[f64], born: &[f64]) -> Option<Vec<usize>> {
    let (n, m) = (predicted.len(), fresh.len());
    if n > m + MAX_DEATHS_PER_SAMPLE {
        return None;
    }
    // Born from new point j on: the cost of the rest.
    let mut born_from = vec![0.0; m + 1];
    for j in (0..m).rev() {
        born_from[j] = born_from[j + 1] + born[j];
    }
    let mut band = (n.saturating_sub(m) + 8).min(n).min(MAX_DEATHS_PER_SAMPLE) + 1;
    loop {
        // cost[d] after i old points: the least cost with d of them gone
        // (so i − d matched to the first new ones); went[i * band + d]:
        // whether old point i went on that path.
        let mut cost = vec![f64::INFINITY; band];
        cost[0] = 0.0;
        let mut next = vec![f64::INFINITY; band];
        let mut went = vec![false; n * band];
        for i in 0..n {
            next.fill(f64::INFINITY);
            for d in 0..band.min(i + 1) {
                if cost[d] == f64::INFINITY {
                    continue;
                }
                let j = i - d;
                if j < m {
                    let c = cost[d] + (predicted[i] - fresh[j]).norm();
                    if c < next[d] {
                        next[d] = c;
                        went[i * band + d] = false;
                    }
                }
                if d + 1 < band {
                    let c = cost[d] + gone[i];
                    if c < next[d + 1] {
                        next[d + 1] = c;
                        went[i * band + d + 1] = true;
                    }
                }
            }
            std::mem::swap(&mut cost, &mut next);
        }
        let best = (0..band)
            .filter(|&d| cost[d] < f64::INFINITY && n - d <= m)
            .min_by(|&a, &b| {
                (cost[a] + born_from[n - a]).total_cmp(&(cost[b] + born_from[n - b]))
            })?;
        // On the band's edge, a wider band might do better.
        let widest = band == n + 1 || band == MAX_DEATHS_PER_SAMPLE + 1;
        if best + 1 == band && !widest {
            band = (2 * band).min(n + 1).min(MAX_DEATHS_PER_SAMPLE + 1);
            continue;
        }
        let mut survived = Vec::with_capacity(n - best);
        let mut d = best;
        for i in (0..n).rev() {
            if went[i * band + d] {
                d -= 1;
            } else {
                survived.push(i);
            }
        }
        survived.reverse();
        return Some(survived);
    }
}

/// One particle's path on the clip's frames, as a cloud is read.
struct Track {
    first: usize,
    frames: Vec<V3>,
    width: f64,
}

/// Every particle of `cloud` as a marker over the clip's `frames` frames
/// at `rate` from `start` (module docs), named `<cloud>/<id>`, in the
/// order of their ids.
pub(super) fn particles(
    cloud: &Cloud,
    start: f64,
    rate: f64,
    frames: usize,
) -> Result<Vec<ClipObject>, String> {
    let mut tracks: BTreeMap<u64, Track> = BTreeMap::new();
    let mut held = 0usize;
    for k in 0..frames {
        let t = start + k as f64 / rate;
        let world: M4 = world_matrix(&cloud.xforms, t);
        let s = nearest_index(&cloud.points, t);
        let (ts, p) = (cloud.points[s].0, &cloud.points[s].1);
        for (j, c) in p.chunks(3).enumerate() {
            let id = cloud.ids.as_ref().map_or(j as u64, |ids| ids[s][j]);
            let x = placed(&world, c);
            let track = tracks.entry(id).or_insert_with(|| Track {
                first: k,
                frames: Vec::new(),
                width: cloud
                    .widths
                    .as_ref()
                    .and_then(|w| w.at(ts, j))
                    .unwrap_or(DEFAULT_POINT_WIDTH_M),
            });
            let next = track.first + track.frames.len();
            if !track.frames.is_empty() && next > k {
                return Err(format!(
                    "point id {id} appears twice in its sample at {ts} s"
                ));
            }
            // Missing between: along the line from where it was last.
            if let Some(&last) = track.frames.last() {
                let gap = (k + 1 - next) as f64;
                for g in next..k {
                    track
                        .frames
                        .push(last + (x - last) * ((g + 1 - next) as f64 / gap));
                }
            }
            held += k + 1 - next;
            track.frames.push(x);
        }
        if held > MAX_SAMPLED_POINTS || tracks.len() > MAX_OBJECTS {
            return Err(format!(
                "{} particles over {frames} frames are more than this reader holds ({MAX_OBJECTS} particles, {MAX_SAMPLED_POINTS} positions)",
                tracks.len()
            ));
        }
    }
    let base = cloud.name.trim_start_matches('/');
    Ok(tracks
        .into_iter()
        .map(|(id, track)| {
            let mut o = ClipObject::marker(
                format!("{base}/{id}"),
                POINT_KIND,
                track.width,
                track.frames,
            );
            o.first_frame = track.first;
            o
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::rc::Rc;

    /// Samples at 1/24 s of the given points (x, y, z each).
    fn samples(rows: &[Vec<[f64; 3]>]) -> Vec<Sample> {
        rows.iter()
            .enumerate()
            .map(|(k, r)| {
                (
                    k as f64 / 24.0,
                    Rc::new(r.iter().flatten().copied().collect()),
                )
            })
            .collect()
    }

    /// Counting ids for the same rows (as Blender writes them).
    fn counting(rows: &[Vec<[f64; 3]>]) -> Vec<Sample> {
        rows.iter()
            .enumerate()
            .map(|(k, r)| {
                (
                    k as f64 / 24.0,
                    Rc::new((0..r.len()).map(|j| j as f64).collect()),
                )
            })
            .collect()
    }

    /// `count` particles falling side by side, 0.2 m apart along x, each at
    /// its own speed, alive from `born[i]` to `dies[i]` (sample indices),
    /// listed as Blender lists them: in index order, the living only.
    fn shot(count: usize, born: &[usize], dies: &[usize], samples: usize) -> Vec<Vec<[f64; 3]>> {
        (0..samples)
            .map(|s| {
                (0..count)
                    .filter(|&i| born[i] <= s && s < dies[i])
                    .map(|i| {
                        let age = (s - born[i]) as f64;
                        [
                            0.2 * i as f64,
                            1.0 - 0.01 * (1.0 + i as f64) * age * age,
                            0.0,
                        ]
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn renumbered_particles_are_followed_through_births_and_deaths() {
        // Five particles born at samples 0, 1, 2, 3, 6; particle 1 dies at
        // sample 5 while 4 is born at 6 and 0 dies at 6: the count goes
        // 1 2 3 4 4 3 3 3, and at sample 6 a birth and a death coincide.
        let born = [0, 1, 2, 3, 6];
        let dies = [6, 5, 99, 99, 99];
        let rows = shot(5, &born, &dies, 8);
        let ids = identities(&samples(&rows), &counting(&rows), None).unwrap();
        for (s, row) in ids.iter().enumerate() {
            let truth: Vec<u64> = (0..5u64)
                .filter(|&i| born[i as usize] <= s && s < dies[i as usize])
                .collect();
            assert_eq!(row, &truth, "sample {s}");
        }
        // Ids that are not a count are kept as they are.
        let mut given = counting(&rows);
        given[2] = (given[2].0, Rc::new(vec![7.0, 3.0, 5.0]));
        let kept = identities(&samples(&rows), &given, None).unwrap();
        assert_eq!(kept[2], [7, 3, 5]);
        // A count that never drops: its ids are the points' own.
        let growing = shot(3, &[0, 1, 2], &[99, 99, 99], 4);
        let ids = identities(&samples(&growing), &counting(&growing), None).unwrap();
        assert_eq!(ids[3], [0, 1, 2]);
    }

    #[test]
    fn many_gone_and_born_at_once_widen_the_band_until_the_best_fits() {
        // 20 points 0.2 m apart; all but 3, 7, 11, 15 and 19 go, and 12
        // are born far off, in one sample: the first band (20 − 17 + 8 =
        // 11 deaths) is too narrow for the 15 that go.
        let old: Vec<V3> = (0..20).map(|i| V3::new(0.2 * i as f64, 0.0, 0.0)).collect();
        let keep = [3, 7, 11, 15, 19];
        let mut fresh: Vec<V3> = keep
            .iter()
            .map(|&i| old[i] + V3::new(0.0, -0.01, 0.0))
            .collect();
        fresh.extend((0..12).map(|j| V3::new(0.3 * j as f64, 5.0, 0.0)));
        let w = |k| vec![0.05; k];
        assert_eq!(align(&old, &fresh, &w(20), &w(17)).unwrap(), keep);
        // More than MAX_DEATHS_PER_SAMPLE gone at once: refused.
        let many: Vec<V3> = (0..300).map(|i| V3::new(i as f64, 0.0, 0.0)).collect();
        assert!(align(&many, &many[..10], &w(300), &w(10)).is_none());
    }

    #[test]
    fn a_particle_missing_from_a_sample_moves_along_the_line_between() {
        let rows = vec![
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
            vec![[1.0, 0.0, 0.0]],
            vec![[0.0, 3.0, 0.0], [1.0, 0.0, 0.0]],
        ];
        let ids: Vec<Sample> = [vec![4.0, 9.0], vec![9.0], vec![4.0, 9.0]]
            .into_iter()
            .enumerate()
            .map(|(k, v)| (k as f64 / 24.0, Rc::new(v)))
            .collect();
        let points = samples(&rows);
        let cloud = Cloud {
            name: "/c".into(),
            ids: Some(identities(&points, &ids, None).unwrap()),
            points,
            widths: None,
            xforms: Vec::new(),
        };
        let objects = particles(&cloud, 0.0, 24.0, 3).unwrap();
        let names: Vec<&str> = objects.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(names, ["c/4", "c/9"]);
        // y up in the file: (0, 1.5, 0) is z = 1.5 halfway.
        assert_eq!(objects[0].centre(1), V3::new(0.0, 0.0, 1.5));
        assert_eq!(objects[0].positions(0).len(), 6);
        let width = crate::formats::fall::chord(&objects[0].positions(0));
        assert!((width - DEFAULT_POINT_WIDTH_M).abs() < 1e-15);
        // One id twice in a sample is refused.
        let twice = vec![(0.0, Rc::new(vec![1.0, 1.0]))];
        let cloud = Cloud {
            ids: Some(identities(&samples(&rows[..1]), &twice, None).unwrap()),
            points: samples(&rows[..1]),
            ..cloud
        };
        let err = particles(&cloud, 0.0, 24.0, 1).unwrap_err();
        assert!(err.contains("appears twice"), "{err}");
    }
}
