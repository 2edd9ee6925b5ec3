//! The settings that define a breeding run, as written to `run.toml`.

use crate::leaf::genome::Genome;
use crate::motion::classify::MotionClass;
use crate::motion::describe::MotionTarget;
use crate::util::setting::Setting;
use serde::{Deserialize, Serialize};

/// Release attitudes per individual by default: the 4, enough for a
/// median to ignore one lucky (or unlucky) drop.
pub const DEFAULT_RELEASES: usize = 4;
/// Most release attitudes per individual (each is a drop).
pub const MAX_RELEASES: usize = 64;

/// Everything that defines a breeding run (written to `run.toml`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BreedSettings {
    /// Prototype name as given (`a`, `b` or a path).
    pub prototype: String,
    /// The aerodynamic law the prototype and its variants fall under
    /// ([`crate::leaf::LeafSpec::under_law`]); absent, the prototype file's
    /// own. `run.toml`'s `prototype_leaf` is the prototype under it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub law: Option<crate::leaf::AeroLawName>,
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
    /// Release attitudes each individual is dropped from (`--releases`):
    /// its score is the lower median of their scores
    /// ([`super::robust`]). A run written before robust fitness has 1.
    #[serde(default = "one_release")]
    pub releases: usize,
    /// Who breeds the children ([`super::strategy`]); a run written before
    /// strategies is the GA.
    #[serde(default = "ga")]
    pub strategy: Strategy,
    /// Generation 0 is half uniform draws over the bounds
    /// ([`super::selection::INITIAL_COPY_SHARE`]); false in a run written
    /// before them, whose generation 0 is all copies of the prototype.
    #[serde(default)]
    pub uniform_start: bool,
    /// Leaves of an earlier run of the same prototype (`--start-from`: its
    /// archive, or its last generation ranked) that take the first places
    /// of generation 0's copies of the prototype ([`super::selection::plan`]). Empty
    /// for a run started from the prototype alone.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub start: Vec<Genome>,
    /// Toward a class, leaves that hold it robustly are scored by how
    /// differently they fall from the others ([`super::novelty`], issue
    /// 60); false in a run written before it, whose scores saturate at 2.
    #[serde(default)]
    pub novelty: bool,
}

/// The strategy of a run whose run.toml predates `--strategy`.
fn ga() -> Strategy {
    Strategy::Ga
}

/// The releases of a run whose run.toml predates `--releases`.
fn one_release() -> usize {
    1
}

impl BreedSettings {
    /// The embedded default: prototype A, floaters, 100 × 8 generations of
    /// 10 s falls, seed 1991 (the year of the paper).
    pub fn default_run() -> BreedSettings {
        BreedSettings {
            prototype: "a".to_string(),
            law: None,
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
            releases: DEFAULT_RELEASES,
            strategy: Strategy::Hybrid,
            uniform_start: true,
            start: Vec::new(),
            novelty: true,
        }
    }

    /// Checks the settings, naming the bad one.
    pub fn validate(&self) -> Result<(), SettingsError> {
        if self.population < 2 {
            return Err(SettingsError(format!(
                "{} must be at least 2, got {}",
                Setting::Population,
                self.population
            )));
        }
        if self.generations == 0 {
            return Err(SettingsError(format!(
                "{} must be at least 1",
                Setting::Generations
            )));
        }
        if self.target == MotionClass::Undetermined {
            return Err(SettingsError(format!(
                "{} must be floater, spinner or lilter",
                Setting::Target
            )));
        }
        if !(self.seconds > 0.0 && self.seconds.is_finite()) {
            return Err(SettingsError(format!(
                "{} must be a positive number, got {}",
                Setting::Duration,
                self.seconds
            )));
        }
        if !(self.initial_scale > 0.0 && self.initial_scale.is_finite()) {
            return Err(SettingsError(format!(
                "{} must be a positive number, got {}",
                Setting::InitialScale,
                self.initial_scale
            )));
        }
        if self.elites >= self.population {
            return Err(SettingsError(format!(
                "elites ({}) must be fewer than the population ({})",
                self.elites, self.population
            )));
        }
        if self.releases == 0 {
            return Err(SettingsError(format!(
                "{} must be at least 1 (each leaf is dropped from that many release \
                 attitudes and scored on their median; the default is 4)",
                Setting::Releases
            )));
        }
        if self.releases > MAX_RELEASES {
            return Err(SettingsError(format!(
                "{} must be at most {MAX_RELEASES}, got {} (every release is one more \
                 drop of every leaf)",
                Setting::Releases,
                self.releases
            )));
        }
        if self.tournament == 0 {
            return Err(SettingsError(
                "the tournament size must be at least 1".to_string(),
            ));
        }
        if !self.start.is_empty() && self.strategy == Strategy::Random {
            return Err(SettingsError(format!(
                "{} cannot be used with {}: random search draws every leaf uniformly over the \
                 bounds, it starts from nothing",
                Setting::StartFrom,
                Setting::Strategy.set("random")
            )));
        }
        Ok(())
    }
}

/// How a run breeds its children ([`super::strategy`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Strategy {
    /// The genetic algorithm alone (what runs before issue 19 did).
    Ga,
    /// CMA-ES alone from generation 1, started at generation 0's best.
    Cmaes,
    /// The GA until the target class is found, then mostly CMA-ES.
    Hybrid,
    /// Random search, the baseline of the benchmark: every child a uniform
    /// draw over the bounds.
    Random,
}

impl Strategy {
    /// The names, as `--strategy` takes them.
    pub const NAMES: [&'static str; 4] = ["ga", "cmaes", "hybrid", "random"];

    /// The name.
    pub fn as_str(self) -> &'static str {
        match self {
            Strategy::Ga => "ga",
            Strategy::Cmaes => "cmaes",
            Strategy::Hybrid => "hybrid",
            Strategy::Random => "random",
        }
    }
}

impl std::fmt::Display for Strategy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A strategy's name that names none.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{strategy}: unknown strategy '{name}'; known: ga, cmaes, hybrid, random", strategy = Setting::Strategy, name = .0)]
pub struct UnknownStrategy(pub String);

impl std::str::FromStr for Strategy {
    type Err = UnknownStrategy;
    fn from_str(s: &str) -> Result<Strategy, UnknownStrategy> {
        match s {
            "ga" => Ok(Strategy::Ga),
            "cmaes" => Ok(Strategy::Cmaes),
            "hybrid" => Ok(Strategy::Hybrid),
            "random" => Ok(Strategy::Random),
            other => Err(UnknownStrategy(other.to_string())),
        }
    }
}

/// Settings that define no run: names the setting and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct SettingsError(pub String);
