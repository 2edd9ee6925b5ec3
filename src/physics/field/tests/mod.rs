//! The field's tests: potential-flow identities and superposition, the
//! regularised cores, tracers, bounds, fronts and keys, validation, TOML.
//! The helpers they share (primitive constructors, finite differences,
//! quadratures) are here.

use std::f64::consts::PI;

use nalgebra::{Matrix3, Vector3};

use super::{Flow, LineSource, LineVortex, PointSource, Primitive, VortexCore, WindField};

mod bounds;
mod cores;
mod keys;
mod potential;
mod reach;
mod tables;
mod tracers;
mod validation;

pub(super) type V3 = Vector3<f64>;

pub(super) fn v(x: f64, y: f64, z: f64) -> V3 {
    V3::new(x, y, z)
}

pub(super) fn point_source(point: V3, flux: f64, core_radius: f64) -> Primitive {
    Primitive::new(Flow::PointSource(PointSource {
        point,
        flux,
        core_radius,
    }))
}

pub(super) fn line_source(point: V3, axis: V3, flux: f64, core_radius: f64) -> Primitive {
    Primitive::new(Flow::LineSource(LineSource {
        point,
        axis,
        flux,
        core_radius,
    }))
}

pub(super) fn vortex(
    point: V3,
    axis: V3,
    circulation: f64,
    core_radius: f64,
    core: VortexCore,
) -> Primitive {
    Primitive::new(Flow::LineVortex(LineVortex {
        point,
        axis,
        circulation,
        core_radius,
        core,
    }))
}

/// J[(i, j)] = ∂v_i/∂x_j by central differences of step h.
pub(super) fn jacobian(f: &dyn Fn(&V3) -> V3, x: &V3, h: f64) -> Matrix3<f64> {
    let mut j = Matrix3::zeros();
    for k in 0..3 {
        let mut e = V3::zeros();
        e[k] = h;
        let col = (f(&(x + e)) - f(&(x - e))) / (2.0 * h);
        j.set_column(k, &col);
    }
    j
}

pub(super) fn div_curl(f: &dyn Fn(&V3) -> V3, x: &V3, h: f64) -> (f64, V3) {
    let j = jacobian(f, x, h);
    let curl = v(
        j[(2, 1)] - j[(1, 2)],
        j[(0, 2)] - j[(2, 0)],
        j[(1, 0)] - j[(0, 1)],
    );
    (j.trace(), curl)
}

/// Two unit vectors completing a right-handed frame (e1, e2, axis).
pub(super) fn frame(axis: &V3) -> (V3, V3) {
    let a = axis.normalize();
    let helper = if a.x.abs() < 0.9 { V3::x() } else { V3::y() };
    let e1 = a.cross(&helper).normalize();
    let e2 = a.cross(&e1);
    (e1, e2)
}

/// ∮ G·dl on the circle centre + R(cos θ e1 + sin θ e2), trapezoid rule.
pub(super) fn circulation(f: &WindField, centre: &V3, axis: &V3, radius: f64, n: usize) -> f64 {
    let (e1, e2) = frame(axis);
    let dth = 2.0 * PI / n as f64;
    (0..n)
        .map(|k| {
            let th = k as f64 * dth;
            let x = centre + radius * (th.cos() * e1 + th.sin() * e2);
            let dl = radius * (-th.sin() * e1 + th.cos() * e2);
            f.velocity(&x, 0.0).dot(&dl) * dth
        })
        .sum()
}

/// Outward flux per unit length through that circle (a coaxial cylinder if centre is on the axis).
pub(super) fn ring_flux(f: &WindField, centre: &V3, axis: &V3, radius: f64, n: usize) -> f64 {
    let (e1, e2) = frame(axis);
    let dth = 2.0 * PI / n as f64;
    (0..n)
        .map(|k| {
            let th = k as f64 * dth;
            let normal = th.cos() * e1 + th.sin() * e2;
            f.velocity(&(centre + radius * normal), 0.0).dot(&normal) * radius * dth
        })
        .sum()
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton on P_n).
pub(super) fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// Outward flux through a sphere: Gauss–Legendre in cos θ, trapezoid in φ.
pub(super) fn sphere_flux(f: &WindField, centre: &V3, radius: f64) -> f64 {
    let nodes = gauss_legendre(48);
    let nphi = 96;
    let dphi = 2.0 * PI / nphi as f64;
    let mut total = 0.0;
    for &(mu, w) in &nodes {
        let s = (1.0 - mu * mu).sqrt();
        for k in 0..nphi {
            let phi = k as f64 * dphi;
            let n = v(s * phi.cos(), s * phi.sin(), mu);
            total += f.velocity(&(centre + radius * n), 0.0).dot(&n) * w * dphi;
        }
    }
    total * radius * radius
}
