//! What dressing a mesh needs from its shape alone: triangle and smooth
//! vertex normals, and UVs from the rest outline. Apart from the frame fit,
//! so that the render mesh and every writer can use them without the clip's
//! types.

use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// Unit normals of triangles (zero for a degenerate one).
pub fn triangle_normals(points: &[V3], triangles: &[[u32; 3]]) -> Vec<V3> {
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| points[i as usize]);
            (b - a)
                .cross(&(c - a))
                .try_normalize(0.0)
                .unwrap_or_default()
        })
        .collect()
}

/// Smooth vertex normals: the area-weighted mean of the normals of the
/// triangles around each vertex (the sum of their cross products),
/// normalised; +z of the frame for a vertex on no triangle.
pub fn vertex_normals(points: &[V3], triangles: &[[u32; 3]]) -> Vec<V3> {
    let mut sum = vec![V3::zeros(); points.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| points[i as usize]);
        let n = (b - a).cross(&(c - a));
        for &i in t {
            sum[i as usize] += n;
        }
    }
    sum.into_iter()
        .map(|n| n.try_normalize(1e-30).unwrap_or_else(V3::z))
        .collect()
}

/// UVs over the bounding box of the rest shape seen along its body z (for a
/// leaf, its outline seen from above): u = (x − x_min) / (x_max − x_min),
/// v = (y − y_min) / (y_max − y_min), both in 0 … 1. A flat extent (a rope)
/// maps to 0.
pub fn outline_uvs(rest: &[V3]) -> Vec<[f64; 2]> {
    let range = |d: usize| {
        let lo = rest.iter().map(|p| p[d]).fold(f64::INFINITY, f64::min);
        let hi = rest.iter().map(|p| p[d]).fold(f64::NEG_INFINITY, f64::max);
        (lo, hi - lo)
    };
    let ((x0, dx), (y0, dy)) = (range(0), range(1));
    let unit = |x: f64, lo: f64, d: f64| if d > 0.0 { (x - lo) / d } else { 0.0 };
    rest.iter()
        .map(|p| [unit(p.x, x0, dx), unit(p.y, y0, dy)])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_and_uvs_of_a_flat_square() {
        let p = vec![
            V3::new(0.0, 0.0, 0.0),
            V3::new(2.0, 0.0, 0.0),
            V3::new(2.0, 1.0, 0.0),
            V3::new(0.0, 1.0, 0.0),
        ];
        let n = vertex_normals(&p, &[[0, 1, 2], [0, 2, 3]]);
        assert!(n.iter().all(|n| (n - V3::z()).norm() < 1e-15));
        assert_eq!(
            outline_uvs(&p),
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
        );
        // A fold: the vertex on the crease gets the mean of both sides.
        let q = vec![
            V3::new(0.0, 0.0, 0.0),
            V3::new(1.0, 0.0, 0.0),
            V3::new(0.0, 1.0, 1.0),
            V3::new(0.0, -1.0, 1.0),
        ];
        let n = vertex_normals(&q, &[[0, 1, 2], [0, 3, 1]]);
        assert!((n[0] - V3::z()).norm() < 1e-12, "{:?}", n[0]);
    }
}
