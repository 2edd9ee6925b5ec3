//! One USD text layer (`.usda`) as written: its prims with their
//! attributes and relationships, and what a prim's values and transform are
//! at a time code. What [`super::read`] (meshes into a clip) and
//! [`super::skel`] (skinning) read a layer through.
//!
//! Of USD's text grammar (Pixar, "USD file formats"; the UsdGeom schemas):
//! `def` prims and their nesting, attributes with a default value and/or
//! `timeSamples` and their metadata, relationships and their targets, the
//! stage's `upAxis` (Y or Z; Y when unset, as USD says), `metersPerUnit`
//! (0.01 when unset) and `timeCodesPerSecond` (24 when unset); each prim's
//! `xformOpOrder` of `translate`, `scale`, `rotateX|Y|Z`, `rotateXYZ` (and
//! the other five orders), `orient` and `transform` ops, with `!invert!`
//! and `!resetXformStack!`. Values between samples are interpolated
//! linearly (quaternions, alone or in arrays, by slerp) and held outside
//! them, as USD does.
//!
//! `class` prims and prims authored `active = false` are left out with all
//! below them, as USD's default traversal leaves them. What this reader
//! refuses: the binary crate format, USDZ packages, and layers that need
//! composing (sublayers, references, payloads, inherits, specializes,
//! variant sets, `over` prims); [`composes`] tells the last apart from a
//! malformed layer, and [`super::stage`] reads all three.

use nalgebra::{Matrix3, Matrix4, Quaternion, Rotation3, UnitQuaternion, Vector3};

type V3 = Vector3<f64>;
type M4 = Matrix4<f64>;

/// One token of USD text.
#[derive(Clone, Debug, PartialEq)]
enum Token {
    /// An identifier, keyword or namespaced name (`xformOp:translate.timeSamples`).
    Ident(String),
    /// A number.
    Number(f64),
    /// A quoted string.
    Str(String),
    /// A path `</a/b>` or an asset path `@a.usd@`.
    Path(String),
    /// One of `( ) [ ] { } = , : ;`.
    Punct(char),
}

/// Splits USD text into tokens, leaving out comments (`#…` and `//…` to
/// the end of the line, `/* … */`) and the `#usda` header line.
fn tokens(text: &str) -> Result<Vec<(Token, usize)>, String> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    let mut line = 1;
    while i < b.len() {
        let c = b[i];
        if c == b'\n' {
            line += 1;
            i += 1;
        } else if c.is_ascii_whitespace() {
            i += 1;
        } else if c == b'#' || b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            let end = text[i + 2..]
                .find("*/")
                .ok_or(format!("line {line}: a comment that never ends"))?;
            line += text[i..i + 2 + end].matches('\n').count();
            i += end + 4;
        } else if c == b'"' || c == b'\'' {
            let triple = b[i..].starts_with(&[c, c, c]);
            let quote = if triple { 3 } else { 1 };
            let mut j = i + quote;
            let mut s = String::new();
            loop {
                if j >= b.len() {
                    return Err(format!("line {line}: a string that never ends"));
                }
                if b[j..].starts_with(&[c, c, c][..quote]) {
                    break;
                }
                if b[j] == b'\\' && j + 1 < b.len() {
                    j += 1;
                }
                if b[j] == b'\n' {
                    line += 1;
                }
                let ch = text[j..].chars().next().unwrap_or('?');
                s.push(ch);
                j += ch.len_utf8();
            }
            out.push((Token::Str(s), line));
            i = j + quote;
        } else if c == b'<' {
            let end = text[i..]
                .find('>')
                .ok_or(format!("line {line}: a path without its `>`"))?;
            out.push((Token::Path(text[i + 1..i + end].to_string()), line));
            i += end + 1;
        } else if c == b'@' {
            let delim = if b[i..].starts_with(b"@@@") {
                "@@@"
            } else {
                "@"
            };
            let start = i + delim.len();
            let end = text[start..]
                .find(delim)
                .ok_or(format!("line {line}: an asset path without its closing @"))?;
            out.push((Token::Path(text[start..start + end].to_string()), line));
            i = start + end + delim.len();
        } else if c.is_ascii_digit() || c == b'-' || c == b'+' || c == b'.' {
            let mut j = i + 1;
            while j < b.len()
                && (b[j].is_ascii_digit()
                    || b[j] == b'.'
                    || ((b[j] == b'e' || b[j] == b'E') && j > i)
                    || ((b[j] == b'-' || b[j] == b'+') && (b[j - 1] == b'e' || b[j - 1] == b'E')))
            {
                j += 1;
            }
            let word = &text[i..j];
            // `-inf`, `+inf`.
            if (word == "-" || word == "+") && text[j..].starts_with("inf") {
                let v = if word == "-" {
                    f64::NEG_INFINITY
                } else {
                    f64::INFINITY
                };
                out.push((Token::Number(v), line));
                i = j + 3;
                continue;
            }
            let v: f64 = word
                .parse()
                .map_err(|_| format!("line {line}: `{word}` is not a number"))?;
            out.push((Token::Number(v), line));
            i = j;
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let mut j = i + 1;
            while j < b.len()
                && (b[j].is_ascii_alphanumeric() || matches!(b[j], b'_' | b':' | b'.'))
            {
                j += 1;
            }
            // A namespaced name ends before a `:` that a value follows
            // (`1: (…)` never starts with a letter, so only trailing `:`).
            let mut word = &text[i..j];
            while word.ends_with(':') {
                word = &word[..word.len() - 1];
                j -= 1;
            }
            let token = match word {
                "inf" => Token::Number(f64::INFINITY),
                "nan" => Token::Number(f64::NAN),
                _ => Token::Ident(word.to_string()),
            };
            out.push((token, line));
            i = j;
        } else if "()[]{}=,:;".contains(c as char) {
            out.push((Token::Punct(c as char), line));
            i += 1;
        } else {
            let ch = text[i..].chars().next().unwrap_or('?');
            return Err(format!("line {line}: unexpected `{ch}`"));
        }
    }
    Ok(out)
}

/// A value of USD text: numbers, strings and tokens, tuples and arrays
/// (both [`Value::List`]), and dictionaries (time samples or metadata).
/// In JSON (how [`super::stage`] carries a layer back from its child
/// process) as that module writes it.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Value {
    Number(f64),
    Str(String),
    Ident(String),
    Path(String),
    List(Vec<Value>),
    Dict(Vec<(Value, Value)>),
}

impl Value {
    pub(super) fn numbers(&self) -> Option<Vec<f64>> {
        match self {
            Value::Number(x) => Some(vec![*x]),
            Value::List(items) => {
                let mut out = Vec::new();
                for v in items {
                    out.extend(v.numbers()?);
                }
                Some(out)
            }
            _ => None,
        }
    }

    pub(super) fn strings(&self) -> Option<Vec<String>> {
        match self {
            Value::List(items) => items
                .iter()
                .map(|v| match v {
                    Value::Str(s) | Value::Ident(s) => Some(s.clone()),
                    _ => None,
                })
                .collect(),
            _ => None,
        }
    }
}

/// An attribute (or a relationship, type `rel`, whose default holds its
/// target paths): its default value, its time samples (time code, value)
/// and its metadata (`interpolation`, `elementSize` of a primvar).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub(super) struct Attribute {
    pub(super) type_name: String,
    pub(super) default: Option<Value>,
    pub(super) samples: Vec<(f64, Value)>,
    pub(super) metadata: Vec<(String, Value)>,
}

impl Attribute {
    /// How many 3-vectors its default (else its first sample) holds: a
    /// mesh's point count.
    pub(super) fn vector_count(&self) -> usize {
        self.default
            .as_ref()
            .or(self.samples.first().map(|(_, v)| v))
            .and_then(Value::numbers)
            .map_or(0, |p| p.len() / 3)
    }

    /// A metadata entry by key.
    pub(super) fn meta(&self, key: &str) -> Option<&Value> {
        self.metadata.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }
}

/// A prim: its type, attributes by name, and children.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub(super) struct Prim {
    pub(super) name: String,
    pub(super) type_name: String,
    pub(super) attributes: Vec<(String, Attribute)>,
    pub(super) children: Vec<Prim>,
    /// A PointInstancer's deactivated instances: its composed
    /// `inactiveIds` list op (prim metadata, UsdGeom's `DeactivateIds`),
    /// sorted.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(super) inactive_ids: Vec<i64>,
}

/// The items of an `SdfInt64ListOp` as one layer's opinion edits the
/// `current` items of weaker ones (Sdf's list editing): an explicit list
/// replaces them; otherwise the deleted items go and the added,
/// prepended and appended ones join (order is not kept: the ids are a
/// set). Returned sorted, without repeats.
pub(super) fn edit_id_list(current: &[i64], op: &IdListOp) -> Vec<i64> {
    let mut out: Vec<i64> = match &op.explicit {
        Some(items) => items.clone(),
        None => current
            .iter()
            .copied()
            .filter(|i| !op.deleted.contains(i))
            .chain(op.added.iter().copied())
            .collect(),
    };
    out.sort_unstable();
    out.dedup();
    out
}

/// One layer's opinion of an id list op: its explicit items, or the items
/// it deletes and those it adds (add, prepend and append alike).
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct IdListOp {
    pub(super) explicit: Option<Vec<i64>>,
    pub(super) deleted: Vec<i64>,
    pub(super) added: Vec<i64>,
}

impl Prim {
    pub(super) fn attribute(&self, name: &str) -> Option<&Attribute> {
        self.attributes
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, a)| a)
    }

    /// A Mesh's faces as triangles (each face a fan from its first
    /// vertex), from its `faceVertexCounts` and `faceVertexIndices`.
    pub(super) fn triangles(&self) -> Result<Vec<[u32; 3]>, String> {
        let numbers = |name: &str| {
            self.attribute(name)
                .and_then(|a| a.default.as_ref())
                .and_then(Value::numbers)
                .unwrap_or_default()
        };
        let (counts, indices) = (numbers("faceVertexCounts"), numbers("faceVertexIndices"));
        // Every count and index is checked before anything is sized by
        // them: a cast alone turns -1 into 0 and 1e300 into a huge count.
        let mut total = 0usize;
        for (k, &c) in counts.iter().enumerate() {
            if !(c.fract() == 0.0 && (3.0..=u32::MAX as f64).contains(&c)) {
                return Err(format!(
                    "mesh `{}`: `faceVertexCounts` [{k}] is {}; a face has a whole number \
                     of vertices, at least 3",
                    self.name,
                    shown(c)
                ));
            }
            total = total.saturating_add(c as usize);
        }
        if total != indices.len() {
            return Err(format!(
                "mesh `{}`: `faceVertexCounts` add up to {total} vertices but \
                 `faceVertexIndices` holds {}",
                self.name,
                indices.len()
            ));
        }
        if let Some((k, i)) = indices
            .iter()
            .enumerate()
            .find(|(_, i)| !(i.fract() == 0.0 && (0.0..=u32::MAX as f64).contains(*i)))
        {
            return Err(format!(
                "mesh `{}`: `faceVertexIndices` [{k}] is {}, not a point's index",
                self.name,
                shown(*i)
            ));
        }
        // A fan of c - 2 triangles a face: fewer than the indices.
        let mut triangles = Vec::with_capacity(indices.len());
        let mut at = 0usize;
        for c in counts {
            let c = c as usize;
            for k in 1..c - 1 {
                triangles.push([
                    indices[at] as u32,
                    indices[at + k] as u32,
                    indices[at + k + 1] as u32,
                ]);
            }
            at += c;
        }
        Ok(triangles)
    }
}

/// A number read from a file, for an error: short even when huge (`1e300`).
fn shown(x: f64) -> String {
    if x.abs() < 1e9 {
        x.to_string()
    } else {
        format!("{x:e}")
    }
}

/// The parser over the tokens, with the line of each for errors.
struct Parser {
    tokens: Vec<(Token, usize)>,
    at: usize,
}

/// The list-editing words that may precede a property (`prepend rel
/// proxyPrim`) or a metadata key (`prepend apiSchemas = …`).
const LIST_OPS: [&str; 5] = ["prepend", "append", "add", "delete", "reorder"];

/// Composition arcs this single-layer reader cannot honour.
const COMPOSED: [&str; 6] = [
    "subLayers",
    "references",
    "payload",
    "inherits",
    "specializes",
    "variantSets",
];

impl Parser {
    fn peek(&self) -> Option<&Token> {
        self.tokens.get(self.at).map(|(t, _)| t)
    }

    fn line(&self) -> usize {
        self.tokens
            .get(self.at.min(self.tokens.len().saturating_sub(1)))
            .map_or(0, |(_, l)| *l)
    }

    fn next(&mut self) -> Result<Token, String> {
        let t = self
            .tokens
            .get(self.at)
            .map(|(t, _)| t.clone())
            .ok_or_else(|| "the file ends in the middle of a statement".to_string())?;
        self.at += 1;
        Ok(t)
    }

    fn expect(&mut self, c: char) -> Result<(), String> {
        let line = self.line();
        match self.next()? {
            Token::Punct(p) if p == c => Ok(()),
            t => Err(format!("line {line}: expected `{c}`, found {t:?}")),
        }
    }

    fn is(&self, c: char) -> bool {
        self.peek() == Some(&Token::Punct(c))
    }

    /// A value: a number, string, token, path, `( … )`, `[ … ]` or `{ … }`.
    fn value(&mut self) -> Result<Value, String> {
        let line = self.line();
        match self.next()? {
            Token::Number(x) => Ok(Value::Number(x)),
            Token::Str(s) => Ok(Value::Str(s)),
            Token::Ident(s) => Ok(Value::Ident(s)),
            Token::Path(s) => Ok(Value::Path(s)),
            Token::Punct(open @ ('(' | '[')) => {
                let close = if open == '(' { ')' } else { ']' };
                let mut items = Vec::new();
                while !self.is(close) {
                    items.push(self.value()?);
                    if !self.is(close) {
                        self.expect(',')?;
                    }
                }
                self.expect(close)?;
                Ok(Value::List(items))
            }
            Token::Punct('{') => {
                // `key: value,` (time samples) or `type name = value`
                // (a dictionary in metadata).
                let mut entries = Vec::new();
                while !self.is('}') {
                    let mut key = self.value()?;
                    if self.is(':') {
                        self.expect(':')?;
                    } else {
                        // A typed dictionary entry: `type name = value`,
                        // keyed by its name.
                        key = self.value()?;
                        self.expect('=')?;
                    }
                    let v = self.value()?;
                    entries.push((key, v));
                    if self.is(',') || self.is(';') {
                        self.next()?;
                    }
                }
                self.expect('}')?;
                Ok(Value::Dict(entries))
            }
            t => Err(format!("line {line}: expected a value, found {t:?}")),
        }
    }

    /// Metadata in `( … )`: `key = value` entries, list-edited ones
    /// (`prepend key = value`) and a bare doc string; returns the keys with
    /// their values.
    fn metadata(&mut self) -> Result<Vec<(String, Value)>, String> {
        Ok(self
            .edited_metadata()?
            .into_iter()
            .map(|(_, key, value)| (key, value))
            .collect())
    }

    /// [`Self::metadata`], each entry with the list-editing word before its
    /// key (`delete`, `prepend`, …; `None` for a plain `key = value`).
    fn edited_metadata(&mut self) -> Result<Vec<(Option<String>, String, Value)>, String> {
        self.expect('(')?;
        let mut out = Vec::new();
        while !self.is(')') {
            let line = self.line();
            match self.next()? {
                Token::Str(_) => {}
                Token::Ident(first) => {
                    // After a list-editing word (`prepend apiSchemas`) or
                    // a type (`dictionary customData`), the last word is
                    // the key.
                    let mut key = first.clone();
                    while let Some(Token::Ident(k)) = self.peek().cloned() {
                        self.next()?;
                        key = k;
                    }
                    let edit =
                        (key != first && LIST_OPS.contains(&first.as_str())).then_some(first);
                    self.expect('=')?;
                    out.push((edit, key, self.value()?));
                }
                t => return Err(format!("line {line}: unexpected {t:?} in metadata")),
            }
            if self.is(';') || self.is(',') {
                self.next()?;
            }
        }
        self.expect(')')?;
        Ok(out)
    }

    /// `def TYPE "name" (meta) { … }` after its specifier; `None` for a
    /// prim USD's default traversal leaves out with all below it: a
    /// `class` (abstract; in a layer that composes nothing, as this reader
    /// requires, nothing inherits from it) or one authored `active = false`.
    fn prim(&mut self, specifier: &str) -> Result<Option<Prim>, String> {
        let line = self.line();
        if specifier == "over" {
            return Err(format!(
                "line {line}: `over` prims compose onto others, which this reader does not do"
            ));
        }
        let mut shown = specifier == "def";
        let mut prim = Prim::default();
        if let Some(Token::Ident(t)) = self.peek() {
            prim.type_name = t.clone();
            self.next()?;
        }
        prim.name = match self.next()? {
            Token::Str(s) => s,
            t => {
                return Err(format!(
                    "line {line}: expected the prim's name, found {t:?}"
                ));
            }
        };
        if self.is('(') {
            for (edit, key, value) in self.edited_metadata()? {
                if key == "active" && matches!(&value, Value::Ident(v) if v == "false") {
                    shown = false;
                }
                if key == "inactiveIds" {
                    let ids = value
                        .numbers()
                        .filter(|v| v.iter().all(|x| x.fract() == 0.0))
                        .ok_or_else(|| {
                            format!(
                                "line {line}: prim `{}`: `inactiveIds` is not a list of ids",
                                prim.name
                            )
                        })?;
                    let ids: Vec<i64> = ids.iter().map(|&x| x as i64).collect();
                    // One layer over nothing: a deletion has nothing to
                    // delete from, so only the others count.
                    let op = match edit.as_deref() {
                        None => IdListOp {
                            explicit: Some(ids),
                            ..IdListOp::default()
                        },
                        Some("delete" | "reorder") => IdListOp::default(),
                        Some(_) => IdListOp {
                            added: ids,
                            ..IdListOp::default()
                        },
                    };
                    prim.inactive_ids = edit_id_list(&prim.inactive_ids, &op);
                }
                if COMPOSED.contains(&key.as_str()) {
                    return Err(format!(
                        "line {line}: prim `{}` has `{key}`, a composition this reader does not do",
                        prim.name
                    ));
                }
            }
        }
        self.expect('{')?;
        while !self.is('}') {
            let line = self.line();
            match self.next()? {
                Token::Ident(w) if matches!(w.as_str(), "def" | "over" | "class") => {
                    prim.children.extend(self.prim(&w)?)
                }
                Token::Ident(w) if w == "variantSet" => {
                    return Err(format!(
                        "line {line}: prim `{}` has a variant set, a composition this reader does not do",
                        prim.name
                    ));
                }
                Token::Ident(w) => self.property(&mut prim, w)?,
                t => {
                    return Err(format!(
                        "line {line}: unexpected {t:?} in prim `{}`",
                        prim.name
                    ));
                }
            }
        }
        self.expect('}')?;
        Ok(shown.then_some(prim))
    }

    /// A property statement whose first word is `first`: qualifiers, a type
    /// (or `rel`), a name (with `.timeSamples`, `.connect`), an optional
    /// `= value` and optional metadata.
    fn property(&mut self, prim: &mut Prim, first: String) -> Result<(), String> {
        let line = self.line();
        let mut word = first;
        while LIST_OPS.contains(&word.as_str())
            || matches!(word.as_str(), "custom" | "uniform" | "varying")
        {
            word = match self.next()? {
                Token::Ident(w) => w,
                t => return Err(format!("line {line}: expected a type, found {t:?}")),
            };
        }
        let mut type_name = word;
        if self.is('[') {
            self.expect('[')?;
            self.expect(']')?;
            type_name.push_str("[]");
        }
        let name = match self.next()? {
            Token::Ident(n) => n,
            t => {
                return Err(format!(
                    "line {line}: expected a property name, found {t:?}"
                ));
            }
        };
        let value = if self.is('=') {
            self.expect('=')?;
            Some(self.value()?)
        } else {
            None
        };
        let metadata = if self.is('(') {
            self.metadata()?
        } else {
            Vec::new()
        };
        let (base, samples) = match name.strip_suffix(".timeSamples") {
            Some(b) => (b.to_string(), true),
            None => (name.clone(), false),
        };
        if base.contains('.') {
            return Ok(()); // connections, splines: not motion
        }
        let at = match prim.attributes.iter().position(|(n, _)| *n == base) {
            Some(k) => k,
            None => {
                prim.attributes.push((base.clone(), Attribute::default()));
                prim.attributes.len() - 1
            }
        };
        let attr = &mut prim.attributes[at].1;
        attr.type_name = type_name;
        attr.metadata.extend(metadata);
        match (samples, value) {
            (true, Some(Value::Dict(entries))) => {
                for (t, v) in entries {
                    let Value::Number(t) = t else {
                        return Err(format!(
                            "line {line}: `{base}`: a time sample's time is not a number"
                        ));
                    };
                    attr.samples.push((t, v));
                }
                attr.samples.sort_by(|a, b| a.0.total_cmp(&b.0));
            }
            (true, _) => {
                return Err(format!(
                    "line {line}: `{name}` is not a dictionary of samples"
                ));
            }
            (false, v) => attr.default = v,
        }
        Ok(())
    }
}

/// The stage as read: its metadata and root prims.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct Layer {
    /// Whether the stage's up axis is y (USD's default), else z.
    pub(super) up_y: bool,
    /// Metres per unit of length (0.01 by default).
    pub(super) meters_per_unit: f64,
    /// Time codes per second (24 by default).
    pub(super) time_codes_per_second: f64,
    /// The root prims.
    pub(super) roots: Vec<Prim>,
}

/// A stage's metadata as authored (`None` where unset), which
/// [`StageMetadata::layer`] reads with USD's defaults: what the text reader
/// and [`super::stage`] each find in a layer's header.
#[derive(Debug, Default)]
pub(super) struct StageMetadata {
    pub(super) up_axis: Option<String>,
    pub(super) meters_per_unit: Option<f64>,
    pub(super) time_codes_per_second: Option<f64>,
    pub(super) frames_per_second: Option<f64>,
}

impl StageMetadata {
    /// The layer of `roots` under this metadata: y up unless the axis is
    /// Z, 0.01 m a unit, and time codes per second, else frames per
    /// second, else 24 (USD's rules); units that are not positive are
    /// refused.
    pub(super) fn layer(self, roots: Vec<Prim>) -> Result<Layer, String> {
        let layer = Layer {
            up_y: self.up_axis.is_none_or(|a| a != "Z"),
            meters_per_unit: self.meters_per_unit.unwrap_or(0.01),
            time_codes_per_second: self
                .time_codes_per_second
                .or(self.frames_per_second)
                .unwrap_or(24.0),
            roots,
        };
        if !(layer.meters_per_unit > 0.0 && layer.time_codes_per_second > 0.0) {
            return Err("metersPerUnit and timeCodesPerSecond must be positive".to_string());
        }
        Ok(layer)
    }
}

/// What a USD file that is not text is, by its first bytes (a binary crate
/// file, a USDZ package), with what to do about it, or `None` for text.
pub(super) fn stored_binary(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"PXR-USDC") {
        Some(
            "a binary USD crate file; write it as text with Pixar's `usdcat --flatten IN -o OUT.usda` (pip install usd-core)",
        )
    } else if bytes.starts_with(b"PK") {
        Some(
            "a USDZ package (a zip archive): unzip it and read the .usda inside, or flatten it with Pixar's `usdcat --flatten IN -o OUT.usda` (pip install usd-core)",
        )
    } else {
        None
    }
}

/// Whether `text` asks for a composition this reader refuses (a
/// composition arc in any metadata, a variant set, an `over`): what
/// [`super::stage`] then composes.
pub(super) fn composes(text: &str) -> bool {
    tokens(text).is_ok_and(|ts| {
        ts.iter().any(|(t, _)| {
            matches!(t, Token::Ident(w) if COMPOSED.contains(&w.as_str()) || w == "variantSet" || w == "over")
        })
    })
}

/// The deepest nesting of brackets (`( [ {`, a prim's body among them)
/// USD text may have. The parser recurses once a level, and so do the
/// walks over the prims read; 25,000 levels overflowed the stack. Real
/// layers nest prims a few dozen deep and values three or four.
pub(super) const MAX_NESTING: usize = 128;

/// `Err` naming the line where `tokens` nest deeper than [`MAX_NESTING`].
fn check_nesting(tokens: &[(Token, usize)]) -> Result<(), String> {
    let mut depth = 0usize;
    for (t, line) in tokens {
        match t {
            Token::Punct('(' | '[' | '{') => {
                depth += 1;
                if depth > MAX_NESTING {
                    return Err(format!(
                        "nesting deeper than {MAX_NESTING} levels at line {line} \
                         (prims and brackets inside one another)"
                    ));
                }
            }
            Token::Punct(')' | ']' | '}') => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    Ok(())
}

/// [`check_nesting`] of USD text, for text handed to the composing reader
/// (whose own parser recurses likewise).
pub(super) fn check_text_nesting(text: &str) -> Result<(), String> {
    check_nesting(&tokens(text)?)
}

pub(super) fn parse(text: &str) -> Result<Layer, String> {
    if let Some(what) = stored_binary(text.as_bytes()) {
        return Err(what.to_string());
    }
    if !text.starts_with("#usda") {
        return Err("not USD text: its first line is not `#usda 1.0`".to_string());
    }
    let tokens = tokens(text)?;
    check_nesting(&tokens)?;
    let mut p = Parser { tokens, at: 0 };
    let mut meta = StageMetadata::default();
    if p.is('(') {
        for (key, v) in p.metadata()? {
            match (key.as_str(), &v) {
                ("upAxis", Value::Str(a)) => meta.up_axis = Some(a.clone()),
                ("metersPerUnit", Value::Number(m)) => meta.meters_per_unit = Some(*m),
                ("timeCodesPerSecond", Value::Number(r)) => meta.time_codes_per_second = Some(*r),
                ("framesPerSecond", Value::Number(r)) => meta.frames_per_second = Some(*r),
                (k, _) if COMPOSED.contains(&k) => {
                    return Err(format!(
                        "the layer has `{k}`, a composition this reader does not do"
                    ));
                }
                _ => {}
            }
        }
    }
    let mut roots = Vec::new();
    while let Some(t) = p.peek().cloned() {
        let line = p.line();
        match t {
            Token::Ident(w) if matches!(w.as_str(), "def" | "over" | "class") => {
                p.next()?;
                roots.extend(p.prim(&w)?);
            }
            t => return Err(format!("line {line}: expected a prim, found {t:?}")),
        }
    }
    meta.layer(roots)
}

/// The value of `a` at time code `t` held from the last sample at or
/// before it (the first sample before them all), else the default: how
/// USD resolves what cannot be interpolated, such as the integer arrays
/// (ids, prototype indices) of a PointInstancer.
pub(super) fn held(a: &Attribute, t: f64) -> Option<Vec<f64>> {
    if a.samples.is_empty() {
        return a.default.as_ref()?.numbers();
    }
    let j = a.samples.partition_point(|(s, _)| *s <= t);
    a.samples[j.saturating_sub(1)].1.numbers()
}

/// The value of `a` at time code `t`: interpolated linearly between the
/// samples around it (slerp for quaternions), held outside them, else the
/// default.
pub(super) fn sample(a: &Attribute, t: f64) -> Option<Vec<f64>> {
    if a.samples.is_empty() {
        return a.default.as_ref()?.numbers();
    }
    let j = a.samples.partition_point(|(s, _)| *s <= t);
    if j == 0 {
        return a.samples[0].1.numbers();
    }
    if j == a.samples.len() {
        return a.samples[j - 1].1.numbers();
    }
    let ((t0, v0), (t1, v1)) = (&a.samples[j - 1], &a.samples[j]);
    let (x, y) = (v0.numbers()?, v1.numbers()?);
    let s = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
    if s == 0.0 || x.len() != y.len() {
        return Some(x);
    }
    if a.type_name.starts_with("quat") && x.len() % 4 == 0 {
        // One quaternion (an `orient` op) or an array of them (a
        // SkelAnimation's joint rotations), each by slerp.
        let q =
            |v: &[f64]| UnitQuaternion::from_quaternion(Quaternion::new(v[0], v[1], v[2], v[3]));
        return Some(
            x.chunks(4)
                .zip(y.chunks(4))
                .flat_map(|(a, b)| {
                    let r = q(a).slerp(&q(b), s);
                    [r.w, r.i, r.j, r.k]
                })
                .collect(),
        );
    }
    Some(x.iter().zip(&y).map(|(a, b)| a + (b - a) * s).collect())
}

/// Rotation by `deg` degrees about axis `k` (0 x, 1 y, 2 z).
fn about(k: usize, deg: f64) -> Matrix3<f64> {
    let axis = [V3::x_axis(), V3::y_axis(), V3::z_axis()][k];
    *Rotation3::from_axis_angle(&axis, deg.to_radians()).matrix()
}

fn homogeneous(m: Matrix3<f64>, t: V3) -> M4 {
    let mut h = M4::identity();
    h.fixed_view_mut::<3, 3>(0, 0).copy_from(&m);
    h.fixed_view_mut::<3, 1>(0, 3).copy_from(&t);
    h
}

/// The transform of the last prim of `chain` (the prims from the root down
/// to it) at time code `t`: each one's local transform composed on its
/// parents', unless its order resets them.
pub(super) fn world_transform(chain: &[&Prim], t: f64) -> Result<M4, String> {
    let mut world = M4::identity();
    for prim in chain {
        let (local, reset) = local_transform(prim, t)?;
        world = if reset { local } else { world * local };
    }
    Ok(world)
}

/// A prim's local transform at time code `t` (column vectors: the first op
/// of `xformOpOrder` is applied last, as USD composes them), and whether
/// its order resets the parents' transforms.
pub(super) fn local_transform(prim: &Prim, t: f64) -> Result<(M4, bool), String> {
    let Some(order) = prim.attribute("xformOpOrder") else {
        return Ok((M4::identity(), false));
    };
    let names = order
        .default
        .as_ref()
        .and_then(Value::strings)
        .ok_or_else(|| format!("prim `{}`: xformOpOrder is not a list of names", prim.name))?;
    let mut m = M4::identity();
    let mut reset = false;
    for name in names {
        if name == "!resetXformStack!" {
            reset = true;
            m = M4::identity();
            continue;
        }
        let (invert, op) = match name.strip_prefix("!invert!") {
            Some(op) => (true, op.to_string()),
            None => (false, name.clone()),
        };
        let attr = prim.attribute(&op).ok_or_else(|| {
            format!(
                "prim `{}`: xformOpOrder names `{op}`, which it lacks",
                prim.name
            )
        })?;
        let v = sample(attr, t)
            .ok_or_else(|| format!("prim `{}`: `{op}` has no numeric value", prim.name))?;
        let kind = op
            .strip_prefix("xformOp:")
            .and_then(|k| k.split(':').next())
            .unwrap_or("");
        let need = |n: usize| -> Result<(), String> {
            if v.len() == n {
                Ok(())
            } else {
                Err(format!(
                    "prim `{}`: `{op}` has {} numbers, expected {n}",
                    prim.name,
                    v.len()
                ))
            }
        };
        let op_m = match kind {
            "translate" => {
                need(3)?;
                homogeneous(Matrix3::identity(), V3::new(v[0], v[1], v[2]))
            }
            "scale" => {
                need(3)?;
                homogeneous(
                    Matrix3::from_diagonal(&V3::new(v[0], v[1], v[2])),
                    V3::zeros(),
                )
            }
            "rotateX" | "rotateY" | "rotateZ" => {
                need(1)?;
                let k = (kind.as_bytes()[6] - b'X') as usize;
                homogeneous(about(k, v[0]), V3::zeros())
            }
            "orient" => {
                need(4)?;
                let q = UnitQuaternion::from_quaternion(Quaternion::new(v[0], v[1], v[2], v[3]));
                homogeneous(*q.to_rotation_matrix().matrix(), V3::zeros())
            }
            "transform" => {
                need(16)?;
                // USD's matrices act on row vectors (translation in the
                // last row): ours on columns, so the transpose.
                M4::from_row_slice(&v).transpose()
            }
            k if k.len() == 9 && k.starts_with("rotate") => {
                need(3)?;
                // rotateXYZ turns about x first, then y, then z.
                let mut r = Matrix3::identity();
                for axis in k[6..].bytes() {
                    let a = axis.wrapping_sub(b'X') as usize;
                    if a > 2 {
                        return Err(format!("prim `{}`: unknown op `{op}`", prim.name));
                    }
                    r = about(a, v[a]) * r;
                }
                homogeneous(r, V3::zeros())
            }
            _ => return Err(format!("prim `{}`: unknown op `{op}`", prim.name)),
        };
        let op_m = if invert {
            op_m.try_inverse()
                .ok_or_else(|| format!("prim `{}`: `{op}` cannot be inverted", prim.name))?
        } else {
            op_m
        };
        m *= op_m;
    }
    Ok((m, reset))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nesting_is_bounded_with_the_line_named() {
        let deep = format!(
            "#usda 1.0\n\ndef \"a\" {{ double[] x = {}1{} }}\n",
            "[".repeat(25_000),
            "]".repeat(25_000)
        );
        let e = parse(&deep).unwrap_err();
        assert!(
            e.contains("nesting deeper than 128 levels at line 3"),
            "{e}"
        );
        let mut defs = String::from("#usda 1.0\n");
        for k in 0..20_000 {
            defs.push_str(&format!("def \"p{k}\" {{\n"));
        }
        defs.push_str(&"}\n".repeat(20_000));
        let e = parse(&defs).unwrap_err();
        assert!(
            e.contains("nesting deeper than 128 levels at line 130"),
            "{e}"
        );
        // Up to the bound, read.
        let mut ok = String::from("#usda 1.0\n");
        for k in 0..MAX_NESTING {
            ok.push_str(&format!("def \"p{k}\" {{\n"));
        }
        ok.push_str(&"}\n".repeat(MAX_NESTING));
        assert!(parse(&ok).is_ok());
    }

    #[test]
    fn face_counts_are_checked_before_use() {
        let mesh = |counts: &str, indices: &str| {
            let text = format!(
                "#usda 1.0\ndef Mesh \"m\" {{ int[] faceVertexCounts = {counts}\n int[] faceVertexIndices = {indices} }}\n"
            );
            parse(&text).unwrap().roots[0].triangles()
        };
        assert_eq!(mesh("[4]", "[0, 1, 2, 3]").unwrap(), [[0, 1, 2], [0, 2, 3]]);
        assert!(mesh("[]", "[]").unwrap().is_empty());
        for (counts, indices, want) in [
            ("[-3]", "[0, 1, 2]", "`faceVertexCounts` [0] is -3"),
            ("[3, 2]", "[0, 1, 2, 0, 1]", "`faceVertexCounts` [1] is 2"),
            ("[3.5]", "[0, 1, 2]", "is 3.5"),
            ("[1e300]", "[0, 1, 2]", "is 1e300"),
            (
                "[3]",
                "[0, 1, 2, 3]",
                "add up to 3 vertices but `faceVertexIndices` holds 4",
            ),
            ("[3]", "[0, -1, 2]", "`faceVertexIndices` [1] is -1"),
            ("[3]", "[0, 1, 5e9]", "`faceVertexIndices` [2] is 5e9"),
        ] {
            let e = mesh(counts, indices).unwrap_err();
            assert!(e.contains("mesh `m`") && e.contains(want), "{counts}: {e}");
        }
    }

    #[test]
    fn rotate_xyz_turns_about_x_first_and_matrices_are_row_vectors() {
        let attr = |t: &str, v: Value| Attribute {
            type_name: t.to_string(),
            default: Some(v),
            samples: vec![],
            metadata: vec![],
        };
        let n = |x: f64| Value::Number(x);
        let prim = Prim {
            inactive_ids: vec![],
            name: "p".into(),
            type_name: "Xform".into(),
            attributes: vec![
                (
                    "xformOp:rotateXYZ".into(),
                    attr("float3", Value::List(vec![n(90.0), n(90.0), n(0.0)])),
                ),
                (
                    "xformOpOrder".into(),
                    attr(
                        "token[]",
                        Value::List(vec![Value::Str("xformOp:rotateXYZ".into())]),
                    ),
                ),
            ],
            children: vec![],
        };
        let (m, _) = local_transform(&prim, 0.0).unwrap();
        // y about x by 90° → z; then z about y by 90° → x.
        let y = m.transform_vector(&V3::y());
        assert!((y - V3::x()).norm() < 1e-12, "{y}");
        // A transform op: translation (1, 2, 3) in the last row.
        let mut row = vec![1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        row.extend([1.0, 2.0, 3.0, 1.0]);
        let prim = Prim {
            attributes: vec![
                (
                    "xformOp:transform".into(),
                    attr("matrix4d", Value::List(row.into_iter().map(n).collect())),
                ),
                (
                    "xformOpOrder".into(),
                    attr(
                        "token[]",
                        Value::List(vec![Value::Str("!invert!xformOp:transform".into())]),
                    ),
                ),
            ],
            ..prim
        };
        let (m, _) = local_transform(&prim, 0.0).unwrap();
        let p = m.transform_point(&V3::zeros().into());
        assert!((p.coords - V3::new(-1.0, -2.0, -3.0)).norm() < 1e-12);
    }

    #[test]
    fn composed_and_binary_layers_are_refused_by_name() {
        let e = parse("PXR-USDC\0\0").unwrap_err();
        assert!(e.contains("usdcat"), "{e}");
        let e = parse("#usda 1.0\ndef Xform \"a\" (\n    references = @other.usda@\n)\n{\n}\n")
            .unwrap_err();
        assert!(e.contains("references") && e.contains("line 2"), "{e}");
        let e = parse("#usda 1.0\nover \"a\" {\n}\n").unwrap_err();
        assert!(e.contains("`over`"), "{e}");
        let e = parse("#usda 1.0\ndef Xform \"a\" {\n  double3 xformOp:translate = (1, 2\n}\n")
            .unwrap_err();
        assert!(e.contains("line"), "{e}");
        // What is refused for composing is what `composes` sends on to
        // openusd; a malformed layer is not.
        for text in [
            "#usda 1.0\ndef Xform \"a\" (\n    references = @other.usda@\n)\n{\n}\n",
            "#usda 1.0\n(\n    subLayers = [@anim.usda@]\n)\n",
            "#usda 1.0\nover \"a\" {\n}\n",
            "#usda 1.0\ndef \"a\" {\n variantSet \"v\" = {\n }\n}\n",
        ] {
            assert!(parse(text).is_err() && composes(text), "{text}");
        }
        assert!(!composes(
            "#usda 1.0\ndef Xform \"a\" {\n  double3 x = (1, 2\n}\n"
        ));
    }

    /// A `class` (abstract) and an inactive prim are left out with all
    /// below them, as USD's default traversal leaves them.
    #[test]
    fn classes_and_inactive_prims_are_left_out() {
        let layer = parse(
            "#usda 1.0\nclass \"_paper\" {\n def Mesh \"m\" {\n }\n}\n\
             def Xform \"a\" {\n def Xform \"off\" (\n active = false\n ) {\n def Mesh \"m\" {\n }\n }\n\
             def Xform \"on\" (\n active = true\n ) {\n }\n}\n",
        )
        .unwrap();
        assert_eq!(layer.roots.len(), 1);
        assert_eq!(layer.roots[0].name, "a");
        let kept: Vec<&str> = layer.roots[0]
            .children
            .iter()
            .map(|c| c.name.as_str())
            .collect();
        assert_eq!(kept, ["on"]);
    }

    #[test]
    fn deactivated_instance_ids_follow_sdf_list_editing() {
        let ids = |meta: &str| {
            let text = format!("#usda 1.0\ndef PointInstancer \"i\" (\n{meta}\n) {{\n}}\n");
            parse(&text).map(|l| l.roots[0].inactive_ids.clone())
        };
        assert_eq!(ids("append inactiveIds = [5, 3]").unwrap(), [3, 5]);
        assert_eq!(ids("inactiveIds = [9, 9, -1]").unwrap(), [-1, 9]);
        // Over nothing, a deletion deletes nothing, and a reordering adds
        // nothing.
        assert_eq!(
            ids("prepend inactiveIds = [1, 2]\ndelete inactiveIds = [2]").unwrap(),
            [1, 2]
        );
        assert!(ids("delete inactiveIds = [2]").unwrap().is_empty());
        assert!(ids("reorder inactiveIds = [2]").unwrap().is_empty());
        assert!(ids("doc = \"no ids\"").unwrap().is_empty());
        let err = ids("inactiveIds = [1.5]").unwrap_err();
        assert!(err.contains("`inactiveIds` is not a list of ids"), "{err}");
        // Layer over layer (the crate reader's prim stacks): an explicit
        // list replaces the weaker ones', deletions remove from them.
        let op = |explicit: Option<Vec<i64>>, deleted: Vec<i64>, added: Vec<i64>| IdListOp {
            explicit,
            deleted,
            added,
        };
        let weak = edit_id_list(&[], &op(None, vec![], vec![4, 2]));
        assert_eq!(weak, [2, 4]);
        assert_eq!(edit_id_list(&weak, &op(None, vec![4], vec![7])), [2, 7]);
        assert_eq!(edit_id_list(&weak, &op(Some(vec![8]), vec![], vec![])), [8]);
    }
}
