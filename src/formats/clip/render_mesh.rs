//! Render meshes: a finer, textured mesh (an OBJ with its own UVs) bound to
//! a simulated leaf, so that it deforms with it.
//!
//! Each render vertex is attached to the simulated triangle nearest to it at
//! rest, by the barycentric coordinates (b₀, b₁, b₂) of its projection onto
//! that triangle's plane and its signed offset h along the triangle's unit
//! normal n: at every frame it is placed at Σ bᵢ pᵢ + h n(p), with pᵢ the
//! triangle's corners then. At rest this gives back the vertex exactly; as
//! the leaf bends, each part of the render mesh follows its triangle (the
//! binding of a cage, or of a cloth proxy, to a finer mesh).
//!
//! The OBJ is read in the leaf file's own coordinates (metres; z the plate
//! normal, x the long axis), the frame its particles are given in.

use crate::formats::error::ExportError;
use nalgebra::Vector3;
use std::collections::HashMap;
use std::path::Path;

type V3 = Vector3<f64>;

/// Where one render vertex sits on the simulated mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Binding {
    /// The simulated triangle (index into the object's triangles).
    pub triangle: u32,
    /// Barycentric coordinates of the projection onto its plane (they sum
    /// to 1; slightly outside 0 … 1 for a vertex beyond the leaf's edge).
    pub barycentric: [f64; 3],
    /// Signed distance along the triangle's unit normal, m.
    pub offset: f64,
}

/// A render mesh bound to a simulated mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderMesh {
    /// Where the mesh came from (for messages and names).
    pub source: String,
    /// Triangles (render vertex indices).
    pub triangles: Vec<[u32; 3]>,
    /// The mesh's own UVs, one per vertex.
    pub uvs: Vec<[f64; 2]>,
    /// The binding of each vertex.
    pub bindings: Vec<Binding>,
}

/// An OBJ as triangles over vertices that each have one position and one
/// UV (an OBJ corner `v/vt` pair becomes one vertex).
#[derive(Clone, Debug, PartialEq)]
pub struct ObjMesh {
    /// Vertex positions, m.
    pub positions: Vec<V3>,
    /// Vertex UVs.
    pub uvs: Vec<[f64; 2]>,
    /// Triangles (polygons split into fans).
    pub triangles: Vec<[u32; 3]>,
}

/// Reads the `v`, `vt` and `f` lines of an OBJ (other lines are ignored);
/// every face corner must name a UV (`v/vt` or `v/vt/vn`).
pub fn read_obj(path: &Path) -> Result<ObjMesh, ExportError> {
    let text = std::fs::read_to_string(path).map_err(|e| ExportError::io(path, e))?;
    parse_obj(&text).map_err(|(line, reason)| {
        ExportError::input(
            path,
            if line > 0 {
                format!("line {line}: {reason}")
            } else {
                reason
            },
        )
    })
}

/// [`read_obj`] on text; errors are (line number, reason), line 0 for the
/// whole file.
pub fn parse_obj(text: &str) -> Result<ObjMesh, (usize, String)> {
    let mut v = Vec::new();
    let mut vt = Vec::new();
    let mut corners: HashMap<(usize, usize), u32> = HashMap::new();
    let mut mesh = ObjMesh {
        positions: Vec::new(),
        uvs: Vec::new(),
        triangles: Vec::new(),
    };
    for (n, line) in text.lines().enumerate() {
        let n = n + 1;
        let mut words = line.split_whitespace();
        let numbers = |words: std::str::SplitWhitespace<'_>, want: usize| {
            let x: Vec<f64> = words
                .take(want)
                .map(str::parse)
                .collect::<Result<_, _>>()
                .map_err(|e| (n, format!("{e}")))?;
            if x.len() < want || !x.iter().all(|x| x.is_finite()) {
                return Err((n, format!("expected {want} finite numbers")));
            }
            Ok(x)
        };
        match words.next() {
            Some("v") => {
                let x = numbers(words, 3)?;
                v.push(V3::new(x[0], x[1], x[2]));
            }
            Some("vt") => {
                let x = numbers(words, 2)?;
                vt.push([x[0], x[1]]);
            }
            Some("f") => {
                let mut face = Vec::new();
                for corner in words {
                    let mut parts = corner.split('/');
                    let index = |s: Option<&str>, len: usize, what: &str| {
                        let s = s.filter(|s| !s.is_empty()).ok_or_else(|| {
                            (n, format!("face corner '{corner}' has no {what} index (every corner needs v/vt)"))
                        })?;
                        let i: i64 = s.parse().map_err(|_| {
                            (n, format!("face corner '{corner}': '{s}' is not an index"))
                        })?;
                        // 1-based, or negative from the end.
                        let k = if i < 0 { len as i64 + i } else { i - 1 };
                        if k < 0 || k >= len as i64 {
                            return Err((
                                n,
                                format!(
                                    "face corner '{corner}': {what} index {i} out of range (1 … {len})"
                                ),
                            ));
                        }
                        Ok(k as usize)
                    };
                    let p = index(parts.next(), v.len(), "vertex")?;
                    let t = index(parts.next(), vt.len(), "texture")?;
                    let next = mesh.positions.len() as u32;
                    let id = *corners.entry((p, t)).or_insert_with(|| {
                        mesh.positions.push(v[p]);
                        mesh.uvs.push(vt[t]);
                        next
                    });
                    face.push(id);
                }
                if face.len() < 3 {
                    return Err((n, format!("a face needs 3 corners, found {}", face.len())));
                }
                for k in 1..face.len() - 1 {
                    mesh.triangles.push([face[0], face[k], face[k + 1]]);
                }
            }
            _ => {}
        }
    }
    if mesh.triangles.is_empty() {
        return Err((0, "no faces (f lines)".into()));
    }
    Ok(mesh)
}

/// The closest point of triangle (a, b, c) to p (Ericson, "Real-Time
/// Collision Detection", §5.1.5: by the Voronoi regions of the corners,
/// edges and face).
fn closest_point(p: V3, a: V3, b: V3, c: V3) -> V3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// The barycentric coordinates of p's projection onto the plane of
/// (a, b, c), and p's signed distance along the unit normal.
fn project(p: V3, a: V3, b: V3, c: V3) -> ([f64; 3], f64) {
    let n = (b - a).cross(&(c - a));
    let area2 = n.norm_squared();
    let unit = n / area2.sqrt();
    let h = (p - a).dot(&unit);
    let q = p - unit * h;
    // Sub-triangle areas over the whole, signed by the normal.
    let wa = (b - q).cross(&(c - q)).dot(&n) / area2;
    let wb = (c - q).cross(&(a - q)).dot(&n) / area2;
    ([wa, wb, 1.0 - wa - wb], h)
}

/// Triangle corners of `triangles` over `points`.
fn corners(points: &[V3], t: &[u32; 3]) -> [V3; 3] {
    t.map(|i| points[i as usize])
}

impl RenderMesh {
    /// Binds `mesh` (in the same frame as `rest`) to the simulated mesh
    /// `rest` + `triangles`: each vertex to its nearest triangle.
    ///
    /// # Errors
    /// [`ExportError::Data`] if the simulated mesh has no triangle of
    /// non-zero area.
    pub fn bind(
        source: &str,
        mesh: &ObjMesh,
        rest: &[V3],
        triangles: &[[u32; 3]],
    ) -> Result<RenderMesh, ExportError> {
        let usable: Vec<usize> = (0..triangles.len())
            .filter(|&t| {
                let [a, b, c] = corners(rest, &triangles[t]);
                (b - a).cross(&(c - a)).norm() > 1e-14
            })
            .collect();
        if usable.is_empty() {
            return Err(ExportError::Data(format!(
                "{source}: the simulated mesh has no triangle to bind the render mesh to"
            )));
        }
        let bindings = mesh
            .positions
            .iter()
            .map(|&p| {
                let (t, _) = usable
                    .iter()
                    .map(|&t| {
                        let [a, b, c] = corners(rest, &triangles[t]);
                        (t, (closest_point(p, a, b, c) - p).norm_squared())
                    })
                    .fold((usable[0], f64::INFINITY), |best, x| {
                        if x.1 < best.1 { x } else { best }
                    });
                let [a, b, c] = corners(rest, &triangles[t]);
                let (barycentric, offset) = project(p, a, b, c);
                Binding {
                    triangle: t as u32,
                    barycentric,
                    offset,
                }
            })
            .collect();
        Ok(RenderMesh {
            source: source.to_string(),
            triangles: mesh.triangles.clone(),
            uvs: mesh.uvs.clone(),
            bindings,
        })
    }

    /// The render vertices on the simulated mesh `points` + `triangles`:
    /// Σ bᵢ pᵢ + h n for each vertex's triangle.
    pub fn place(&self, points: &[V3], triangles: &[[u32; 3]]) -> Vec<V3> {
        let normals = super::dress::triangle_normals(points, triangles);
        self.bindings
            .iter()
            .map(|b| {
                let t = b.triangle as usize;
                let [p0, p1, p2] = corners(points, &triangles[t]);
                p0 * b.barycentric[0]
                    + p1 * b.barycentric[1]
                    + p2 * b.barycentric[2]
                    + normals[t] * b.offset
            })
            .collect()
    }

    /// Number of render vertices.
    pub fn vertex_count(&self) -> usize {
        self.bindings.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const QUAD: &str = "# a unit square in two triangles, with a seam\n\
        v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0.01\n\
        vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n\
        f 1/1 2/2 3/3 4/4\nf 1/5/1 3/3\n";

    #[test]
    fn obj_faces_become_fans_of_v_vt_vertices() {
        let e = parse_obj(QUAD).unwrap_err();
        assert_eq!(e.0, 12);
        assert!(e.1.contains("3 corners"), "{e:?}");
        let m = parse_obj(&QUAD.replace("f 1/5/1 3/3\n", "f 1/5/1 3/3 4/4\n")).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [4, 2, 3]]);
        assert_eq!(m.positions.len(), 5, "v1 with two UVs is two vertices");
        assert_eq!(m.uvs[4], [0.5, 0.5]);
        let e = parse_obj("v 0 0 0\nf 1 1 1\n").unwrap_err();
        assert!(e.1.contains("no texture index"), "{e:?}");
        let e = parse_obj("v 0 0 0\nvt 0 0\nf 1/1 2/1 1/1\n").unwrap_err();
        assert!(e.1.contains("out of range"), "{e:?}");
    }

    #[test]
    fn a_binding_gives_back_the_rest_vertex_and_follows_a_moved_triangle() {
        let rest = vec![
            V3::new(0.0, 0.0, 0.0),
            V3::new(1.0, 0.0, 0.0),
            V3::new(0.0, 1.0, 0.0),
        ];
        let tris = [[0, 1, 2]];
        let mesh = ObjMesh {
            positions: vec![V3::new(0.2, 0.3, 0.05), V3::new(1.5, -0.5, -0.02)],
            uvs: vec![[0.0, 0.0], [1.0, 1.0]],
            triangles: vec![[0, 1, 0]],
        };
        let r = RenderMesh::bind("t", &mesh, &rest, &tris).unwrap();
        for (b, want) in r.bindings[0].barycentric.iter().zip([0.5, 0.2, 0.3]) {
            assert!((b - want).abs() < 1e-15, "{:?}", r.bindings[0]);
        }
        assert!((r.bindings[0].offset - 0.05).abs() < 1e-15);
        for (a, b) in r.place(&rest, &tris).iter().zip(&mesh.positions) {
            assert!((a - b).norm() < 1e-15, "{a:?} {b:?}");
        }
        // Turn the triangle a quarter about x and move it: the vertex turns
        // with it, its offset along the new normal.
        let q = nalgebra::UnitQuaternion::from_scaled_axis(V3::x() * std::f64::consts::FRAC_PI_2);
        let moved: Vec<V3> = rest
            .iter()
            .map(|x| q * x + V3::new(0.0, 0.0, 3.0))
            .collect();
        let placed = r.place(&moved, &tris);
        let want = q * mesh.positions[0] + V3::new(0.0, 0.0, 3.0);
        assert!((placed[0] - want).norm() < 1e-15);
    }

    #[test]
    fn the_nearest_triangle_is_chosen() {
        let rest = vec![
            V3::new(0.0, 0.0, 0.0),
            V3::new(1.0, 0.0, 0.0),
            V3::new(0.0, 1.0, 0.0),
            V3::new(5.0, 5.0, 0.0),
            V3::new(6.0, 5.0, 0.0),
            V3::new(5.0, 6.0, 0.0),
        ];
        let mesh = ObjMesh {
            positions: vec![V3::new(5.2, 5.2, 0.0), V3::new(0.1, 0.1, 0.0)],
            uvs: vec![[0.0; 2]; 2],
            triangles: vec![[0, 1, 0]],
        };
        let r = RenderMesh::bind("t", &mesh, &rest, &[[0, 1, 2], [3, 4, 5]]).unwrap();
        assert_eq!(r.bindings[0].triangle, 1);
        assert_eq!(r.bindings[1].triangle, 0);
    }
}
