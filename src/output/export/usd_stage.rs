//! A USD stage that the text reader ([`super::usd_layer`]) does not read
//! alone: a binary crate file (`.usdc`, or a `.usd` holding one), a USDZ
//! package, or layers that need composing (sublayers, references,
//! payloads, inherits, specializes, variant sets). The openusd crate opens
//! and composes it (LIVRPS strength order, layer offsets on references
//! and sublayers, variant selections); this module reads the composed
//! prims back as one flat [`Layer`], as Pixar's `usdcat --flatten` would
//! write it, so that the meshes, transforms and skins are read by the same
//! code as a text layer's.
//!
//! What is kept of each prim: its name, type, attributes (type, default,
//! time samples, `interpolation` and `elementSize`) and relationships
//! (their composed targets). Prims that are not defined (`over` alone),
//! abstract (`class`) or inactive are left out, as USD's default traversal
//! does. Stage metadata (`upAxis`, `metersPerUnit`, `timeCodesPerSecond`,
//! `framesPerSecond`) is the root layer's, as in USD.
//!
//! Single-precision values are read as the shortest decimal that gives
//! them back, which is what USD writes for them in text: a `.usdc` and the
//! `.usda` that `usdcat` writes of it then read to the same bits.
//!
//! openusd 0.6 trusts the counts and offsets a crate file gives: a damaged
//! one made it index out of bounds, or ask for an allocation of exabytes,
//! which aborts the process (24 of 400 crate files of the test data with
//! bytes flipped, cut or overwritten at random). So it runs in a child
//! process, the leafmagic
//! executable's hidden `compose-usd` command ([`compose_usd_stage`]), which
//! hands the flat layer back as JSON; whatever becomes of the child, the
//! reader ends with an error that names the file.
//! (openusd 0.8 bounds those counts, but needs Rust 1.96.)

use super::usd_layer::{Attribute, IdListOp, Layer, Prim, StageMetadata, Value, edit_id_list};
use crate::util::confined::ReadScope;
use openusd::{gf, sdf, usd};
use std::path::Path;
use std::process::Command;

/// The composed stage at `path` as one flat layer, read in a child process
/// (the module docs say why), or why it cannot be read.
pub(super) fn flatten(path: &Path, _scope: &ReadScope) -> Result<Layer, String> {
    let program = std::env::current_exe()
        .map_err(|e| format!("cannot find the leafmagic executable to read USD with: {e}"))?;
    let out = reader(&program, path)
        .env("RUST_BACKTRACE", "0")
        .output()
        .map_err(|e| format!("cannot start {} to read USD: {e}", program.display()))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    let said = stderr.trim();
    match out.status.code() {
        Some(0) => serde_json::from_slice(&out.stdout)
            .map_err(|e| format!("the USD reader's answer did not read back: {e}")),
        Some(1) if !said.is_empty() => Err(said.to_string()),
        _ => Err(format!(
            "the USD library (openusd) stopped on it ({}{}): it is probably damaged; \
             Pixar's `usdcat --flatten IN -o OUT.usda` (pip install usd-core) says what is \
             wrong with it, and leafmagic reads what that writes",
            out.status,
            // What the runtime says when a count read from the file asked
            // for more memory than there is.
            said.lines()
                .find(|l| l.starts_with("memory allocation of"))
                .map_or(String::new(), |l| format!(": {l}"))
        )),
    }
}

/// Address space the child may take: [`MEMORY_BASE`] and
/// [`MEMORY_PER_BYTE`] times the file's size. A damaged crate file of
/// 1 kB otherwise had openusd fill gigabytes before failing (25 s); with
/// the cap the allocation fails at once and the file is refused. A 30 MB
/// point cache needs 0.6 GB.
const MEMORY_BASE: u64 = 2 << 30;

/// See [`MEMORY_BASE`]: the most a crate file's LZ4 and integer coding
/// expand by, with room for openusd's own structures.
const MEMORY_PER_BYTE: u64 = 400;

/// The command that reads `path` in a child process: `program compose-usd
/// PATH`, under a cap on its address space where a POSIX shell can set one
/// (`ulimit -v`).
fn reader(program: &Path, path: &Path) -> Command {
    let shell = Path::new("/bin/sh");
    if cfg!(unix) && shell.exists() {
        let size = std::fs::metadata(path).map_or(0, |m| m.len());
        let cap_kib = MEMORY_BASE.saturating_add(size.saturating_mul(MEMORY_PER_BYTE)) / 1024;
        let mut cmd = Command::new(shell);
        cmd.arg("-c")
            .arg(r#"ulimit -v "$1" 2>/dev/null; exec "$2" compose-usd "$3""#)
            .arg("sh")
            .arg(cap_kib.to_string())
            .arg(program)
            .arg(path);
        cmd
    } else {
        let mut cmd = Command::new(program);
        cmd.arg("compose-usd").arg(path);
        cmd
    }
}

/// The composed stage at `path` as one flat layer, in JSON: what the
/// hidden `leafmagic compose-usd FILE` prints, in the child process that
/// reads a binary, packaged or composed USD file (the module docs say
/// why). Errors are openusd's own words for a file it cannot open or
/// compose.
pub fn compose_usd_stage(path: &Path) -> Result<String, String> {
    let layer = compose(path)?;
    serde_json::to_string(&layer).map_err(|e| e.to_string())
}

/// The composed stage at `path` as one flat layer, in this process.
fn compose(path: &Path) -> Result<Layer, String> {
    let file = path
        .to_str()
        .ok_or_else(|| "its path is not UTF-8, which the USD reader needs".to_string())?;
    let stage = usd::Stage::open(file).map_err(|e| format!("{e:#}"))?;
    if let Some(e) = stage.composition_errors().first() {
        return Err(format!("it does not compose: {e}"));
    }
    let meta = {
        let root = stage.root_layer();
        let data = root.data();
        let field = |key: &str| {
            data.try_field(&sdf::Path::abs_root(), key)
                .ok()
                .flatten()
                .and_then(|v| value(&v))
        };
        let number = |key: &str| match field(key) {
            Some(Value::Number(x)) => Some(x),
            _ => None,
        };
        StageMetadata {
            up_axis: match field("upAxis") {
                Some(Value::Str(a)) => Some(a),
                _ => None,
            },
            meters_per_unit: number("metersPerUnit"),
            time_codes_per_second: number("timeCodesPerSecond"),
            frames_per_second: number("framesPerSecond"),
        }
    };
    meta.layer(children(&stage.prim(sdf::Path::abs_root()))?)
}

/// An openusd call's error in our words.
fn failed(e: anyhow::Error) -> String {
    format!("{e:#}")
}

/// The composed children of `prim` that a default traversal visits.
fn children(prim: &usd::Prim) -> Result<Vec<Prim>, String> {
    let mut out = Vec::new();
    for child in prim.children().map_err(failed)? {
        let shown = child.is_defined().map_err(failed)?
            && child.is_active().map_err(failed)?
            && !child.is_abstract().map_err(failed)?;
        if shown {
            out.push(flat_prim(&child)?);
        }
    }
    Ok(out)
}

/// A PointInstancer's composed `inactiveIds`: each layer's list op of
/// its prim stack applied over the weaker ones' (openusd 0.6 composes
/// only the metadata it knows of).
fn inactive_ids(prim: &usd::Prim) -> Result<Vec<i64>, String> {
    let stage = prim.stage();
    let mut ids = Vec::new();
    for (layer, path) in prim.prim_stack().map_err(failed)?.iter().rev() {
        let Some(layer) = stage.layer(layer) else {
            continue;
        };
        let field = layer
            .data()
            .try_field(path, "inactiveIds")
            .map_err(|e| format!("its `inactiveIds` in {}: {e}", layer.identifier()))?;
        match field.as_deref() {
            None => {}
            Some(sdf::Value::Int64ListOp(op)) => {
                let op = IdListOp {
                    explicit: op.explicit.then(|| op.explicit_items.clone()),
                    deleted: op.deleted_items.clone(),
                    added: op
                        .added_items
                        .iter()
                        .chain(&op.prepended_items)
                        .chain(&op.appended_items)
                        .copied()
                        .collect(),
                };
                ids = edit_id_list(&ids, &op);
            }
            Some(v) => {
                return Err(format!(
                    "its `inactiveIds` in {} is not a list of ids ({v:?})",
                    layer.identifier()
                ));
            }
        }
    }
    Ok(ids)
}

/// One composed prim and those below it.
fn flat_prim(prim: &usd::Prim) -> Result<Prim, String> {
    let path = prim.path();
    let mut flat = Prim {
        name: path.name().unwrap_or_default().to_string(),
        type_name: prim
            .type_name()
            .map_err(failed)?
            .map(|t| t.as_str().to_string())
            .unwrap_or_default(),
        attributes: Vec::new(),
        children: Vec::new(),
        inactive_ids: Vec::new(),
    };
    let at = |e: String| format!("prim `{path}`: {e}");
    if flat.type_name == "PointInstancer" {
        flat.inactive_ids = inactive_ids(prim).map_err(at)?;
    }
    for a in prim.attributes().map_err(|e| at(failed(e)))? {
        let name = property_name(a.path());
        let read = || -> Result<Attribute, String> {
            let default = a.get::<sdf::Value>().map_err(failed)?;
            let samples = a.time_samples().map_err(failed)?.unwrap_or_default();
            if let Some((t, _)) = samples.iter().find(|(t, _)| !t.is_finite()) {
                return Err(format!("a time sample at time code {t}"));
            }
            let mut metadata = Vec::new();
            for key in ["interpolation", "elementSize"] {
                if let Some(v) = a.get_metadata::<sdf::Value>(key).map_err(failed)? {
                    metadata.extend(value(&v).map(|v| (key.to_string(), v)));
                }
            }
            Ok(Attribute {
                type_name: a
                    .type_name()
                    .map_err(failed)?
                    .map(|t| t.as_str().to_string())
                    .unwrap_or_default(),
                default: default.as_ref().and_then(value),
                // A blocked sample (`None` in text) has no value to hold.
                samples: samples
                    .iter()
                    .filter_map(|(t, v)| value(v).map(|v| (*t, v)))
                    .collect(),
                metadata,
            })
        };
        let attribute = read().map_err(|e| at(format!("`{name}`: {e}")))?;
        flat.attributes.push((name, attribute));
    }
    for r in prim.relationships().map_err(|e| at(failed(e)))? {
        let name = property_name(r.path());
        let targets = r
            .targets()
            .map_err(|e| at(format!("`{name}`: {}", failed(e))))?;
        let default = Value::List(
            targets
                .iter()
                .map(|p| Value::Path(p.as_str().to_string()))
                .collect(),
        );
        flat.attributes.push((
            name,
            Attribute {
                type_name: "rel".to_string(),
                default: Some(default),
                ..Attribute::default()
            },
        ));
    }
    flat.children = children(prim)?;
    Ok(flat)
}

/// The name of the property at `path` (`xformOp:translate`).
fn property_name(path: &sdf::Path) -> String {
    path.split_property()
        .map_or_else(|| path.as_str().to_string(), |(_, name)| name.to_string())
}

/// An f32 as the shortest decimal that gives it back, in f64: what USD
/// writes for it in text, so that text and crate files read the same.
/// Where the f32 lies exactly halfway between two such decimals (-16.7578125
/// between -16.757812 and -16.757813), USD writes the even one and Rust's
/// formatter the other (505 of the 7.2 million numbers of a point cache
/// of 10,000 vertices and 240 frames): the even one is taken.
fn single(x: f32) -> f64 {
    if !x.is_finite() || x == 0.0 {
        return f64::from(x);
    }
    let text = format!("{:e}", x.abs());
    let Some((mantissa, exp)) = text.split_once('e') else {
        return f64::from(x);
    };
    let digits = mantissa.replace('.', "");
    let (Ok(n), Ok(exp)) = (digits.parse::<u64>(), exp.parse::<i32>()) else {
        return f64::from(x);
    };
    let len = digits.len() as i32;
    // n × 10^(exp − len + 1), or with one more digit.
    let at =
        |n: u64, len: i32| -> f64 { format!("{n}e{}", exp - len + 1).parse().unwrap_or(f64::NAN) };
    let mut value = at(n, len);
    let exact = f64::from(x.abs());
    if n % 2 == 1 {
        let (other, middle) = if exact > value {
            (n + 1, 10 * n + 5)
        } else {
            (n - 1, 10 * n - 5)
        };
        let other_value = at(other, len);
        if at(middle, len + 1) == exact && other_value as f32 == x.abs() {
            value = other_value;
        }
    }
    if value.is_finite() {
        value.copysign(f64::from(x))
    } else {
        f64::from(x)
    }
}

/// Numbers as a tuple, the text reader's shape for a vector.
fn tuple(xs: impl IntoIterator<Item = f64>) -> Value {
    Value::List(xs.into_iter().map(Value::Number).collect())
}

/// An array of `T`, each as `f` gives it.
fn array<T>(xs: &[T], f: impl Fn(&T) -> Value) -> Value {
    Value::List(xs.iter().map(f).collect())
}

fn vec2f(v: &gf::Vec2f) -> Value {
    tuple([single(v.x), single(v.y)])
}
fn vec3f(v: &gf::Vec3f) -> Value {
    tuple([single(v.x), single(v.y), single(v.z)])
}
fn vec4f(v: &gf::Vec4f) -> Value {
    tuple([single(v.x), single(v.y), single(v.z), single(v.w)])
}
fn vec2d(v: &gf::Vec2d) -> Value {
    tuple([v.x, v.y])
}
fn vec3d(v: &gf::Vec3d) -> Value {
    tuple([v.x, v.y, v.z])
}
fn vec4d(v: &gf::Vec4d) -> Value {
    tuple([v.x, v.y, v.z, v.w])
}
/// A half-precision number (openusd's `f16`) as USD text writes it: to
/// six significant digits, C++'s default for a stream (`0.818848` for
/// 0.81884765625), not its shortest decimal. So a crate file's quaths
/// (Houdini writes orientations so) read as its text's.
fn half<T: Copy + Into<f32>>(x: &T) -> f64 {
    let x = f64::from((*x).into());
    if !x.is_finite() || x == 0.0 {
        return x;
    }
    format!("{x:.5e}").parse().unwrap_or(x)
}
fn vec3h(v: &gf::Vec3h) -> Value {
    tuple([half(&v.x), half(&v.y), half(&v.z)])
}
/// Quaternions as USD text writes them: (real, i, j, k).
fn quatf(q: &gf::Quatf) -> Value {
    tuple([single(q.w), single(q.x), single(q.y), single(q.z)])
}
fn quatd(q: &gf::Quatd) -> Value {
    tuple([q.w, q.x, q.y, q.z])
}
fn quath(q: &gf::Quath) -> Value {
    tuple([half(&q.w), half(&q.x), half(&q.y), half(&q.z)])
}
/// A matrix as its rows, as USD text writes it.
fn matrix(m: &[f64], size: usize) -> Value {
    Value::List(
        m.chunks(size)
            .map(|row| tuple(row.iter().copied()))
            .collect(),
    )
}

/// A composed value in the text reader's shapes ([`Value`]): numbers,
/// tuples, arrays, strings and tokens, paths; `None` for what no reader of
/// ours reads (dictionaries, list edits, blocks).
fn value(v: &sdf::Value) -> Option<Value> {
    use sdf::Value as S;
    let n = |x: f64| Value::Number(x);
    Some(match v {
        S::Bool(b) => n(f64::from(u8::from(*b))),
        S::Uchar(x) => n(f64::from(*x)),
        S::Int(x) => n(f64::from(*x)),
        S::Uint(x) => n(f64::from(*x)),
        S::Int64(x) => n(*x as f64),
        S::Uint64(x) => n(*x as f64),
        S::Half(x) => n(half(x)),
        S::Float(x) => n(single(*x)),
        S::Double(x) => n(*x),
        S::BoolVec(xs) => array(xs, |b| n(f64::from(u8::from(*b)))),
        S::UcharVec(xs) => array(xs, |x| n(f64::from(*x))),
        S::IntVec(xs) => array(xs, |x| n(f64::from(*x))),
        S::UintVec(xs) => array(xs, |x| n(f64::from(*x))),
        S::Int64Vec(xs) => array(xs, |x| n(*x as f64)),
        S::Uint64Vec(xs) => array(xs, |x| n(*x as f64)),
        S::HalfVec(xs) => array(xs, |x| n(half(x))),
        S::FloatVec(xs) => array(xs, |x| n(single(*x))),
        S::DoubleVec(xs) => array(xs, |x| n(*x)),
        S::String(s) => Value::Str(s.clone()),
        S::Token(t) => Value::Str(t.as_str().to_string()),
        S::StringVec(xs) => array(xs, |s| Value::Str(s.clone())),
        S::TokenVec(xs) => array(xs, |t| Value::Str(t.as_str().to_string())),
        S::AssetPath(a) => Value::Str(a.authored_path.clone()),
        S::Quath(q) => quath(q),
        S::Quatf(q) => quatf(q),
        S::Quatd(q) => quatd(q),
        S::QuathVec(qs) => array(qs, quath),
        S::QuatfVec(qs) => array(qs, quatf),
        S::QuatdVec(qs) => array(qs, quatd),
        S::Vec2f(v) => vec2f(v),
        S::Vec2d(v) => vec2d(v),
        S::Vec3h(v) => vec3h(v),
        S::Vec3f(v) => vec3f(v),
        S::Vec3d(v) => vec3d(v),
        S::Vec4f(v) => vec4f(v),
        S::Vec4d(v) => vec4d(v),
        S::Vec2fVec(vs) => array(vs, vec2f),
        S::Vec2dVec(vs) => array(vs, vec2d),
        S::Vec3hVec(vs) => array(vs, vec3h),
        S::Vec3fVec(vs) => array(vs, vec3f),
        S::Vec3dVec(vs) => array(vs, vec3d),
        S::Vec4fVec(vs) => array(vs, vec4f),
        S::Vec4dVec(vs) => array(vs, vec4d),
        S::Matrix2d(m) => matrix(&m.0, 2),
        S::Matrix3d(m) => matrix(&m.0, 3),
        S::Matrix4d(m) => matrix(&m.0, 4),
        S::Matrix2dVec(ms) => array(ms, |m| matrix(&m.0, 2)),
        S::Matrix3dVec(ms) => array(ms, |m| matrix(&m.0, 3)),
        S::Matrix4dVec(ms) => array(ms, |m| matrix(&m.0, 4)),
        S::PathVec(ps) => array(ps, |p| Value::Path(p.as_str().to_string())),
        _ => return None,
    })
}

/// A [`Value`] in JSON, compact where a point cache is large: a number as
/// itself, a string as itself, a list as an array; the rest one-key
/// objects: `{"i": …}` an identifier, `{"p": …}` a path, `{"d": [[k, v],
/// …]}` a dictionary, `{"n": "inf"}` a number JSON has none for (`inf`,
/// `-inf`, `NaN`). Serde's derived form tags every number (`{"Number":
/// 0.1}`), which made a 10,000-vertex cache of 240 frames 186 MB.
impl serde::Serialize for Value {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Value::Number(x) if x.is_finite() => s.serialize_f64(*x),
            Value::Number(x) => one_key(s, "n", &x.to_string()),
            Value::Str(text) => s.serialize_str(text),
            Value::Ident(text) => one_key(s, "i", text),
            Value::Path(text) => one_key(s, "p", text),
            Value::List(items) => s.collect_seq(items),
            Value::Dict(entries) => one_key(s, "d", entries),
        }
    }
}

/// `{key: value}`.
fn one_key<S: serde::Serializer, T: serde::Serialize + ?Sized>(
    s: S,
    key: &str,
    value: &T,
) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut map = s.serialize_map(Some(1))?;
    map.serialize_entry(key, value)?;
    map.end()
}

impl<'de> serde::Deserialize<'de> for Value {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ValueVisitor)
    }
}

/// Reads what [`Value`]'s `Serialize` writes.
struct ValueVisitor;

impl<'de> serde::de::Visitor<'de> for ValueVisitor {
    type Value = Value;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a USD value: a number, a string, an array or a one-key object")
    }
    fn visit_f64<E>(self, x: f64) -> Result<Value, E> {
        Ok(Value::Number(x))
    }
    fn visit_i64<E>(self, x: i64) -> Result<Value, E> {
        Ok(Value::Number(x as f64))
    }
    fn visit_u64<E>(self, x: u64) -> Result<Value, E> {
        Ok(Value::Number(x as f64))
    }
    fn visit_str<E>(self, text: &str) -> Result<Value, E> {
        Ok(Value::Str(text.to_string()))
    }
    fn visit_string<E>(self, text: String) -> Result<Value, E> {
        Ok(Value::Str(text))
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut items = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(1 << 16));
        while let Some(v) = seq.next_element()? {
            items.push(v);
        }
        Ok(Value::List(items))
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        use serde::de::Error;
        let key: String = map
            .next_key()?
            .ok_or_else(|| A::Error::custom("an empty object is no USD value"))?;
        let value = match key.as_str() {
            "n" => {
                let word: String = map.next_value()?;
                Value::Number(word.parse().map_err(A::Error::custom)?)
            }
            "i" => Value::Ident(map.next_value()?),
            "p" => Value::Path(map.next_value()?),
            "d" => Value::Dict(map.next_value()?),
            other => return Err(A::Error::custom(format!("no USD value is keyed `{other}`"))),
        };
        Ok(value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_take_the_text_reader_s_shapes() {
        // f32 as the decimal USD text writes for it, not its binary value.
        assert_eq!(single(0.1), 0.1);
        assert_ne!(f64::from(0.1f32), 0.1);
        // Halfway between two shortest decimals, the even one, as USD
        // writes it (Rust's formatter gives -16.757813).
        let tie = 16.0 + 97.0 / 128.0; // 16.7578125, an f32 exactly
        assert_eq!(single(-tie), -16.757812);
        assert_eq!(single(tie), 16.757812);
        assert_eq!(single(-2.5), -2.5);
        assert_eq!(single(0.0).to_bits(), 0.0f64.to_bits());
        assert_eq!(single(-0.0).to_bits(), (-0.0f64).to_bits());
        assert_eq!(single(1e-40), 1e-40);
        assert_eq!(single(f32::MAX), 3.4028235e38);
        // A half as USD text writes it, to six significant digits (the
        // values of a Houdini quath in tests/data/usd/instanced).
        assert_eq!(half(&(1677.0f32 / 2048.0)), 0.818848);
        assert_eq!(half(&(-1175.0f32 / 2048.0)), -0.57373);
        assert_eq!(half(&(1874.0f32 / 131_072.0)), 0.0142975);
        assert_eq!(half(&-0.0f32).to_bits(), (-0.0f64).to_bits());
        // Every one reads back as the f32 it came from.
        for bits in (0..u32::MAX).step_by(9_973) {
            let x = f32::from_bits(bits);
            if x.is_finite() {
                assert_eq!(single(x) as f32, x, "{x:e}");
            }
        }
        // Quaternions real part first, as `(w, x, y, z)` in text.
        let q = sdf::Value::Quatf(gf::Quatf {
            w: 0.5,
            x: 1.0,
            y: 2.0,
            z: 3.0,
        });
        assert_eq!(value(&q).unwrap().numbers().unwrap(), [0.5, 1.0, 2.0, 3.0]);
        // Matrices as their rows.
        let mut m = [0.0; 16];
        m.iter_mut().enumerate().for_each(|(k, x)| *x = k as f64);
        let Some(Value::List(rows)) = value(&sdf::Value::Matrix4d(gf::Matrix4d(m))) else {
            panic!("a matrix is a list of rows");
        };
        assert_eq!(rows.len(), 4);
        assert_eq!(rows[1].numbers().unwrap(), [4.0, 5.0, 6.0, 7.0]);
        // Tokens are strings; dictionaries are not read.
        let t = sdf::Value::TokenVec(vec!["xformOp:translate".into()]);
        assert_eq!(value(&t).unwrap().strings().unwrap(), ["xformOp:translate"]);
        assert_eq!(value(&sdf::Value::Dictionary(Default::default())), None);
    }

    #[test]
    fn a_layer_comes_back_from_json_as_it_went_with_numbers_json_lacks() {
        let layer = Layer {
            up_y: false,
            meters_per_unit: 1.0,
            time_codes_per_second: 24.0,
            roots: vec![Prim {
                name: "card".into(),
                type_name: "Mesh".into(),
                attributes: vec![(
                    "points".into(),
                    Attribute {
                        type_name: "point3f[]".into(),
                        default: Some(Value::List(
                            [0.1, f64::INFINITY, f64::NEG_INFINITY, -0.0]
                                .map(Value::Number)
                                .into(),
                        )),
                        samples: vec![(1.5, Value::Number(f64::NAN))],
                        metadata: vec![("interpolation".into(), Value::Str("vertex".into()))],
                    },
                )],
                children: Vec::new(),
                inactive_ids: vec![-3, 5],
            }],
        };
        let json = serde_json::to_string(&layer).unwrap();
        let back: Layer = serde_json::from_str(&json).unwrap();
        let a = back.roots[0].attribute("points").unwrap();
        let p = a.default.as_ref().unwrap().numbers().unwrap();
        assert_eq!(p[..3], [0.1, f64::INFINITY, f64::NEG_INFINITY]);
        assert!(p[3] == 0.0 && p[3].is_sign_negative());
        assert!(matches!(a.samples[0], (1.5, Value::Number(x)) if x.is_nan()));
        assert_eq!(a.meta("interpolation"), Some(&Value::Str("vertex".into())));
        assert!(!back.up_y);
        assert_eq!(back.roots[0].inactive_ids, [-3, 5]);
        // A prim without deactivated ids carries no field for them.
        let mut plain = layer;
        plain.roots[0].inactive_ids.clear();
        assert!(!serde_json::to_string(&plain).unwrap().contains("inactive"));
    }
}
