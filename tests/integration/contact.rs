//! Ground contact against closed forms (docs/design/numerics.md, "Oracles", O11): first impact at
//! √(2H/g), bounce heights e^{2k} H, a slide stopping at v₀²/(2 μ_k g), a
//! block on a slope held by static friction below the friction angle and
//! sliding at g (sin θ − μ_k cos θ) above it; for free particles and for rigid
//! bodies.

use crate::common::{V3, parts};
use leafmagic::physics::integrate::Simulator;
use leafmagic::physics::model::Ground;
use leafmagic::physics::model::RigidGroup;
use leafmagic::physics::model::{Model, STANDARD_GRAVITY as G};
use leafmagic::physics::params::Integrator;
use leafmagic::physics::state::State;

fn ground(mu_s: f64, mu_k: f64, e: f64) -> Ground {
    Ground {
        height: 0.0,
        static_friction: mu_s,
        kinetic_friction: mu_k,
        restitution: e,
    }
}

fn particle(height: f64, gravity: V3, ground: Ground) -> Model {
    let mut p = parts(1);
    p.mass = vec![0.2];
    p.rest_position = vec![V3::new(0.0, 0.0, height)];
    p.gravity = gravity;
    p.ground = Some(ground);
    Model::new(p).unwrap()
}

/// A rigid box of `mass` (eight corner particles), size `s`, resting on z = 0.
fn block(s: V3, mass: f64, gravity: V3, ground: Ground) -> Model {
    let mut p = parts(8);
    p.mass = vec![mass / 8.0; 8];
    p.rest_position = (0..8)
        .map(|k| {
            V3::new(
                if k & 1 == 0 { -0.5 } else { 0.5 } * s.x,
                if k & 2 == 0 { -0.5 } else { 0.5 } * s.y,
                if k & 4 == 0 { 0.0 } else { 1.0 } * s.z,
            )
        })
        .collect();
    p.gravity = gravity;
    p.ground = Some(ground);
    p.rigid = vec![RigidGroup {
        members: (0..8).collect(),
    }];
    Model::new(p).unwrap()
}

fn centre(model: &Model, s: &State) -> V3 {
    model.centre_of_mass(&s.position)
}

#[test]
fn first_impact_and_bounce_heights() {
    let (h0, e, dt) = (1.0, 0.6, 1e-5);
    let model = particle(h0, V3::new(0.0, 0.0, -G), ground(0.5, 0.4, e));
    let mut s = State::at_rest(&model);
    let mut sim = Simulator::new(&model, Integrator::Symplectic);
    let mut first_impact = None;
    let mut peaks = Vec::new();
    let (mut rising, mut top) = (false, 0.0);
    for k in 1..=(3.0 / dt) as usize {
        sim.step(&model, &mut s, dt).unwrap();
        if first_impact.is_none() && sim.contacts_resolved() > 0 {
            first_impact = Some(k as f64 * dt);
        }
        let (z, vz) = (s.position[0].z, s.velocity[0].z);
        if vz > 0.0 {
            rising = true;
            top = z;
        } else if rising {
            rising = false;
            peaks.push(top.max(z));
        }
    }
    let t_impact = (2.0 * h0 / G).sqrt();
    let t = first_impact.unwrap();
    assert!(
        (t - t_impact).abs() <= 2.0 * dt,
        "first impact at {t}, expected {t_impact}"
    );
    assert!(peaks.len() >= 3, "{peaks:?}");
    for (k, peak) in peaks.iter().take(3).enumerate() {
        let expected = e.powi(2 * (k as i32 + 1)) * h0;
        assert!(
            (peak - expected).abs() < 5e-3 * expected,
            "bounce {}: {peak} m, expected {expected} m",
            k + 1
        );
    }
}

#[test]
fn a_sliding_particle_stops_at_v0_squared_over_2_mu_g() {
    let (v0, mu_k, dt) = (3.0, 0.3, 1e-4);
    let model = particle(0.0, V3::new(0.0, 0.0, -G), ground(0.5, mu_k, 0.0));
    let mut s = State::at_rest(&model);
    s.velocity[0] = V3::new(v0 * 0.6, v0 * 0.8, 0.0);
    let mut sim = Simulator::new(&model, Integrator::Symplectic);
    for _ in 0..(2.0 / dt) as usize {
        sim.step(&model, &mut s, dt).unwrap();
    }
    let d = s.position[0].xy().norm();
    let expected = v0 * v0 / (2.0 * mu_k * G);
    assert!(
        s.velocity[0].norm() == 0.0,
        "still moving: {:?}",
        s.velocity[0]
    );
    assert!(
        (d - expected).abs() < 2.0 * v0 * dt,
        "slid {d} m, expected {expected} m"
    );
    // Straight along the initial direction, and on the ground.
    assert!((s.position[0].y / s.position[0].x - 0.8 / 0.6).abs() < 1e-9);
    assert_eq!(s.position[0].z, 0.0);
}

#[test]
fn a_sliding_rigid_block_stops_at_v0_squared_over_2_mu_g() {
    let (v0, mu_k, dt) = (2.0, 0.4, 2e-4);
    let model = block(
        V3::new(0.4, 0.3, 0.1),
        1.0,
        V3::new(0.0, 0.0, -G),
        ground(0.5, mu_k, 0.0),
    );
    let mut s = State::at_rest(&model);
    for v in &mut s.velocity {
        *v = V3::new(v0, 0.0, 0.0);
    }
    let c0 = centre(&model, &s);
    for integrator in [Integrator::Symplectic, Integrator::Verlet] {
        let mut s = s.clone();
        let mut sim = Simulator::new(&model, integrator);
        for _ in 0..(1.5 / dt) as usize {
            sim.step(&model, &mut s, dt).unwrap();
        }
        let c = centre(&model, &s);
        let d = c.x - c0.x;
        let expected = v0 * v0 / (2.0 * mu_k * G);
        let ke = model.rigid[0].kinetic_energy(&s.position, &s.velocity);
        assert!(ke < 1e-12, "{integrator}: still moving, KE {ke:e} J");
        assert!(
            (d - expected).abs() < 0.01 * expected,
            "{integrator}: slid {d} m, expected {expected} m"
        );
        assert!(
            (c.z - c0.z).abs() < 1e-6,
            "{integrator}: sank or rose by {}",
            c.z - c0.z
        );
    }
}

/// Gravity tilted by θ about y is a slope of angle θ.
fn slope(theta: f64) -> V3 {
    V3::new(G * theta.sin(), 0.0, -G * theta.cos())
}

#[test]
fn static_friction_holds_below_the_friction_angle() {
    let (mu_s, mu_k, dt): (f64, f64, f64) = (0.5, 0.35, 1e-3);
    let theta = (0.9 * mu_s).atan();
    for model in [
        particle(0.0, slope(theta), ground(mu_s, mu_k, 0.2)),
        block(
            V3::new(0.3, 0.3, 0.1),
            2.0,
            slope(theta),
            ground(mu_s, mu_k, 0.2),
        ),
    ] {
        let mut s = State::at_rest(&model);
        let c0 = centre(&model, &s);
        let mut sim = Simulator::new(&model, Integrator::Verlet);
        for _ in 0..(2.0 / dt) as usize {
            sim.step(&model, &mut s, dt).unwrap();
        }
        let moved = (centre(&model, &s) - c0).norm();
        assert!(moved < 1e-9, "{} particles: crept {moved:e} m", model.len());
    }
}

#[test]
fn kinetic_friction_above_the_friction_angle() {
    let (mu_s, mu_k, dt, t): (f64, f64, f64, f64) = (0.5, 0.35, 1e-4, 1.0);
    let theta = (1.3 * mu_s).atan();
    let a = G * (theta.sin() - mu_k * theta.cos());
    for model in [
        particle(0.0, slope(theta), ground(mu_s, mu_k, 0.0)),
        block(
            V3::new(0.4, 0.4, 0.05),
            2.0,
            slope(theta),
            ground(mu_s, mu_k, 0.0),
        ),
    ] {
        let mut s = State::at_rest(&model);
        let c0 = centre(&model, &s);
        let mut sim = Simulator::new(&model, Integrator::Symplectic);
        for _ in 0..(t / dt).round() as usize {
            sim.step(&model, &mut s, dt).unwrap();
        }
        let d = centre(&model, &s).x - c0.x;
        let expected = 0.5 * a * t * t;
        assert!(
            (d - expected).abs() < 0.01 * expected,
            "{} particles: slid {d} m, expected {expected} m",
            model.len()
        );
    }
}

/// Rigid bodies touch only the ground, so each one's contact solve is its
/// own: a block sliding to rest moves to the bit as it does alone when a
/// second block lands beside it at the same time, bouncing and tumbling
/// while the first settles. (Solved jointly, the sweeps ran until every
/// body's contacts had converged, so a neighbour changed a body's motion
/// and kept it iterating: 16 plates resting on the ground took 9.5 s to
/// blow along it where they now take 6.0.)
#[test]
fn a_rigid_body_on_the_ground_moves_as_it_does_alone() {
    let g = ground(0.5, 0.4, 0.3);
    let gravity = V3::new(0.0, 0.0, -G);
    let alone = block(V3::new(0.4, 0.3, 0.1), 1.0, gravity, g);
    let other = block(V3::new(0.2, 0.5, 0.3), 0.7, gravity, g);
    let mut p = parts(16);
    p.mass = alone.mass.iter().chain(&other.mass).copied().collect();
    p.rest_position = alone
        .rest_position
        .iter()
        .copied()
        .chain(other.rest_position.iter().map(|x| {
            // Five metres away, tilted, and 2 cm up: it lands, bounces and
            // turns over while the first block slides.
            let turned = nalgebra::Rotation3::from_euler_angles(0.4, 0.3, 0.0) * x;
            turned + V3::new(5.0, 0.0, 0.2)
        }))
        .collect();
    p.gravity = gravity;
    p.ground = Some(g);
    p.rigid = vec![
        RigidGroup {
            members: (0..8).collect(),
        },
        RigidGroup {
            members: (8..16).collect(),
        },
    ];
    let both = Model::new(p).unwrap();
    let dt = 1e-3;
    for integrator in [Integrator::Symplectic, Integrator::Verlet] {
        let mut s1 = State::at_rest(&alone);
        let mut s2 = State::at_rest(&both);
        for (i, v) in s1.velocity.iter_mut().enumerate() {
            *v = V3::new(1.5, 0.2, 0.0);
            s2.velocity[i] = *v;
        }
        let mut sim1 = Simulator::new(&alone, integrator);
        let mut sim2 = Simulator::new(&both, integrator);
        let mut landed = false;
        for _ in 0..800 {
            sim1.step(&alone, &mut s1, dt).unwrap();
            sim2.step(&both, &mut s2, dt).unwrap();
            landed |= (8..16).any(|i| s2.position[i].z < 0.0);
            for i in 0..8 {
                assert_eq!(s1.position[i], s2.position[i], "{integrator}: particle {i}");
                assert_eq!(s1.velocity[i], s2.velocity[i], "{integrator}: particle {i}");
            }
        }
        assert!(
            landed,
            "{integrator}: the second block never touched the ground"
        );
        let moved = (centre(&alone, &s1) - centre(&alone, &State::at_rest(&alone))).x;
        assert!(
            moved > 0.1,
            "{integrator}: the first block slid only {moved} m"
        );
    }
}
