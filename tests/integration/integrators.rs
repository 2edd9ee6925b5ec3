//! Discrete-exact oracles for each integrator (docs/design/numerics.md, "Oracles":
//! O1–O4, O7)
//! and stability boundaries at 0.99 / 1.01 × the predicted limit.

use crate::common::*;
use leafmagic::physics::integrate::Simulator;
use leafmagic::physics::model::Model;
use leafmagic::physics::params::Integrator;
use leafmagic::physics::stability;
use leafmagic::physics::state::State;

fn run(model: &Model, integrator: Integrator, h: f64, steps: usize, state: &mut State) {
    let mut sim = Simulator::new(model, integrator);
    for _ in 0..steps {
        sim.step(model, state, h).unwrap();
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

/// O3: after n steps from rest, forward Euler is off by +g h t/2, symplectic
/// Euler by −g h t/2, Verlet (and RK4) not at all. The sign tells the
/// paper's scheme from the semi-implicit one.
#[test]
fn free_fall_error_sign_identifies_the_scheme() {
    let g = 9.81;
    let model = falling_particle(0.01, g);
    let (h, n) = (1e-3, 500);
    let t = h * n as f64;
    let exact = -0.5 * g * t * t;
    for (integrator, expected_error) in [
        (Integrator::Euler, 0.5 * g * h * t),
        (Integrator::Symplectic, -0.5 * g * h * t),
        (Integrator::Verlet, 0.0),
        (Integrator::Rk4, 0.0),
    ] {
        let mut s = State::at_rest(&model);
        run(&model, integrator, h, n, &mut s);
        let error = s.position[0].z - exact;
        assert!(
            (error - expected_error).abs() < 1e-12,
            "{integrator}: error {error:e}, expected {expected_error:e}"
        );
    }
}

/// O4: a particle with linear drag and gravity follows v_n = v∞ + (v0 − v∞) rⁿ
/// and x_n = x0 + n h v∞ + τ (v0 − v∞)(1 − rⁿ), with r = 1 − h/τ for forward
/// Euler and r = 1/(1 + h/τ) for backward Euler, exactly.
#[test]
fn linear_drag_is_discrete_exact_for_forward_and_backward_euler() {
    let (m, alpha, g) = (0.002, 0.01, 9.81);
    let tau = m / alpha;
    let mut p = parts(1);
    p.mass = vec![m];
    p.particle_drag = vec![alpha];
    p.gravity = V3::new(0.0, 0.0, -g);
    let model = Model::new(p).unwrap();
    let v0 = V3::new(0.3, -0.2, 1.5);
    let v_inf = V3::new(0.0, 0.0, -g * tau);
    let h = 0.01;
    for (integrator, r) in [
        (Integrator::Euler, 1.0 - h / tau),
        (Integrator::Implicit, 1.0 / (1.0 + h / tau)),
    ] {
        let mut s = State::at_rest(&model);
        s.velocity[0] = v0;
        let mut sim = Simulator::new(&model, integrator);
        for n in 1..=200 {
            sim.step(&model, &mut s, h).unwrap();
            let rn = r.powi(n);
            let v = v_inf + (v0 - v_inf) * rn;
            let x = v_inf * (n as f64 * h) + (v0 - v_inf) * (tau * (1.0 - rn));
            assert!(
                (s.velocity[0] - v).norm() < 1e-12 * v.norm(),
                "{integrator} v at {n}"
            );
            assert!(
                (s.position[0] - x).norm() < 1e-12 * x.norm().max(1e-3),
                "{integrator} x at {n}"
            );
        }
    }
}

/// O1: the discrete invariants of the undamped oscillator, exact to round-off.
#[test]
fn undamped_oscillator_invariants_per_scheme() {
    let (m, k) = (0.5, 8.0);
    let w2 = k / m;
    let model = oscillator(m, k, 0.0);
    let h = 0.05;
    let n = 400;
    let x0 = 1e-4;
    let mut states: Vec<(Integrator, Vec<(f64, f64)>)> = Vec::new();
    for integrator in Integrator::ALL {
        let mut s = State::at_rest(&model);
        s.position[1].x += x0;
        let mut sim = Simulator::new(&model, integrator);
        let mut path = vec![(x0, 0.0)];
        for _ in 0..n {
            sim.step(&model, &mut s, h).unwrap();
            path.push((s.position[1].x - 1.0, s.velocity[1].x));
        }
        states.push((integrator, path));
    }
    let e = |x: f64, v: f64| v * v + w2 * x * x;
    let e0 = e(x0, 0.0);
    let y = (w2.sqrt()) * h;
    // |R(iy)|² of RK4.
    let rk4_factor = 1.0 - y.powi(6) / 72.0 + y.powi(8) / 576.0;
    for (integrator, path) in &states {
        for (step, &(x, v)) in path.iter().enumerate() {
            let nf = step as i32;
            let (value, expected) = match integrator {
                Integrator::Euler => (e(x, v), e0 * (1.0 + y * y).powi(nf)),
                Integrator::Implicit => (e(x, v), e0 * (1.0 + y * y).powi(-nf)),
                Integrator::Symplectic => (v * v + w2 * x * x - h * w2 * x * v, e0),
                Integrator::Verlet => (
                    v * v + w2 * x * x * (1.0 - w2 * h * h / 4.0),
                    e0 * (1.0 - w2 * h * h / 4.0),
                ),
                Integrator::Rk4 => (e(x, v), e0 * rk4_factor.powi(nf)),
            };
            // The implicit step solves its linear system by CG to 1e-12.
            let tolerance = if *integrator == Integrator::Implicit {
                1e-8
            } else {
                1e-10
            };
            // Positions are stored as 1 + x, so precision is relative to the start.
            assert!(
                (value - expected).abs() < tolerance * expected.abs().max(e0),
                "{integrator} step {step}: invariant {value:e} vs {expected:e}"
            );
        }
    }
}

/// Verlet's numerical frequency obeys sin(ω̃h/2) = ωh/2 (O1): the sign
/// changes of x come every π/ω̃.
#[test]
fn verlet_period_matches_its_discrete_frequency() {
    let (m, k) = (1.0, 9.0);
    let model = oscillator(m, k, 0.0);
    let h = 0.1;
    let w = (k / m).sqrt();
    let w_num = 2.0 / h * (w * h / 2.0).asin();
    let mut s = State::at_rest(&model);
    s.position[1].x += 0.01;
    let mut sim = Simulator::new(&model, Integrator::Verlet);
    let mut crossings = Vec::new();
    let mut prev = 0.01;
    for n in 1..=2000 {
        sim.step(&model, &mut s, h).unwrap();
        let x = s.position[1].x - 1.0;
        if prev > 0.0 && x <= 0.0 {
            // Linear interpolation of the crossing time inside the step.
            crossings.push(h * (n as f64 - 1.0 + prev / (prev - x)));
        }
        prev = x;
    }
    let period = (crossings.last().unwrap() - crossings[0]) / (crossings.len() - 1) as f64;
    let expected = 2.0 * std::f64::consts::PI / w_num;
    assert!(
        rel(period, expected) < 2e-4,
        "period {period} vs {expected}"
    );
    assert!(
        rel(period, 2.0 * std::f64::consts::PI / w) > 1e-3,
        "must differ from the exact period"
    );
}

/// Largest energy in the second half of `n` steps over the largest in the
/// first half: about 1 or less when bounded (a symplectic scheme near its
/// limit swings widely but does not grow), huge when unstable.
fn growth(model: &Model, integrator: Integrator, h: f64, n: usize) -> f64 {
    let mut s = State::at_rest(model);
    // Tiny, so that the spring stays linear long after growth is evident.
    s.position[1].x += 1e-9;
    let mut sim = Simulator::new(model, integrator);
    let k = model.springs[0].stiffness;
    let m = model.mass[1];
    let e = |s: &State| m * s.velocity[1].norm_squared() + k * (s.position[1].x - 1.0).powi(2);
    let e0 = e(&s);
    let (mut first, mut second) = (e0, 0.0f64);
    for step in 0..n {
        if sim.step(model, &mut s, h).is_err() {
            return f64::INFINITY;
        }
        if e(&s) > 1e6 * e0 {
            return f64::INFINITY;
        }
        if step < n / 2 {
            first = first.max(e(&s));
        } else {
            second = second.max(e(&s));
        }
    }
    second / first
}

/// O2: the estimator's dt_max is the boundary between decay and growth for
/// every explicit scheme, undamped and damped.
#[test]
fn stability_boundary_at_099_and_101_of_the_estimate() {
    for &(m, k, zeta) in &[(0.2f64, 50.0f64, 0.0), (0.2, 50.0, 0.3), (1e-5, 2.0, 0.1)] {
        let c = 2.0 * zeta * (k * m).sqrt();
        let model = oscillator(m, k, c);
        let est = stability::estimate(&model);
        for integrator in Integrator::EXPLICIT {
            let limit = est.dt_max(integrator).unwrap();
            if limit == 0.0 {
                // Forward Euler on an undamped spring: unstable at any step.
                assert_eq!(integrator, Integrator::Euler);
                assert_eq!(zeta, 0.0);
                let h = 0.01 * (m / k).sqrt();
                assert!(growth(&model, integrator, h, 5000) > 1.1);
                continue;
            }
            let w = (k / m).sqrt();
            let n = (4000.0 / (w * limit)).max(4000.0) as usize;
            let below = growth(&model, integrator, 0.99 * limit, n);
            let above = growth(&model, integrator, 1.01 * limit, n);
            assert!(
                below <= 1.01,
                "{integrator} ζ={zeta}: grew {below} at 0.99 × {limit:e}"
            );
            assert!(
                above > 10.0,
                "{integrator} ζ={zeta}: only {above} at 1.01 × {limit:e}"
            );
        }
    }
}

/// Damped oscillator, exact solution (O2, ζ < 1).
fn damped_exact(w: f64, zeta: f64, x0: f64, t: f64) -> (f64, f64) {
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let a = x0;
    let b = zeta * w * x0 / wd;
    let e = (-zeta * w * t).exp();
    let (s, c) = (wd * t).sin_cos();
    let x = e * (a * c + b * s);
    let v = e * (-zeta * w * (a * c + b * s) + (-a * wd * s + b * wd * c));
    (x, v)
}

/// O7: observed orders 1, 1, 2, 4, 1 on the damped oscillator.
#[test]
fn convergence_orders() {
    let (m, k, zeta): (f64, f64, f64) = (1.0, 4.0, 0.1);
    let w = (k / m).sqrt();
    let model = oscillator(m, k, 2.0 * zeta * w * m);
    let t_end = 2.0;
    let x0 = 0.1;
    let (x_ref, v_ref) = damped_exact(w, zeta, x0, t_end);
    for integrator in Integrator::ALL {
        let mut errors = Vec::new();
        for j in 0..5 {
            let n = 40usize << j;
            let h = t_end / n as f64;
            let mut s = State::at_rest(&model);
            s.position[1].x += x0;
            run(&model, integrator, h, n, &mut s);
            let e = ((s.position[1].x - 1.0 - x_ref).powi(2)
                + (s.velocity[1].x - v_ref).powi(2) / (w * w))
                .sqrt();
            errors.push(e);
        }
        let orders: Vec<f64> = errors.windows(2).map(|p| (p[0] / p[1]).log2()).collect();
        let expected = integrator.order() as f64;
        // The last three halvings must all show the order within 0.1.
        for p in &orders[1..] {
            assert!(
                (p - expected).abs() < 0.1,
                "{integrator}: orders {orders:?}, errors {errors:?}"
            );
        }
        assert!(
            *errors.last().unwrap() > 1e3 * f64::EPSILON * x0,
            "errors must be above round-off"
        );
    }
}

/// Dense output: a projectile under gravity alone moves on a parabola,
/// which velocity Verlet follows exactly at any step and the cubic Hermite
/// interpolant reproduces exactly between steps; so frames sampled with a
/// step that does not divide the frame (3.7 steps per frame, and one step
/// spanning 2.5 frames) land on the closed form to round-off.
#[test]
fn frames_between_steps_are_interpolated_exactly_on_a_parabola() {
    use leafmagic::physics::run::run_sampled;
    let mut parts = crate::common::parts(1);
    parts.gravity = V3::new(0.0, 0.0, -9.81);
    let model = Model::new(parts).unwrap();
    let frame = 1.0 / 240.0;
    for steps_per_frame in [3.7, 0.4] {
        let mut state = State::at_rest(&model);
        let v0 = V3::new(0.3, -0.2, 2.0);
        state.velocity[0] = v0;
        let mut seen = 0;
        run_sampled(
            &model,
            &mut state,
            Integrator::Verlet,
            frame / steps_per_frame,
            frame,
            240,
            |k, x| {
                let t = k as f64 * frame;
                let exact = v0 * t + 0.5 * model.gravity * t * t;
                assert!(
                    (x[0] - exact).norm() < 1e-13,
                    "frame {k} at {steps_per_frame} steps/frame: {:?} vs {exact:?}",
                    x[0]
                );
                assert_eq!(k, seen);
                seen += 1;
            },
        )
        .unwrap();
        assert_eq!(seen, 241, "every frame 0..=240 is sampled once");
        assert!(state.time >= 1.0 - 1e-12 && state.time < 1.0 + frame / steps_per_frame);
    }
}

/// The divergence check sums |v|² and |x|² over the particles before it
/// looks at any one: a model of many particles, each well within the
/// runaway limits, once stopped as "diverged" because the sums were not
/// (30,000 free particles at 100 m/s sum to 3 × 10⁸ m²/s², three times the
/// limit's square). Only a particle past a limit is a runaway: these fly on
/// ballistically, exactly, while one of them past the speed limit is named.
#[test]
fn many_particles_within_the_limits_are_not_a_runaway() {
    use leafmagic::physics::integrate::RUNAWAY_SPEED;
    use leafmagic::physics::model::ModelParts;
    let n = 30_000;
    let model = Model::new(ModelParts {
        mass: vec![1e-3; n],
        fixed: vec![false; n],
        rest_position: (0..n).map(|i| V3::new(i as f64 * 1e-2, 0.0, 0.0)).collect(),
        ..Default::default()
    })
    .unwrap();
    let mut state = State::at_rest(&model);
    state.velocity = vec![V3::new(0.0, 100.0, 0.0); n];
    let sum_v2: f64 = state.velocity.iter().map(|v| v.norm_squared()).sum();
    assert!(sum_v2 > RUNAWAY_SPEED * RUNAWAY_SPEED);
    let start = state.clone();
    let mut sim = Simulator::new(&model, Integrator::Verlet);
    let dt = 1e-3;
    for _ in 0..10 {
        sim.step(&model, &mut state, dt).unwrap();
    }
    let t = 10.0 * dt;
    for i in [0, n / 2, n - 1] {
        let expected = start.position[i] + start.velocity[i] * t + model.gravity * (0.5 * t * t);
        assert!((state.position[i] - expected).norm() < 1e-12, "{i}");
    }
    // One particle past the limit is still a runaway, and is named.
    state.velocity[n / 3].y = 2.0 * RUNAWAY_SPEED;
    let err = sim.step(&model, &mut state, dt).unwrap_err().to_string();
    assert!(err.contains(&format!("particle {}", n / 3)), "{err}");
    assert!(err.contains("velocity ran away"), "{err}");
}
