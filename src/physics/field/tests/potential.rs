//! Potential-flow identities (O8) and superposition.

use std::f64::consts::PI;

use proptest::prelude::*;

use super::super::{
    Bounds, Flow, Interpolation, Keyframes, LineSink, PointSink, Primitive, Region, VortexCore,
    WindField,
};
use super::{
    V3, circulation, div_curl, frame, line_source, point_source, ring_flux, sphere_flux, v, vortex,
};

#[test]
fn divergence_and_curl_vanish_away_from_cores() {
    let axis = v(1.0, 2.0, 2.0);
    let tiny = 1e-9; // cores far smaller than any sample distance
    let fields: Vec<(&str, WindField)> = vec![
        (
            "uniform",
            WindField::new(vec![Primitive::uniform(v(1.0, -2.0, 0.5))]),
        ),
        (
            "point_source",
            WindField::new(vec![point_source(v(0.1, 0.2, 0.3), 1.7, tiny)]),
        ),
        (
            "line_source",
            WindField::new(vec![line_source(v(0.1, 0.2, 0.3), axis, 1.7, tiny)]),
        ),
        (
            "line_vortex lamb_oseen",
            WindField::new(vec![vortex(
                v(0.1, 0.2, 0.3),
                axis,
                2.0,
                0.01,
                VortexCore::LambOseen,
            )]),
        ),
        (
            "line_vortex rankine",
            WindField::new(vec![vortex(
                v(0.1, 0.2, 0.3),
                axis,
                2.0,
                0.01,
                VortexCore::Rankine,
            )]),
        ),
        (
            "superposition",
            WindField::new(vec![
                Primitive::uniform(v(0.3, 0.0, 1.2)),
                point_source(v(-0.5, 0.0, 0.0), -0.8, tiny),
                line_source(v(0.5, 0.5, 0.0), v(0.0, 0.0, 1.0), 1.1, tiny),
                vortex(
                    v(0.0, -0.5, 0.0),
                    v(0.0, 1.0, 1.0),
                    3.0,
                    0.01,
                    VortexCore::LambOseen,
                ),
            ]),
        ),
    ];
    let samples = [
        v(1.0, 0.3, -0.7),
        v(-0.9, 1.4, 0.6),
        v(0.7, -1.1, 1.5),
        v(2.0, 2.0, -1.0),
    ];
    for (name, f) in &fields {
        for x in &samples {
            let g = |y: &V3| f.velocity(y, 0.0);
            let (div, curl) = div_curl(&g, x, 1e-5);
            // Scale |v|/ρ with ρ ~ 0.5 here: compare against a gradient scale of the field.
            let scale = f.speed_bound().min(10.0) + f.velocity(x, 0.0).norm();
            assert!(div.abs() < 1e-6 * scale, "{name} at {x:?}: div = {div}");
            assert!(
                curl.norm() < 1e-6 * scale,
                "{name} at {x:?}: curl = {curl:?}"
            );
            assert!(f.velocity(x, 0.0).norm() > 0.0);
        }
    }
}

#[test]
fn smoothed_sources_have_the_exact_core_divergence() {
    // Line source: div = a ε²/(π(ρ² + ε²)²); point source: div = 3aε²/(4π(r² + ε²)^{5/2}).
    let (a, eps) = (1.7, 0.1);
    let axis = v(0.0, 0.0, 1.0);
    let line = WindField::new(vec![line_source(V3::zeros(), axis, a, eps)]);
    let point = WindField::new(vec![point_source(V3::zeros(), a, eps)]);
    for &rho in &[0.0, 0.03, 0.1, 0.25, 0.6] {
        let x = v(rho, 0.0, 0.4);
        let (div, curl) = div_curl(&|y: &V3| line.velocity(y, 0.0), &x, 1e-5);
        let exact = a * eps * eps / (PI * (rho * rho + eps * eps).powi(2));
        assert!(
            (div - exact).abs() < 1e-6 * exact.max(1.0),
            "line ρ={rho}: {div} vs {exact}"
        );
        assert!(curl.norm() < 1e-6);
        let x = v(rho, 0.0, 0.0);
        let (div, curl) = div_curl(&|y: &V3| point.velocity(y, 0.0), &x, 1e-5);
        let s = rho * rho + eps * eps;
        let exact = 3.0 * a * eps * eps / (4.0 * PI * s * s * s.sqrt());
        assert!(
            (div - exact).abs() < 1e-6 * exact.max(1.0),
            "point r={rho}: {div} vs {exact}"
        );
        assert!(curl.norm() < 1e-6);
    }
}

#[test]
fn paper_source_formula_is_divergence_free_only_as_a_line_source() {
    // v = a/(2πr) r̂ with r the 3-D distance ("spherical", figure 2 read literally)
    // has div = a/(2πr²); with ρ the distance to an axis (our line_source) it is 0.
    let a = 1.3;
    let spherical = |x: &V3| x * (a / (2.0 * PI * x.norm_squared()));
    let line = WindField::new(vec![line_source(V3::zeros(), v(0.0, 0.0, 1.0), a, 1e-12)]);
    for x in [v(0.4, 0.3, 0.5), v(-0.2, 0.7, -1.5), v(1.0, 0.0, 3.0)] {
        let (div_sph, _) = div_curl(&spherical, &x, 1e-5);
        let expected = a / (2.0 * PI * x.norm_squared());
        assert!((div_sph - expected).abs() < 1e-6 * expected);
        assert!(div_sph > 0.01);
        let (div_line, _) = div_curl(&|y: &V3| line.velocity(y, 0.0), &x, 1e-5);
        assert!(div_line.abs() < 1e-7, "line source div {div_line} at {x:?}");
        // The line source has no component along its axis, however far along it we are.
        assert_eq!(line.velocity(&x, 0.0).z, 0.0);
    }
}

#[test]
fn vortex_circulation_and_lamb_oseen_enclosed_circulation() {
    let gamma = 2.0;
    let axis = v(0.0, 1.0, 1.0);
    let p = v(0.2, -0.1, 0.3);
    for core in [VortexCore::LambOseen, VortexCore::Rankine] {
        let f = WindField::new(vec![vortex(p, axis, gamma, 1e-3, core)]);
        // Coaxial circle.
        let c = circulation(&f, &p, &axis, 0.5, 64);
        assert!((c - gamma).abs() < 1e-12, "{core:?}: {c}");
        // Off-centre circle that still encloses the axis.
        let (e1, _) = frame(&axis);
        let c = circulation(&f, &(p + 0.2 * e1), &axis, 0.5, 256);
        assert!((c - gamma).abs() < 1e-10, "{core:?} off-centre: {c}");
        // Circle not enclosing the axis.
        let c = circulation(&f, &(p + 1.0 * e1), &axis, 0.5, 256);
        assert!(c.abs() < 1e-10, "{core:?} not enclosing: {c}");
        // Sign: right-hand rule, reversed axis reverses the circulation.
        let f_rev = WindField::new(vec![vortex(p, -axis, gamma, 1e-3, core)]);
        assert!((circulation(&f_rev, &p, &axis, 0.5, 64) + gamma).abs() < 1e-12);
    }
    // Lamb–Oseen: circulation within ρ is Γ(1 − e^{−ρ²/r_c²}).
    let rc = 0.1;
    let f = WindField::new(vec![vortex(p, axis, gamma, rc, VortexCore::LambOseen)]);
    for rho in [0.02, 0.05, 0.1, 0.2, 0.3] {
        let c = circulation(&f, &p, &axis, rho, 64);
        let exact = gamma * (1.0 - (-(rho * rho) / (rc * rc)).exp());
        assert!((c - exact).abs() < 1e-13, "ρ={rho}: {c} vs {exact}");
    }
    // Rankine: solid body inside, Γρ²/R².
    let f = WindField::new(vec![vortex(p, axis, gamma, rc, VortexCore::Rankine)]);
    let c = circulation(&f, &p, &axis, 0.05, 64);
    assert!((c - gamma * 0.25).abs() < 1e-13);
}

#[test]
fn source_fluxes_match_smoothed_closed_forms() {
    let a = 1.7;
    // Point source through a centred sphere: a R³/(R² + ε²)^{3/2}.
    let c = v(0.3, -0.2, 0.1);
    for (eps, r) in [(0.1, 0.5), (0.2, 0.1), (1e-6, 1.0)] {
        let f = WindField::new(vec![point_source(c, a, eps)]);
        let flux = sphere_flux(&f, &c, r);
        let exact = a * r.powi(3) / (r * r + eps * eps).powf(1.5);
        assert!(
            (flux - exact).abs() < 1e-12,
            "ε={eps} R={r}: {flux} vs {exact}"
        );
    }
    // Off-centre sphere enclosing a near-singular source: a (Gauss); not enclosing: 0.
    let f = WindField::new(vec![point_source(c, a, 1e-9)]);
    let flux = sphere_flux(&f, &(c + v(0.2, 0.1, 0.0)), 1.0);
    assert!((flux - a).abs() < 1e-9, "off-centre: {flux}");
    let flux = sphere_flux(&f, &(c + v(2.0, 0.0, 0.0)), 1.0);
    assert!(flux.abs() < 1e-10, "outside: {flux}");
    // Sink: positive strength means inflow.
    let sink = WindField::new(vec![Primitive::new(Flow::PointSink(PointSink {
        point: c,
        flux: a,
        core_radius: 0.1,
    }))]);
    let exact = a * 0.125 / (0.25f64 + 0.01).powf(1.5);
    assert!((sphere_flux(&sink, &c, 0.5) + exact).abs() < 1e-12);

    // Line source through a coaxial cylinder, per unit length: a R²/(R² + ε²).
    let axis = v(1.0, -1.0, 0.5);
    for (eps, r) in [(0.1, 0.5), (0.3, 0.1), (1e-9, 1.0)] {
        let f = WindField::new(vec![line_source(c, axis, a, eps)]);
        let flux = ring_flux(&f, &(c + 3.0 * axis), &axis, r, 64);
        let exact = a * r * r / (r * r + eps * eps);
        assert!(
            (flux - exact).abs() < 1e-12,
            "ε={eps} R={r}: {flux} vs {exact}"
        );
    }
    let f = WindField::new(vec![Primitive::new(Flow::LineSink(LineSink {
        point: c,
        axis,
        flux: a,
        core_radius: 1e-9,
    }))]);
    let (e1, _) = frame(&axis);
    assert!((ring_flux(&f, &(c + 0.3 * e1), &axis, 1.0, 256) + a).abs() < 1e-10);
    assert!(ring_flux(&f, &(c + 2.0 * e1), &axis, 1.0, 256).abs() < 1e-10);
}

fn coord() -> impl Strategy<Value = f64> {
    -2.0..2.0f64
}

proptest! {
    #[test]
    fn superposition_is_linear(
        x in (coord(), coord(), coord()),
        s1 in -5.0..5.0f64,
        s2 in -5.0..5.0f64,
        u in (coord(), coord(), coord()),
        t in -1.0..4.0f64,
    ) {
        let x = v(x.0, x.1, x.2);
        let u = v(u.0, u.1, u.2);
        let p = v(0.1, -0.3, 0.2);
        let axis = v(0.3, 0.4, 1.0);
        let make = |s: f64| -> Vec<Primitive> {
            vec![
                Primitive::uniform(u * s),
                point_source(p, s, 0.05),
                line_source(p, axis, s, 0.05),
                vortex(p, axis, s, 0.05, VortexCore::LambOseen),
                vortex(-p, axis, s, 0.05, VortexCore::Rankine),
            ]
        };
        let keys = Keyframes { keys: vec![(0.0, 0.5), (2.0, 1.5)], interpolation: Interpolation::Linear };
        let bounds = Bounds { region: Region::Sphere { center: p, radius: 0.5 }, falloff: 1.0 };
        let with = |ps: Vec<Primitive>| -> Vec<Primitive> {
            ps.into_iter().map(|q| q.with_keys(keys.clone()).with_bounds(bounds.clone())).collect()
        };
        let a = WindField::new(with(make(s1)));
        let b = WindField::new(with(make(s2)));
        let sum = WindField::new(with(make(s1 + s2)));
        let both = WindField::new(with(make(s1)).into_iter().chain(with(make(s2))).collect());
        let (ga, gb) = (a.velocity(&x, t), b.velocity(&x, t));
        let tol = 1e-12 * (1.0 + a.speed_bound() + b.speed_bound());
        // Field of the sum of strengths = sum of fields.
        prop_assert!((sum.velocity(&x, t) - (ga + gb)).norm() < tol);
        // Field of the union of primitives = sum of fields.
        prop_assert!((both.velocity(&x, t) - (ga + gb)).norm() < tol);
        // And each field is the sum of its primitives.
        let parts: V3 = a.primitives().iter().map(|q| q.velocity(&x, t)).sum();
        prop_assert!((a.velocity(&x, t) - parts).norm() < tol);
        prop_assert!(a.velocity(&x, t).norm() <= a.speed_bound() * (1.0 + 1e-12));
    }
}
