//! Which aerodynamic law a model's triangles obey, as the model holds it:
//! the law's name and coefficients, read from a leaf file's keys and
//! validated by the law itself. Data only (the model imports this file), so
//! it reaches each law's `coefficients` file and nothing of the engine; the
//! law's forces, rate bounds and cost dispatch from [`crate::physics::aero`].

use super::keys::{AeroKeys, Key};
use super::linear::coefficients as linear;
use super::quadratic::coefficients::QuadraticAero;
use super::unsteady::coefficients::UnsteadyAero;
use crate::physics::model::error::ModelError;
use serde::{Deserialize, Serialize};

/// Which aerodynamic law turns relative wind into force on triangles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AeroLaw {
    /// The paper's linear law, eq. 9–10: F = αⁿ A vⁿ + αᵗ A vᵗ at each corner
    /// ([`crate::physics::aero::linear`]); α is each triangle's.
    #[default]
    Linear,
    /// Quadratic drag with lift and a moving centre of pressure, per
    /// triangle ([`crate::physics::aero::quadratic`]); the triangles' α must then be 0.
    Quadratic(QuadraticAero),
    /// Unsteady thin-plate aerodynamics per triangle: added mass with its
    /// fluid impulse, translational and rotational circulation, rotational
    /// damping, drag by angle of attack with skin friction
    /// ([`crate::physics::aero::unsteady`]); the triangles' α must be 0.
    Unsteady(UnsteadyAero),
}

impl AeroLaw {
    /// The name leaf and scene files give the law (`[aero] law = "..."`).
    pub fn name(&self) -> &'static str {
        self.law_name().as_str()
    }

    /// The law's name as a value.
    pub fn law_name(&self) -> AeroLawName {
        match self {
            AeroLaw::Linear => AeroLawName::Linear,
            AeroLaw::Quadratic(_) => AeroLawName::Quadratic,
            AeroLaw::Unsteady(_) => AeroLawName::Unsteady,
        }
    }

    /// Every coefficient finite and in its physical range, as the law
    /// itself judges it; errors name the field as `aero.<name>`.
    pub fn validate(&self) -> Result<(), ModelError> {
        match self {
            AeroLaw::Linear => Ok(()),
            AeroLaw::Quadratic(law) => law.validate(),
            AeroLaw::Unsteady(law) => law.validate(),
        }
    }

    /// Whether the law's force is each triangle's αⁿ, αᵗ (the other laws
    /// replace them, and then leftover α must be 0).
    pub fn uses_triangle_alpha(&self) -> bool {
        matches!(self, AeroLaw::Linear)
    }

    /// Whether the law needs each plate's measured geometry (chords, added
    /// mass; [`crate::physics::model::SurfaceGeometry`]).
    pub fn needs_surface_geometry(&self) -> bool {
        matches!(self, AeroLaw::Unsteady(_))
    }

    /// Whether the law adds mass (a tensor per particle that Newton's law
    /// solves with: [`crate::physics::forces::Forces::acceleration`]).
    pub fn adds_mass(&self) -> bool {
        matches!(self, AeroLaw::Unsteady(_))
    }

    /// Law `name` with the coefficients `keys` set and every other one at
    /// its default. A key of another law is refused by name, as is a
    /// required key left out; ranges are [`AeroLaw::validate`]'s (the model
    /// calls it).
    pub fn from_keys(name: AeroLawName, keys: &AeroKeys) -> Result<AeroLaw, ModelError> {
        let own = name.keys();
        for (key, _) in keys.iter() {
            if !own.iter().any(|k| k.name == key.name) {
                let owners: Vec<String> = AeroLawName::ALL
                    .iter()
                    .filter(|l| l.keys().iter().any(|k| k.name == key.name))
                    .map(|l| format!("\"{}\"", l.as_str()))
                    .collect();
                let takes: Vec<&str> = own.iter().map(|k| k.name).collect();
                return Err(ModelError {
                    item: format!("aero.{}", key.name),
                    reason: format!(
                        "not used by law = \"{}\" (remove it): it belongs to law = {}; law = \"{}\" takes {}",
                        name.as_str(),
                        owners.join(" or "),
                        name.as_str(),
                        takes.join(", ")
                    ),
                });
            }
        }
        Ok(match name {
            AeroLawName::Linear => {
                linear::check_required(keys)?;
                AeroLaw::Linear
            }
            AeroLawName::Quadratic => AeroLaw::Quadratic(QuadraticAero::from_keys(keys)),
            AeroLawName::Unsteady => AeroLaw::Unsteady(UnsteadyAero::from_keys(keys)),
        })
    }
}

/// The name of an aerodynamic law in a leaf file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AeroLawName {
    /// The paper's linear law, eq. 9–10.
    #[default]
    Linear,
    /// Quadratic drag with lift and a moving centre of pressure.
    Quadratic,
    /// Added mass, translational and rotational circulation, rotational
    /// damping, drag by angle of attack and skin friction.
    Unsteady,
}

impl AeroLawName {
    /// Every law, in the order leaf files list their keys.
    pub const ALL: [AeroLawName; 3] = [
        AeroLawName::Linear,
        AeroLawName::Quadratic,
        AeroLawName::Unsteady,
    ];

    /// The name as leaf files write it.
    pub fn as_str(self) -> &'static str {
        match self {
            AeroLawName::Linear => "linear",
            AeroLawName::Quadratic => "quadratic",
            AeroLawName::Unsteady => "unsteady",
        }
    }

    /// The `[aero]` keys the law reads (besides `law`), as its own
    /// coefficients file declares them.
    pub fn keys(self) -> &'static [Key] {
        match self {
            AeroLawName::Linear => linear::KEYS,
            AeroLawName::Quadratic => QuadraticAero::KEYS,
            AeroLawName::Unsteady => UnsteadyAero::KEYS,
        }
    }
}

impl std::str::FromStr for AeroLawName {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        AeroLawName::ALL
            .into_iter()
            .find(|l| l.as_str() == s)
            .ok_or_else(|| {
                format!("unknown aerodynamic law '{s}': expected linear, quadratic or unsteady")
            })
    }
}

/// Every key of every law once, in the order leaf files write them: the
/// laws in [`AeroLawName::ALL`] order, each law's keys in its own order, a
/// key two laws share where it first appears.
pub fn all_keys() -> &'static [Key] {
    static ALL: std::sync::LazyLock<Vec<Key>> = std::sync::LazyLock::new(|| {
        let mut all: Vec<Key> = Vec::new();
        for law in AeroLawName::ALL {
            for key in law.keys() {
                if !all.iter().any(|k| k.name == key.name) {
                    all.push(*key);
                }
            }
        }
        all
    });
    &ALL
}

/// `law` and the names of [`all_keys`]: what an `[aero]` table may hold
/// (serde lists them for an unknown key).
pub fn all_names() -> &'static [&'static str] {
    static NAMES: std::sync::LazyLock<Vec<&'static str>> = std::sync::LazyLock::new(|| {
        std::iter::once("law")
            .chain(all_keys().iter().map(|k| k.name))
            .collect()
    });
    &NAMES
}

/// The key named `name`, of any law.
pub fn key(name: &str) -> Option<Key> {
    all_keys().iter().find(|k| k.name == name).copied()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::aero::keys::{KeyKind, KeyValue};

    /// Every key a law declares is read into its coefficients: set alone,
    /// each one moves them off the defaults (a key declared but not read
    /// would be accepted and ignored).
    #[test]
    fn every_declared_key_reaches_the_coefficients() {
        for name in [AeroLawName::Quadratic, AeroLawName::Unsteady] {
            let defaults = AeroLaw::from_keys(name, &AeroKeys::default()).unwrap();
            for key in name.keys() {
                let mut keys = AeroKeys::default();
                let value = match key.kind {
                    KeyKind::Number => KeyValue::Number(0.123_456),
                    KeyKind::Flag => KeyValue::Flag(true),
                };
                keys.set(*key, value);
                let law = AeroLaw::from_keys(name, &keys).unwrap();
                assert_ne!(law, defaults, "{}: {} is not read", name.as_str(), key.name);
            }
        }
        assert!(AeroLaw::from_keys(AeroLawName::Linear, &AeroKeys::default()).is_err());
    }

    /// A key of another law is refused, naming the key and both laws.
    #[test]
    fn another_laws_key_names_the_key_and_the_laws() {
        let mut keys = AeroKeys::default();
        keys.set(key("cl_amplitude").unwrap(), KeyValue::Number(1.0));
        let err = AeroLaw::from_keys(AeroLawName::Unsteady, &keys).unwrap_err();
        assert_eq!(err.item, "aero.cl_amplitude");
        assert!(
            err.reason.contains("law = \"unsteady\"") && err.reason.contains("\"quadratic\""),
            "{}",
            err.reason
        );
    }
}
