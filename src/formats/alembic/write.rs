//! Alembic (`.abc`) export: the point cache Maya, Houdini and Blender read
//! natively (Maya reads no PC2 without a plug-in). One Ogawa file, laid out
//! as the Alembic 1.8 library lays it out (the reader's module docs,
//! [`super::read`], describe the layout): per object an `AbcGeom_Xform`
//! named as the object (its USD identifier, `_2`, `_3` … appended where two
//! objects' identifiers are the same) carrying the moving
//! frame as a matrix per frame, over an `AbcGeom_PolyMesh` `<name>_mesh`
//! with the shown vertices in that frame (written once for a rigid object),
//! its faces (triangles, wound clockwise as Alembic winds them) and bounds.
//! Time: one uniform sampling at the clip's rate from t = 0. Space: y up in
//! metres, as Alembic clients expect (Blender's importer turns it back to
//! z up). Each stored sample carries a 128-bit key, MurmurHash3 (x64,
//! 128-bit, seed 0) of its bytes, as the Alembic library computes it
//! (a test checks it against the keys in a file Blender wrote), which
//! readers use to share equal samples.

use crate::formats::clip::look::shown;
use crate::formats::clip::{Clip, ClipObject};
use crate::formats::error::ExportError;
use crate::formats::usd::unique_identifiers;
use nalgebra::{Matrix4, Vector3};
use std::path::Path;

type V3 = Vector3<f64>;

/// The Ogawa file being written: data and groups appended in order, each
/// addressed by its offset (data with the top bit set).
struct Ogawa(Vec<u8>);

const DATA: u64 = 1 << 63;

impl Ogawa {
    fn data(&mut self, bytes: &[u8]) -> u64 {
        if bytes.is_empty() {
            return DATA;
        }
        let at = self.0.len() as u64;
        self.0.extend((bytes.len() as u64).to_le_bytes());
        self.0.extend(bytes);
        at | DATA
    }
    fn group(&mut self, children: &[u64]) -> u64 {
        if children.is_empty() {
            return 0;
        }
        let at = self.0.len() as u64;
        self.0.extend((children.len() as u64).to_le_bytes());
        for c in children {
            self.0.extend(c.to_le_bytes());
        }
        at
    }
}

/// MurmurHash3 x64 128 of `data` with `seed` (Appleby's public-domain
/// algorithm), as 16 little-endian bytes: the key of a stored sample.
fn murmur3_128(data: &[u8], seed: u64) -> [u8; 16] {
    const C1: u64 = 0x87c3_7b91_1142_53d5;
    const C2: u64 = 0x4cf5_ad43_2745_937f;
    let fmix = |mut k: u64| {
        k ^= k >> 33;
        k = k.wrapping_mul(0xff51_afd7_ed55_8ccd);
        k ^= k >> 33;
        k = k.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        k ^ (k >> 33)
    };
    let (mut h1, mut h2) = (seed, seed);
    let blocks = data.chunks_exact(16);
    let tail = blocks.remainder();
    for b in blocks {
        let k1 = u64::from_le_bytes(b[..8].try_into().expect("8"));
        let k2 = u64::from_le_bytes(b[8..].try_into().expect("8"));
        h1 ^= k1.wrapping_mul(C1).rotate_left(31).wrapping_mul(C2);
        h1 = h1
            .rotate_left(27)
            .wrapping_add(h2)
            .wrapping_mul(5)
            .wrapping_add(0x52dc_e729);
        h2 ^= k2.wrapping_mul(C2).rotate_left(33).wrapping_mul(C1);
        h2 = h2
            .rotate_left(31)
            .wrapping_add(h1)
            .wrapping_mul(5)
            .wrapping_add(0x3849_5ab5);
    }
    let mut last = [0u8; 16];
    last[..tail.len()].copy_from_slice(tail);
    let (k1, k2) = (
        u64::from_le_bytes(last[..8].try_into().expect("8")),
        u64::from_le_bytes(last[8..].try_into().expect("8")),
    );
    if tail.len() > 8 {
        h2 ^= k2.wrapping_mul(C2).rotate_left(33).wrapping_mul(C1);
    }
    if !tail.is_empty() {
        h1 ^= k1.wrapping_mul(C1).rotate_left(31).wrapping_mul(C2);
    }
    let len = data.len() as u64;
    h1 ^= len;
    h2 ^= len;
    h1 = h1.wrapping_add(h2);
    h2 = h2.wrapping_add(h1);
    h1 = fmix(h1);
    h2 = fmix(h2);
    h1 = h1.wrapping_add(h2);
    h2 = h2.wrapping_add(h1);
    let mut out = [0u8; 16];
    out[..8].copy_from_slice(&h1.to_le_bytes());
    out[8..].copy_from_slice(&h2.to_le_bytes());
    out
}

/// Plain-old-data types written here, by Alembic's codes.
#[derive(Clone, Copy)]
enum Pod {
    Bool = 0,
    U8 = 1,
    U32 = 5,
    I32 = 6,
    F32 = 10,
    F64 = 11,
}

/// A property to write: its header and its samples' bytes (one entry: the
/// same at every sample; else one per sample).
struct Property {
    name: &'static str,
    /// 1 scalar, 2 array.
    kind: u32,
    pod: Pod,
    extent: u32,
    /// How many samples it has (each frame, or 1).
    samples: u32,
    /// Its time sampling: 0 the identity, 1 the clip's.
    sampling: u32,
    metadata: &'static str,
    values: Vec<Vec<u8>>,
}

impl Property {
    /// A scalar (`kind` 1) or array (2) property named `name` of `extent`
    /// values of `pod` per sample, `samples` samples at the clip's time
    /// sampling, with `values` stored (one: the same at every sample).
    fn new(
        name: &'static str,
        kind: u32,
        pod: Pod,
        extent: u32,
        samples: u32,
        values: Vec<Vec<u8>>,
    ) -> Property {
        Property {
            name,
            kind,
            pod,
            extent,
            samples,
            sampling: 1,
            metadata: "",
            values,
        }
    }

    /// With `metadata`.
    fn with_metadata(self, metadata: &'static str) -> Property {
        Property { metadata, ..self }
    }

    /// At the identity time sampling (0), as the library writes constant
    /// schema properties.
    fn untimed(self) -> Property {
        Property {
            sampling: 0,
            ..self
        }
    }

    /// Its group (each stored sample a keyed datum, an array's with its
    /// dimensions after it, empty: one rank, from the size) and its packed
    /// header.
    fn write(&self, f: &mut Ogawa) -> (u64, Vec<u8>) {
        let mut children = Vec::new();
        for v in &self.values {
            let mut datum = murmur3_128(v, 0).to_vec();
            datum.extend(v);
            children.push(f.data(&datum));
            if self.kind == 2 {
                children.push(DATA);
            }
        }
        let constant = self.values.len() == 1;
        // Size hint 2 (every number below in 4 bytes), a time sampling,
        // homogeneous, constant or every sample stored, metadata inline.
        let mut info = self.kind | (2 << 2) | ((self.pod as u32) << 4) | 0x100 | 0x400;
        if constant {
            info |= 0x800;
        }
        info |= self.extent << 12;
        info |= 0xff << 20;
        let mut h = info.to_le_bytes().to_vec();
        for n in [self.samples, self.sampling, self.name.len() as u32] {
            h.extend(n.to_le_bytes());
        }
        h.extend(self.name.as_bytes());
        h.extend((self.metadata.len() as u32).to_le_bytes());
        h.extend(self.metadata.as_bytes());
        (f.group(&children), h)
    }
}

/// A compound property's group: its sub-properties, then their headers.
/// (`subs` are written compounds: their group and their own header.)
fn compound(f: &mut Ogawa, props: &[Property], subs: Vec<(u64, Vec<u8>)>) -> u64 {
    let mut children = Vec::new();
    let mut headers = Vec::new();
    for p in props {
        let (g, h) = p.write(f);
        children.push(g);
        headers.extend(h);
    }
    for (g, h) in subs {
        children.push(g);
        headers.extend(h);
    }
    let h = f.data(&headers);
    children.push(h);
    f.group(&children)
}

/// A compound sub-property's header: named `name`, metadata inline.
fn compound_header(name: &str, metadata: &str) -> Vec<u8> {
    let info: u32 = (2 << 2) | (0xff << 20);
    let mut h = info.to_le_bytes().to_vec();
    h.extend((name.len() as u32).to_le_bytes());
    h.extend(name.as_bytes());
    h.extend((metadata.len() as u32).to_le_bytes());
    h.extend(metadata.as_bytes());
    h
}

/// An object's group: its properties' compound, its children's groups,
/// their headers (name and inline metadata each) and 32 bytes of hashes.
fn object(f: &mut Ogawa, properties: u64, children: &[(String, &str, u64)]) -> u64 {
    let mut groups = vec![properties];
    let mut headers = Vec::new();
    for (name, metadata, g) in children {
        groups.push(*g);
        headers.extend((name.len() as u32).to_le_bytes());
        headers.extend(name.as_bytes());
        headers.push(0xff);
        headers.extend((metadata.len() as u32).to_le_bytes());
        headers.extend(metadata.as_bytes());
    }
    headers.extend(murmur3_128(&headers, 0));
    headers.extend([0u8; 16]);
    let h = f.data(&headers);
    groups.push(h);
    f.group(&groups)
}

const XFORM: &str = "schema=AbcGeom_Xform_v3;schemaObjTitle=AbcGeom_Xform_v3:.xform";
const POLYMESH: &str = "schema=AbcGeom_PolyMesh_v1;schemaBaseType=AbcGeom_GeomBase_v1;schemaObjTitle=AbcGeom_PolyMesh_v1:.geom";

/// A face-varying V2f geometry parameter's metadata (the library's, its
/// keys sorted as it writes them).
const UV: &str = "arrayExtent=1;geoScope=fvr;interpretation=vector;isGeomParam=true;podExtent=2;podName=float32_t";

/// z up (leafmagic) to y up (Alembic): (x, y, z) → (x, z, −y).
fn y_up(p: &V3) -> V3 {
    V3::new(p.x, p.z, -p.y)
}

fn f32s(points: &[V3]) -> Vec<u8> {
    points
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .flat_map(|c| (c as f32).to_le_bytes())
        .collect()
}

fn f64s(values: impl IntoIterator<Item = f64>) -> Vec<u8> {
    values.into_iter().flat_map(f64::to_le_bytes).collect()
}

/// The bounds of `points` as Alembic's box: min x, y, z, max x, y, z.
fn bounds(points: &[V3]) -> Vec<u8> {
    let lo = points
        .iter()
        .fold(V3::repeat(f64::INFINITY), |a, p| a.inf(p));
    let hi = points
        .iter()
        .fold(V3::repeat(f64::NEG_INFINITY), |a, p| a.sup(p));
    f64s([lo.x, lo.y, lo.z, hi.x, hi.y, hi.z])
}

/// One object as an Xform over a PolyMesh; its group.
fn write_object(f: &mut Ogawa, clip: &Clip, o: &ClipObject, id: &str) -> Result<u64, ExportError> {
    let framed = o.framed();
    let surface = shown(o, &framed);
    if surface.triangles.is_empty() {
        return Err(ExportError::Data(format!(
            "{}: object {} has no faces (a rope); Alembic export writes meshes: export it as glb or usd",
            clip.name, o.name
        )));
    }
    let frames = clip.frames as u32;
    // The mesh: its shown vertices in the moving frame, y up.
    let local = |k: usize| -> Vec<V3> {
        let l = framed.local_at(k);
        let l = match &o.render {
            Some(r) => r.place(l, &o.triangles),
            None => l.to_vec(),
        };
        l.iter().map(y_up).collect()
    };
    let shapes: Vec<Vec<V3>> = if framed.deforms() {
        (0..clip.frames).map(local).collect()
    } else {
        vec![local(0)]
    };
    let indices: Vec<u8> = surface
        .triangles
        .iter()
        // Alembic winds faces clockwise.
        .flat_map(|t| [t[0], t[2], t[1]])
        .flat_map(|i| (i as i32).to_le_bytes())
        .collect();
    let counts: Vec<u8> = surface
        .triangles
        .iter()
        .flat_map(|_| 3i32.to_le_bytes())
        .collect();
    let samples = |v: &Vec<_>| if v.len() > 1 { frames } else { 1 };
    // The texture coordinates, as the library writes a PolyMesh's `uv`: an
    // indexed face-varying geometry parameter, one value per vertex and,
    // per face corner, its vertex (the faces' own indices), so that a
    // dressed leaf's texture lands where its USD and glTF put it.
    let uv_values: Vec<u8> = surface
        .uvs
        .iter()
        .flat_map(|u| [u[0] as f32, u[1] as f32])
        .flat_map(f32::to_le_bytes)
        .collect();
    let uv = compound(
        f,
        &[
            Property::new(".vals", 2, Pod::F32, 2, 1, vec![uv_values]).with_metadata(UV),
            Property::new(".indices", 2, Pod::U32, 1, 1, vec![indices.clone()]),
        ],
        Vec::new(),
    );
    let uv = (uv, compound_header("uv", UV));
    let geom = compound(
        f,
        &[
            Property::new(
                ".selfBnds",
                1,
                Pod::F64,
                6,
                samples(&shapes),
                shapes.iter().map(|s| bounds(s)).collect(),
            )
            .with_metadata("interpretation=box"),
            Property::new(
                "P",
                2,
                Pod::F32,
                3,
                samples(&shapes),
                shapes.iter().map(|s| f32s(s)).collect(),
            )
            .with_metadata("geoScope=vtx;interpretation=point"),
            Property::new(".faceIndices", 2, Pod::I32, 1, 1, vec![indices]),
            Property::new(".faceCounts", 2, Pod::I32, 1, 1, vec![counts]),
        ],
        vec![uv],
    );
    let geom_props = compound(
        f,
        &[],
        vec![(
            geom,
            compound_header(
                ".geom",
                "schema=AbcGeom_PolyMesh_v1;schemaBaseType=AbcGeom_GeomBase_v1",
            ),
        )],
    );
    let mesh = object(f, geom_props, &[]);
    // The moving frame: [R c; 0 1] in y up, Imath's row-vector matrix, whose
    // rows are the columns of ours.
    let to_y = Matrix4::new(
        1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    );
    let matrices: Vec<Vec<u8>> = (0..clip.frames)
        .map(|k| {
            let m = framed.rotation[k]
                .to_homogeneous()
                .append_translation(&framed.origin[k]);
            let m = to_y * m * to_y.transpose();
            f64s(m.iter().copied())
        })
        .collect();
    let xform = compound(
        f,
        &[
            // Readers take an Xform's sample count and sampling from
            // `.inherits` (Alembic's IXformSchema): one per frame, all equal.
            Property::new(".inherits", 1, Pod::Bool, 1, frames, vec![vec![1]]),
            // One matrix op (type 3 in the high nibble).
            Property::new(".ops", 1, Pod::U8, 1, 1, vec![vec![0x30]]).untimed(),
            Property::new(".vals", 1, Pod::F64, 16, frames, matrices),
            // Its presence says the transform is not a constant identity.
            Property::new("isNotConstantIdentity", 1, Pod::Bool, 1, 1, vec![vec![1]]).untimed(),
            Property::new(
                ".animChans",
                2,
                Pod::U32,
                1,
                1,
                vec![(0u32..16).flat_map(u32::to_le_bytes).collect()],
            ),
        ],
        Vec::new(),
    );
    let xform_props = compound(
        f,
        &[],
        vec![(xform, compound_header(".xform", "schema=AbcGeom_Xform_v3"))],
    );
    Ok(object(
        f,
        xform_props,
        &[(format!("{id}_mesh"), POLYMESH, mesh)],
    ))
}

/// Writes `clip` as an Alembic archive at `path` (written aside and moved
/// into place, so a failed export leaves nothing half-written); returns
/// its size in bytes.
pub fn write_abc(clip: &Clip, path: &Path) -> Result<usize, ExportError> {
    clip.validate()?;
    let mut f = Ogawa(b"Ogawa\xff\x00\x01".to_vec());
    f.0.extend(0u64.to_le_bytes());
    let version = f.data(&0i32.to_le_bytes());
    let file_version = f.data(&10709i32.to_le_bytes());
    let ids = unique_identifiers(
        clip.objects.iter().map(|o| o.name.as_str()),
        &mut Default::default(),
    );
    let mut children = Vec::new();
    for (o, id) in clip.objects.iter().zip(ids) {
        let group = write_object(&mut f, clip, o, &id)?;
        children.push((id, XFORM, group));
    }
    let top = object(&mut f, 0, &children);
    // The archive's metadata (`key=value;…`): the law the falls were
    // simulated under, when known, beside the application.
    let law = if clip.aero_law.is_empty() {
        String::new()
    } else {
        format!(";leafmagic_aero_law={}", clip.aero_law)
    };
    let metadata = f.data(
        format!(
            "_ai_Application=leafmagic {};FramesPerTimeUnit={}{law}",
            env!("CARGO_PKG_VERSION"),
            clip.fps
        )
        .as_bytes(),
    );
    // Sampling 0, the identity; 1, uniform at the clip's rate from 0.
    let mut ts = Vec::new();
    for (max, tpc) in [(1u32, 1.0), (clip.frames as u32, 1.0 / clip.fps)] {
        ts.extend(max.to_le_bytes());
        ts.extend(tpc.to_le_bytes());
        ts.extend(1u32.to_le_bytes());
        ts.extend(0.0f64.to_le_bytes());
    }
    let samplings = f.data(&ts);
    let root = f.group(&[version, file_version, top, metadata, samplings, DATA]);
    f.0[8..16].copy_from_slice(&root.to_le_bytes());
    let size = f.0.len();
    crate::util::io::write_atomic(path, &f.0).map_err(|e| ExportError::io(path, e))?;
    Ok(size)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex(s: &str) -> Vec<u8> {
        (0..s.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
            .collect()
    }

    #[test]
    fn sample_keys_are_the_alembic_library_s() {
        // The P and .faceIndices samples of tests/data/blender/tumble_thick.abc
        // (Blender 5.0.1, Alembic 1.8.3) and the keys the library wrote
        // before them.
        for (values, key) in [
            (
                "0ad7a3bc000000000ad7a33b0ad7a33c000000000ad7a33b0ad7a33c000000000ad7a3bb0ad7a3bc000000000ad7a3bb",
                "3b56be7c3305fe90cc132fcba6e10197",
            ),
            (
                "03000000020000000100000000000000",
                "e1511475973df847566ced44251759be",
            ),
        ] {
            assert_eq!(murmur3_128(&hex(values), 0).to_vec(), hex(key));
        }
        // Tails of every length hash apart.
        let keys: std::collections::HashSet<[u8; 16]> =
            (0..40).map(|n| murmur3_128(&vec![7u8; n], 0)).collect();
        assert_eq!(keys.len(), 40);
    }
}
