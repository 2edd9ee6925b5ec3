//! Free parameters: numbers of the scene file a search may change, each
//! named by its path in the file and held to its bounds, substituted into
//! the parsed document before it is compiled.

use super::error::Where;
use crate::sim::scene::SceneSpec;
use crate::util::bad_input::BadInput;

/// What may be free, as path patterns (`[]` an index): wind primitives'
/// strengths, positions, cores, key values, bounds and fronts; leaf
/// groups' release position, attitude and velocities.
pub const SUPPORTED: &[&str] = &[
    "wind[].velocity[]",
    "wind[].flux",
    "wind[].circulation",
    "wind[].point[]",
    "wind[].core_radius",
    "wind[].keys[][1]",
    "wind[].bounds.radius",
    "wind[].bounds.falloff",
    "wind[].bounds.center[]",
    "wind[].bounds.point[]",
    "wind[].bounds.min[]",
    "wind[].bounds.max[]",
    "wind[].front.speed",
    "wind[].front.offset",
    "wind[].front.falloff",
    "leaf[].position[]",
    "leaf[].rotation_deg[]",
    "leaf[].velocity[]",
    "leaf[].angular_velocity[]",
];

/// One step of a path into the document.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Step {
    /// A table key.
    Key(String),
    /// An array index.
    Index(usize),
}

/// A checked free parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Free {
    /// The path as written (`wind[1].circulation`).
    pub parameter: String,
    /// The path resolved (a leaf group's name replaced by its index).
    pub path: Vec<Step>,
    /// Lower bound.
    pub min: f64,
    /// Upper bound.
    pub max: f64,
    /// The file's value.
    pub written: f64,
}

impl Free {
    /// The value at `u` in [0, 1] of the bounds.
    pub fn value(&self, u: f64) -> f64 {
        self.min + (self.max - self.min) * u
    }
}

/// Splits `wind[1].keys[0][1]` into steps; an index that is not a number
/// is kept as a key (a leaf group's name) for [`resolve`].
fn parse(text: &str) -> Option<Vec<(String, Vec<String>)>> {
    let mut out = Vec::new();
    for part in text.split('.') {
        let (key, rest) = part.split_once('[').map_or((part, ""), |(k, r)| (k, r));
        if key.is_empty() || !key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return None;
        }
        let mut indices = Vec::new();
        if !rest.is_empty() {
            let rest = rest.strip_suffix(']')?;
            for i in rest.split("][") {
                if i.is_empty() || i.contains(['[', ']']) {
                    return None;
                }
                indices.push(i.to_string());
            }
        }
        out.push((key.to_string(), indices));
    }
    Some(out)
}

fn pattern(parts: &[(String, Vec<String>)]) -> String {
    parts
        .iter()
        .map(|(k, ix)| {
            let mut s = k.clone();
            for (n, i) in ix.iter().enumerate() {
                // A key's value index stays literal (`keys[][1]`): only the
                // multiplier of a key is free, never its time.
                if k == "keys" && n == 1 {
                    s.push_str(&format!("[{i}]"));
                } else {
                    s.push_str("[]");
                }
            }
            s
        })
        .collect::<Vec<_>>()
        .join(".")
}

/// The steps of `parts`, a `[[leaf]]` name in the first index replaced by
/// the group's index.
fn resolve(parts: &[(String, Vec<String>)], spec: &SceneSpec) -> Result<Vec<Step>, String> {
    let mut steps = Vec::new();
    for (n, (key, indices)) in parts.iter().enumerate() {
        steps.push(Step::Key(key.clone()));
        for i in indices {
            let index = match i.parse::<usize>() {
                Ok(v) => v,
                Err(_) if n == 0 && key == "leaf" => spec
                    .leaves
                    .iter()
                    .position(|l| &l.name == i)
                    .ok_or_else(|| format!("no [[leaf]] named '{i}'"))?,
                Err(_) => return Err(format!("'{i}' is not an index")),
            };
            steps.push(Step::Index(index));
        }
    }
    Ok(steps)
}

/// The number at `path` in `doc`.
pub fn get(doc: &toml::Table, path: &[Step]) -> Option<f64> {
    let mut v: Option<&toml::Value> = None;
    for s in path {
        v = match (s, v) {
            (Step::Key(k), None) => doc.get(k),
            (Step::Key(k), Some(toml::Value::Table(t))) => t.get(k),
            (Step::Index(i), Some(toml::Value::Array(a))) => a.get(*i),
            _ => None,
        };
        v?;
    }
    match v? {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(n) => Some(*n as f64),
        _ => None,
    }
}

/// Sets the number at `path` in `doc` (which [`get`] found there).
pub fn set(doc: &mut toml::Table, path: &[Step], value: f64) {
    let Some((Step::Key(first), rest)) = path.split_first() else {
        return;
    };
    let Some(mut v) = doc.get_mut(first) else {
        return;
    };
    for s in rest {
        let next = match (s, v) {
            (Step::Key(k), toml::Value::Table(t)) => t.get_mut(k),
            (Step::Index(i), toml::Value::Array(a)) => a.get_mut(*i),
            _ => None,
        };
        let Some(n) = next else { return };
        v = n;
    }
    *v = toml::Value::Float(value);
}

/// Checks every `[[free]]` of `spec` against the parsed `doc`: a
/// supported path to a number written in the file, finite bounds with
/// `min` < `max`, each named once. Whether the bounds are ones the scene
/// accepts is checked by the caller, which compiles the scene at them.
///
/// # Errors
/// The first bad field.
pub fn check(spec: &SceneSpec, doc: &toml::Table, at: &Where<'_>) -> Result<Vec<Free>, BadInput> {
    let mut out: Vec<Free> = Vec::new();
    for (i, f) in spec.free.iter().enumerate() {
        let p = format!("free[{i}]");
        let field = format!("{p}.parameter");
        let parts = parse(&f.parameter).ok_or_else(|| {
            at.err(
                &field,
                format!(
                    "'{}' is not a path like wind[1].circulation or leaf[east].position[2]",
                    f.parameter
                ),
            )
        })?;
        let shape = pattern(&parts);
        if !SUPPORTED.contains(&shape.as_str()) {
            return Err(at.err(
                &field,
                format!(
                    "'{}' cannot be free (yet): a free parameter is one of {}; a leaf's release time is not yet supported",
                    f.parameter,
                    SUPPORTED.join(", ")
                ),
            ));
        }
        let path = resolve(&parts, spec).map_err(|e| at.err(&field, e))?;
        let written = get(doc, &path).ok_or_else(|| {
            at.err(
                &field,
                format!(
                    "'{}' is not written in the file: write the field (any value within the bounds) so the scene runs as it is",
                    f.parameter
                ),
            )
        })?;
        let (Some(min), Some(max)) = (f.min, f.max) else {
            let which = if f.min.is_none() { "min" } else { "max" };
            return Err(at.err(
                format!("{p}.{which}"),
                "a free parameter needs bounds: `min` and `max`",
            ));
        };
        for (k, v) in [("min", min), ("max", max)] {
            if !v.is_finite() {
                return Err(at.err(format!("{p}.{k}"), format!("must be finite, got {v}")));
            }
        }
        if min >= max {
            return Err(at.err(
                format!("{p}.max"),
                format!("must be above `min` ({min}), got {max}"),
            ));
        }
        if let Some(other) = out.iter().position(|o| o.path == path) {
            return Err(at.err(
                &field,
                format!("free[{other}] already frees '{}'", out[other].parameter),
            ));
        }
        out.push(Free {
            parameter: f.parameter.clone(),
            path,
            min,
            max,
            written,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_parse_into_patterns() {
        let p = parse("wind[3].keys[1][1]").unwrap();
        assert_eq!(pattern(&p), "wind[].keys[][1]");
        let p = parse("leaf[east].position[2]").unwrap();
        assert_eq!(pattern(&p), "leaf[].position[]");
        assert_eq!(
            pattern(&parse("wind[0].keys[1][0]").unwrap()),
            "wind[].keys[][0]"
        );
        assert!(parse("wind[1.flux").is_none());
        assert!(parse("wind[].flux").is_none());
        assert!(parse("").is_none());
    }

    #[test]
    fn get_and_set_reach_nested_numbers() {
        let mut doc: toml::Table = toml::from_str(
            "[[wind]]\nkind = \"uniform\"\nvelocity = [0, 0, 1]\nbounds = { shape = \"sphere\", center = [0.0, 0.0, 0.0], radius = 1, falloff = 0.1 }\n",
        )
        .unwrap();
        let path = vec![
            Step::Key("wind".into()),
            Step::Index(0),
            Step::Key("velocity".into()),
            Step::Index(2),
        ];
        assert_eq!(get(&doc, &path), Some(1.0));
        set(&mut doc, &path, 2.5);
        assert_eq!(get(&doc, &path), Some(2.5));
        let radius = vec![
            Step::Key("wind".into()),
            Step::Index(0),
            Step::Key("bounds".into()),
            Step::Key("radius".into()),
        ];
        assert_eq!(get(&doc, &radius), Some(1.0));
        let missing = vec![Step::Key("wind".into()), Step::Index(1)];
        assert_eq!(get(&doc, &missing), None);
    }
}
