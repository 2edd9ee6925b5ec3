//! A triangle whose edge spring has broken is no longer a surface: it feels
//! no wind, while intact triangles keep their exact eq. 9–10 force.

use crate::common::{V3, parts};
use leafmagic::physics::field::{Primitive, WindField};
use leafmagic::physics::forces::{Forces, triangle_aero};
use leafmagic::physics::integrate::Simulator;
use leafmagic::physics::model::{Hinge, Model, Spring, Triangle};
use leafmagic::physics::params::Integrator;
use leafmagic::physics::state::State;

/// Two triangles sharing edge 1–2, every edge a spring; the spring 0–1 of
/// the first triangle breaks at 5 % strain.
fn kite() -> Model {
    let mut p = parts(4);
    p.mass = vec![1e-3; 4];
    p.rest_position = vec![
        V3::new(0.0, 0.0, 0.0),
        V3::new(0.1, 0.0, 0.0),
        V3::new(0.0, 0.1, 0.0),
        V3::new(0.1, 0.1, 0.0),
    ];
    let edges = [(0, 1), (1, 2), (2, 0), (1, 3), (3, 2)];
    p.springs = edges
        .iter()
        .map(|&(i, j)| Spring {
            i,
            j,
            rest_length: (p.rest_position[i] - p.rest_position[j]).norm(),
            stiffness: 50.0,
            damping: 0.0,
            break_strain: ((i, j) == (0, 1)).then_some(0.05),
        })
        .collect();
    p.triangles = vec![
        Triangle {
            corners: [0, 1, 2],
            alpha_n: 1.0,
            alpha_t: 0.1,
        },
        Triangle {
            corners: [1, 3, 2],
            alpha_n: 1.0,
            alpha_t: 0.1,
        },
    ];
    p.wind = WindField::new(vec![Primitive::uniform(V3::new(0.3, 0.2, 5.0))]);
    Model::new(p).unwrap()
}

#[test]
fn a_torn_triangle_feels_no_wind() {
    let model = kite();
    let mut s = State::at_rest(&model);
    // Pull particle 0 away so spring 0-1 breaks on the first step.
    s.position[0].x = -0.01;
    let mut sim = Simulator::new(&model, Integrator::Symplectic);
    sim.step(&model, &mut s, 1e-5).unwrap();
    assert_eq!(s.spring_alive, vec![false, true, true, true, true]);
    // The force the simulator now applies equals gravity-free springs plus
    // the aero of the intact triangle alone.
    let mut forces = Forces::new(&model);
    forces.tear(&s.spring_alive);
    assert_eq!(forces.torn().triangles, [true, false]);
    let mut total = vec![V3::zeros(); 4];
    forces.total(
        &model,
        &s.position,
        &s.velocity,
        &s.spring_alive,
        s.time,
        &mut total,
    );
    let mut intact = model.clone();
    intact.triangles.remove(0);
    let wind: Vec<V3> = s
        .position
        .iter()
        .map(|x| model.wind.velocity(x, s.time))
        .collect();
    let mut expected = vec![V3::zeros(); 4];
    leafmagic::physics::forces::springs(
        &model,
        &s.position,
        &s.velocity,
        &s.spring_alive,
        &mut expected,
    );
    triangle_aero(
        &intact,
        &s.position,
        &s.velocity,
        Some(&wind),
        &mut expected,
    );
    assert_eq!(total, expected);
    // Particle 0 now belongs to no intact surface: only its spring 2-0 acts.
    let mut spring_only = vec![V3::zeros(); 4];
    leafmagic::physics::forces::springs(
        &model,
        &s.position,
        &s.velocity,
        &s.spring_alive,
        &mut spring_only,
    );
    assert_eq!(total[0], spring_only[0]);
    assert!(
        total[3] != spring_only[3],
        "the intact triangle still feels the wind"
    );
}

/// The kite with a bending hinge along its shared edge 1–2 (apexes 0 and
/// 3), folded at rest by 0.4 rad and stiff enough to matter.
fn hinged_kite() -> Model {
    let plain = kite();
    let mut p = parts(4);
    p.mass = plain.mass.clone();
    p.rest_position = plain.rest_position.clone();
    p.springs = plain.springs.clone();
    p.triangles = plain.triangles.clone();
    p.wind = plain.wind.clone();
    p.hinges = vec![Hinge {
        edge: [1, 2],
        apexes: [0, 3],
        rest_angle: 0.4,
        stiffness: 2e-3,
        damping: 1e-5,
    }];
    Model::new(p).unwrap()
}

/// A hinge bends two wings against each other; once a spring along a wing
/// has broken that wing is torn, and the hinge acts no more. Oracle: from a
/// state whose spring 0–1 is broken, the hinged kite moves exactly as the
/// kite without the hinge, under every integrator, while with the spring
/// intact the hinge changes the motion.
#[test]
fn a_hinge_with_a_torn_wing_bends_no_more() {
    let hinged = hinged_kite();
    let plain = kite();
    let fall = |model: &Model, integrator: Integrator, broken: bool| {
        let mut s = State::at_rest(model);
        s.spring_alive[0] = !broken;
        let mut sim = Simulator::new(model, integrator);
        for _ in 0..200 {
            sim.step(model, &mut s, 1e-4).unwrap();
        }
        s
    };
    for integrator in Integrator::ALL {
        let torn = fall(&hinged, integrator, true);
        assert!(!torn.spring_alive[0]);
        assert_eq!(
            torn.position,
            fall(&plain, integrator, true).position,
            "{integrator}: the torn hinge still acts"
        );
        let intact = fall(&hinged, integrator, false);
        assert!(
            intact.spring_alive[0],
            "{integrator}: the spring should hold"
        );
        assert_ne!(
            intact.position,
            fall(&plain, integrator, false).position,
            "{integrator}: the intact hinge should act"
        );
    }
    let mut forces = Forces::new(&hinged);
    let mut alive = vec![true; 5];
    forces.tear(&alive);
    assert_eq!(forces.torn().hinges, Vec::<bool>::new());
    alive[4] = false; // 3–2: on the other wing
    forces.tear(&alive);
    assert_eq!(forces.torn().hinges, [true]);
    assert_eq!(forces.torn().triangles, [false, true]);
}
