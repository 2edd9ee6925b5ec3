//! Which force terms and passes a model needs: the scene compiler's decision,
//! made once per model and obeyed by the force path ([`crate::physics::forces::Forces`])
//! and the stepper ([`crate::physics::integrate::Simulator`]).
//!
//! [`Terms::needed`] keeps a term only if the model holds something it acts
//! on: no wind evaluation in still air (or when nothing feels the wind), no
//! contact pass without ground, no breaking checks without breakable springs,
//! no rigid-body pass without rigid bodies. A term left out is not evaluated
//! at all, so it costs nothing; a term kept on a model that gives it nothing
//! to do ([`Terms::all`]) costs its loop and adds exact zeros. Every run,
//! `drop` included, goes through this one decision.

use crate::physics::model::Model;
use crate::physics::params::Integrator;

/// The force terms and passes of one run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Terms {
    /// m g on every particle.
    pub gravity: bool,
    /// Springs with dashpots.
    pub springs: bool,
    /// Bending hinges.
    pub hinges: bool,
    /// Per-triangle aerodynamics (eq. 6–10).
    pub aero: bool,
    /// Sampling the wind field G(x, t) at every particle (else still air).
    pub wind: bool,
    /// Linear drag on particles (eq. 7).
    pub particle_drag: bool,
    /// Rigid-body accelerations and the after-step projection.
    pub rigid: bool,
    /// The after-step ground contact pass.
    pub contact: bool,
    /// The after-step spring breaking check.
    pub breaking: bool,
}

/// One line of [`Terms::explain`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Decision {
    /// What was decided about.
    pub name: &'static str,
    /// Whether it is kept (evaluated) in the run.
    pub kept: bool,
    /// Why, with the numbers behind it.
    pub reason: String,
}

impl Terms {
    /// Every term on (a model that gives some of them nothing to do still
    /// runs their loops): the baseline the compiler is measured against.
    pub fn all() -> Terms {
        Terms {
            gravity: true,
            springs: true,
            hinges: true,
            aero: true,
            wind: true,
            particle_drag: true,
            rigid: true,
            contact: true,
            breaking: true,
        }
    }

    /// Only the terms `model` can feel.
    pub fn needed(model: &Model) -> Terms {
        let aero = !model.triangles.is_empty();
        let particle_drag = model.particle_drag.iter().any(|&a| a != 0.0);
        Terms {
            gravity: model.gravity.iter().any(|&g| g != 0.0),
            springs: !model.springs.is_empty(),
            hinges: !model.hinges.is_empty(),
            aero,
            wind: !model.wind.is_still() && (aero || particle_drag),
            particle_drag,
            rigid: !model.rigid.is_empty(),
            contact: model.ground.is_some(),
            breaking: model.springs.iter().any(|s| s.break_strain.is_some()),
        }
    }

    /// What is kept and what is left out for `model` stepped by `integrator`,
    /// and why.
    pub fn explain(&self, model: &Model, integrator: Integrator) -> Vec<Decision> {
        let n = model.len();
        let count = |k: usize, what: &str| format!("{k} {what}");
        let breakable = model
            .springs
            .iter()
            .filter(|s| s.break_strain.is_some())
            .count();
        let dragged = model.particle_drag.iter().filter(|&&a| a != 0.0).count();
        let g = model.gravity;
        let mut out = vec![
            Decision {
                name: "gravity",
                kept: self.gravity,
                reason: format!("g = ({}, {}, {}) m/s²", g.x, g.y, g.z),
            },
            Decision {
                name: "springs",
                kept: self.springs,
                reason: count(model.springs.len(), "springs"),
            },
            Decision {
                name: "bending hinges",
                kept: self.hinges,
                reason: count(model.hinges.len(), "hinges"),
            },
            Decision {
                name: "triangle aerodynamics",
                kept: self.aero,
                // The paper's law, the default, goes without saying.
                reason: if model.aero == crate::physics::model::AeroLaw::default() {
                    count(model.triangles.len(), "triangles")
                } else {
                    format!(
                        "{}, {} law",
                        count(model.triangles.len(), "triangles"),
                        model.aero.name()
                    )
                },
            },
            Decision {
                name: "wind evaluation",
                kept: self.wind,
                reason: if model.wind.is_still() {
                    "still air: no wind primitive".to_string()
                } else if !self.aero && !self.particle_drag {
                    format!(
                        "{} primitives, but nothing feels the wind (no triangles, no particle drag)",
                        model.wind.primitives().len()
                    )
                } else {
                    format!(
                        "{} primitives sampled at {n} particles per force evaluation",
                        model.wind.primitives().len()
                    )
                },
            },
            Decision {
                name: "particle drag",
                kept: self.particle_drag,
                reason: format!("{dragged} of {n} particles have eq. 7 drag"),
            },
            Decision {
                name: "rigid bodies",
                kept: self.rigid,
                reason: format!(
                    "{} bodies, {} member particles",
                    model.rigid.len(),
                    model.rigid.iter().map(|b| b.members.len()).sum::<usize>()
                ),
            },
            Decision {
                name: "ground contact",
                kept: self.contact,
                reason: match model.ground {
                    Some(gr) => format!(
                        "plane z = {} m, μ_s = {}, μ_k = {}, e = {}",
                        gr.height, gr.static_friction, gr.kinetic_friction, gr.restitution
                    ),
                    None => "no ground".to_string(),
                },
            },
            Decision {
                name: "spring breaking",
                kept: self.breaking,
                reason: count(breakable, "breakable springs"),
            },
        ];
        for (name, used) in [
            ("rk4 stage buffers", integrator == Integrator::Rk4),
            (
                "verlet carried acceleration",
                integrator == Integrator::Verlet,
            ),
            (
                "implicit solver (CG) scratch",
                integrator == Integrator::Implicit,
            ),
        ] {
            out.push(Decision {
                name,
                kept: used,
                reason: format!("integrator {integrator}"),
            });
        }
        out
    }
}
