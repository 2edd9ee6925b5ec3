//! Rigid bodies from particles against closed forms: torque-free precession of
//! a symmetric top, steady spin about a principal axis, momentum exchange with
//! a spring-coupled particle.

use crate::common::{V3, parts};
use leafmagic::physics::integrate::Simulator;
use leafmagic::physics::model::RigidGroup;
use leafmagic::physics::model::{Model, Spring};
use leafmagic::physics::params::Integrator;
use leafmagic::physics::state::State;

/// A symmetric top about the body z axis: six particles of mass m on a ring
/// of radius a in the x-y plane and two on the axis at ±b.
/// I₃ = 6 m a², I₁ = I₂ = 3 m a² + 2 m b².
fn top(m: f64, a: f64, b: f64) -> (Model, f64, f64) {
    let mut p = parts(8);
    p.mass = vec![m; 8];
    let mut x = Vec::new();
    for k in 0..6 {
        let phi = k as f64 * std::f64::consts::PI / 3.0;
        x.push(V3::new(a * phi.cos(), a * phi.sin(), 0.0));
    }
    x.push(V3::new(0.0, 0.0, b));
    x.push(V3::new(0.0, 0.0, -b));
    p.rest_position = x;
    p.rigid = vec![RigidGroup {
        members: (0..8).collect(),
    }];
    let i3 = 6.0 * m * a * a;
    let i1 = 3.0 * m * a * a + 2.0 * m * b * b;
    (Model::new(p).unwrap(), i1, i3)
}

fn spin(model: &Model, omega: V3) -> State {
    let mut s = State::at_rest(model);
    for (v, x) in s.velocity.iter_mut().zip(&s.position) {
        *v = omega.cross(x);
    }
    s
}

fn axis(s: &State) -> V3 {
    (s.position[6] - s.position[7]).normalize()
}

fn angular_momentum(model: &Model, s: &State) -> V3 {
    let body = &model.rigid[0];
    let (c, vc) = body.centre(&s.position, &s.velocity);
    body.angular_momentum(&s.position, &s.velocity, &c, &vc)
}

/// Torque-free symmetric top: L is fixed in space and the symmetry axis
/// turns about it at Ω = |L| / I₁ (the space-cone precession), keeping its
/// angle to L; |L| and the energy ½ ω·L stay constant.
#[test]
fn torque_free_symmetric_top_precesses_at_l_over_i1() {
    let (model, i1, i3) = top(0.1, 0.2, 0.35);
    assert!(
        (i1 - i3).abs() > 0.1 * i3,
        "the top should be clearly oblate or prolate"
    );
    let omega0 = V3::new(3.0, 0.0, 7.0);
    let l0 = V3::new(i1 * omega0.x, 0.0, i3 * omega0.z);
    let precession = l0.norm() / i1;
    for (integrator, dt, tol) in [
        (Integrator::Rk4, 1e-3_f64, 1e-8),
        (Integrator::Verlet, 2e-4, 2e-4),
        (Integrator::Symplectic, 1e-5, 1e-3),
    ] {
        let mut s = spin(&model, omega0);
        let mut sim = Simulator::new(&model, integrator);
        let body = &model.rigid[0];
        let e0 = body.kinetic_energy(&s.position, &s.velocity);
        let l_start = angular_momentum(&model, &s);
        assert!((l_start - l0).norm() < 1e-12 * l0.norm());
        let steps = (2.0 / dt).round() as usize;
        for _ in 0..steps {
            sim.step(&model, &mut s, dt).unwrap();
        }
        let t = steps as f64 * dt;
        let expected =
            nalgebra::UnitQuaternion::from_scaled_axis(l0.normalize() * precession * t) * V3::z();
        let err = (axis(&s) - expected).norm();
        let l = angular_momentum(&model, &s);
        let e = body.kinetic_energy(&s.position, &s.velocity);
        assert!(err < tol, "{integrator}: axis off by {err:e} after {t} s");
        assert!(
            (l - l0).norm() < tol * l0.norm(),
            "{integrator}: L drifted by {:e}",
            (l - l0).norm() / l0.norm()
        );
        assert!(
            (e - e0).abs() < tol * e0,
            "{integrator}: energy drifted by {:e}",
            (e - e0).abs() / e0
        );
        // Still exactly rigid: every pair distance as at rest.
        for i in 0..8 {
            for j in i + 1..8 {
                let d = (s.position[i] - s.position[j]).norm();
                let d0 = (model.rest_position[i] - model.rest_position[j]).norm();
                assert!(
                    (d - d0).abs() < 1e-12,
                    "{integrator}: shape changed by {}",
                    d - d0
                );
            }
        }
    }
}

/// Spinning about a principal axis is a steady state: ω stays put, and the
/// phase ω t is tracked to second order by Verlet (the error quarters when
/// the step halves).
#[test]
fn spin_about_a_principal_axis_keeps_spinning() {
    let (model, _, _) = top(0.1, 0.2, 0.35);
    for (omega0, member) in [(V3::new(0.0, 0.0, 9.0), 0), (V3::new(6.0, 0.0, 0.0), 6)] {
        let t = 3.0;
        let mut errors = Vec::new();
        for dt in [2e-3_f64, 1e-3] {
            let mut s = spin(&model, omega0);
            let mut sim = Simulator::new(&model, Integrator::Verlet);
            for _ in 0..(t / dt).round() as usize {
                sim.step(&model, &mut s, dt).unwrap();
            }
            let body = &model.rigid[0];
            let (c, _) = body.centre(&s.position, &s.velocity);
            let inv = body.world_inertia(&s.position, &c).try_inverse().unwrap();
            let omega = inv * angular_momentum(&model, &s);
            assert!(
                (omega - omega0).norm() < 1e-9 * omega0.norm(),
                "ω moved from {omega0:?} to {omega:?}"
            );
            let r0 = model.rest_position[member];
            let expected = nalgebra::UnitQuaternion::from_scaled_axis(omega0 * t) * r0;
            errors.push((s.position[member] - expected).norm() / r0.norm());
        }
        let order = (errors[0] / errors[1]).log2();
        assert!(errors[1] < 1e-3, "phase error {:e}", errors[1]);
        assert!((order - 2.0).abs() < 0.1, "order {order} ({errors:?})");
    }
}

/// A rigid body and a free particle joined by a spring: the spring pulls the
/// body through its member, so total momentum is conserved to round-off and
/// total angular momentum to the integrator's accuracy.
#[test]
fn spring_coupled_body_exchanges_momentum_exactly() {
    let (top_model, _, _) = top(0.1, 0.2, 0.35);
    let mut p = parts(9);
    p.mass = top_model.mass.clone();
    p.mass.push(0.05);
    p.rest_position = top_model.rest_position.clone();
    p.rest_position.push(V3::new(0.8, 0.1, 0.0));
    p.springs = vec![Spring {
        i: 0,
        j: 8,
        rest_length: 0.5,
        stiffness: 40.0,
        damping: 0.01,
        break_strain: None,
    }];
    p.rigid = vec![RigidGroup {
        members: (0..8).collect(),
    }];
    let model = Model::new(p).unwrap();
    let mut s = State::at_rest(&model);
    s.velocity[8] = V3::new(0.0, 1.5, 0.4);
    let momentum = |s: &State| -> V3 {
        s.velocity
            .iter()
            .zip(&model.mass)
            .map(|(v, m)| v * *m)
            .sum()
    };
    let ang = |s: &State| -> V3 {
        s.position
            .iter()
            .zip(&s.velocity)
            .zip(&model.mass)
            .map(|((x, v), m)| x.cross(v) * *m)
            .sum()
    };
    let (p0, l0) = (momentum(&s), ang(&s));
    let mut sim = Simulator::new(&model, Integrator::Rk4);
    for _ in 0..4000 {
        sim.step(&model, &mut s, 5e-4).unwrap();
    }
    let (p1, l1) = (momentum(&s), ang(&s));
    assert!(
        (p1 - p0).norm() < 1e-13,
        "momentum changed by {:e}",
        (p1 - p0).norm()
    );
    assert!(
        (l1 - l0).norm() < 1e-7 * l0.norm(),
        "angular momentum changed by {:e}",
        (l1 - l0).norm() / l0.norm()
    );
    // The body really moved and turned.
    let (c, _) = model.rigid[0].centre(&s.position, &s.velocity);
    assert!(c.norm() > 0.01, "the body did not move: {c:?}");
}

/// Bad rigid groups are rejected, naming the group.
#[test]
fn degenerate_rigid_groups_are_rejected() {
    let mut p = parts(4);
    p.rest_position = vec![
        V3::new(0.0, 0.0, 0.0),
        V3::new(1.0, 0.0, 0.0),
        V3::new(2.0, 0.0, 0.0),
        V3::new(0.0, 1.0, 0.0),
    ];
    p.rigid = vec![RigidGroup {
        members: vec![0, 1, 2],
    }];
    let e = Model::new(p.clone()).unwrap_err();
    assert_eq!(e.item, "rigid[0].members");
    assert!(e.reason.contains("line"), "{e}");
    p.rigid = vec![
        RigidGroup {
            members: vec![0, 1, 3],
        },
        RigidGroup {
            members: vec![1, 2, 3],
        },
    ];
    let e = Model::new(p.clone()).unwrap_err();
    assert_eq!(e.item, "rigid[1].members");
    p.fixed[3] = true;
    p.rigid.truncate(1);
    let e = Model::new(p).unwrap_err();
    assert!(e.reason.contains("fixed"), "{e}");
}

/// A rigid leaf (a scene leaf with `rigid = true`) moved by the summed
/// aerodynamic force of its triangles reaches the exact terminal speed of the
/// paper's linear law: falling level at speed u, each triangle's corners take
/// 3 A (αⁿ n_z² + αᵗ (1 − n_z²)) u upwards in all, which balances M g.
#[test]
fn a_rigid_leaf_falls_at_the_linear_laws_terminal_speed() {
    let text = "name = \"rigid-leaf\"\nduration = 20.0\n\n[[leaf]]\nname = \"leaf\"\nleaf = \"a\"\nrigid = true\nrotation_deg = [10.0, 2.0, 0.0]\n";
    let scene =
        leafmagic::sim::scene::Scene::from_toml(text, "rigid-leaf.toml", std::path::Path::new("."))
            .unwrap();
    assert!(scene.model.springs.is_empty() && scene.model.hinges.is_empty());
    let (_, s) = scene.run_with(None, |_, _| {}).unwrap();
    let m = &scene.model;
    let mut balance = 0.0;
    for t in &m.triangles {
        let [a, b, c] = t.corners;
        let n = (s.position[b] - s.position[a]).cross(&(s.position[c] - s.position[a]));
        let (area, nz) = (0.5 * n.norm(), n.z / n.norm());
        balance += 3.0 * area * (t.alpha_n * nz * nz + t.alpha_t * (1.0 - nz * nz));
    }
    let terminal = m.total_mass() * m.gravity.norm() / balance;
    let (_, v) = m.rigid[0].centre(&s.position, &s.velocity);
    assert!(
        (-v.z - terminal).abs() < 1e-9 * terminal,
        "descends at {} m/s, the law gives {terminal} m/s",
        -v.z
    );
    assert!(v.xy().norm() < 1e-5, "still gliding: {v:?}");
}
