//! The settings that define a breeding run, as written to `run.toml`.

use crate::motion::classify::MotionClass;
use crate::motion::describe::MotionTarget;
use serde::{Deserialize, Serialize};

/// Everything that defines a breeding run (written to `run.toml`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BreedSettings {
    /// Prototype name as given (`a`, `b` or a path).
    pub prototype: String,
    /// The motion class bred for.
    pub target: MotionClass,
    /// Individuals per generation.
    pub population: usize,
    /// Generations in all, numbered from 0: generation 0 is the prototype's
    /// copies, each later one is bred from the one before.
    pub generations: usize,
    /// Seed of every random stream.
    pub seed: u64,
    /// Simulated seconds of each drop.
    pub seconds: f64,
    /// Variation scale of generation 0 (the paper's first round).
    pub initial_scale: f64,
    /// Individuals copied unchanged into the next generation.
    pub elites: usize,
    /// Tournament size for parent selection.
    pub tournament: usize,
    /// Keep a MAP-Elites archive: the best leaf of every cell of descent
    /// speed × rotation rate seen over the whole run.
    #[serde(default)]
    pub archive: bool,
    /// Breed toward motion descriptors (`--like`, `--target-features`)
    /// instead of toward the class alone; see [`crate::motion::describe`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub like: Option<MotionTarget>,
}

impl BreedSettings {
    /// The embedded default: prototype A, floaters, 100 × 8 generations of
    /// 10 s falls, seed 1991 (the year of the paper).
    pub fn default_run() -> BreedSettings {
        BreedSettings {
            prototype: "a".to_string(),
            target: MotionClass::Floater,
            population: 100,
            generations: 8,
            seed: 1991,
            seconds: 10.0,
            initial_scale: 1.0,
            elites: 10,
            tournament: 3,
            archive: false,
            like: None,
        }
    }

    /// Checks the settings, naming the bad one.
    pub fn validate(&self) -> Result<(), SettingsError> {
        if self.population < 2 {
            return Err(SettingsError(format!(
                "--population must be at least 2, got {}",
                self.population
            )));
        }
        if self.generations == 0 {
            return Err(SettingsError(
                "--generations must be at least 1".to_string(),
            ));
        }
        if self.target == MotionClass::Undetermined {
            return Err(SettingsError(
                "--target must be floater, spinner or lilter".to_string(),
            ));
        }
        if !(self.seconds > 0.0 && self.seconds.is_finite()) {
            return Err(SettingsError(format!(
                "--seconds must be a positive number, got {}",
                self.seconds
            )));
        }
        if !(self.initial_scale > 0.0 && self.initial_scale.is_finite()) {
            return Err(SettingsError(format!(
                "the initial scale must be positive, got {}",
                self.initial_scale
            )));
        }
        if self.elites >= self.population {
            return Err(SettingsError(format!(
                "elites ({}) must be fewer than the population ({})",
                self.elites, self.population
            )));
        }
        if self.tournament == 0 {
            return Err(SettingsError(
                "the tournament size must be at least 1".to_string(),
            ));
        }
        Ok(())
    }
}

/// Settings that define no run: names the setting and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct SettingsError(pub String);
