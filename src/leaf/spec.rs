//! Leaf files: a flat layout of particles, springs and triangles plus folds,
//! read from TOML, validated, and turned into a [`Model`]. The paper's two
//! prototypes (figure 4) are embedded so the tool runs without any file.
//! Every field is documented in `prototypes/README.md`.

use crate::physics::aero::keys::{AeroKeys, Key, KeyKind, KeyValue};
use crate::physics::aero::law as laws;
/// The name of an aerodynamic law in a leaf file (the law's own type).
pub use crate::physics::aero::law::AeroLawName;
use crate::physics::field::WindField;
use crate::physics::model::{
    AeroLaw, Hinge, Model, ModelError, ModelParts, RigidGroup, STANDARD_GRAVITY, Spring, Triangle,
};
use crate::util::bad_input::BadInput;
use nalgebra::{Unit, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Prototype A of the paper's figure 4 (symmetric star, three flaps).
pub const PROTOTYPE_A: &str = include_str!("../../prototypes/leaf-a.toml");
/// Prototype B of the paper's figure 4 (asymmetric strip with three flaps).
pub const PROTOTYPE_B: &str = include_str!("../../prototypes/leaf-b.toml");

/// A leaf as written in a file. Positions are the flat (unfolded) layout;
/// folds turn vertices about hinges when the model is built.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LeafSpec {
    /// Short name, used in outputs.
    pub name: String,
    /// Aerodynamic law and coefficients shared by all triangles.
    pub aero: AeroSpec,
    /// Limits the genome respects when varying this leaf.
    #[serde(default)]
    pub bounds: Bounds,
    /// Bending stiffness of every edge shared by two triangles (absent: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bending: Option<BendingSpec>,
    /// Gravity, m/s² (default: standard gravity down z).
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    /// Point masses.
    #[serde(rename = "particle")]
    pub particles: Vec<ParticleSpec>,
    /// Springs with dashpots.
    #[serde(rename = "spring", default)]
    pub springs: Vec<SpringSpec>,
    /// Wind-catching triangles.
    #[serde(rename = "triangle", default)]
    pub triangles: Vec<TriangleSpec>,
    /// Folds applied in order to the flat layout.
    #[serde(rename = "fold", default)]
    pub folds: Vec<FoldSpec>,
    /// Wind (still air when absent).
    #[serde(default, skip_serializing_if = "WindField::is_still")]
    pub wind: WindField,
    /// Move all particles as one rigid body (after Hahn 1988, as scenes'
    /// rigid objects): springs and bending then change nothing. What
    /// `leafmagic plate` writes: a uniform rigid plate, as in the
    /// falling-plate literature.
    #[serde(default, skip_serializing_if = "is_false")]
    pub rigid: bool,
}

fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -STANDARD_GRAVITY]
}

/// The aerodynamic law of a leaf: `[aero] law = "linear"` (eq. 9–10, the
/// default) with `alpha_n`, `alpha_t`; `law = "quadratic"`
/// ([`crate::physics::aero::quadratic`]) or `law = "unsteady"`
/// ([`crate::physics::aero::unsteady`]) with optional overrides of their
/// literature coefficients. Each law declares its own keys
/// ([`AeroLawName::keys`]); this table holds the ones a file sets, and the
/// law turns them into its coefficients ([`AeroSpec::resolve`]).
#[derive(Clone, Debug, PartialEq)]
pub struct AeroSpec {
    /// Which law; `linear` is the paper's.
    pub law: AeroLawName,
    /// The keys set besides `law`, of any law (another law's key is refused
    /// by [`AeroSpec::resolve`], by name).
    keys: AeroKeys,
}

fn law_name<'de, D: serde::Deserializer<'de>>(d: D) -> Result<AeroLawName, D::Error> {
    crate::util::named::by_name(d, &["linear", "quadratic", "unsteady"])
}

impl Serialize for AeroSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut table = s.serialize_struct("AeroSpec", 1 + self.keys.iter().count())?;
        table.serialize_field("law", &self.law)?;
        // In one order whatever the file's, as when each key was a field.
        for key in laws::all_keys() {
            let Some(value) = self.keys.get(key.name) else {
                continue;
            };
            match value {
                KeyValue::Number(x) => table.serialize_field(key.name, &x)?,
                KeyValue::Flag(b) => table.serialize_field(key.name, &b)?,
            }
        }
        table.end()
    }
}

impl<'de> Deserialize<'de> for AeroSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::{self, MapAccess, Visitor};
        /// `law`, or a key of some law; an unknown name is refused as
        /// serde refuses an unknown field (naming it and every known one).
        enum Field {
            Law,
            Key(Key),
        }
        impl<'de> Deserialize<'de> for Field {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                struct Name;
                impl Visitor<'_> for Name {
                    type Value = Field;
                    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                        f.write_str("field identifier")
                    }
                    fn visit_str<E: de::Error>(self, v: &str) -> Result<Field, E> {
                        if v == "law" {
                            return Ok(Field::Law);
                        }
                        laws::key(v)
                            .map(Field::Key)
                            .ok_or_else(|| E::unknown_field(v, laws::all_names()))
                    }
                }
                d.deserialize_identifier(Name)
            }
        }
        struct Law(AeroLawName);
        impl<'de> Deserialize<'de> for Law {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                law_name(d).map(Law)
            }
        }
        struct Table;
        impl<'de> Visitor<'de> for Table {
            type Value = AeroSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("struct AeroSpec")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<AeroSpec, A::Error> {
                let mut law = None;
                let mut keys = AeroKeys::default();
                while let Some(field) = map.next_key::<Field>()? {
                    match field {
                        Field::Law if law.is_some() => {
                            return Err(de::Error::duplicate_field("law"));
                        }
                        Field::Law => law = Some(map.next_value::<Law>()?.0),
                        Field::Key(key) => {
                            if keys.get(key.name).is_some() {
                                return Err(de::Error::duplicate_field(key.name));
                            }
                            let value = match key.kind {
                                KeyKind::Number => KeyValue::Number(map.next_value()?),
                                KeyKind::Flag => KeyValue::Flag(map.next_value()?),
                            };
                            keys.set(key, value);
                        }
                    }
                }
                Ok(AeroSpec {
                    law: law.unwrap_or_default(),
                    keys,
                })
            }
        }
        d.deserialize_struct("AeroSpec", laws::all_names(), Table)
    }
}

impl AeroSpec {
    /// This table with `KEY = VALUE` lines added (as a leaf file's `[aero]`
    /// table spells them), read by the leaf-file parser, so they are checked
    /// as a leaf file's are; the error is the parser's.
    pub fn with_lines(&self, lines: &[String]) -> Result<AeroSpec, String> {
        let mut table = toml::to_string(self).map_err(|e| e.to_string())?;
        for line in lines {
            table.push_str(line);
            table.push('\n');
        }
        toml::from_str(&table).map_err(|e| e.to_string())
    }

    /// The paper's linear law with these coefficients.
    pub fn linear(alpha_n: f64, alpha_t: f64) -> AeroSpec {
        let mut spec = AeroSpec::named(AeroLawName::Linear);
        spec.set_number("alpha_n", alpha_n);
        spec.set_number("alpha_t", alpha_t);
        spec
    }

    /// The quadratic law with the literature's coefficients.
    pub fn quadratic() -> AeroSpec {
        AeroSpec::named(AeroLawName::Quadratic)
    }

    /// The unsteady law with its default coefficients.
    pub fn unsteady() -> AeroSpec {
        AeroSpec::named(AeroLawName::Unsteady)
    }

    /// Law `law` with no key set (the linear law then still needs its α).
    pub fn named(law: AeroLawName) -> AeroSpec {
        AeroSpec {
            law,
            keys: AeroKeys::default(),
        }
    }

    /// The number key `name` is set to (`alpha_n`, `cd_normal`, ...), if set.
    pub fn number(&self, name: &str) -> Option<f64> {
        self.keys.number(name)
    }

    /// The flag key `name` is set to (`buoyancy`), if set.
    pub fn flag(&self, name: &str) -> Option<bool> {
        self.keys.flag(name)
    }

    /// Sets the number key `name` (of any law: [`AeroSpec::resolve`] judges
    /// whether it belongs to this one).
    ///
    /// # Panics
    /// If no law has a number key `name` (a name in code, not from a file).
    pub fn set_number(&mut self, name: &str, value: f64) {
        match laws::key(name) {
            Some(key) if key.kind == KeyKind::Number => self.keys.set(key, KeyValue::Number(value)),
            _ => panic!("no aerodynamic law has a number key {name:?}"),
        }
    }

    /// Whether this table's law reads key `name`.
    pub fn takes(&self, name: &str) -> bool {
        self.law.keys().iter().any(|k| k.name == name)
    }

    /// Unsets key `name`.
    pub fn remove(&mut self, name: &str) {
        self.keys.remove(name);
    }

    /// The model's law with its coefficients: each law's own keys set or
    /// defaulted, its required ones present, the other laws' keys rejected
    /// by name (a coefficient that would be silently ignored is a mistake).
    /// Their ranges are the law's one validation, which [`Model::new`]
    /// runs.
    pub fn resolve(&self) -> Result<AeroLaw, ModelError> {
        AeroLaw::from_keys(self.law, &self.keys)
    }
}

/// The paper's linear-law coefficients (αⁿ, αᵗ), kg/(m²·s): those of its
/// two prototypes (`prototypes/leaf-a.toml`, `leaf-b.toml`). A leaf of
/// another law falls under the paper's law with these
/// ([`LeafSpec::under_law`]); `leafmagic plate` gives them to a linear-law
/// plate.
pub const PAPER_ALPHA: (f64, f64) = (0.47, 0.047);

/// Bending hinges on every edge shared by two triangles, resisting changes of
/// the fold angle from its value in the folded rest shape.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BendingSpec {
    /// Bending stiffness k_b, N·m/rad.
    pub stiffness: f64,
    /// Bending damping c_b, N·m·s/rad.
    #[serde(default)]
    pub damping: f64,
}

/// One point mass.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticleSpec {
    /// Flat-layout position, m.
    pub position: [f64; 3],
    /// Mass, kg.
    pub mass: f64,
    /// Pinned in space.
    #[serde(default, skip_serializing_if = "is_false")]
    pub fixed: bool,
    /// Linear drag α of eq. 7, kg/s, for a particle in no triangle.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub drag: f64,
}

/// One spring.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringSpec {
    /// The two particle indices.
    pub ends: [usize; 2],
    /// Stiffness k, N/m.
    pub stiffness: f64,
    /// Dashpot coefficient c, N·s/m.
    #[serde(default)]
    pub damping: f64,
    /// Group name; the genome scales stiffness per group.
    #[serde(default = "default_group")]
    pub group: String,
    /// Rest length, m (default: the distance in the folded shape).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rest_length: Option<f64>,
    /// Breaking strain (l − L)/L (default: unbreakable).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub break_strain: Option<f64>,
}

fn default_group() -> String {
    "edge".to_string()
}

/// One triangle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TriangleSpec {
    /// The three corner particle indices.
    pub corners: [usize; 3],
    /// The paper's flap label (1, 2, 3 in figure 4), if this is a flap.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flap: Option<u8>,
    /// Overrides the leaf's αⁿ.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha_n: Option<f64>,
    /// Overrides the leaf's αᵗ.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha_t: Option<f64>,
}

/// A fold: the vertices in `moves` turn about the hinge line by `angle_deg`;
/// positive turns them up (towards +z, the side of the leaf's normal).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FoldSpec {
    /// The paper's flap label this fold belongs to, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flap: Option<u8>,
    /// A name for folds that are not flaps (e.g. a camber of the blade).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The two particles on the hinge line.
    pub hinge: [usize; 2],
    /// The particles carried by the fold.
    pub moves: Vec<usize>,
    /// Fold angle, degrees, + up.
    pub angle_deg: f64,
}

/// Physical bounds for variation: [`crate::leaf::genome::mutate`] clamps every
/// gene to these, so no variant is an invalid model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Bounds {
    /// Range of each fold angle, degrees (signed: a flap may go from up to
    /// down; bending hinges keep a flat flap stiff).
    pub fold_deg: [f64; 2],
    /// Range of each particle's mass factor (mass distribution).
    pub mass_factor: [f64; 2],
    /// Range of the total mass factor (areal density).
    pub total_mass_factor: [f64; 2],
    /// Range of each spring group's stiffness relative to the prototype.
    pub stiffness_factor: [f64; 2],
    /// Range of the overall size relative to the prototype.
    pub size_factor: [f64; 2],
    /// Range of the outline's aspect ratio relative to the prototype's: the
    /// flat layout stretched by √a along x and 1/√a along y (area kept).
    /// Default [1, 1]: not varied unless the file asks.
    pub aspect_ratio: [f64; 2],
    /// Range of the factor on the linear law's tangential/normal drag ratio
    /// αᵗ/αⁿ (αᵗ scaled, αⁿ kept; eq. 9–10). Default [1, 1]; inert under
    /// the other laws.
    pub drag_ratio: [f64; 2],
    /// Range of the camber: the flat layout bowed across y into a parabolic
    /// arc whose height is this fraction of the layout's extent along y (+
    /// up, 0 flat). Default [0, 0].
    pub camber: [f64; 2],
    /// Range of the petiole (stem) mass added at the leaf's base, the
    /// particle farthest along −y in the flat layout, as a fraction of the
    /// blade's mass. Default [0, 0].
    pub petiole_mass: [f64; 2],
}

impl Default for Bounds {
    fn default() -> Self {
        Bounds {
            fold_deg: [-60.0, 60.0],
            mass_factor: [0.25, 4.0],
            total_mass_factor: [0.5, 2.0],
            stiffness_factor: [0.5, 4.0],
            size_factor: [0.5, 2.0],
            aspect_ratio: [1.0, 1.0],
            drag_ratio: [1.0, 1.0],
            camber: [0.0, 0.0],
            petiole_mass: [0.0, 0.0],
        }
    }
}

impl Bounds {
    /// Each range finite and ordered; factor ranges positive.
    pub fn validate(&self) -> Result<(), ModelError> {
        let ranges = [
            ("fold_deg", self.fold_deg, false),
            ("mass_factor", self.mass_factor, true),
            ("total_mass_factor", self.total_mass_factor, true),
            ("stiffness_factor", self.stiffness_factor, true),
            ("size_factor", self.size_factor, true),
            ("aspect_ratio", self.aspect_ratio, true),
            ("drag_ratio", self.drag_ratio, true),
            ("camber", self.camber, false),
            ("petiole_mass", self.petiole_mass, false),
        ];
        for (name, [lo, hi], positive) in ranges {
            let reason = if !(lo.is_finite() && hi.is_finite()) {
                Some(format!("must be finite, got [{lo}, {hi}]"))
            } else if lo > hi {
                Some(format!("minimum {lo} exceeds maximum {hi}"))
            } else if positive && lo <= 0.0 {
                Some(format!("factors must be > 0, got minimum {lo}"))
            } else {
                None
            };
            if let Some(reason) = reason {
                return Err(ModelError {
                    item: format!("bounds.{name}"),
                    reason,
                });
            }
        }
        Ok(())
    }
}

fn is_false(b: &bool) -> bool {
    !*b
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// A leaf file that could not be read or is invalid: the file, the line,
/// the field and the reason, as every input's error ([`BadInput`]).
pub type LeafError = BadInput;

impl LeafSpec {
    /// This leaf under the aerodynamic law `law`, all else kept (layout,
    /// masses, folds, bounds, wind). A leaf already of that law keeps its
    /// own coefficients; otherwise its `[aero]` becomes the law's defaults:
    /// the paper's linear law with [`PAPER_ALPHA`] (the prototypes' αⁿ, αᵗ),
    /// the unsteady and quadratic laws with their literature coefficients
    /// (and triangles' own αⁿ, αᵗ, which only the linear law reads, are
    /// dropped).
    pub fn under_law(self, law: AeroLawName) -> LeafSpec {
        if self.aero.law == law {
            return self;
        }
        let aero = match law {
            AeroLawName::Linear => AeroSpec::linear(PAPER_ALPHA.0, PAPER_ALPHA.1),
            other => AeroSpec::named(other),
        };
        let mut triangles = self.triangles;
        if law != AeroLawName::Linear {
            for t in &mut triangles {
                (t.alpha_n, t.alpha_t) = (None, None);
            }
        }
        LeafSpec {
            aero,
            triangles,
            ..self
        }
    }

    /// Parses and validates TOML text; `source` names it in errors.
    pub fn from_toml(text: &str, source: &str) -> Result<LeafSpec, LeafError> {
        LeafSpec::from_toml_with_model(text, source).map(|(spec, _)| spec)
    }

    /// [`LeafSpec::from_toml`] and the model that validated it: building a
    /// model measures every plate's chords (O(triangles²), most of a fine
    /// plate's load), so a caller that needs both builds it once.
    pub fn from_toml_with_model(text: &str, source: &str) -> Result<(LeafSpec, Model), LeafError> {
        let spec: LeafSpec =
            toml::from_str(text).map_err(|e| BadInput::toml_parse(source, text, &e))?;
        let model = spec
            .model()
            .map_err(|e| BadInput::in_toml(source, text, e.item, e.reason))?;
        Ok((spec, model))
    }

    /// Reads a leaf file.
    pub fn read(path: &Path) -> Result<LeafSpec, LeafError> {
        LeafSpec::read_with_model(path).map(|(spec, _)| spec)
    }

    /// Reads a leaf file, with its model ([`LeafSpec::from_toml_with_model`]).
    pub fn read_with_model(path: &Path) -> Result<(LeafSpec, Model), LeafError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| BadInput::file(path.display().to_string(), format!("cannot read: {e}")))?;
        LeafSpec::from_toml_with_model(&text, &path.display().to_string())
    }

    /// `a` or `b` for the embedded prototypes, otherwise a file path.
    pub fn load(name_or_path: &str) -> Result<LeafSpec, LeafError> {
        LeafSpec::load_with_model(name_or_path).map(|(spec, _)| spec)
    }

    /// [`LeafSpec::load`] with the leaf's model.
    pub fn load_with_model(name_or_path: &str) -> Result<(LeafSpec, Model), LeafError> {
        match name_or_path {
            "a" | "A" => LeafSpec::from_toml_with_model(PROTOTYPE_A, "prototype a"),
            "b" | "B" => LeafSpec::from_toml_with_model(PROTOTYPE_B, "prototype b"),
            path => LeafSpec::read_with_model(Path::new(path)),
        }
    }

    /// The TOML text of this leaf (round-trips through [`LeafSpec::from_toml`]).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a leaf always serialises")
    }

    /// The folded rest shape: the flat layout with every fold applied in order.
    pub fn folded_positions(&self) -> Result<Vec<Vector3<f64>>, ModelError> {
        let mut x: Vec<Vector3<f64>> = self
            .particles
            .iter()
            .map(|p| Vector3::from(p.position))
            .collect();
        let n = x.len();
        // Positions must be finite before folds turn them (a NaN hinge would
        // otherwise be reported as coincident particles).
        for (i, p) in x.iter().enumerate() {
            for (axis, value) in p.iter().enumerate() {
                if !value.is_finite() {
                    return Err(ModelError {
                        item: format!("particle[{i}].position[{axis}]"),
                        reason: format!("must be a finite number, got {value}"),
                    });
                }
            }
        }
        for (f, fold) in self.folds.iter().enumerate() {
            let item = |field: &str| format!("fold[{f}].{field}");
            for &i in fold.hinge.iter() {
                if i >= n {
                    return Err(ModelError {
                        item: item("hinge"),
                        reason: format!(
                            "particle index {i} out of range (there are {n} particles)"
                        ),
                    });
                }
            }
            if !fold.angle_deg.is_finite() {
                return Err(ModelError {
                    item: item("angle_deg"),
                    reason: format!("must be a finite number, got {}", fold.angle_deg),
                });
            }
            let (a, b) = (x[fold.hinge[0]], x[fold.hinge[1]]);
            let Some(axis) = Unit::try_new(b - a, 1e-12) else {
                return Err(ModelError {
                    item: item("hinge"),
                    reason: "the hinge particles coincide".to_string(),
                });
            };
            for &m in &fold.moves {
                if m >= n {
                    return Err(ModelError {
                        item: item("moves"),
                        reason: format!(
                            "particle index {m} out of range (there are {n} particles)"
                        ),
                    });
                }
                if fold.hinge.contains(&m) {
                    return Err(ModelError {
                        item: item("moves"),
                        reason: format!("particle {m} is on the hinge and cannot move"),
                    });
                }
            }
            // "Up" is towards +z: pick the turning sense in which the first
            // moved vertex rises, so the sign does not depend on hinge order.
            let Some(&first) = fold.moves.first() else {
                continue;
            };
            let lever = x[first] - a;
            let sense = if axis.cross(&lever).z >= 0.0 {
                1.0
            } else {
                -1.0
            };
            let rotation =
                UnitQuaternion::from_axis_angle(&axis, sense * fold.angle_deg.to_radians());
            for &m in &fold.moves {
                x[m] = a + rotation * (x[m] - a);
            }
        }
        Ok(x)
    }

    /// One hinge per edge shared by exactly two triangles (in triangle order,
    /// so indices are stable), at the fold angle of the rest shape.
    fn hinges(&self, rest: &[Vector3<f64>], bending: &BendingSpec) -> Vec<Hinge> {
        let mut out = Vec::new();
        let n = rest.len();
        for (i, t) in self.triangles.iter().enumerate() {
            for u in &self.triangles[i + 1..] {
                if t.corners.iter().chain(&u.corners).any(|&c| c >= n) {
                    continue; // reported by Model::new
                }
                let shared: Vec<usize> = t
                    .corners
                    .iter()
                    .copied()
                    .filter(|c| u.corners.contains(c))
                    .collect();
                if shared.len() != 2 {
                    continue;
                }
                let p = t.corners.iter().copied().find(|c| !shared.contains(c));
                let q = u.corners.iter().copied().find(|c| !shared.contains(c));
                let (Some(p), Some(q)) = (p, q) else { continue };
                let mut hinge = Hinge {
                    edge: [shared[0], shared[1]],
                    apexes: [p, q],
                    rest_angle: 0.0,
                    stiffness: bending.stiffness,
                    damping: bending.damping,
                };
                if let Some((theta, _)) = crate::physics::forces::dihedral(rest, &hinge) {
                    hinge.rest_angle = theta;
                    out.push(hinge);
                }
            }
        }
        out
    }

    /// Builds and validates the model of this leaf.
    pub fn model(&self) -> Result<Model, ModelError> {
        self.bounds.validate()?;
        let rest = self.folded_positions()?;
        let n = rest.len();
        let mut springs = Vec::with_capacity(self.springs.len());
        for (s, spec) in self.springs.iter().enumerate() {
            let [i, j] = spec.ends;
            if i >= n || j >= n {
                return Err(ModelError {
                    item: format!("spring[{s}].ends"),
                    reason: format!(
                        "particle index {} out of range (there are {n} particles)",
                        i.max(j)
                    ),
                });
            }
            springs.push(Spring {
                i,
                j,
                rest_length: spec
                    .rest_length
                    .unwrap_or_else(|| (rest[i] - rest[j]).norm()),
                stiffness: spec.stiffness,
                damping: spec.damping,
                break_strain: spec.break_strain,
            });
        }
        let hinges = match &self.bending {
            None => Vec::new(),
            Some(b) => {
                for (name, value) in [("stiffness", b.stiffness), ("damping", b.damping)] {
                    if !(value.is_finite() && value >= 0.0) {
                        return Err(ModelError {
                            item: format!("bending.{name}"),
                            reason: format!("must be a finite number ≥ 0, got {value}"),
                        });
                    }
                }
                self.hinges(&rest, b)
            }
        };
        let aero = self.aero.resolve()?;
        let mut triangles = Vec::with_capacity(self.triangles.len());
        for (k, t) in self.triangles.iter().enumerate() {
            let (alpha_n, alpha_t) = if aero.uses_triangle_alpha() {
                (
                    t.alpha_n
                        .or(self.aero.number("alpha_n"))
                        .unwrap_or_default(),
                    t.alpha_t
                        .or(self.aero.number("alpha_t"))
                        .unwrap_or_default(),
                )
            } else {
                if t.alpha_n.is_some() || t.alpha_t.is_some() {
                    return Err(ModelError {
                        item: format!("triangle[{k}].alpha_n"),
                        reason: format!("per-triangle α is not used by law = \"{}\"", aero.name()),
                    });
                }
                (0.0, 0.0)
            };
            triangles.push(Triangle {
                corners: t.corners,
                alpha_n,
                alpha_t,
            });
        }
        Model::new(ModelParts {
            mass: self.particles.iter().map(|p| p.mass).collect(),
            fixed: self.particles.iter().map(|p| p.fixed).collect(),
            particle_drag: self.particles.iter().map(|p| p.drag).collect(),
            rest_position: rest,
            springs,
            triangles,
            hinges,
            aero,
            wind: self.wind.clone(),
            gravity: Vector3::from(self.gravity),
            rigid: if self.rigid {
                vec![RigidGroup {
                    members: (0..n).collect(),
                }]
            } else {
                Vec::new()
            },
            ..Default::default()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper's coefficients are its prototypes' own; a leaf keeps its
    /// law's coefficients under that law, and under another law it builds
    /// (the prototypes under the unsteady law and back).
    #[test]
    fn under_law_switches_the_law_and_keeps_the_rest() {
        for p in ["a", "b"] {
            let spec = LeafSpec::load(p).unwrap();
            assert_eq!(spec.aero, AeroSpec::linear(PAPER_ALPHA.0, PAPER_ALPHA.1));
            assert_eq!(spec.clone().under_law(AeroLawName::Linear), spec);
            let real = spec.clone().under_law(AeroLawName::Unsteady);
            assert_eq!(real.aero, AeroSpec::unsteady());
            assert_eq!(real.particles, spec.particles);
            assert_eq!(real.folds, spec.folds);
            assert!(matches!(
                real.model().unwrap().aero,
                crate::physics::model::AeroLaw::Unsteady(_)
            ));
            assert_eq!(real.clone().under_law(AeroLawName::Linear), spec);
        }
        let mut odd = LeafSpec::load("a").unwrap();
        odd.aero = AeroSpec::linear(1.0, 0.5);
        odd.triangles[0].alpha_n = Some(2.0);
        assert_eq!(odd.clone().under_law(AeroLawName::Linear), odd);
        let quadratic = odd.under_law(AeroLawName::Quadratic);
        assert_eq!(quadratic.triangles[0].alpha_n, None);
        quadratic.model().unwrap();
    }

    #[test]
    fn embedded_prototypes_load_and_round_trip() {
        for p in ["a", "b"] {
            let spec = LeafSpec::load(p).unwrap();
            let again = LeafSpec::from_toml(&spec.to_toml(), "round trip").unwrap();
            assert_eq!(spec, again);
        }
    }

    #[test]
    fn a_positive_fold_raises_the_flap_tip() {
        let spec = LeafSpec::load("a").unwrap();
        let x = spec.folded_positions().unwrap();
        for fold in &spec.folds {
            for &m in &fold.moves {
                assert!(
                    x[m].z > 0.0,
                    "fold {:?} moved {m} to z = {}",
                    fold.flap,
                    x[m].z
                );
            }
        }
        let mut down = spec.clone();
        down.folds[0].angle_deg = -20.0;
        let x = down.folded_positions().unwrap();
        assert!(x[down.folds[0].moves[0]].z < 0.0);
    }
}
