//! Alembic (`.abc`) point caches as Blender, Houdini and Maya write them:
//! the Ogawa container and the AbcGeom schemas a falling leaf needs, read
//! by our own code (no maintained Rust reader exists; the layout below is
//! the one the Alembic 1.8 library writes, its `Ogawa` and `AbcCoreOgawa`
//! layers, read here from the bytes).
//!
//! - **Ogawa**: `Ogawa`, a byte 0xff once the writer has finished (a file
//!   still being written is refused), a version, then the root group's
//!   offset. A group is a count and that many 8-byte child offsets, the top
//!   bit marking data; data is a size and its bytes. Offset 0 is an empty
//!   child. Every offset and size is checked against the file, and groups
//!   nest at most [`MAX_DEPTH`] deep, so a damaged file is refused, not
//!   followed round in a loop.
//! - **Archive**: the root group holds the archive and file versions, the
//!   top object, the archive's metadata, its time samplings and its indexed
//!   metadata.
//! - **Objects**: an object group holds its properties (a compound), its
//!   children, and their headers (names and metadata, the schema among
//!   them). A compound holds its properties and their packed headers
//!   (property kind, plain-old-data type and extent, sample count, the
//!   first and last samples that change, time sampling, name, metadata).
//!   A scalar property stores one datum per stored sample, an array
//!   property a datum and its dimensions; each datum starts with a 16-byte
//!   hash.
//! - **What is read**: every `AbcGeom_PolyMesh` (and `SubD`, read as its
//!   cage) with its `P`, `.faceIndices` and `.faceCounts`, placed by the
//!   `AbcGeom_Xform` objects above it (`.ops` and `.vals`: scale,
//!   translate, rotate about an axis, matrix, rotate about x, y or z, the
//!   first op outermost; `.inherits` false starts again from the world).
//!   Faces are fans from their first vertex, their order reversed: Alembic
//!   winds faces clockwise, and Blender, Houdini and Maya turn them back
//!   on import.
//! - **Time**: seconds, from each property's time sampling (uniform,
//!   cyclic or acyclic); the clip is sampled as a USD layer is
//!   ([`super::usda_read`]), one frame per shortest interval between
//!   samples, each property at its nearest sample.
//! - **Space**: Alembic is y up (Blender's exporter turns z up into it,
//!   Maya and Houdini are y up) and carries no unit; metres are assumed,
//!   as Blender and Houdini write them.

use super::clip::{Clip, ClipObject};
use super::read::{MAX_FRAMES, check_points, key_rate, sampled_frames};
use nalgebra::{Matrix4, Rotation3, Unit, Vector3};
use std::rc::Rc;

type V3 = Vector3<f64>;
type M4 = Matrix4<f64>;

/// Deepest nesting of groups followed (objects under objects, compounds
/// under compounds): far beyond any scene, and a bound on a damaged file
/// whose offsets loop.
pub const MAX_DEPTH: usize = 256;

/// Most objects read: a damaged file whose objects share one group many
/// times over would otherwise be walked exponentially often.
pub const MAX_OBJECTS: usize = 100_000;

/// The Ogawa container over a file's bytes.
struct Ogawa<'a> {
    bytes: &'a [u8],
}

/// A child of an Ogawa group.
#[derive(Clone, Copy, Debug)]
enum Child {
    Group(u64),
    Data(u64),
}

const DATA_BIT: u64 = 1 << 63;

impl<'a> Ogawa<'a> {
    fn u64_at(&self, pos: u64) -> Result<u64, String> {
        let p = usize::try_from(pos).map_err(|_| format!("offset {pos} is past its end"))?;
        self.bytes
            .get(p..p.checked_add(8).ok_or("an offset overflows")?)
            .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
            .ok_or_else(|| {
                format!(
                    "offset {pos} is past its end ({} bytes): it is damaged or cut short",
                    self.bytes.len()
                )
            })
    }

    /// The children of the group at `pos` (none at offset 0).
    fn group(&self, pos: u64) -> Result<Vec<Child>, String> {
        if pos == 0 {
            return Ok(Vec::new());
        }
        let n = self.u64_at(pos)?;
        let room = (self.bytes.len() as u64).saturating_sub(pos + 8) / 8;
        if n > room {
            return Err(format!(
                "a group at offset {pos} lists {n} children, more than the file holds: it is damaged"
            ));
        }
        (0..n)
            .map(|k| {
                let c = self.u64_at(pos + 8 + 8 * k)?;
                Ok(if c & DATA_BIT != 0 {
                    Child::Data(c & !DATA_BIT)
                } else {
                    Child::Group(c)
                })
            })
            .collect()
    }

    /// The bytes of the data at `pos` (empty at offset 0).
    fn data(&self, pos: u64) -> Result<&'a [u8], String> {
        if pos == 0 {
            return Ok(&[]);
        }
        let size = self.u64_at(pos)?;
        let start = pos + 8;
        let end = start
            .checked_add(size)
            .filter(|&e| e <= self.bytes.len() as u64)
            .ok_or_else(|| {
                format!(
                    "data at offset {pos} of {size} bytes runs past the file's end: it is damaged"
                )
            })?;
        Ok(&self.bytes[start as usize..end as usize])
    }

    fn child_data(&self, children: &[Child], k: usize, what: &str) -> Result<&'a [u8], String> {
        match children.get(k) {
            Some(Child::Data(p)) => self.data(*p),
            _ => Err(format!("no {what} where the Alembic layout puts it")),
        }
    }
}

/// Reads little-endian numbers from a byte slice, each read checked.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| format!("{what} runs past its record: it is damaged"))?;
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }
    fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.take(1, what)?[0])
    }
    fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4, what)?.try_into().expect("4"),
        ))
    }
    fn f64(&mut self, what: &str) -> Result<f64, String> {
        Ok(f64::from_le_bytes(
            self.take(8, what)?.try_into().expect("8"),
        ))
    }
    /// A u32 stored in 1, 2 or 4 bytes (a property header's size hint).
    fn hinted(&mut self, hint: u32, what: &str) -> Result<u32, String> {
        Ok(match hint {
            0 => u32::from(self.u8(what)?),
            1 => u32::from(u16::from_le_bytes(
                self.take(2, what)?.try_into().expect("2"),
            )),
            _ => self.u32(what)?,
        })
    }
    fn done(&self) -> bool {
        self.at >= self.bytes.len()
    }
}

/// When a property's samples are taken: the first sample's time (and the
/// others' within a cycle) and the time per cycle, or every sample's time
/// (acyclic).
#[derive(Clone, Debug)]
struct TimeSampling {
    times: Vec<f64>,
    /// `None`: acyclic.
    per_cycle: Option<f64>,
}

impl TimeSampling {
    /// Time of sample `k`, s.
    fn time(&self, k: usize) -> f64 {
        match self.per_cycle {
            None => self.times[k.min(self.times.len() - 1)],
            Some(tpc) => {
                let n = self.times.len();
                self.times[k % n] + (k / n) as f64 * tpc
            }
        }
    }
}

/// The archive's time samplings (its data child 4).
fn time_samplings(bytes: &[u8]) -> Result<Vec<TimeSampling>, String> {
    let mut c = Cursor { bytes, at: 0 };
    let mut out = Vec::new();
    while !c.done() {
        let _max_sample = c.u32("a time sampling")?;
        let tpc = c.f64("a time sampling")?;
        let n = c.u32("a time sampling")? as usize;
        if n == 0 || n > bytes.len() / 8 {
            return Err(format!("a time sampling of {n} times: it is damaged"));
        }
        let times = (0..n)
            .map(|_| c.f64("a time sampling's times"))
            .collect::<Result<Vec<_>, _>>()?;
        if !times.iter().all(|t| t.is_finite()) || tpc.is_nan() {
            return Err("a time sampling's times are not finite".to_string());
        }
        // Acyclic sampling writes DBL_MAX / 32 as its time per cycle.
        let per_cycle = (tpc < f64::MAX / 64.0).then_some(tpc);
        out.push(TimeSampling { times, per_cycle });
    }
    if out.is_empty() {
        // Sampling 0 is the identity (every file writes it; be lenient).
        out.push(TimeSampling {
            times: vec![0.0],
            per_cycle: Some(1.0),
        });
    }
    Ok(out)
}

/// The archive's indexed metadata strings, the empty one first.
fn indexed_metadata(bytes: &[u8]) -> Result<Vec<String>, String> {
    let mut c = Cursor { bytes, at: 0 };
    let mut out = vec![String::new()];
    while !c.done() {
        let n = c.u8("an indexed metadata string")? as usize;
        out.push(String::from_utf8_lossy(c.take(n, "an indexed metadata string")?).into_owned());
    }
    Ok(out)
}

/// A metadata string's value for `key` (`k=v;k=v`).
fn meta<'m>(metadata: &'m str, key: &str) -> Option<&'m str> {
    metadata
        .split(';')
        .filter_map(|kv| kv.split_once('='))
        .find(|(k, _)| *k == key)
        .map(|(_, v)| v)
}

/// Plain-old-data types, by the codes Alembic writes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Pod {
    Bool,
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    U64,
    I64,
    F16,
    F32,
    F64,
    Str,
    WStr,
}

impl Pod {
    fn of(code: u32) -> Option<Pod> {
        use Pod::*;
        [
            Bool, U8, I8, U16, I16, U32, I32, U64, I64, F16, F32, F64, Str, WStr,
        ]
        .get(code as usize)
        .copied()
    }
}

/// One property's header.
#[derive(Clone, Debug)]
struct PropertyHeader {
    name: String,
    /// 0 compound, 1 scalar, 2 or 3 array (3: an array whose every sample
    /// holds one value, "scalar-like", which Alembic stores as an array).
    kind: u32,
    pod: Option<Pod>,
    /// Samples written, and the first and last that change (the others
    /// repeat a stored one).
    samples: usize,
    first_changed: usize,
    last_changed: usize,
    sampling: usize,
}

impl PropertyHeader {
    /// Which stored sample sample `k` is (Alembic stores the first, then
    /// those from the first change to the last).
    fn stored(&self, k: usize) -> usize {
        let k = k.min(self.samples.saturating_sub(1));
        if k < self.first_changed || (self.first_changed == 0 && self.last_changed == 0) {
            0
        } else if k >= self.last_changed {
            self.last_changed - self.first_changed + 1
        } else {
            k - self.first_changed + 1
        }
    }
}

/// A compound's property headers (its last, data, child); `indexed`
/// metadata strings are in the archive (the properties' metadata is
/// checked and passed over: nothing read here needs it).
fn property_headers(bytes: &[u8], indexed: usize) -> Result<Vec<PropertyHeader>, String> {
    let mut c = Cursor { bytes, at: 0 };
    let mut out = Vec::new();
    while !c.done() {
        let info = c.u32("a property header")?;
        let kind = info & 3;
        let hint = (info >> 2) & 3;
        let mut h = PropertyHeader {
            name: String::new(),
            kind,
            pod: None,
            samples: 0,
            first_changed: 0,
            last_changed: 0,
            sampling: 0,
        };
        if kind != 0 {
            h.pod = Some(
                Pod::of((info >> 4) & 0xf)
                    .ok_or_else(|| format!("a property of unknown type {}", (info >> 4) & 0xf))?,
            );
            h.samples = c.hinted(hint, "a property header")? as usize;
            if info & 0x200 != 0 {
                h.first_changed = c.hinted(hint, "a property header")? as usize;
                h.last_changed = c.hinted(hint, "a property header")? as usize;
                if h.first_changed > h.last_changed {
                    return Err(
                        "a property's changed samples are out of order: it is damaged".into(),
                    );
                }
            } else if info & 0x800 != 0 {
                (h.first_changed, h.last_changed) = (0, 0);
            } else {
                // Every sample stored (one sample: first 1, last 0, and
                // sample 0 is the first stored).
                (h.first_changed, h.last_changed) = (1, h.samples.saturating_sub(1));
            }
            if info & 0x100 != 0 {
                h.sampling = c.hinted(hint, "a property header")? as usize;
            }
        }
        let n = c.hinted(hint, "a property name")? as usize;
        h.name = String::from_utf8_lossy(c.take(n, "a property name")?).into_owned();
        let index = ((info >> 20) & 0xff) as usize;
        if index == 0xff {
            let n = c.hinted(hint, "a property's metadata")? as usize;
            c.take(n, "a property's metadata")?;
        } else if index >= indexed {
            return Err(format!(
                "a property's metadata index {index} is not in the file"
            ));
        }
        out.push(h);
    }
    Ok(out)
}

/// Decodes `bytes` of `pod` into numbers (a string type is not numbers;
/// a trailing partial value is dropped).
fn numbers(pod: Pod, bytes: &[u8]) -> Option<Vec<f64>> {
    fn each<const W: usize>(bytes: &[u8], f: impl Fn([u8; W]) -> f64) -> Vec<f64> {
        bytes
            .chunks_exact(W)
            .map(|c| f(c.try_into().expect("chunks of W")))
            .collect()
    }
    Some(match pod {
        Pod::Bool | Pod::U8 => bytes.iter().map(|&b| f64::from(b)).collect(),
        Pod::I8 => bytes.iter().map(|&b| f64::from(b as i8)).collect(),
        Pod::U16 => each(bytes, |b| f64::from(u16::from_le_bytes(b))),
        Pod::I16 => each(bytes, |b| f64::from(i16::from_le_bytes(b))),
        Pod::U32 => each(bytes, |b| f64::from(u32::from_le_bytes(b))),
        Pod::I32 => each(bytes, |b| f64::from(i32::from_le_bytes(b))),
        Pod::U64 => each(bytes, |b| u64::from_le_bytes(b) as f64),
        Pod::I64 => each(bytes, |b| i64::from_le_bytes(b) as f64),
        Pod::F16 => each(bytes, |b| half_to_f64(u16::from_le_bytes(b))),
        Pod::F32 => each(bytes, |b| f64::from(f32::from_le_bytes(b))),
        Pod::F64 => each(bytes, f64::from_le_bytes),
        Pod::Str | Pod::WStr => return None,
    })
}

/// An IEEE half's value.
fn half_to_f64(h: u16) -> f64 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = i32::from((h >> 10) & 0x1f);
    let frac = f64::from(h & 0x3ff);
    sign * match exp {
        0 => frac * 2f64.powi(-24),
        31 if frac == 0.0 => f64::INFINITY,
        31 => f64::NAN,
        _ => (1.0 + frac / 1024.0) * 2f64.powi(exp - 15),
    }
}

/// A property found in a compound: its header and where its samples are.
struct Property {
    header: PropertyHeader,
    /// Its group (0: none), and the group's children (samples; for an
    /// array, datum and dimensions; for a compound, its properties).
    group: u64,
    children: Vec<Child>,
}

/// The archive, with what every property read needs.
struct Archive<'a> {
    ogawa: Ogawa<'a>,
    samplings: Vec<TimeSampling>,
    metadata: Vec<String>,
}

impl Archive<'_> {
    /// The properties of the compound group at `pos`.
    fn compound(&self, pos: u64) -> Result<Vec<Property>, String> {
        let children = self.ogawa.group(pos)?;
        let Some(Child::Data(h)) = children.last().copied() else {
            return Ok(Vec::new());
        };
        let headers = property_headers(self.ogawa.data(h)?, self.metadata.len())?;
        headers
            .into_iter()
            .enumerate()
            .map(|(k, header)| {
                let group = match children.get(k) {
                    Some(Child::Group(g)) if k + 1 < children.len() => *g,
                    _ => 0,
                };
                let children = self.ogawa.group(group)?;
                Ok(Property {
                    header,
                    group,
                    children,
                })
            })
            .collect()
    }

    /// The compound property `name` of the compound at `pos`, as its
    /// group's position.
    fn sub_compound(&self, pos: u64, name: &str) -> Result<Option<u64>, String> {
        Ok(self
            .compound(pos)?
            .into_iter()
            .find(|p| p.header.name == name && p.header.kind == 0)
            .map(|p| p.group))
    }

    /// Sample `k` of `p` as numbers, and its time, s.
    fn sample(&self, p: &Property, k: usize) -> Result<(Vec<f64>, f64), String> {
        let h = &p.header;
        let pod = h.pod.ok_or("a compound has no samples")?;
        let stored = h.stored(k);
        // An array's samples are (datum, dimensions) pairs.
        let slot = if h.kind >= 2 { 2 * stored } else { stored };
        let datum = match p.children.get(slot) {
            Some(Child::Data(d)) => self.ogawa.data(*d)?,
            None if h.samples == 0 => &[],
            _ => {
                return Err(format!(
                    "property `{}`: sample {k} is not where the Alembic layout puts it",
                    h.name
                ));
            }
        };
        // A 16-byte hash, then the values.
        let values = if datum.len() >= 16 {
            &datum[16..]
        } else {
            &[][..]
        };
        let v = numbers(pod, values)
            .ok_or_else(|| format!("property `{}` holds strings, not numbers", h.name))?;
        let sampling = self.samplings.get(h.sampling).ok_or_else(|| {
            format!(
                "property `{}` names time sampling {}, of {}",
                h.name,
                h.sampling,
                self.samplings.len()
            )
        })?;
        Ok((v, sampling.time(k)))
    }

    /// Every sample of `p`: (time, numbers), each stored sample decoded
    /// once and shared by the samples that repeat it.
    fn samples(&self, p: &Property) -> Result<Vec<Sample>, String> {
        let n = p.header.samples.max(1);
        if n > MAX_FRAMES {
            return Err(format!(
                "property `{}` has {n} samples, more than the {MAX_FRAMES} this reader samples",
                p.header.name
            ));
        }
        let mut decoded: Vec<Option<Rc<Vec<f64>>>> = Vec::new();
        (0..n)
            .map(|k| {
                let stored = p.header.stored(k);
                if decoded.len() <= stored {
                    decoded.resize(stored + 1, None);
                }
                let (v, t) = match &decoded[stored] {
                    Some(v) => (Rc::clone(v), self.time(p, k)?),
                    None => {
                        let (v, t) = self.sample(p, k)?;
                        let v = Rc::new(v);
                        decoded[stored] = Some(Rc::clone(&v));
                        (v, t)
                    }
                };
                Ok((t, v))
            })
            .collect()
    }

    /// The time of sample `k` of `p`, s.
    fn time(&self, p: &Property, k: usize) -> Result<f64, String> {
        self.samplings
            .get(p.header.sampling)
            .map(|s| s.time(k))
            .ok_or_else(|| {
                format!(
                    "property `{}` names a time sampling the file lacks",
                    p.header.name
                )
            })
    }
}

/// A sample of a property: its time, s, and its numbers (shared by the
/// samples that repeat a stored one).
type Sample = (f64, Rc<Vec<f64>>);

/// An object's transform over time: its local matrix per sample (column
/// vectors), and whether it inherits its parent's.
#[derive(Clone, Debug)]
struct Xform {
    samples: Vec<(f64, M4)>,
    inherits: bool,
}

/// The matrix of Alembic xform ops `ops` (encoded: type in the high
/// nibble) with channel values `vals`, the first op outermost.
fn xform_matrix(ops: &[f64], vals: &[f64]) -> Result<M4, String> {
    let mut m = M4::identity();
    let mut at = 0;
    for &op in ops {
        let kind = (op as u32) >> 4;
        let width = match kind {
            0 | 1 => 3,
            2 => 4,
            3 => 16,
            4..=6 => 1,
            _ => return Err(format!("an xform op of unknown type {kind}")),
        };
        let v = vals
            .get(at..at + width)
            .ok_or("an xform's ops need more values than it holds")?;
        at += width;
        let axis = |x: f64, y: f64, z: f64, deg: f64| {
            Rotation3::from_axis_angle(&Unit::new_normalize(V3::new(x, y, z)), deg.to_radians())
                .to_homogeneous()
        };
        let op_m = match kind {
            0 => M4::new_nonuniform_scaling(&V3::new(v[0], v[1], v[2])),
            1 => M4::new_translation(&V3::new(v[0], v[1], v[2])),
            2 if V3::new(v[0], v[1], v[2]).norm() > 0.0 => axis(v[0], v[1], v[2], v[3]),
            2 => M4::identity(),
            // Rows of Imath's row-vector matrix: its transpose acts on columns.
            3 => M4::from_row_slice(v).transpose(),
            4 => axis(1.0, 0.0, 0.0, v[0]),
            5 => axis(0.0, 1.0, 0.0, v[0]),
            _ => axis(0.0, 0.0, 1.0, v[0]),
        };
        m *= op_m;
    }
    Ok(m)
}

/// A mesh found in the archive: its full name, faces as triangles, `P`
/// per sample, and the transforms above it (the root first).
struct Mesh {
    name: String,
    triangles: Vec<[u32; 3]>,
    points: Vec<Sample>,
    xforms: Vec<Xform>,
}

/// Walks the object whose group's `children` are given (named `path`),
/// with the transforms above it, collecting meshes.
fn walk(
    a: &Archive<'_>,
    children: &[Child],
    path: &str,
    above: &mut Vec<Xform>,
    out: &mut Vec<Mesh>,
    depth: usize,
    seen: &mut usize,
) -> Result<(), String> {
    if depth > MAX_DEPTH {
        return Err(format!("objects nest over {MAX_DEPTH} deep: it is damaged"));
    }
    *seen += 1;
    if *seen > MAX_OBJECTS {
        return Err(format!(
            "it holds over {MAX_OBJECTS} objects: it is damaged, or too big for this reader"
        ));
    }
    let Some(Child::Data(h)) = children.last().copied() else {
        return Ok(());
    };
    let headers = a.ogawa.data(h)?;
    // The last 32 bytes are hashes.
    let headers = &headers[..headers.len().saturating_sub(32)];
    let mut c = Cursor {
        bytes: headers,
        at: 0,
    };
    let mut k = 0;
    while !c.done() {
        let n = c.u32("an object header")? as usize;
        let name = String::from_utf8_lossy(c.take(n, "an object's name")?).into_owned();
        let index = c.u8("an object header")? as usize;
        let md = if index == 0xff {
            let n = c.u32("an object's metadata")? as usize;
            String::from_utf8_lossy(c.take(n, "an object's metadata")?).into_owned()
        } else {
            a.metadata.get(index).cloned().ok_or_else(|| {
                format!("object `{name}`: metadata index {index} is not in the file")
            })?
        };
        k += 1;
        let Some(Child::Group(obj)) = children.get(k).copied().filter(|_| k + 1 < children.len())
        else {
            return Err(format!(
                "object `{path}/{name}` is not where its header says"
            ));
        };
        let full = format!("{path}/{name}");
        let at = |e: String| format!("object `{full}`: {e}");
        let own = a.ogawa.group(obj)?;
        let props = match own.first().copied() {
            Some(Child::Group(p)) => p,
            _ => 0,
        };
        let schema = meta(&md, "schema").unwrap_or("");
        let mut pushed = false;
        if schema.starts_with("AbcGeom_Xform") {
            let x = a
                .sub_compound(props, ".xform")?
                .ok_or_else(|| at("an Xform without `.xform`".into()))?;
            above.push(read_xform(a, x).map_err(at)?);
            pushed = true;
        } else if schema.starts_with("AbcGeom_PolyMesh") || schema.starts_with("AbcGeom_SubD") {
            let g = a
                .sub_compound(props, ".geom")?
                .ok_or_else(|| at("a mesh without `.geom`".into()))?;
            out.push(read_mesh(a, g, &full, above).map_err(at)?);
        }
        walk(a, &own, &full, above, out, depth + 1, seen)?;
        if pushed {
            above.pop();
        }
    }
    Ok(())
}

/// An Xform's `.xform` compound at `pos`.
fn read_xform(a: &Archive<'_>, pos: u64) -> Result<Xform, String> {
    let props = a.compound(pos)?;
    let find = |n: &str| props.iter().find(|p| p.header.name == n);
    let inherits = match find(".inherits") {
        Some(p) => a.sample(p, 0)?.0.first().is_none_or(|&b| b != 0.0),
        None => true,
    };
    let ops = match find(".ops") {
        Some(p) => a.sample(p, 0)?.0,
        None => Vec::new(),
    };
    let samples = match find(".vals") {
        Some(p) => a
            .samples(p)?
            .into_iter()
            .map(|(t, v)| xform_matrix(&ops, &v).map(|m| (t, m)))
            .collect::<Result<_, _>>()?,
        None => vec![(0.0, xform_matrix(&ops, &[])?)],
    };
    Ok(Xform { samples, inherits })
}

/// A mesh's `.geom` compound at `pos`.
fn read_mesh(a: &Archive<'_>, pos: u64, name: &str, above: &[Xform]) -> Result<Mesh, String> {
    let props = a.compound(pos)?;
    let find = |n: &str| {
        props
            .iter()
            .find(|p| p.header.name == n && p.header.kind != 0)
            .ok_or_else(|| format!("no `{n}`"))
    };
    let p = find("P")?;
    let points = a.samples(p)?;
    let indices = a.samples(find(".faceIndices")?)?;
    let counts = a.samples(find(".faceCounts")?)?;
    if indices.windows(2).any(|w| w[0].1 != w[1].1) || counts.windows(2).any(|w| w[0].1 != w[1].1) {
        return Err("its faces change over time; a fall needs one mesh throughout".into());
    }
    let (indices, counts) = (&indices[0].1, &counts[0].1);
    let vertices = points[0].1.len() / 3;
    check_points(name, points.len(), vertices)?;
    let mut triangles = Vec::new();
    let mut at = 0usize;
    for &n in counts.iter() {
        let n = n as usize;
        let face = indices
            .get(at..at + n)
            .ok_or("its face counts need more indices than it holds")?;
        at += n;
        if face.iter().any(|&i| i < 0.0 || i as usize >= vertices) {
            return Err(format!("a face names a vertex past its {vertices}"));
        }
        // Clockwise in Alembic: reversed, as importers turn them.
        let f: Vec<u32> = face.iter().rev().map(|&i| i as u32).collect();
        for k in 1..f.len().saturating_sub(1) {
            triangles.push([f[0], f[k], f[k + 1]]);
        }
    }
    if points
        .iter()
        .any(|(_, p)| p.len() != 3 * vertices || p.is_empty())
    {
        return Err("its point count changes over time, or it has none".into());
    }
    Ok(Mesh {
        name: name.to_string(),
        triangles,
        points,
        xforms: above.to_vec(),
    })
}

/// The value of a sampled quantity at time `t`: its nearest sample
/// (Alembic's default sample selector).
fn nearest<T>(samples: &[(f64, T)], t: f64) -> &T {
    let j = samples.partition_point(|(s, _)| *s < t);
    let pick = if j == 0 {
        0
    } else if j == samples.len() || t - samples[j - 1].0 <= samples[j].0 - t {
        j - 1
    } else {
        j
    };
    &samples[pick].1
}

/// The clip of the Alembic file `bytes`, named `name`.
pub fn read_abc(bytes: &[u8], name: &str) -> Result<Clip, String> {
    if bytes.len() < 16 || &bytes[..5] != b"Ogawa" {
        return Err("not an Alembic file (no Ogawa header; HDF5 Alembic files from before 2013 are not read: re-export them)".into());
    }
    if bytes[5] != 0xff {
        return Err("its writer has not finished it (Ogawa's frozen byte is not set): it is still being written or was cut short".into());
    }
    let ogawa = Ogawa { bytes };
    let root = ogawa.group(ogawa.u64_at(8)?)?;
    if root.len() < 6 {
        return Err("its root group is not an Alembic archive's".into());
    }
    let samplings = time_samplings(ogawa.child_data(&root, 4, "time samplings")?)?;
    let metadata = indexed_metadata(ogawa.child_data(&root, 5, "indexed metadata")?)?;
    let Child::Group(top) = root[2] else {
        return Err("no top object".into());
    };
    let archive = Archive {
        ogawa,
        samplings,
        metadata,
    };
    let mut meshes = Vec::new();
    let top = archive.ogawa.group(top)?;
    walk(&archive, &top, "", &mut Vec::new(), &mut meshes, 0, &mut 0)?;
    if meshes.is_empty() {
        return Err("no PolyMesh with points in it".into());
    }
    // The key grid: every sample time of points and transforms.
    let mut times: Vec<f64> = meshes
        .iter()
        .flat_map(|m| {
            m.points
                .iter()
                .map(|s| s.0)
                .chain(m.xforms.iter().flat_map(|x| x.samples.iter().map(|s| s.0)))
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times.dedup();
    let shortest = times
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    let rate = key_rate(shortest).unwrap_or(24.0);
    let (start, end) = (times[0], *times.last().expect("one time at least"));
    let frames = sampled_frames(start, end, rate)?;
    let objects = meshes
        .iter()
        .map(|m| {
            let vertices = m.points[0].1.len() / 3;
            check_points(&m.name, frames, vertices)?;
            let frame_list = (0..frames)
                .map(|k| {
                    let t = start + k as f64 / rate;
                    let mut world = M4::identity();
                    for x in &m.xforms {
                        let local = *nearest(&x.samples, t);
                        world = if x.inherits { world * local } else { local };
                    }
                    nearest(&m.points, t)
                        .chunks(3)
                        .map(|c| {
                            let p = world
                                .transform_point(&V3::new(c[0], c[1], c[2]).into())
                                .coords;
                            // y up to z up.
                            V3::new(p.x, -p.z, p.y)
                        })
                        .collect()
                })
                .collect();
            Ok(ClipObject::read_mesh(
                m.name.trim_start_matches('/').to_string(),
                m.triangles.clone(),
                frame_list,
            ))
        })
        .collect::<Result<Vec<_>, String>>()?;
    Clip::read(name, rate, frames, objects)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An Ogawa file built by hand: data and groups appended, each at the
    /// offset `put` returns.
    struct Builder(Vec<u8>);

    impl Builder {
        fn new() -> Builder {
            let mut b = b"Ogawa\xff\x00\x01".to_vec();
            b.extend(0u64.to_le_bytes());
            Builder(b)
        }
        fn data(&mut self, bytes: &[u8]) -> u64 {
            let at = self.0.len() as u64;
            self.0.extend((bytes.len() as u64).to_le_bytes());
            self.0.extend(bytes);
            at | DATA_BIT
        }
        fn group(&mut self, children: &[u64]) -> u64 {
            let at = self.0.len() as u64;
            self.0.extend((children.len() as u64).to_le_bytes());
            for c in children {
                self.0.extend(c.to_le_bytes());
            }
            at
        }
        /// An archive whose top object is `top` (its group's offset, given
        /// to `make_top` to build it there).
        fn archive(mut self, make_top: impl FnOnce(&mut Builder, u64) -> u64) -> Vec<u8> {
            let version = self.data(&0i32.to_le_bytes());
            let file_version = self.data(&10709i32.to_le_bytes());
            let mut ts = Vec::new();
            ts.extend(1u32.to_le_bytes());
            ts.extend((1.0f64 / 24.0).to_le_bytes());
            ts.extend(1u32.to_le_bytes());
            ts.extend(0.0f64.to_le_bytes());
            let samplings = self.data(&ts);
            let top = make_top(&mut self, 0);
            let root = self.group(&[version, file_version, top, DATA_BIT, samplings, DATA_BIT]);
            self.0[8..16].copy_from_slice(&root.to_le_bytes());
            self.0
        }
    }

    /// Object headers naming one child `a` with no metadata, and the 32
    /// bytes of hashes after them.
    fn one_child() -> Vec<u8> {
        let mut h = Vec::new();
        h.extend(1u32.to_le_bytes());
        h.extend(b"a");
        h.push(0);
        h.extend([0u8; 32]);
        h
    }

    #[test]
    fn damaged_unfinished_and_foreign_files_are_refused_by_what_is_wrong() {
        let err = read_abc(b"\x89HDF\r\n\x1a\n________", "x").unwrap_err();
        assert!(
            err.contains("not an Alembic file") && err.contains("HDF5"),
            "{err}"
        );
        let mut unfinished = Builder::new().archive(|b, _| b.group(&[]));
        unfinished[5] = 0;
        let err = read_abc(&unfinished, "x").unwrap_err();
        assert!(err.contains("has not finished it"), "{err}");
        // An object whose child is itself: refused, not followed forever.
        let looped = Builder::new().archive(|b, _| {
            let headers = b.data(&one_child());
            let at = b.0.len() as u64 + 8 + 8;
            // [properties (none), the child (this very group), headers]:
            // the group starts after its own count, at `at - 16`.
            b.group(&[0, at - 16, headers])
        });
        let err = read_abc(&looped, "x").unwrap_err();
        assert!(err.contains("nest over 256 deep"), "{err}");
        // Every prefix of a real file ends in an error, never a panic.
        let real = Builder::new().archive(|b, _| {
            let headers = b.data(&one_child());
            let child = b.group(&[]);
            b.group(&[0, child, headers])
        });
        assert_eq!(
            read_abc(&real, "x").unwrap_err(),
            "no PolyMesh with points in it"
        );
        for cut in 0..real.len() {
            assert!(read_abc(&real[..cut], "x").is_err());
        }
        // A group that claims more children than the file holds.
        let mut greedy = real.clone();
        let root = u64::from_le_bytes(greedy[8..16].try_into().unwrap()) as usize;
        greedy[root..root + 8].copy_from_slice(&u64::MAX.to_le_bytes());
        let err = read_abc(&greedy, "x").unwrap_err();
        assert!(err.contains("more than the file holds"), "{err}");
    }

    #[test]
    fn xform_ops_compose_with_the_first_outermost() {
        let p = |m: &M4, x: V3| m.transform_point(&x.into()).coords;
        // translate (1, 2, 3), then rotate 90° about z: the rotation acts
        // first on the point.
        let m = xform_matrix(&[16.0, 96.0], &[1.0, 2.0, 3.0, 90.0]).unwrap();
        assert!((p(&m, V3::x()) - V3::new(1.0, 3.0, 3.0)).norm() < 1e-12);
        // A matrix op is Imath's row-vector matrix: its translation is
        // its last row.
        let mut rows = [0.0; 16];
        for k in 0..4 {
            rows[5 * k] = 1.0;
        }
        rows[12..15].copy_from_slice(&[5.0, 6.0, 7.0]);
        let m = xform_matrix(&[48.0], &rows).unwrap();
        assert_eq!(p(&m, V3::zeros()), V3::new(5.0, 6.0, 7.0));
        // Scale, and a rotation about an axis in degrees.
        let m = xform_matrix(&[0.0, 32.0], &[2.0, 3.0, 4.0, 0.0, 0.0, 1.0, 90.0]).unwrap();
        assert!((p(&m, V3::x()) - V3::new(0.0, 3.0, 0.0)).norm() < 1e-12);
        let err = xform_matrix(&[16.0], &[1.0]).unwrap_err();
        assert!(err.contains("more values than it holds"), "{err}");
        assert!(xform_matrix(&[112.0], &[1.0]).is_err());
    }

    #[test]
    fn stored_samples_follow_the_first_and_last_changes() {
        let h = |first, last, samples| PropertyHeader {
            name: String::new(),
            kind: 1,
            pod: Some(Pod::F32),
            samples,
            first_changed: first,
            last_changed: last,
            sampling: 0,
        };
        // Constant: every sample is the first.
        assert_eq!(h(0, 0, 10).stored(7), 0);
        // Samples 3..=6 change; before, the first; after, the last stored.
        let p = h(3, 6, 10);
        let stored: Vec<usize> = (0..10).map(|k| p.stored(k)).collect();
        assert_eq!(stored, [0, 0, 0, 1, 2, 3, 4, 4, 4, 4]);
        let cyclic = TimeSampling {
            times: vec![0.0, 0.25],
            per_cycle: Some(1.0),
        };
        assert_eq!(cyclic.time(3), 1.25);
        assert_eq!(half_to_f64(0x3c00), 1.0);
        assert_eq!(half_to_f64(0xc000), -2.0);
    }
}
