//! The Alembic archive under the schemas: the Ogawa container (groups and
//! data, every offset checked), the archive's time samplings and indexed
//! metadata, and properties with their headers and samples (the layout in
//! the module docs of [`super`]).

use crate::formats::sampling::MAX_FRAMES;
use std::rc::Rc;

/// Deepest nesting of groups followed (objects under objects, compounds
/// under compounds): far beyond any scene, and a bound on a damaged file
/// whose offsets loop.
pub const MAX_DEPTH: usize = 256;

/// Most objects read: a damaged file whose objects share one group many
/// times over would otherwise be walked exponentially often.
pub const MAX_OBJECTS: usize = 100_000;

/// The Ogawa container over a file's bytes.
pub(super) struct Ogawa<'a> {
    pub(super) bytes: &'a [u8],
}

/// A child of an Ogawa group.
#[derive(Clone, Copy, Debug)]
pub(super) enum Child {
    Group(u64),
    Data(u64),
}

pub(super) const DATA_BIT: u64 = 1 << 63;

impl<'a> Ogawa<'a> {
    pub(super) fn u64_at(&self, pos: u64) -> Result<u64, String> {
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
    pub(super) fn group(&self, pos: u64) -> Result<Vec<Child>, String> {
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
    pub(super) fn data(&self, pos: u64) -> Result<&'a [u8], String> {
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

    pub(super) fn child_data(
        &self,
        children: &[Child],
        k: usize,
        what: &str,
    ) -> Result<&'a [u8], String> {
        match children.get(k) {
            Some(Child::Data(p)) => self.data(*p),
            _ => Err(format!("no {what} where the Alembic layout puts it")),
        }
    }
}

/// Reads little-endian numbers from a byte slice, each read checked.
pub(super) struct Cursor<'a> {
    pub(super) bytes: &'a [u8],
    pub(super) at: usize,
}

impl<'a> Cursor<'a> {
    pub(super) fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| format!("{what} runs past its record: it is damaged"))?;
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }
    pub(super) fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.take(1, what)?[0])
    }
    pub(super) fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4, what)?.try_into().expect("4"),
        ))
    }
    pub(super) fn f64(&mut self, what: &str) -> Result<f64, String> {
        Ok(f64::from_le_bytes(
            self.take(8, what)?.try_into().expect("8"),
        ))
    }
    /// A u32 stored in 1, 2 or 4 bytes (a property header's size hint).
    pub(super) fn hinted(&mut self, hint: u32, what: &str) -> Result<u32, String> {
        Ok(match hint {
            0 => u32::from(self.u8(what)?),
            1 => u32::from(u16::from_le_bytes(
                self.take(2, what)?.try_into().expect("2"),
            )),
            _ => self.u32(what)?,
        })
    }
    pub(super) fn done(&self) -> bool {
        self.at >= self.bytes.len()
    }
}

/// When a property's samples are taken: the first sample's time (and the
/// others' within a cycle) and the time per cycle, or every sample's time
/// (acyclic).
#[derive(Clone, Debug)]
pub(super) struct TimeSampling {
    pub(super) times: Vec<f64>,
    /// `None`: acyclic.
    pub(super) per_cycle: Option<f64>,
}

impl TimeSampling {
    /// Time of sample `k`, s.
    pub(super) fn time(&self, k: usize) -> f64 {
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
pub(super) fn time_samplings(bytes: &[u8]) -> Result<Vec<TimeSampling>, String> {
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
pub(super) fn indexed_metadata(bytes: &[u8]) -> Result<Vec<String>, String> {
    let mut c = Cursor { bytes, at: 0 };
    let mut out = vec![String::new()];
    while !c.done() {
        let n = c.u8("an indexed metadata string")? as usize;
        out.push(String::from_utf8_lossy(c.take(n, "an indexed metadata string")?).into_owned());
    }
    Ok(out)
}

/// A metadata string's value for `key` (`k=v;k=v`).
pub(super) fn meta<'m>(metadata: &'m str, key: &str) -> Option<&'m str> {
    metadata
        .split(';')
        .filter_map(|kv| kv.split_once('='))
        .find(|(k, _)| *k == key)
        .map(|(_, v)| v)
}

/// Plain-old-data types, by the codes Alembic writes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Pod {
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
    pub(super) fn of(code: u32) -> Option<Pod> {
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
pub(super) struct PropertyHeader {
    pub(super) name: String,
    /// 0 compound, 1 scalar, 2 or 3 array (3: an array whose every sample
    /// holds one value, "scalar-like", which Alembic stores as an array).
    pub(super) kind: u32,
    pub(super) pod: Option<Pod>,
    /// Samples written, and the first and last that change (the others
    /// repeat a stored one).
    pub(super) samples: usize,
    pub(super) first_changed: usize,
    pub(super) last_changed: usize,
    pub(super) sampling: usize,
}

impl PropertyHeader {
    /// Which stored sample sample `k` is (Alembic stores the first, then
    /// those from the first change to the last).
    pub(super) fn stored(&self, k: usize) -> usize {
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
pub(super) fn property_headers(
    bytes: &[u8],
    indexed: usize,
) -> Result<Vec<PropertyHeader>, String> {
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
pub(super) fn numbers(pod: Pod, bytes: &[u8]) -> Option<Vec<f64>> {
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
pub(super) fn half_to_f64(h: u16) -> f64 {
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
pub(super) struct Property {
    pub(super) header: PropertyHeader,
    /// Its group (0: none), and the group's children (samples; for an
    /// array, datum and dimensions; for a compound, its properties).
    pub(super) group: u64,
    pub(super) children: Vec<Child>,
}

/// The archive, with what every property read needs.
pub(super) struct Archive<'a> {
    pub(super) ogawa: Ogawa<'a>,
    pub(super) samplings: Vec<TimeSampling>,
    pub(super) metadata: Vec<String>,
}

impl Archive<'_> {
    /// The properties of the compound group at `pos`.
    pub(super) fn compound(&self, pos: u64) -> Result<Vec<Property>, String> {
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
    pub(super) fn sub_compound(&self, pos: u64, name: &str) -> Result<Option<u64>, String> {
        Ok(self
            .compound(pos)?
            .into_iter()
            .find(|p| p.header.name == name && p.header.kind == 0)
            .map(|p| p.group))
    }

    /// Sample `k` of `p` as numbers, and its time, s.
    pub(super) fn sample(&self, p: &Property, k: usize) -> Result<(Vec<f64>, f64), String> {
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
    pub(super) fn samples(&self, p: &Property) -> Result<Vec<Sample>, String> {
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
    pub(super) fn time(&self, p: &Property, k: usize) -> Result<f64, String> {
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
pub(super) type Sample = (f64, Rc<Vec<f64>>);

/// The value of a sampled quantity at time `t`: its nearest sample
/// (Alembic's default sample selector).
pub(super) fn nearest<T>(samples: &[(f64, T)], t: f64) -> &T {
    &samples[nearest_index(samples, t)].1
}

/// The index of the sample nearest `t` ([`nearest`]).
pub(super) fn nearest_index<T>(samples: &[(f64, T)], t: f64) -> usize {
    let j = samples.partition_point(|(s, _)| *s < t);
    if j == 0 {
        0
    } else if j == samples.len() || t - samples[j - 1].0 <= samples[j].0 - t {
        j - 1
    } else {
        j
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
