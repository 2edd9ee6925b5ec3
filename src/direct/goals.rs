//! Goals, checked against the compiled scene, and judged on a run: for each
//! of a goal's leaves, whether it met the goal and how far it was from it
//! (0 when met), measured on the leaf's centre of mass at the frames.

use super::error::Where;
use super::geometry::{Aabb, Cylinder, Polygon};
use crate::sim::scene::{GoalKind, GoalSpec, ObjectKind, Scene, SceneSpec, Shape};
use crate::util::bad_input::BadInput;
use nalgebra::{Vector2, Vector3};

type V3 = Vector3<f64>;

/// A leaf counts as touching the ground when its lowest particle is this
/// near it, m (contact holds particles at the plane; this leaves room for
/// the step's rounding).
pub const TOUCH: f64 = 2e-3;
/// How a time outside a goal's window counts in its distance, m/s: a
/// second early or late weighs as a metre off (about a leaf's fall in it).
pub const TIME_WEIGHT: f64 = 1.0;

/// Where a `land` goal's leaves should touch down.
#[derive(Clone, Debug, PartialEq)]
pub enum Region {
    /// A polygon on the ground: the horizontal distance counts.
    Polygon(Polygon),
    /// A box: the distance of the centre of mass at touchdown.
    Box(Aabb),
}

/// What a `pass` goal's leaves should pass through.
#[derive(Clone, Debug, PartialEq)]
pub enum Target {
    /// A ball about a point.
    Point {
        /// Its centre, m.
        point: V3,
        /// Its radius, m.
        tolerance: f64,
    },
    /// A box.
    Box(Aabb),
}

/// What a goal asks, checked.
#[derive(Clone, Debug, PartialEq)]
pub enum Aim {
    /// First touch the ground inside `region` between `after` and `before`.
    Land {
        /// The region.
        region: Region,
        /// Window start, s.
        after: f64,
        /// Window end, s.
        before: f64,
        /// The ground's height, m.
        ground: f64,
    },
    /// Be at `target` at time `at`.
    Pass {
        /// The target.
        target: Target,
        /// The time, s.
        at: f64,
    },
    /// Stay inside `region` from `after` until `until`.
    Stay {
        /// The volume.
        region: Aabb,
        /// Window start, s.
        after: f64,
        /// Window end, s.
        until: f64,
    },
    /// Be inside the open cylinder `object` (scene object index) at `by`.
    Enter {
        /// The rigid cylinder's index in the scene's objects.
        object: usize,
        /// Its radius, m.
        radius: f64,
        /// Its height, m.
        height: f64,
        /// Particles around each ring.
        segments: usize,
        /// Rings up its wall.
        rings: usize,
        /// The time, s.
        by: f64,
    },
}

/// A checked goal.
#[derive(Clone, Debug, PartialEq)]
pub struct Goal {
    /// Its name.
    pub name: String,
    /// Its leaves, as indices into the scene's objects.
    pub leaves: Vec<usize>,
    /// What it asks.
    pub aim: Aim,
}

impl Goal {
    /// The last time the goal looks at, s: a run need go no further.
    pub fn end(&self) -> f64 {
        match self.aim {
            Aim::Land { before, .. } => before,
            Aim::Pass { at, .. } => at,
            Aim::Stay { until, .. } => until,
            Aim::Enter { by, .. } => by,
        }
    }
}

/// The fields each kind reads (besides `name`, `leaves`, `kind`).
fn fields_of(kind: GoalKind) -> &'static [&'static str] {
    match kind {
        GoalKind::Land => &["polygon", "min", "max", "after", "before"],
        GoalKind::Pass => &["point", "tolerance", "min", "max", "at"],
        GoalKind::Stay => &["min", "max", "after", "until"],
        GoalKind::Enter => &["object", "by"],
    }
}

fn present(g: &GoalSpec) -> Vec<&'static str> {
    let mut v = Vec::new();
    let mut add = |set: bool, name| {
        if set {
            v.push(name)
        }
    };
    add(g.polygon.is_some(), "polygon");
    add(g.min.is_some(), "min");
    add(g.max.is_some(), "max");
    add(g.point.is_some(), "point");
    add(g.tolerance.is_some(), "tolerance");
    add(g.object.is_some(), "object");
    add(g.after.is_some(), "after");
    add(g.before.is_some(), "before");
    add(g.at.is_some(), "at");
    add(g.until.is_some(), "until");
    add(g.by.is_some(), "by");
    v
}

/// Checks every `[[goal]]` of `spec` against the compiled `scene`.
///
/// # Errors
/// The first bad field: a goal naming no leaf or an unknown one, a field
/// that does not apply to its kind or is missing, an empty, degenerate or
/// self-crossing polygon, an empty box, a time outside the run, a `land`
/// goal without ground, an `enter` goal naming no rigid cylinder.
pub fn check(spec: &SceneSpec, scene: &Scene, at: &Where<'_>) -> Result<Vec<Goal>, BadInput> {
    let mut out: Vec<Goal> = Vec::new();
    for (i, g) in spec.goals.iter().enumerate() {
        let p = format!("goal[{i}]");
        if g.name.trim().is_empty() {
            return Err(at.err(format!("{p}.name"), "is empty"));
        }
        if let Some(other) = out.iter().position(|o| o.name == g.name) {
            return Err(at.err(
                format!("{p}.name"),
                format!("'{}' is already the name of goal[{other}]", g.name),
            ));
        }
        for f in present(g) {
            if !fields_of(g.kind).contains(&f) {
                return Err(at.err(
                    format!("{p}.{f}"),
                    format!("`{f}` does not apply to kind \"{}\"", g.kind.name()),
                ));
            }
        }
        let leaves = leaves_of(spec, scene, g, &p, at)?;
        let aim = aim_of(spec, scene, g, &p, at)?;
        out.push(Goal {
            name: g.name.clone(),
            leaves,
            aim,
        });
    }
    Ok(out)
}

/// The scene objects a goal's `leaves` name: a `[[leaf]]` group's copies,
/// or one copy by its own name.
fn leaves_of(
    spec: &SceneSpec,
    scene: &Scene,
    g: &GoalSpec,
    p: &str,
    at: &Where<'_>,
) -> Result<Vec<usize>, BadInput> {
    let field = format!("{p}.leaves");
    let names = g.leaves.as_ref().map(|l| l.names()).unwrap_or_default();
    if names.is_empty() {
        return Err(at.err(
            field,
            "names no leaf: give `leaves`, a [[leaf]] name or a list of them",
        ));
    }
    // Leaves are the first objects, in file order, `count` copies each.
    let mut groups = Vec::new();
    let mut first = 0;
    for l in &spec.leaves {
        groups.push((l.name.as_str(), first..first + l.count));
        first += l.count;
    }
    let mut out: Vec<usize> = Vec::new();
    for name in &names {
        let found: Vec<usize> = match groups.iter().find(|(n, _)| n == name) {
            Some((_, range)) => range.clone().collect(),
            None => scene
                .objects
                .iter()
                .position(|o| o.kind == ObjectKind::Leaf && &o.name == name)
                .into_iter()
                .collect(),
        };
        if found.is_empty() {
            let known: Vec<&str> = groups.iter().map(|(n, _)| *n).collect();
            return Err(at.err(
                field,
                format!(
                    "no [[leaf]] named '{name}' (the leaves are: {})",
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    }
                ),
            ));
        }
        for k in found {
            if !out.contains(&k) {
                out.push(k);
            }
        }
    }
    Ok(out)
}

fn need<T: Copy>(v: Option<T>, p: &str, f: &str, why: &str, at: &Where<'_>) -> Result<T, BadInput> {
    v.ok_or_else(|| at.err(format!("{p}.{f}"), format!("is required: {why}")))
}

/// A time of the run: finite, within [0, duration].
fn time(v: f64, p: &str, f: &str, duration: f64, at: &Where<'_>) -> Result<f64, BadInput> {
    if v.is_finite() && (0.0..=duration).contains(&v) {
        Ok(v)
    } else {
        Err(at.err(
            format!("{p}.{f}"),
            format!("must be a time within the run, 0 to {duration} s, got {v}"),
        ))
    }
}

fn window(after: f64, end: f64, p: &str, end_name: &str, at: &Where<'_>) -> Result<(), BadInput> {
    if after < end {
        Ok(())
    } else {
        Err(at.err(
            format!("{p}.{end_name}"),
            format!("must come after `after` ({after} s), got {end} s"),
        ))
    }
}

fn aabb(g: &GoalSpec, p: &str, at: &Where<'_>) -> Result<Option<Aabb>, BadInput> {
    match (g.min, g.max) {
        (None, None) => Ok(None),
        (Some(_), None) => Err(at.err(format!("{p}.max"), "a box needs `min` and `max`")),
        (None, Some(_)) => Err(at.err(format!("{p}.min"), "a box needs `min` and `max`")),
        (Some(min), Some(max)) => {
            for (f, v) in [("min", min), ("max", max)] {
                if v.iter().any(|c| !c.is_finite()) {
                    return Err(at.err(format!("{p}.{f}"), "must be finite"));
                }
            }
            if (0..3).any(|k| min[k] >= max[k]) {
                return Err(at.err(
                    format!("{p}.max"),
                    format!("must be above `min` along every axis: min {min:?}, max {max:?}"),
                ));
            }
            Ok(Some(Aabb {
                min: V3::from(min),
                max: V3::from(max),
            }))
        }
    }
}

fn polygon(v: &[[f64; 2]], p: &str, at: &Where<'_>) -> Result<Polygon, BadInput> {
    let field = format!("{p}.polygon");
    if v.len() < 3 {
        return Err(at.err(
            field,
            format!("needs at least 3 vertices [x, y], got {}", v.len()),
        ));
    }
    if v.iter().flatten().any(|c| !c.is_finite()) {
        return Err(at.err(field, "vertices must be finite"));
    }
    let poly = Polygon {
        vertices: v.to_vec(),
    };
    if let Some((a, b)) = poly.crossing() {
        return Err(at.err(
            field,
            format!(
                "crosses itself: edge {a} (vertex {a} to {}) meets edge {b} (vertex {b} to {}); a region's outline must not cross or touch itself",
                (a + 1) % v.len(),
                (b + 1) % v.len()
            ),
        ));
    }
    if poly.area().abs() < 1e-12 {
        return Err(at.err(field, "encloses no area"));
    }
    Ok(poly)
}

fn aim_of(
    spec: &SceneSpec,
    scene: &Scene,
    g: &GoalSpec,
    p: &str,
    at: &Where<'_>,
) -> Result<Aim, BadInput> {
    let duration = spec.duration;
    let after = time(g.after.unwrap_or(0.0), p, "after", duration, at)?;
    match g.kind {
        GoalKind::Land => {
            let Some(ground) = spec.ground else {
                return Err(at.err(
                    format!("{p}.kind"),
                    "a `land` goal needs a [ground] to land on",
                ));
            };
            let region = match (&g.polygon, aabb(g, p, at)?) {
                (Some(_), Some(_)) => {
                    return Err(at.err(
                        format!("{p}.polygon"),
                        "give a `polygon` or a box (`min`, `max`), not both",
                    ));
                }
                (Some(v), None) => Region::Polygon(polygon(v, p, at)?),
                (None, Some(b)) => Region::Box(b),
                (None, None) => {
                    return Err(at.err(
                        format!("{p}.polygon"),
                        "is required: where to land, a `polygon` on the ground or a box (`min`, `max`)",
                    ));
                }
            };
            let before = time(g.before.unwrap_or(duration), p, "before", duration, at)?;
            window(after, before, p, "before", at)?;
            Ok(Aim::Land {
                region,
                after,
                before,
                ground: ground.height,
            })
        }
        GoalKind::Pass => {
            let at_time = need(g.at, p, "at", "the time to pass through", at)?;
            let at_time = time(at_time, p, "at", duration, at)?;
            let target = match (g.point, aabb(g, p, at)?) {
                (Some(_), Some(_)) => {
                    return Err(at.err(
                        format!("{p}.point"),
                        "give a `point` or a box (`min`, `max`), not both",
                    ));
                }
                (Some(point), None) => {
                    if point.iter().any(|c| !c.is_finite()) {
                        return Err(at.err(format!("{p}.point"), "must be finite"));
                    }
                    let tolerance =
                        need(g.tolerance, p, "tolerance", "how near the point counts", at)?;
                    if !(tolerance.is_finite() && tolerance > 0.0) {
                        return Err(at.err(
                            format!("{p}.tolerance"),
                            format!("must be a finite distance > 0, got {tolerance}"),
                        ));
                    }
                    Target::Point {
                        point: V3::from(point),
                        tolerance,
                    }
                }
                (None, Some(b)) => {
                    if g.tolerance.is_some() {
                        return Err(at.err(
                            format!("{p}.tolerance"),
                            "applies to a `point`, not to a box",
                        ));
                    }
                    Target::Box(b)
                }
                (None, None) => {
                    return Err(at.err(
                        format!("{p}.point"),
                        "is required: what to pass through, a `point` (with `tolerance`) or a box (`min`, `max`)",
                    ));
                }
            };
            Ok(Aim::Pass {
                target,
                at: at_time,
            })
        }
        GoalKind::Stay => {
            let Some(region) = aabb(g, p, at)? else {
                return Err(at.err(
                    format!("{p}.min"),
                    "is required: the volume to stay in, `min` and `max`",
                ));
            };
            let until = need(g.until, p, "until", "how long to stay", at)?;
            let until = time(until, p, "until", duration, at)?;
            window(after, until, p, "until", at)?;
            Ok(Aim::Stay {
                region,
                after,
                until,
            })
        }
        GoalKind::Enter => {
            let name = g.object.clone().ok_or_else(|| {
                at.err(
                    format!("{p}.object"),
                    "is required: the [[rigid]] cylinder to enter",
                )
            })?;
            let by = need(g.by, p, "by", "the time to be inside by", at)?;
            let by = time(by, p, "by", duration, at)?;
            let rigid = spec.rigid.iter().find(|r| r.name == name);
            let (Some(r), Some(object)) =
                (rigid, scene.objects.iter().position(|o| o.name == name))
            else {
                return Err(at.err(
                    format!("{p}.object"),
                    format!("no [[rigid]] object named '{name}'"),
                ));
            };
            if r.shape != Shape::Cylinder {
                return Err(at.err(
                    format!("{p}.object"),
                    format!("'{name}' is a box; entering is judged for cylinders (bins) only"),
                ));
            }
            Ok(Aim::Enter {
                object,
                radius: r.radius.unwrap_or(0.0),
                height: r.height.unwrap_or(0.0),
                segments: r.segments.unwrap_or(16),
                rings: r.rings.unwrap_or(2),
                by,
            })
        }
    }
}

/// What the judging needs of a run, per frame: every leaf's centre of mass
/// and lowest height, and the pose of every object a goal enters.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tracks {
    /// Output frames per second (frame k is at k / frame_rate).
    pub frame_rate: f64,
    /// Per scene object: the leaf's centre of mass per frame (empty for
    /// other objects).
    pub centre: Vec<Vec<V3>>,
    /// Per scene object: the leaf's lowest particle height per frame.
    pub lowest: Vec<Vec<f64>>,
    /// Per scene object: an entered cylinder per frame.
    pub cylinder: Vec<Vec<Cylinder>>,
}

impl Tracks {
    /// Empty tracks for `scene`.
    pub fn new(scene: &Scene) -> Tracks {
        let n = scene.objects.len();
        Tracks {
            frame_rate: scene.frame_rate,
            centre: vec![Vec::new(); n],
            lowest: vec![Vec::new(); n],
            cylinder: vec![Vec::new(); n],
        }
    }

    /// Records one frame of `positions` for `goals`.
    pub fn record(&mut self, scene: &Scene, goals: &[Goal], positions: &[V3]) {
        for (k, o) in scene.objects.iter().enumerate() {
            if o.kind != ObjectKind::Leaf {
                continue;
            }
            let mut m = 0.0;
            let mut c = V3::zeros();
            let mut low = f64::INFINITY;
            for &i in &o.particles {
                let w = scene.model.mass[i];
                m += w;
                c += positions[i] * w;
                low = low.min(positions[i].z);
            }
            self.centre[k].push(if m > 0.0 { c / m } else { c });
            self.lowest[k].push(low);
        }
        for g in goals {
            if let Aim::Enter {
                object,
                radius,
                height,
                segments,
                rings,
                ..
            } = g.aim
            {
                if self.cylinder[object].len()
                    == self.centre.iter().map(Vec::len).max().unwrap_or(0)
                {
                    continue; // recorded already this frame (two goals, one bin)
                }
                let ps = &scene.objects[object].particles;
                let base = positions[*ps.last().expect("a cylinder has particles")];
                let rim = (rings - 1) * segments..rings * segments;
                let rim_centre =
                    rim.clone().map(|s| positions[ps[s]]).sum::<V3>() / segments as f64;
                let axis = (rim_centre - base)
                    .try_normalize(1e-12)
                    .unwrap_or_else(V3::z);
                self.cylinder[object].push(Cylinder {
                    base,
                    axis,
                    radius,
                    height,
                });
            }
        }
    }

    fn frames(&self, object: usize) -> usize {
        self.centre[object].len()
    }

    /// Frame index nearest time `t`, within the recorded frames.
    fn frame(&self, object: usize, t: f64) -> usize {
        ((t * self.frame_rate).round().max(0.0) as usize).min(self.frames(object) - 1)
    }

    /// The centre of mass at time `t`, linear between frames.
    pub fn centre_at(&self, object: usize, t: f64) -> V3 {
        let c = &self.centre[object];
        let x = (t * self.frame_rate).max(0.0);
        let k = (x.floor() as usize).min(c.len() - 1);
        if k + 1 >= c.len() {
            return c[c.len() - 1];
        }
        let f = x - k as f64;
        c[k] * (1.0 - f) + c[k + 1] * f
    }
}

/// One leaf against one goal.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LeafVerdict {
    /// Whether it met the goal.
    pub met: bool,
    /// How far it was from meeting it, m (0 when met).
    pub distance: f64,
}

/// A goal judged on a run.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GoalResult {
    /// The fraction of its leaves that met it.
    pub met_fraction: f64,
    /// Their mean distance to it, m.
    pub mean_distance: f64,
    /// Per leaf, in the goal's order.
    pub leaves: Vec<LeafVerdict>,
}

/// Judges `goal` on `tracks`.
pub fn judge(goal: &Goal, tracks: &Tracks) -> GoalResult {
    let leaves: Vec<LeafVerdict> = goal
        .leaves
        .iter()
        .map(|&k| judge_leaf(goal, tracks, k))
        .collect();
    let n = leaves.len().max(1) as f64;
    GoalResult {
        met_fraction: leaves.iter().filter(|v| v.met).count() as f64 / n,
        mean_distance: leaves.iter().map(|v| v.distance).sum::<f64>() / n,
        leaves,
    }
}

fn verdict(distance: f64) -> LeafVerdict {
    LeafVerdict {
        met: distance == 0.0,
        distance,
    }
}

fn judge_leaf(goal: &Goal, t: &Tracks, k: usize) -> LeafVerdict {
    match &goal.aim {
        Aim::Land {
            region,
            after,
            before,
            ground,
        } => {
            let place = |c: V3| match region {
                Region::Polygon(p) => p.distance(Vector2::new(c.x, c.y)),
                Region::Box(b) => b.distance(c),
            };
            let last = t.frame(k, *before);
            let touch = (0..=last).find(|&f| t.lowest[k][f] - ground <= TOUCH);
            match touch {
                Some(f) => {
                    let when = f as f64 / t.frame_rate;
                    let early = (after - when).max(0.0) * TIME_WEIGHT;
                    verdict(place(t.centre[k][f]) + early)
                }
                // Still in the air: how far from the region, and how high.
                None => {
                    let c = t.centre[k][last];
                    let d = place(c) + (t.lowest[k][last] - ground - TOUCH).max(0.0);
                    LeafVerdict {
                        met: false,
                        distance: d.max(TOUCH),
                    }
                }
            }
        }
        Aim::Pass { target, at } => {
            let c = t.centre_at(k, *at);
            verdict(match target {
                Target::Point { point, tolerance } => ((c - point).norm() - tolerance).max(0.0),
                Target::Box(b) => b.distance(c),
            })
        }
        Aim::Stay {
            region,
            after,
            until,
        } => {
            let (a, b) = (t.frame(k, *after), t.frame(k, *until));
            verdict(
                (a..=b)
                    .map(|f| region.distance(t.centre[k][f]))
                    .fold(0.0, f64::max),
            )
        }
        Aim::Enter { object, by, .. } => {
            let f = t.frame(k, *by);
            verdict(t.cylinder[*object][f].distance(t.centre[k][f]))
        }
    }
}
