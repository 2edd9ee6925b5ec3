//! Regularised cores (O9, §4): finite everywhere, exact outside, bounded by
//! `speed_bound`.

use std::f64::consts::PI;

use super::super::flows::one_minus_exp_over;
use super::super::{Flow, Primitive, VortexCore, WindField};
use super::{V3, line_source, point_source, v, vortex};

#[test]
fn cores_are_finite_and_zero_on_the_axis() {
    let p = v(0.1, 0.2, -0.3);
    let axis = v(0.0, 1.0, 1.0);
    let prims = [
        point_source(p, 2.0, 0.05),
        line_source(p, axis, 2.0, 0.05),
        vortex(p, axis, 2.0, 0.05, VortexCore::LambOseen),
        vortex(p, axis, 2.0, 0.05, VortexCore::Rankine),
    ];
    for q in &prims {
        let f = WindField::new(vec![q.clone()]);
        // Exactly at the point / on the axis (several points along it).
        let along: &[f64] = match q.flow() {
            Flow::PointSource(_) => &[0.0],
            _ => &[0.0, 0.5, -2.0],
        };
        for &s in along {
            let on_axis = p + s * axis;
            let g = f.velocity(&on_axis, 0.0);
            if s == 0.0 {
                assert_eq!(g, V3::zeros(), "{:?}", q.flow());
            }
            // Elsewhere on the axis only round-off in ρ remains.
            assert!(g.norm() < 1e-12 * f.speed_bound(), "{:?}: {g:?}", q.flow());
        }
        // A grid through the core, including the axis.
        for i in -10..=10 {
            for j in -10..=10 {
                let x = p + v(i as f64 * 0.01, j as f64 * 0.01, 0.0);
                let g = f.velocity(&x, 0.0);
                assert!(g.iter().all(|c| c.is_finite()));
                assert!(g.norm() <= f.speed_bound() * (1.0 + 1e-12));
            }
        }
    }
    // Near the Taylor switch of (1 − e^{−q})/q the vortex stays smooth.
    let below = one_minus_exp_over(1e-6 * (1.0 - 1e-9));
    let above = one_minus_exp_over(1e-6 * (1.0 + 1e-9));
    assert!((below - above).abs() < 1e-14);
    assert_eq!(one_minus_exp_over(0.0), 1.0);
}

/// Tangential speed of a z-axis vortex at distance ρ.
fn v_theta(f: &WindField, rho: f64) -> f64 {
    f.velocity(&v(rho, 0.0, 0.7), 0.0).y
}

#[test]
fn lamb_oseen_peak_and_far_field() {
    let (gamma, rc) = (2.0, 0.05);
    let f = WindField::new(vec![vortex(
        V3::zeros(),
        V3::z(),
        gamma,
        rc,
        VortexCore::LambOseen,
    )]);
    // Golden-section search for the peak.
    let (mut lo, mut hi) = (0.5 * rc, 2.0 * rc);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..100 {
        let (a, b) = (hi - g * (hi - lo), lo + g * (hi - lo));
        if v_theta(&f, a) > v_theta(&f, b) {
            hi = b;
        } else {
            lo = a;
        }
    }
    let rho_max = 0.5 * (lo + hi);
    assert!(
        (rho_max / rc - 1.1209).abs() < 1e-4,
        "peak at {}",
        rho_max / rc
    );
    let vmax = v_theta(&f, rho_max) / (gamma / (2.0 * PI * rc));
    assert!((vmax - 0.6382).abs() < 1e-4, "v_max ratio {vmax}");
    // speed_bound is that peak, from above.
    let exact_peak = v_theta(&f, rho_max);
    assert!(f.speed_bound() >= exact_peak && f.speed_bound() < exact_peak * (1.0 + 1e-6));
    // Far field: the singular Γ/(2πρ).
    for rho in [10.0 * rc, 30.0 * rc, 1e3 * rc] {
        let singular = gamma / (2.0 * PI * rho);
        assert!((v_theta(&f, rho) - singular).abs() < 1e-12 * singular);
    }
}

#[test]
fn rankine_core_is_continuous_and_exact_outside() {
    let (gamma, r) = (2.0, 0.05);
    let f = WindField::new(vec![vortex(
        V3::zeros(),
        V3::z(),
        gamma,
        r,
        VortexCore::Rankine,
    )]);
    let at_r = gamma / (2.0 * PI * r);
    assert!((v_theta(&f, r) - at_r).abs() < 1e-12 * at_r);
    for d in [1e-3, 1e-6, 1e-9] {
        let jump = (v_theta(&f, r * (1.0 + d)) - v_theta(&f, r * (1.0 - d))).abs();
        assert!(jump < 2.0 * d * at_r, "jump {jump} at δ={d}");
    }
    // Solid-body rotation inside, free vortex outside.
    assert!((v_theta(&f, 0.4 * r) - 0.4 * at_r).abs() < 1e-12 * at_r);
    for rho in [1.5 * r, 20.0 * r] {
        let singular = gamma / (2.0 * PI * rho);
        assert!((v_theta(&f, rho) - singular).abs() < 1e-14 * singular);
    }
    assert!((f.speed_bound() - at_r).abs() < 1e-12 * at_r);
    // Right-hand rule: +Γ about +z at +x points along +y.
    assert!(v_theta(&f, 0.3) > 0.0);
}

#[test]
fn smoothed_sources_match_singular_far_field_and_speed_bound() {
    let (a, eps) = (1.5, 0.01);
    let line = WindField::new(vec![line_source(V3::zeros(), V3::z(), a, eps)]);
    let point = WindField::new(vec![point_source(V3::zeros(), a, eps)]);
    for rho in [1.0, 3.0] {
        let exact = a / (2.0 * PI * rho);
        let got = line.velocity(&v(rho, 0.0, 5.0), 0.0).x;
        assert!((got - exact).abs() < 2.0 * (eps / rho).powi(2) * exact);
        let exact = a / (4.0 * PI * rho * rho);
        let got = point.velocity(&v(0.0, 0.0, rho), 0.0).z;
        assert!((got - exact).abs() < 3.0 * (eps / rho).powi(2) * exact);
    }
    // Peaks: line source at ρ = ε, point source at r = ε/√2.
    let line_peak = line.velocity(&v(eps, 0.0, 0.0), 0.0).norm();
    assert!((line.speed_bound() - line_peak).abs() < 1e-12 * line_peak);
    let point_peak = point.velocity(&v(eps / 2f64.sqrt(), 0.0, 0.0), 0.0).norm();
    assert!((point.speed_bound() - point_peak).abs() < 1e-12 * point_peak);
    for k in 1..200 {
        let r = k as f64 * 1e-4;
        assert!(line.velocity(&v(r, 0.0, 0.0), 0.0).norm() <= line_peak * (1.0 + 1e-12));
        assert!(point.velocity(&v(r, 0.0, 0.0), 0.0).norm() <= point_peak * (1.0 + 1e-12));
    }
}

#[test]
fn rankine_half_body_stagnation_point() {
    // Uniform U along +x plus a line source a on the z axis: stagnation at x = −a/(2πU).
    let (u, a) = (1.2, 0.9);
    let f = WindField::new(vec![
        Primitive::uniform(v(u, 0.0, 0.0)),
        line_source(V3::zeros(), V3::z(), a, 1e-9),
    ]);
    let xs = -a / (2.0 * PI * u);
    assert!(f.velocity(&v(xs, 0.0, 0.4), 0.0).norm() < 1e-12 * u);
    // Flow reaches it from upstream and is pushed back from the source side.
    assert!(f.velocity(&v(xs * 1.01, 0.0, 0.0), 0.0).x > 0.0);
    assert!(f.velocity(&v(xs * 0.99, 0.0, 0.0), 0.0).x < 0.0);
    // Far downstream the source's flux a spreads over a body of half-width a/(2U):
    // on the body's asymptote the wind is U again.
    let far = f.velocity(&v(1e7, a / (2.0 * u), 0.0), 0.0);
    assert!((far - v(u, 0.0, 0.0)).norm() < 1e-7);
}
