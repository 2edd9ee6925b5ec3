//! The regions goals name, and a point's distance to each (0 inside): a
//! polygon on the ground (horizontal distance), an axis-aligned box, a ball
//! about a point, and an open cylinder's inside (the bin).

use nalgebra::{Vector2, Vector3};

type V2 = Vector2<f64>;
type V3 = Vector3<f64>;

/// A simple polygon in the ground plane (x, y), vertices in order.
#[derive(Clone, Debug, PartialEq)]
pub struct Polygon {
    /// The vertices, m.
    pub vertices: Vec<[f64; 2]>,
}

impl Polygon {
    /// Whether (x, y) is inside (even–odd rule; the boundary counts as
    /// inside through [`Polygon::distance`], which is 0 there).
    pub fn contains(&self, p: V2) -> bool {
        let v = &self.vertices;
        let mut inside = false;
        let mut j = v.len() - 1;
        for i in 0..v.len() {
            let (a, b) = (v[i], v[j]);
            if (a[1] > p.y) != (b[1] > p.y) {
                let x = a[0] + (p.y - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if p.x < x {
                    inside = !inside;
                }
            }
            j = i;
        }
        inside
    }

    /// Horizontal distance from (x, y) to the polygon, 0 inside.
    pub fn distance(&self, p: V2) -> f64 {
        if self.contains(p) {
            return 0.0;
        }
        self.edges()
            .map(|(a, b)| segment_distance(p, a, b))
            .fold(f64::INFINITY, f64::min)
    }

    fn edges(&self) -> impl Iterator<Item = (V2, V2)> + '_ {
        let n = self.vertices.len();
        (0..n).map(move |i| {
            let a = self.vertices[i];
            let b = self.vertices[(i + 1) % n];
            (V2::new(a[0], a[1]), V2::new(b[0], b[1]))
        })
    }

    /// The signed area, m² (positive counter-clockwise).
    pub fn area(&self) -> f64 {
        self.edges()
            .map(|(a, b)| a.x * b.y - b.x * a.y)
            .sum::<f64>()
            / 2.0
    }

    /// The first two edges (indices) that cross or touch, other than
    /// neighbours sharing their common vertex: a polygon with such a pair
    /// has no single inside.
    pub fn crossing(&self) -> Option<(usize, usize)> {
        let e: Vec<(V2, V2)> = self.edges().collect();
        let n = e.len();
        for i in 0..n {
            for j in i + 1..n {
                let neighbours = j == i + 1 || (i == 0 && j == n - 1);
                if neighbours {
                    // Neighbours meet at their shared vertex; they cross
                    // only if they fold back over each other.
                    let (a, b) = if j == i + 1 {
                        (e[i], e[j])
                    } else {
                        (e[j], e[i])
                    };
                    let u = a.1 - a.0;
                    let w = b.1 - b.0;
                    if cross(u, w) == 0.0 && u.dot(&w) < 0.0 {
                        return Some((i, j));
                    }
                    continue;
                }
                if segments_meet(e[i].0, e[i].1, e[j].0, e[j].1) {
                    return Some((i, j));
                }
            }
        }
        None
    }
}

fn cross(a: V2, b: V2) -> f64 {
    a.x * b.y - a.y * b.x
}

fn segment_distance(p: V2, a: V2, b: V2) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

/// Whether the closed segments ab and cd share a point.
fn segments_meet(a: V2, b: V2, c: V2, d: V2) -> bool {
    let o1 = cross(b - a, c - a);
    let o2 = cross(b - a, d - a);
    let o3 = cross(d - c, a - c);
    let o4 = cross(d - c, b - c);
    if ((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0))
        && ((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0))
    {
        return true;
    }
    let on = |p: V2, q: V2, r: V2| {
        r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
    };
    (o1 == 0.0 && on(a, b, c))
        || (o2 == 0.0 && on(a, b, d))
        || (o3 == 0.0 && on(c, d, a))
        || (o4 == 0.0 && on(c, d, b))
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner, m.
    pub min: V3,
    /// Upper corner, m.
    pub max: V3,
}

impl Aabb {
    /// Distance from `p` to the box, 0 inside.
    pub fn distance(&self, p: V3) -> f64 {
        let below = self.min - p;
        let above = p - self.max;
        below.sup(&above).sup(&V3::zeros()).norm()
    }
}

/// The inside of an open cylinder: base centre, unit axis, radius, height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cylinder {
    /// Centre of the base, m.
    pub base: V3,
    /// Unit axis, base to rim.
    pub axis: V3,
    /// Radius, m.
    pub radius: f64,
    /// Height, m.
    pub height: f64,
}

impl Cylinder {
    /// Distance from `p` to the cylinder's inside, 0 inside.
    pub fn distance(&self, p: V3) -> f64 {
        let d = p - self.base;
        let along = d.dot(&self.axis);
        let radial = (d - self.axis * along).norm();
        let r = (radial - self.radius).max(0.0);
        let a = (-along).max(along - self.height).max(0.0);
        r.hypot(a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ell() -> Polygon {
        // An "L": 0..1 wide at the bottom, 0..0.4 up to 2.
        Polygon {
            vertices: vec![
                [0.0, 0.0],
                [1.0, 0.0],
                [1.0, 0.4],
                [0.4, 0.4],
                [0.4, 2.0],
                [0.0, 2.0],
            ],
        }
    }

    #[test]
    fn polygon_inside_outside_and_distance() {
        let l = ell();
        assert!(l.contains(V2::new(0.2, 1.5)));
        assert!(l.contains(V2::new(0.8, 0.2)));
        // The notch of the L is outside, 0.2 from the nearest edge.
        assert!(!l.contains(V2::new(0.8, 0.6)));
        assert!((l.distance(V2::new(0.8, 0.6)) - 0.2).abs() < 1e-12);
        assert!((l.distance(V2::new(0.7, 0.8)) - 0.3).abs() < 1e-12);
        // Beyond the corner (1, 0): the distance to the corner.
        assert!((l.distance(V2::new(1.3, -0.4)) - 0.5).abs() < 1e-12);
        assert_eq!(l.distance(V2::new(0.1, 0.1)), 0.0);
        assert!((l.area() - (1.0 * 0.4 + 0.4 * 1.6)).abs() < 1e-12);
        assert_eq!(l.crossing(), None);
    }

    #[test]
    fn bow_tie_crosses_and_fold_back_is_found() {
        let bow = Polygon {
            vertices: vec![[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]],
        };
        assert_eq!(bow.crossing(), Some((0, 2)));
        let fold = Polygon {
            vertices: vec![[0.0, 0.0], [2.0, 0.0], [1.0, 0.0]],
        };
        assert!(fold.crossing().is_some());
    }

    #[test]
    fn box_and_cylinder_distances() {
        let b = Aabb {
            min: V3::new(0.0, 0.0, 0.0),
            max: V3::new(1.0, 1.0, 1.0),
        };
        assert_eq!(b.distance(V3::new(0.5, 0.5, 0.5)), 0.0);
        assert!((b.distance(V3::new(2.0, 0.5, -1.0)) - 2f64.sqrt()).abs() < 1e-12);
        let c = Cylinder {
            base: V3::zeros(),
            axis: V3::z(),
            radius: 0.3,
            height: 0.6,
        };
        assert_eq!(c.distance(V3::new(0.1, 0.1, 0.3)), 0.0);
        assert!((c.distance(V3::new(0.7, 0.0, 0.3)) - 0.4).abs() < 1e-12);
        assert!((c.distance(V3::new(0.0, 0.6, 0.9)) - 0.3f64.hypot(0.3)).abs() < 1e-12);
    }
}
