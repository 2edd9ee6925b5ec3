//! Tracers (O10): particles advected by a vortex, RK4 and forward Euler.

use std::f64::consts::PI;

use super::super::{VortexCore, WindField};
use super::{V3, frame, v, vortex};

#[test]
fn rk4_tracer_stays_on_its_circle() {
    let gamma = 2.0;
    let axis = v(1.0, 2.0, 2.0) / 3.0;
    let p = v(0.3, -0.1, 0.2);
    let f = WindField::new(vec![vortex(p, axis, gamma, 0.01, VortexCore::LambOseen)]);
    let (e1, _) = frame(&axis);
    let rho = 0.3;
    let x0 = p + rho * e1 + 0.5 * axis;
    let omega = gamma / (2.0 * PI * rho * rho);
    let period = 2.0 * PI / omega;
    let n = 2000;
    let h = period / n as f64;
    let mut x = x0;
    let mut t = 0.0;
    let mut max_drift: f64 = 0.0;
    for k in 0..n {
        let k1 = f.velocity(&x, t);
        let k2 = f.velocity(&(x + 0.5 * h * k1), t + 0.5 * h);
        let k3 = f.velocity(&(x + 0.5 * h * k2), t + 0.5 * h);
        let k4 = f.velocity(&(x + h * k3), t + h);
        x += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        t = (k + 1) as f64 * h;
        let d = x - p;
        let r = (d - axis * axis.dot(&d)).norm();
        max_drift = max_drift.max((r - rho).abs());
        // Quarter turn: angle ωt.
        if k + 1 == n / 4 {
            let (e1, e2) = frame(&axis);
            let ang = (d.dot(&e2)).atan2(d.dot(&e1));
            assert!((ang - omega * t).abs() < 1e-10, "{ang} vs {}", omega * t);
        }
    }
    assert!(max_drift < 1e-11 * rho, "radius drift {max_drift}");
    assert!((x - x0).norm() < 1e-10, "after one period {:?}", x - x0);
}

#[test]
fn forward_euler_tracer_spirals_out_discrete_exactly() {
    // O10: ρ²_{n+1} = ρ²_n + (hΓ/(2πρ_n))² outside the core.
    let gamma = 2.0;
    let f = WindField::new(vec![vortex(
        V3::zeros(),
        V3::z(),
        gamma,
        1e-3,
        VortexCore::Rankine,
    )]);
    let h = 0.01;
    let mut x = v(0.3, 0.0, 0.0);
    let mut rho2 = 0.09f64;
    for _ in 0..200 {
        x += h * f.velocity(&x, 0.0);
        rho2 += (h * gamma / (2.0 * PI * rho2.sqrt())).powi(2);
        let got = x.x * x.x + x.y * x.y;
        assert!((got - rho2).abs() < 1e-13 * rho2);
    }
    assert!(rho2 > 0.09 * 1.01);
}
