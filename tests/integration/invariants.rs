//! Conservation laws and invariances (docs/design/numerics.md, "Oracles": O4
//! anisotropic, O5, O12, O13) and the force terms' edge cases.

use crate::common::*;
use leafmagic::leaf::LeafSpec;
use leafmagic::physics::field::{Primitive, WindField};
use leafmagic::physics::forces::{self, Forces};
use leafmagic::physics::integrate::{SimError, Simulator, break_limits, break_springs};
use leafmagic::physics::model::{Model, ModelParts, Spring};
use leafmagic::physics::params::Integrator;
use leafmagic::physics::params::TimeStep;
use leafmagic::physics::state::State;
use leafmagic::sim::drop::{DropParams, drop_leaf};

fn momentum(model: &Model, s: &State) -> V3 {
    s.velocity
        .iter()
        .zip(&model.mass)
        .map(|(v, m)| v * *m)
        .sum()
}

fn angular_momentum(model: &Model, s: &State) -> V3 {
    s.position
        .iter()
        .zip(&s.velocity)
        .zip(&model.mass)
        .map(|((x, v), m)| x.cross(&(v * *m)))
        .sum()
}

fn two_body(damping: f64) -> Model {
    let mut p = parts(2);
    p.mass = vec![0.3, 0.7];
    p.rest_position = vec![V3::new(0.0, 0.0, 0.0), V3::new(0.5, 0.1, -0.2)];
    p.springs = vec![Spring {
        i: 0,
        j: 1,
        rest_length: 0.4,
        stiffness: 30.0,
        damping,
        break_strain: None,
    }];
    Model::new(p).unwrap()
}

/// O5: internal forces cancel, so every scheme keeps total momentum to
/// round-off; symplectic Euler and Verlet also keep angular momentum exactly
/// for a central spring without dashpot.
#[test]
fn two_body_momentum_and_angular_momentum() {
    for damping in [0.0, 0.5] {
        let model = two_body(damping);
        for integrator in Integrator::ALL {
            let mut s = State::at_rest(&model);
            s.velocity = vec![V3::new(0.1, 0.4, -0.3), V3::new(-0.2, 0.05, 0.6)];
            let p0 = momentum(&model, &s);
            let l0 = angular_momentum(&model, &s);
            let mut sim = Simulator::new(&model, integrator);
            for _ in 0..2000 {
                sim.step(&model, &mut s, 1e-3).unwrap();
            }
            assert!(
                (momentum(&model, &s) - p0).norm() < 1e-13,
                "{integrator} momentum drifted"
            );
            let drift = (angular_momentum(&model, &s) - l0).norm();
            if damping == 0.0 && matches!(integrator, Integrator::Symplectic | Integrator::Verlet) {
                assert!(
                    drift < 1e-13,
                    "{integrator}: angular momentum drift {drift:e}"
                );
            }
            if integrator == Integrator::Euler {
                assert!(
                    drift > 1e-9,
                    "forward Euler should drift in angular momentum, got {drift:e}"
                );
            }
        }
    }
}

/// O4 (anisotropic): a flat triangle of equal masses translating without
/// rotation relaxes each axis with its own time constant, τₙ = m/(αⁿ A) along
/// the normal and τₜ = m/(αᵗ A) in the plane (each corner carries the full
/// area, see `force::triangle_aero`); forward Euler matches the discrete
/// solution exactly.
#[test]
fn translating_triangle_relaxes_normal_and_tangential_velocity_separately() {
    let (m, an, at) = (1e-4, 0.5, 0.05);
    let model = flat_triangle(m, an, at);
    let area = 0.5 * 0.1 * 0.1;
    let (tau_n, tau_t) = (m / (an * area), m / (at * area));
    let h = 1e-3;
    let v0 = V3::new(0.3, -0.1, 0.8);
    let mut s = State::at_rest(&model);
    s.velocity = vec![v0; 3];
    let mut sim = Simulator::new(&model, Integrator::Euler);
    for n in 1..=300 {
        sim.step(&model, &mut s, h).unwrap();
        let expect = V3::new(
            v0.x * (1.0 - h / tau_t).powi(n),
            v0.y * (1.0 - h / tau_t).powi(n),
            v0.z * (1.0 - h / tau_n).powi(n),
        );
        for v in &s.velocity {
            assert!((v - expect).norm() < 1e-13, "step {n}: {v:?} vs {expect:?}");
        }
    }
}

/// O12: flipping a triangle's winding leaves the aerodynamic force unchanged,
/// because (n·v) n is invariant under n → −n.
#[test]
fn triangle_winding_does_not_change_the_aero_force() {
    let model = flat_triangle(1e-4, 0.5, 0.05);
    let mut flipped_parts = parts(3);
    flipped_parts.mass = model.mass.clone();
    flipped_parts.rest_position = model.rest_position.clone();
    let mut tri = model.triangles[0];
    tri.corners = [0, 2, 1];
    flipped_parts.triangles = vec![tri];
    let flipped = Model::new(flipped_parts).unwrap();
    let x = vec![
        V3::new(0.0, 0.0, 0.01),
        V3::new(0.1, 0.02, 0.0),
        V3::new(0.0, 0.1, -0.03),
    ];
    let v = vec![
        V3::new(0.1, 0.2, -0.5),
        V3::new(0.0, -0.3, 0.4),
        V3::new(0.7, 0.1, 0.0),
    ];
    let mut fa = vec![V3::zeros(); 3];
    let mut fb = vec![V3::zeros(); 3];
    forces::triangle_aero(&model, &x, &v, None, &mut fa);
    forces::triangle_aero(&flipped, &x, &v, None, &mut fb);
    for (a, b) in fa.iter().zip(&fb) {
        assert!(
            (a - b).norm() <= 1e-15 * a.norm().max(1e-12),
            "{a:?} vs {b:?}"
        );
        assert!(a.norm() > 0.0);
    }
}

/// A triangle squeezed flat during a run gets no force, never NaN; zero wind
/// on a resting triangle gives zero force (O12).
#[test]
fn degenerate_triangles_and_still_air_give_zero_force() {
    let model = flat_triangle(1e-4, 0.5, 0.05);
    let collinear = vec![
        V3::new(0.0, 0.0, 0.0),
        V3::new(0.1, 0.0, 0.0),
        V3::new(0.2, 0.0, 0.0),
    ];
    let v = vec![V3::new(0.0, 0.0, -1.0); 3];
    let mut f = vec![V3::zeros(); 3];
    forces::triangle_aero(&model, &collinear, &v, None, &mut f);
    assert!(
        f.iter().all(|x| x.norm() == 0.0),
        "collinear triangle got {f:?}"
    );
    let nearly = vec![
        V3::new(0.0, 0.0, 0.0),
        V3::new(0.1, 0.0, 0.0),
        V3::new(0.2, 1e-200, 0.0),
    ];
    forces::triangle_aero(&model, &nearly, &v, None, &mut f);
    assert!(
        f.iter().all(|x| x.iter().all(|c| c.is_finite())),
        "got {f:?}"
    );
    let mut g = vec![V3::zeros(); 3];
    forces::triangle_aero(
        &model,
        &model.rest_position,
        &[V3::zeros(); 3],
        None,
        &mut g,
    );
    assert!(g.iter().all(|x| x.norm() == 0.0));
}

/// O12 (Galilean): adding U to every velocity and to the wind shifts the
/// trajectory by U t, to round-off.
#[test]
fn galilean_invariance_with_uniform_wind() {
    let spec = LeafSpec::load("a").unwrap();
    let model = spec.model().unwrap();
    let u = V3::new(0.7, -0.4, 0.3);
    let mut moving = spec.clone();
    moving.wind = WindField::new(vec![Primitive::uniform(u)]);
    let moving = moving.model().unwrap();
    let released = |m: &Model| {
        State::released(
            m,
            leafmagic::sim::drop::release_rotation([10.0, 2.0]),
            V3::zeros(),
        )
    };
    let mut a = released(&model);
    let mut b = released(&moving);
    for v in &mut b.velocity {
        *v += u;
    }
    let h = 1.0 / 240.0 / 6.0;
    let mut sa = Simulator::new(&model, Integrator::Verlet);
    let mut sb = Simulator::new(&moving, Integrator::Verlet);
    for _ in 0..1440 {
        sa.step(&model, &mut a, h).unwrap();
        sb.step(&moving, &mut b, h).unwrap();
    }
    let t = a.time;
    for (xa, xb) in a.position.iter().zip(&b.position) {
        assert!((xb - (xa + u * t)).norm() < 1e-11, "{xa:?} + Ut vs {xb:?}");
    }
}

/// Permuting particle indices permutes the result and changes nothing else.
#[test]
fn permuting_particles_gives_the_same_fall() {
    let spec = LeafSpec::load("b").unwrap();
    let n = spec.particles.len();
    let perm: Vec<usize> = (0..n).map(|i| (i * 3 + 5) % n).collect(); // new index of old i
    let mut permuted = spec.clone();
    for (old, p) in spec.particles.iter().enumerate() {
        permuted.particles[perm[old]] = p.clone();
    }
    for s in &mut permuted.springs {
        s.ends = [perm[s.ends[0]], perm[s.ends[1]]];
    }
    for t in &mut permuted.triangles {
        t.corners = t.corners.map(|c| perm[c]);
    }
    for f in &mut permuted.folds {
        f.hinge = f.hinge.map(|c| perm[c]);
        f.moves = f.moves.iter().map(|&c| perm[c]).collect();
    }
    let params = DropParams {
        seconds: 1.0,
        record_particles: true,
        ..Default::default()
    };
    let a = drop_leaf(&spec.model().unwrap(), &params).unwrap();
    let b = drop_leaf(&permuted.model().unwrap(), &params).unwrap();
    let (pa, pb) = (a.particles.unwrap(), b.particles.unwrap());
    for (fa, fb) in pa.iter().zip(&pb) {
        for old in 0..n {
            assert!(
                (fa[old] - fb[perm[old]]).norm() < 1e-12,
                "particle {old} differs"
            );
        }
    }
}

/// O13: a spring pulled at constant speed s breaks at the first step after
/// t_b = L ε_b / s, and exerts no force from then on.
#[test]
fn spring_breaks_at_the_predicted_step_and_stops_acting() {
    let (rest, strain, speed, h) = (0.2, 0.1, 0.3, 1e-3);
    let mut p: ModelParts = parts(2);
    p.fixed = vec![true, true]; // both ends kinematic: one still, one moving at constant speed
    p.rest_position = vec![V3::zeros(), V3::new(rest, 0.0, 0.0)];
    p.springs = vec![Spring {
        i: 0,
        j: 1,
        rest_length: rest,
        stiffness: 5.0,
        damping: 0.0,
        break_strain: Some(strain),
    }];
    let model = Model::new(p).unwrap();
    let mut s = State::at_rest(&model);
    s.velocity[1] = V3::new(speed, 0.0, 0.0);
    let t_break = rest * strain / speed;
    let expected_step = (t_break / h).ceil() as usize; // 1-based count of steps taken
    let mut sim = Simulator::new(&model, Integrator::Symplectic);
    let mut broke_at = None;
    for n in 1..=200 {
        sim.step(&model, &mut s, h).unwrap();
        if broke_at.is_none() && !s.spring_alive[0] {
            broke_at = Some(n);
        }
    }
    assert_eq!(broke_at, Some(expected_step));
    let mut f = vec![V3::zeros(); 2];
    forces::springs(&model, &s.position, &s.velocity, &s.spring_alive, &mut f);
    assert!(f.iter().all(|x| x.norm() == 0.0));
    // A broken spring never heals, even back at its rest length.
    s.position[1] = V3::new(rest, 0.0, 0.0);
    assert_eq!(break_springs(&model, &mut s, &break_limits(&model)), 0);
    assert!(!s.spring_alive[0]);
}

/// A step far beyond the stability limit stops with an error naming the
/// step, the particle and the likely cause, instead of returning NaN.
#[test]
fn divergence_is_reported_with_its_cause() {
    let model = LeafSpec::load("a").unwrap().model().unwrap();
    let est = leafmagic::physics::stability::estimate(&model);
    let limit = est.dt_max(Integrator::Symplectic).unwrap();
    let h = 3.0 * limit;
    let mut s = State::released(
        &model,
        leafmagic::sim::drop::release_rotation([10.0, 2.0]),
        V3::zeros(),
    );
    let mut sim = Simulator::new(&model, Integrator::Symplectic);
    let err = (0..100_000)
        .find_map(|_| sim.step(&model, &mut s, h).err())
        .expect("must diverge");
    let SimError::Diverged(d) = &err else {
        panic!("unexpected {err}")
    };
    assert!(d.particle < model.len());
    assert_eq!(d.dt_max, Some(limit));
    let msg = err.to_string();
    for needle in [
        "step",
        "particle",
        "dt_max",
        "too large for the stiffness",
        "spring",
    ] {
        assert!(msg.contains(needle), "message lacks '{needle}': {msg}");
    }
    // With auto dt the same leaf is fine.
    let ok = drop_leaf(
        &model,
        &DropParams {
            seconds: 2.0,
            dt: TimeStep::Auto,
            ..Default::default()
        },
    );
    assert!(ok.is_ok());
}

/// The per-source breakdown adds up to the total force.
#[test]
fn force_terms_sum_to_the_total() {
    let spec = LeafSpec::load("a").unwrap();
    let mut spec_wind = spec.clone();
    spec_wind.wind = WindField::new(vec![Primitive::uniform(V3::new(0.5, 0.0, 0.2))]);
    let model = spec_wind.model().unwrap();
    let mut s = State::released(
        &model,
        leafmagic::sim::drop::release_rotation([30.0, 5.0]),
        V3::zeros(),
    );
    s.velocity
        .iter_mut()
        .enumerate()
        .for_each(|(i, v)| *v = V3::new(0.01 * i as f64, -0.2, 0.1));
    let mut forces = Forces::new(&model);
    let mut total = vec![V3::zeros(); model.len()];
    forces.total(
        &model,
        &s.position,
        &s.velocity,
        &s.spring_alive,
        0.0,
        &mut total,
    );
    for (p, total_p) in total.iter().enumerate() {
        let t = forces.terms_on(&model, &s.position, &s.velocity, &s.spring_alive, 0.0, p);
        let sum = t.gravity + t.spring + t.bending + t.aero + t.drag;
        assert!((sum - total_p).norm() < 1e-15 + 1e-12 * total_p.norm());
    }
}

/// A diagnosis never prints NaN: non-finite magnitudes are said in words.
#[test]
fn diagnoses_say_non_finite_in_words() {
    let diverged = SimError::Diverged(Box::new(leafmagic::physics::integrate::Divergence {
        step: 3,
        time: 0.01,
        particle: 2,
        quantity: "position",
        value: f64::NAN,
        integrator: Integrator::Euler,
        dt: 1e-3,
        dt_max: Some(1e-4),
        dominant_force: ("spring", f64::INFINITY),
        stiffest_spring: Some(0),
    }));
    let failed = SimError::SolverFailed {
        step: 7,
        time: 0.5,
        iterations: 12,
        residual: f64::NAN,
    };
    for e in [diverged, failed] {
        let msg = e.to_string();
        for word in msg.split(|c: char| !c.is_ascii_alphanumeric()) {
            assert!(
                !word.eq_ignore_ascii_case("nan") && !word.eq_ignore_ascii_case("inf"),
                "{msg}"
            );
        }
        assert!(msg.contains("step"), "{msg}");
    }
}
