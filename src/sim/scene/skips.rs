//! What exact skipping ([`crate::physics::skip`]) leaves out for each object
//! of a scene at a given time, for `scene --explain`.

use super::compiled::Scene;
use crate::physics::skip::{WindSkip, bounding_box, feels_wind, groups};
use crate::physics::terms::Terms;

/// One object (a connected group of particles: a leaf, or a rope with what
/// hangs on it) and the wind primitives skipped for it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GroupSkips {
    /// The scene objects in the group, joined by `+`.
    pub objects: String,
    /// Indices of the primitives evaluated at its particles.
    pub reached: Vec<usize>,
    /// Indices of the primitives skipped, and why.
    pub skipped: Vec<(usize, &'static str)>,
}

impl Scene {
    /// Per object, which wind primitives the force path evaluates and which
    /// it skips at the initial positions and time `t` (empty when skipping
    /// cannot apply: no wind sampled, or no primitive limited by bounds, a
    /// front or keys and every object feeling the wind).
    pub fn wind_skips(&self, t: f64) -> Vec<GroupSkips> {
        let model = &self.model;
        let prims = model.wind.primitives();
        if !WindSkip::new(model, Terms::needed(model).wind).is_on() {
            return Vec::new();
        }
        let x = &self.initial.position;
        groups(model)
            .iter()
            .map(|members| {
                let names: Vec<&str> = self
                    .objects
                    .iter()
                    .filter(|o| o.particles.first().is_some_and(|f| members.contains(f)))
                    .map(|o| o.name.as_str())
                    .collect();
                let mut reached = Vec::new();
                let mut skipped = Vec::new();
                let feels = feels_wind(model, members);
                for (i, p) in prims.iter().enumerate() {
                    let why = if feels {
                        bounding_box(x, members).and_then(|(lo, hi)| p.unreached_box(&lo, &hi, t))
                    } else {
                        Some("the object feels no wind: no triangles, no drag")
                    };
                    match why {
                        Some(why) => skipped.push((i, why)),
                        None => reached.push(i),
                    }
                }
                GroupSkips {
                    objects: names.join("+"),
                    reached,
                    skipped,
                }
            })
            .collect()
    }
}
