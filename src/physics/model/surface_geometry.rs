//! What the unsteady aerodynamic law needs to know about the plate each
//! triangle belongs to, measured once on the rest shape: the triangle's
//! share of the plate's added mass, and the plate's chord through the
//! triangle in every direction of its plane.
//!
//! # Why the plate, not the triangle
//!
//! A plate's added mass scales with its own size, ∝ ρ L³, not with its
//! triangles': a per-triangle rule written with each triangle's own length
//! would fall as the mesh is refined (Σ ρ hᵢ Aᵢ → 0). The same holds for
//! the rotational circulation (∝ c², c the plate's chord across the
//! rotation axis) and for skin friction (∝ 1/√Re with Re on the plate's
//! chord along the flow). So each triangle carries numbers measured on its
//! *plate*: the set of triangles joined to it through shared edges.
//!
//! # Added mass density
//!
//! The kinetic energy of the flow around a flat plate moving along its
//! normal with speed W is ½ m_a W² (Lamb 1932, §§ 92, 108). For a disk of
//! radius a the potential jump across the plate is (4/π) W √(a² − r²) and
//! m_a = (8/3) ρ a³; the disk turning about a diameter has added moment of
//! inertia (16/45) ρ a⁵. The true operator is non-local (the flow at one
//! point depends on the whole plate's motion), so no local density
//! reproduces both: the translational profile (4/π)ρ√(a² − r²) gives
//! (8/15) ρ a⁵ for the rotation, 1.5 × too much. We take the one-parameter
//! family
//!
//! μ(x) = ρ C (d (2h − d))^p / h^(2p−1),
//!
//! d the distance from x to the plate's edge and h the plate's inradius
//! (largest d), for which ∫μ = π C ρ a³/(p + 1) and ∫μ x² / ∫μ = a²/(2(p + 2))
//! on a disk (d(2h − d) = a² − r² there). p = 7/4 and C = 22/(3π) give the
//! disk's exact m_a and its exact added moment of inertia. On a square of
//! side L the same rule gives m_a = 0.4244 ρ L³, 6.7 % below the 0.4548 ρ L³
//! of the classical tables (C_A = 0.579 on (π/4) L³: DNV-RP-C205,
//! table A-2, as recalled, not re-read here); on long strips it falls short
//! of the 2-D value π ρ (w/2)² per length (a local rule cannot see the
//! aspect ratio). The density is integrated over each triangle with its
//! three barycentric weights (a sub-triangle rule), so a corner's share is
//! m_k = ∫ μ β_k dA: the lumped form of the consistent "added-mass matrix"
//! ∫ μ β_k β_l dA, as the body's own mass is lumped.
//!
//! # Chords
//!
//! For the chord in direction e through a triangle, the line through its
//! centroid along e is cut by the plate's triangles; the chord is the
//! length of the stretch of that line, around the centroid, that lies on
//! the plate. Sampled at [`CHORD_SAMPLES`] directions, uniformly in a
//! pseudo-angle (no trigonometry at run time, see [`SurfaceGeometry::chord`]).
//!
//! A folded leaf is measured on its rest shape projected onto its best-fit
//! plane (the plane of least squared distance to its particles).

use nalgebra::{Matrix3, Vector2, Vector3};

type V3 = Vector3<f64>;
type V2 = Vector2<f64>;

/// Directions at which a triangle's chord is sampled over a half-turn.
pub const CHORD_SAMPLES: usize = 16;

/// Exponent p of the added-mass density (module docs).
pub const ADDED_MASS_EXPONENT: f64 = 1.75;

/// Prefactor C of the added-mass density: (8/3)(p + 1)/π, so that a disk
/// gets (8/3) ρ a³.
pub const ADDED_MASS_PREFACTOR: f64 =
    8.0 / 3.0 * (ADDED_MASS_EXPONENT + 1.0) / std::f64::consts::PI;

/// One triangle's share of its plate, measured on the rest shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceGeometry {
    /// Added mass of each corner per unit fluid density, m³ (multiply by ρ).
    pub added_mass: [f64; 3],
    /// The rest edges e₁ = x_b − x_a, e₂ = x_c − x_a in the triangle's rest
    /// tangent basis (t₁ along e₁): e₁ = (`[0]`, 0), e₂ = (`[1]`, `[2]`).
    pub rest_edges: [f64; 3],
    /// The plate's chord through the centroid at the pseudo-angles of
    /// [`SurfaceGeometry::chord`], m; entry 0 and the last are the same direction.
    pub chords: [f64; CHORD_SAMPLES + 1],
    /// Index of the plate (triangles connected through shared edges,
    /// [`plates`]) this triangle belongs to.
    pub plate: usize,
}

impl SurfaceGeometry {
    /// The plate's chord through this triangle along the current in-plane
    /// direction whose coordinates on the current edges are (s₁, s₂)
    /// (d = s₁ e₁ + s₂ e₂), m. The direction is carried back to the rest
    /// shape by the triangle's own deformation, so a rigid motion of the
    /// plate reads the same chord. Linear in a pseudo-angle
    /// t = Dₓ/(|Dₓ| + D_y) ∈ [−1, 1] (D_y ≥ 0), which is monotonic in the
    /// angle: one division instead of an arctangent. Only d's direction
    /// counts: any positive multiple of (s₁, s₂) reads the same chord, so
    /// callers need not normalise it.
    #[inline]
    pub fn chord(&self, s1: f64, s2: f64) -> f64 {
        let [e1x, e2x, e2y] = self.rest_edges;
        let (mut dx, mut dy) = (s1 * e1x + s2 * e2x, s2 * e2y);
        if dy < 0.0 || (dy == 0.0 && dx < 0.0) {
            dx = -dx;
            dy = -dy;
        }
        let norm = dx.abs() + dy;
        if norm <= 0.0 {
            return self.chords[0];
        }
        let pos = (1.0 - dx / norm) * 0.5 * CHORD_SAMPLES as f64;
        // pos ≥ 0 (|dx| ≤ norm), so truncation is its floor, to the bit,
        // without the call to libm's floor that the baseline x86-64 target
        // (no SSE4.1 `roundsd`) makes (3 % of an unsteady-law drop, perf).
        // Through i32: a signed conversion is one instruction on x86-64
        // (cvttsd2si), an unsigned one a dozen; pos ≤ CHORD_SAMPLES fits.
        let j = (pos as i32 as usize).min(CHORD_SAMPLES - 1);
        let f = pos - j as f64;
        self.chords[j] * (1.0 - f) + self.chords[j + 1] * f
    }
}

/// The unit direction at pseudo-angle sample `j` (module docs), in the rest
/// tangent basis.
fn sample_direction(j: usize) -> V2 {
    let t = 1.0 - 2.0 * j as f64 / CHORD_SAMPLES as f64;
    V2::new(t, 1.0 - t.abs()).normalize()
}

/// The triangles grouped into plates: connected through shared edges.
pub fn plates(corners: &[[usize; 3]]) -> Vec<Vec<usize>> {
    let mut parent: Vec<usize> = (0..corners.len()).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut by_edge: std::collections::HashMap<(usize, usize), usize> = Default::default();
    for (t, c) in corners.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (c[k], c[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            if let Some(&u) = by_edge.get(&key) {
                let (ru, rt) = (find(&mut parent, u), find(&mut parent, t));
                parent[ru.max(rt)] = ru.min(rt);
            } else {
                by_edge.insert(key, t);
            }
        }
    }
    let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for t in 0..corners.len() {
        let r = find(&mut parent, t);
        groups.entry(r).or_default().push(t);
    }
    groups.into_values().collect()
}

fn segment_distance(p: V2, a: V2, b: V2) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let s = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * s)).norm()
}

/// The stretch [lo, hi] of the line p + s e inside the 2-D triangle, if any.
fn clip(p: V2, e: V2, tri: [V2; 3]) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    let orient = (tri[1] - tri[0]).perp(&(tri[2] - tri[0])).signum();
    for k in 0..3 {
        let (a, b) = (tri[k], tri[(k + 1) % 3]);
        // Inside: orient · (b − a) × (x − a) ≥ 0.
        let edge = b - a;
        let f0 = orient * edge.perp(&(p - a));
        let f1 = orient * edge.perp(&e);
        if f1 == 0.0 {
            if f0 < 0.0 {
                return None;
            }
        } else {
            let s = -f0 / f1;
            if f1 > 0.0 {
                lo = lo.max(s);
            } else {
                hi = hi.min(s);
            }
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// Measures every triangle's [`SurfaceGeometry`] on the rest shape `x`.
pub fn surface_geometry(x: &[V3], corners: &[[usize; 3]]) -> Vec<SurfaceGeometry> {
    let mut out = vec![
        SurfaceGeometry {
            added_mass: [0.0; 3],
            rest_edges: [0.0; 3],
            chords: [0.0; CHORD_SAMPLES + 1],
            plate: 0,
        };
        corners.len()
    ];
    for (index, plate) in plates(corners).into_iter().enumerate() {
        for &t in &plate {
            out[t].plate = index;
        }
        measure_plate(x, corners, &plate, &mut out);
    }
    out
}

fn measure_plate(x: &[V3], corners: &[[usize; 3]], plate: &[usize], out: &mut [SurfaceGeometry]) {
    // Best-fit plane: the particles' covariance, smallest eigenvector normal.
    let mut ids: Vec<usize> = plate.iter().flat_map(|&t| corners[t]).collect();
    ids.sort_unstable();
    ids.dedup();
    let centre = ids.iter().map(|&i| x[i]).sum::<V3>() / ids.len() as f64;
    let mut cov = Matrix3::zeros();
    for &i in &ids {
        let r = x[i] - centre;
        cov += r * r.transpose();
    }
    let eig = cov.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let u1: V3 = eig.eigenvectors.column(order[0]).into();
    let u2: V3 = eig.eigenvectors.column(order[1]).into();
    let flat = |p: V3| V2::new((p - centre).dot(&u1), (p - centre).dot(&u2));
    let tri2: Vec<[V2; 3]> = plate
        .iter()
        .map(|&t| corners[t].map(|i| flat(x[i])))
        .collect();

    // The plate's edge: triangle edges used once.
    let mut uses: std::collections::HashMap<(usize, usize), u32> = Default::default();
    for &t in plate {
        let c = corners[t];
        for k in 0..3 {
            let (a, b) = (c[k], c[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut boundary: Vec<(V2, V2)> = uses
        .iter()
        .filter(|(_, n)| **n == 1)
        .map(|(&(a, b), _)| (flat(x[a]), flat(x[b])))
        .collect();
    // A deterministic order (the map's is not): the minimum is the same,
    // but keep every run's arithmetic identical.
    boundary.sort_by(|p, q| {
        (p.0.x, p.0.y, p.1.x, p.1.y)
            .partial_cmp(&(q.0.x, q.0.y, q.1.x, q.1.y))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let edge_distance = |p: V2| {
        boundary
            .iter()
            .map(|&(a, b)| segment_distance(p, a, b))
            .fold(f64::INFINITY, f64::min)
    };

    // Quadrature points: s² sub-triangles per triangle, about 1024 points
    // per plate but at least 4 and at most 64 per triangle.
    let s = ((1024.0 / plate.len() as f64).sqrt().ceil() as usize).clamp(2, 8);
    let mut points: Vec<(usize, [f64; 3], f64)> = Vec::new(); // (triangle slot, β, d)
    let subs = sub_centroids(s);
    for (slot, tri) in tri2.iter().enumerate() {
        for b in &subs {
            let p = tri[0] * b[0] + tri[1] * b[1] + tri[2] * b[2];
            points.push((slot, *b, edge_distance(p)));
        }
    }
    let h = points.iter().map(|p| p.2).fold(0.0, f64::max);
    let p_exp = ADDED_MASS_EXPONENT;
    let density = |d: f64| {
        if h <= 0.0 {
            return 0.0;
        }
        let d = d.min(h);
        ADDED_MASS_PREFACTOR * (d * (2.0 * h - d)).powf(p_exp) / h.powf(2.0 * p_exp - 1.0)
    };
    let sub = 1.0 / (s * s) as f64;
    for &(slot, b, d) in &points {
        let t = plate[slot];
        let [a, bb, c] = corners[t];
        let area = 0.5 * (x[bb] - x[a]).cross(&(x[c] - x[a])).norm();
        let m = density(d) * area * sub;
        for (share, weight) in out[t].added_mass.iter_mut().zip(b) {
            *share += m * weight;
        }
    }

    // Rest tangent bases and chords.
    let grid = TriangleGrid::new(&tri2);
    let mut scratch = ChordScratch::default();
    for (slot, &t) in plate.iter().enumerate() {
        let [a, b, c] = corners[t];
        let (e1, e2) = (x[b] - x[a], x[c] - x[a]);
        let n = e1.cross(&e2).normalize();
        let t1 = e1.normalize();
        let t2 = n.cross(&t1);
        out[t].rest_edges = [e1.norm(), e2.dot(&t1), e2.dot(&t2)];
        let centroid = (tri2[slot][0] + tri2[slot][1] + tri2[slot][2]) / 3.0;
        for j in 0..CHORD_SAMPLES {
            let d = sample_direction(j);
            let dir3 = t1 * d.x + t2 * d.y;
            let proj = V2::new(dir3.dot(&u1), dir3.dot(&u2));
            let len = proj.norm();
            out[t].chords[j] = if len < 1e-9 {
                0.0
            } else {
                chord_through(centroid, proj / len, &tri2, &grid, &mut scratch) / len
            };
        }
        // The last sample is the first direction again.
        out[t].chords[CHORD_SAMPLES] = out[t].chords[0];
    }
}

/// Barycentric centroids of the s² sub-triangles of a triangle (each 1/s²
/// of its area).
fn sub_centroids(s: usize) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(s * s);
    let sf = s as f64;
    for i in 0..s {
        for j in 0..s - i {
            // Upright sub-triangle with corners (i, j), (i+1, j), (i, j+1).
            let (u, v) = ((i as f64 + 1.0 / 3.0) / sf, (j as f64 + 1.0 / 3.0) / sf);
            out.push([1.0 - u - v, u, v]);
            if i + j + 1 < s {
                let (u, v) = ((i as f64 + 2.0 / 3.0) / sf, (j as f64 + 2.0 / 3.0) / sf);
                out.push([1.0 - u - v, u, v]);
            }
        }
    }
    out
}

/// The plate's triangles binned on a uniform grid over its plane, so that
/// a chord's line meets only the triangles of the cells it crosses: every
/// triangle against every line made measuring a plate quadratic in its
/// triangles (a 5.4k-particle strip took 30 s, a 20k one 8 minutes).
struct TriangleGrid {
    origin: V2,
    /// Cell width along x and y, m.
    cell: V2,
    /// Cells along x and y.
    size: [usize; 2],
    /// The triangles (slots) registered in each cell, row-major, ascending.
    cells: Vec<Vec<u32>>,
    /// How many triangles the plate has.
    triangles: usize,
}

impl TriangleGrid {
    /// About one cell per triangle. Each triangle is registered in the
    /// cells its bounding box overlaps and their neighbours: a whole cell
    /// of margin, so a line that only grazes it, which `clip` may still
    /// count as a touch after rounding, finds it.
    fn new(tris: &[[V2; 3]]) -> TriangleGrid {
        let (mut lo, mut hi) = (V2::repeat(f64::INFINITY), V2::repeat(f64::NEG_INFINITY));
        for t in tris {
            for v in t {
                lo = lo.inf(v);
                hi = hi.sup(v);
            }
        }
        let extent = (hi - lo).map(|d| d.max(f64::MIN_POSITIVE));
        let side = (extent.x * extent.y / tris.len().max(1) as f64).sqrt();
        let count = |d: f64| {
            let n = if side > 0.0 { (d / side).ceil() } else { 1.0 };
            n.clamp(1.0, 4096.0) as usize
        };
        let size = [count(extent.x), count(extent.y)];
        let cell = V2::new(extent.x / size[0] as f64, extent.y / size[1] as f64);
        let mut grid = TriangleGrid {
            origin: lo,
            cell,
            size,
            cells: vec![Vec::new(); size[0] * size[1]],
            triangles: tris.len(),
        };
        for (slot, t) in tris.iter().enumerate() {
            let (a, b) = (t[0].inf(&t[1]).inf(&t[2]), t[0].sup(&t[1]).sup(&t[2]));
            let (i0, i1) = (grid.index(a.x, 0).saturating_sub(1), grid.index(b.x, 0) + 1);
            let (j0, j1) = (grid.index(a.y, 1).saturating_sub(1), grid.index(b.y, 1) + 1);
            for j in j0..=j1.min(size[1] - 1) {
                for i in i0..=i1.min(size[0] - 1) {
                    grid.cells[j * size[0] + i].push(slot as u32);
                }
            }
        }
        grid
    }

    /// The cell index along `axis` of coordinate `v`, clamped to the grid.
    fn index(&self, v: f64, axis: usize) -> usize {
        let k = ((v - self.origin[axis]) / self.cell[axis]).floor();
        if k.is_nan() || k < 0.0 {
            0
        } else {
            (k as usize).min(self.size[axis] - 1)
        }
    }

    /// Every triangle registered in a cell the line p + s e crosses,
    /// ascending, into `scratch.found`: along the axis e leans on most, each column
    /// (or row) of cells, between the rows the line enters and leaves it by.
    fn along_line(&self, p: V2, e: V2, scratch: &mut ChordScratch) {
        let major = usize::from(e.y.abs() > e.x.abs());
        let minor = 1 - major;
        scratch.seen.resize(self.triangles, false);
        scratch.found.clear();
        // Where the line crosses the boundary between columns (or rows).
        let at = |edge: usize| {
            let m = self.origin[major] + edge as f64 * self.cell[major];
            p[minor] + (m - p[major]) * e[minor] / e[major]
        };
        // Past the grid by a cell or more, the line meets no triangle there
        // (the clamped index would offer the edge row's).
        let (first, last) = (
            self.origin[minor] - self.cell[minor],
            self.origin[minor] + (self.size[minor] + 1) as f64 * self.cell[minor],
        );
        for k in 0..self.size[major] {
            let (u, w) = (at(k), at(k + 1));
            if u.max(w) < first || u.min(w) > last {
                continue;
            }
            let (r0, r1) = (self.index(u.min(w), minor), self.index(u.max(w), minor));
            for r in r0..=r1 {
                let (i, j) = if major == 0 { (k, r) } else { (r, k) };
                for &slot in &self.cells[j * self.size[0] + i] {
                    let slot = slot as usize;
                    if !scratch.seen[slot] {
                        scratch.seen[slot] = true;
                        scratch.found.push(slot);
                    }
                }
            }
        }
        for &slot in &scratch.found {
            scratch.seen[slot] = false;
        }
        scratch.found.sort_unstable();
    }
}

/// Buffers of [`chord_through`], reused across its calls.
#[derive(Default)]
struct ChordScratch {
    spans: Vec<(f64, f64)>,
    seen: Vec<bool>,
    found: Vec<usize>,
}

/// Length of the stretch of the line p + s e (e unit) on the plate around
/// s = 0. The triangles the grid offers are every one the line can cross,
/// in the plate's order, so the spans, and the chord to the bit, are those
/// of all the triangles (a test holds it).
fn chord_through(
    p: V2,
    e: V2,
    tris: &[[V2; 3]],
    grid: &TriangleGrid,
    scratch: &mut ChordScratch,
) -> f64 {
    grid.along_line(p, e, scratch);
    let ChordScratch { spans, found, .. } = scratch;
    spans.clear();
    spans.extend(found.iter().filter_map(|&slot| clip(p, e, tris[slot])));
    merged_span_length(spans)
}

/// The length of the merged span holding s = 0 (or nearest it) among
/// `spans` (sorted here).
fn merged_span_length(spans: &mut [(f64, f64)]) -> f64 {
    spans.sort_by(|a, b| a.0.total_cmp(&b.0));
    let scale = spans
        .iter()
        .map(|s| s.1.abs().max(s.0.abs()))
        .fold(0.0, f64::max);
    let tol = 1e-9 * scale.max(1e-12);
    // Merge the overlapping spans; keep the one holding 0 (or nearest it).
    let mut best = (0.0, 0.0);
    let mut current: Option<(f64, f64)> = None;
    let consider = |span: (f64, f64), best: &mut (f64, f64)| {
        if span.0 <= tol && span.1 >= -tol {
            *best = span;
        }
    };
    for &s in spans.iter() {
        current = match current {
            Some((lo, hi)) if s.0 <= hi + tol => Some((lo, hi.max(s.1))),
            Some(done) => {
                consider(done, &mut best);
                Some(s)
            }
            None => Some(s),
        };
    }
    if let Some(done) = current {
        consider(done, &mut best);
    }
    best.1 - best.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize, side: f64) -> (Vec<V3>, Vec<[usize; 3]>) {
        let mut x = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                x.push(V3::new(
                    side * (i as f64 / n as f64 - 0.5),
                    side * (j as f64 / n as f64 - 0.5),
                    0.0,
                ));
            }
        }
        let id = |i: usize, j: usize| j * (n + 1) + i;
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (x, t)
    }

    #[test]
    fn chords_of_a_square_grid() {
        let (x, t) = grid(6, 0.1);
        let g = surface_geometry(&x, &t);
        // Along x and y, every centroid sees the full side.
        for (k, tri) in t.iter().enumerate() {
            let e1 = x[tri[1]] - x[tri[0]];
            let e2 = x[tri[2]] - x[tri[0]];
            let n = e1.cross(&e2);
            let n2 = n.norm_squared();
            let coords = |d: V3| (d.dot(&e2.cross(&n)) / n2, d.dot(&n.cross(&e1)) / n2);
            let (s1, s2) = coords(V3::x());
            assert!(
                (g[k].chord(s1, s2) - 0.1).abs() < 1e-9,
                "{}",
                g[k].chord(s1, s2)
            );
            let (s1, s2) = coords(-V3::y());
            assert!((g[k].chord(s1, s2) - 0.1).abs() < 1e-9);
        }
    }

    /// The grid offers every triangle a chord's line can cross: on plates
    /// of every shape, a long strip, a folded leaf's plane and a mesh of
    /// random triangles, each chord is the one that clipping every triangle
    /// gives, to the bit.
    #[test]
    fn the_grid_finds_every_chord_that_all_triangles_give() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(17);
        let mut meshes: Vec<Vec<[V2; 3]>> = Vec::new();
        for (n, side) in [(1, 0.1), (6, 0.1), (16, 0.03)] {
            let (x, t) = grid(n, side);
            meshes.push(t.iter().map(|c| c.map(|i| x[i].xy())).collect());
        }
        // A strip 40 cells long and 2 across, turned 30°.
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let (x, t) = grid(40, 1.0);
        meshes.push(
            t.iter()
                .filter(|c| c.iter().all(|&i| x[i].y.abs() <= 0.0251))
                .map(|k| k.map(|i| V2::new(c * x[i].x - s * x[i].y, s * x[i].x + c * x[i].y)))
                .collect(),
        );
        // Scattered triangles, overlapping and apart, of every size.
        meshes.push(
            (0..300)
                .map(|_| {
                    let o = V2::new(rng.random_range(-1.0..1.0), rng.random_range(-0.2..0.2));
                    let r = 10f64.powf(rng.random_range(-3.0..-0.5));
                    [0, 1, 2].map(|_| o + V2::new(rng.random_range(-r..r), rng.random_range(-r..r)))
                })
                .collect(),
        );
        for tris in &meshes {
            let grid = TriangleGrid::new(tris);
            let mut scratch = ChordScratch::default();
            let mut spans = Vec::new();
            for (k, t) in tris.iter().enumerate() {
                // Through the centroid, through a corner and along an edge.
                for p in [(t[0] + t[1] + t[2]) / 3.0, t[k % 3]] {
                    for j in 0..=2 * CHORD_SAMPLES {
                        let e = if j == 2 * CHORD_SAMPLES {
                            (t[1] - t[0]).normalize()
                        } else {
                            let a = std::f64::consts::PI * j as f64 / CHORD_SAMPLES as f64;
                            V2::new(a.cos(), a.sin())
                        };
                        spans.clear();
                        spans.extend(tris.iter().filter_map(|&t| clip(p, e, t)));
                        let all = merged_span_length(&mut spans);
                        let gridded = chord_through(p, e, tris, &grid, &mut scratch);
                        assert_eq!(all.to_bits(), gridded.to_bits(), "triangle {k}, {j}");
                    }
                }
            }
        }
    }

    #[test]
    fn separate_plates_are_found() {
        let (mut x, mut t) = grid(2, 0.1);
        let (x2, t2) = grid(2, 0.1);
        let off = x.len();
        x.extend(x2.iter().map(|p| p + V3::new(1.0, 0.0, 0.0)));
        t.extend(t2.iter().map(|c| c.map(|i| i + off)));
        assert_eq!(plates(&t).len(), 2);
        let g = surface_geometry(&x, &t);
        let total = |r: std::ops::Range<usize>| -> f64 {
            r.map(|k| g[k].added_mass.iter().sum::<f64>()).sum()
        };
        assert!((total(0..8) - total(8..16)).abs() < 1e-15);
    }
}
