//! The mutable part of a simulation: positions, velocities, which springs
//! still hold, and time. Structure of arrays, indices shared with the model.

use crate::physics::model::Model;
use nalgebra::{UnitQuaternion, Vector3};

/// Everything that changes during a run.
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    /// Particle positions, m.
    pub position: Vec<Vector3<f64>>,
    /// Particle velocities, m/s.
    pub velocity: Vec<Vector3<f64>>,
    /// `false` once a spring has broken; its index stays valid.
    pub spring_alive: Vec<bool>,
    /// Simulated time, s.
    pub time: f64,
}

impl State {
    /// The model's rest shape, at rest, all springs intact, at t = 0.
    pub fn at_rest(model: &Model) -> State {
        State {
            position: model.rest_position.clone(),
            velocity: vec![Vector3::zeros(); model.len()],
            spring_alive: vec![true; model.springs.len()],
            time: 0.0,
        }
    }

    /// The rest shape turned by `rotation` about its centre of mass and then
    /// moved so that the centre of mass sits at `centre`; at rest.
    pub fn released(model: &Model, rotation: UnitQuaternion<f64>, centre: Vector3<f64>) -> State {
        let com = model.centre_of_mass(&model.rest_position);
        let mut state = State::at_rest(model);
        for x in &mut state.position {
            *x = centre + rotation * (*x - com);
        }
        state
    }

    /// Number of springs that have broken so far.
    pub fn broken_springs(&self) -> usize {
        self.spring_alive.iter().filter(|a| !**a).count()
    }
}
