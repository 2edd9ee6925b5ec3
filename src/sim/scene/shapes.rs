//! Particle layouts of the built-in shapes, in their local frames.

use nalgebra::Vector3;
use std::f64::consts::TAU;

type V3 = Vector3<f64>;

/// A spring between two particles of a part (local indices); the rest length
/// is the distance in the part's layout.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PartSpring {
    /// Local particle indices.
    pub ends: [usize; 2],
    /// Stiffness, N/m.
    pub stiffness: f64,
    /// Dashpot coefficient, N·s/m.
    pub damping: f64,
    /// Breaking strain, if breakable.
    pub break_strain: Option<f64>,
}

/// Particles, springs and surface triangles of one shape, local frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Part {
    /// Masses, kg.
    pub mass: Vec<f64>,
    /// Positions, m.
    pub position: Vec<V3>,
    /// Pinned particles.
    pub fixed: Vec<bool>,
    /// Springs.
    pub springs: Vec<PartSpring>,
    /// Surface triangles (local indices).
    pub triangles: Vec<[usize; 3]>,
}

/// A box of edge lengths `size` centred on the origin: a particle of mass
/// `mass`/8 at each corner (corner k has x, y, z signs from bits 0, 1, 2)
/// and two triangles per face.
pub fn cuboid(size: V3, mass: f64) -> Part {
    let position: Vec<V3> = (0..8)
        .map(|k| {
            let s = |bit: usize| if k >> bit & 1 == 0 { -0.5 } else { 0.5 };
            V3::new(s(0) * size.x, s(1) * size.y, s(2) * size.z)
        })
        .collect();
    // Faces as corner quads (a, b, c, d) around the face.
    let faces = [
        [0, 2, 6, 4], // −x
        [1, 5, 7, 3], // +x
        [0, 4, 5, 1], // −y
        [2, 3, 7, 6], // +y
        [0, 1, 3, 2], // −z
        [4, 6, 7, 5], // +z
    ];
    let triangles = faces
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .collect();
    Part {
        mass: vec![mass / 8.0; 8],
        position,
        fixed: vec![false; 8],
        springs: Vec::new(),
        triangles,
    }
}

/// An open-topped cylinder (a bin) of `radius` and `height`, base centre at
/// the origin, axis +z: `rings` rings of `segments` particles sharing
/// `wall_mass` (ring r at height r·height/(rings − 1)), then one particle of
/// `base_mass` at the base centre. Triangles cover the wall and the base.
pub fn bin(
    radius: f64,
    height: f64,
    segments: usize,
    rings: usize,
    wall_mass: f64,
    base_mass: f64,
) -> Part {
    let mut part = Part::default();
    let each = wall_mass / (segments * rings) as f64;
    for r in 0..rings {
        let z = height * r as f64 / (rings - 1) as f64;
        for s in 0..segments {
            let phi = TAU * s as f64 / segments as f64;
            part.position
                .push(V3::new(radius * phi.cos(), radius * phi.sin(), z));
            part.mass.push(each);
        }
    }
    let centre = part.position.len();
    part.position.push(V3::zeros());
    part.mass.push(base_mass);
    part.fixed = vec![false; part.position.len()];
    let id = |r: usize, s: usize| r * segments + s % segments;
    for r in 0..rings - 1 {
        for s in 0..segments {
            let (a, b) = (id(r, s), id(r, s + 1));
            let (c, d) = (id(r + 1, s + 1), id(r + 1, s));
            part.triangles.push([a, b, c]);
            part.triangles.push([a, c, d]);
        }
    }
    for s in 0..segments {
        part.triangles.push([centre, id(0, s + 1), id(0, s)]);
    }
    part
}

/// A `width` × `height` sheet in the local x-y plane centred on the origin,
/// `nx` × `ny` cells: particles on the grid (index j (nx + 1) + i, row j = ny
/// at the top, +y), springs along the grid lines and both diagonals of every
/// cell, two triangles per cell.
#[allow(clippy::too_many_arguments)]
pub fn sheet(
    width: f64,
    height: f64,
    nx: usize,
    ny: usize,
    mass: f64,
    stiffness: f64,
    shear_stiffness: f64,
    damping: f64,
    break_strain: Option<f64>,
) -> Part {
    let mut part = Part::default();
    let count = (nx + 1) * (ny + 1);
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    for j in 0..=ny {
        for i in 0..=nx {
            part.position.push(V3::new(
                width * (i as f64 / nx as f64 - 0.5),
                height * (j as f64 / ny as f64 - 0.5),
                0.0,
            ));
        }
    }
    part.mass = vec![mass / count as f64; count];
    part.fixed = vec![false; count];
    let mut spring = |a: usize, b: usize, k: f64| {
        part.springs.push(PartSpring {
            ends: [a, b],
            stiffness: k,
            damping,
            break_strain,
        })
    };
    for j in 0..=ny {
        for i in 0..=nx {
            if i < nx {
                spring(id(i, j), id(i + 1, j), stiffness);
            }
            if j < ny {
                spring(id(i, j), id(i, j + 1), stiffness);
            }
            if i < nx && j < ny {
                spring(id(i, j), id(i + 1, j + 1), shear_stiffness);
                spring(id(i + 1, j), id(i, j + 1), shear_stiffness);
            }
        }
    }
    for j in 0..ny {
        for i in 0..nx {
            part.triangles
                .push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            part.triangles
                .push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    part
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(p: &Part) -> f64 {
        p.triangles
            .iter()
            .map(|&[a, b, c]| {
                let x = &p.position;
                0.5 * (x[b] - x[a]).cross(&(x[c] - x[a])).norm()
            })
            .sum()
    }

    #[test]
    fn shapes_have_their_surface_area_and_mass() {
        let b = cuboid(V3::new(0.4, 0.2, 0.1), 2.0);
        assert!((area(&b) - 2.0 * (0.08 + 0.04 + 0.02)).abs() < 1e-12);
        assert!((b.mass.iter().sum::<f64>() - 2.0).abs() < 1e-15);
        let s = sheet(1.0, 0.5, 4, 2, 0.3, 10.0, 5.0, 0.0, None);
        assert!((area(&s) - 0.5).abs() < 1e-12);
        assert_eq!(s.springs.len(), 5 * 2 + 4 * 3 + 2 * 4 * 2);
        let c = bin(0.5, 1.0, 64, 2, 3.0, 1.0);
        let exact = TAU * 0.5 * 1.0 + std::f64::consts::PI * 0.25;
        assert!((area(&c) - exact).abs() < 0.01 * exact);
        assert!((c.mass.iter().sum::<f64>() - 4.0).abs() < 1e-12);
    }
}
