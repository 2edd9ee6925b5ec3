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
//!   Every `AbcGeom_Points` (a baked particle system), each particle an
//!   object of its own over its own life ([`points`]).
//! - **Time**: seconds, from each property's time sampling (uniform,
//!   cyclic or acyclic); the clip is sampled as a USD layer is
//!   ([`crate::formats::usd::read_usda_keys`]), one frame per shortest interval between
//!   samples, each property at its nearest sample.
//! - **Space**: Alembic is y up (Blender's exporter turns z up into it,
//!   Maya and Houdini are y up) and carries no unit; metres are assumed,
//!   as Blender and Houdini write them.
//!
//! The container and properties are [`archive`]'s, the transforms
//! [`xform`]'s, the particles [`points`]'; the meshes and the clip are
//! read here.

use crate::formats::clip::{Clip, ClipObject};
use crate::formats::sampling::{check_points, key_rate, sampled_frames};
use archive::{
    Archive, Child, Cursor, Ogawa, Sample, indexed_metadata, meta, nearest, time_samplings,
};
use points::{Cloud, particles, read_cloud};
use xform::{Xform, placed, read_xform, world_matrix};

mod archive;
mod points;
mod xform;

pub use archive::{MAX_DEPTH, MAX_OBJECTS};
pub use points::{DEFAULT_POINT_WIDTH_M, MAX_DEATHS_PER_SAMPLE};

/// A mesh found in the archive: its full name, faces as triangles, `P`
/// per sample, and the transforms above it (the root first).
struct Mesh {
    name: String,
    triangles: Vec<[u32; 3]>,
    points: Vec<Sample>,
    xforms: Vec<Xform>,
}

/// What a walk of the archive finds: its meshes and its point clouds.
#[derive(Default)]
struct Found {
    meshes: Vec<Mesh>,
    clouds: Vec<Cloud>,
}

/// Walks the object whose group's `children` are given (named `path`),
/// with the transforms above it, collecting meshes and point clouds.
fn walk(
    a: &Archive<'_>,
    children: &[Child],
    path: &str,
    above: &mut Vec<Xform>,
    out: &mut Found,
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
        let at = |e: String| format!("object `{}`: {e}", full.trim_start_matches('/'));
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
            out.meshes.push(read_mesh(a, g, &full, above).map_err(at)?);
        } else if schema.starts_with("AbcGeom_Points") {
            let g = a
                .sub_compound(props, ".geom")?
                .ok_or_else(|| at("a Points object without `.geom`".into()))?;
            out.clouds.push(read_cloud(a, g, &full, above).map_err(at)?);
        }
        walk(a, &own, &full, above, out, depth + 1, seen)?;
        if pushed {
            above.pop();
        }
    }
    Ok(())
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
    let mut found = Found::default();
    let top = archive.ogawa.group(top)?;
    walk(&archive, &top, "", &mut Vec::new(), &mut found, 0, &mut 0)?;
    let Found { meshes, clouds } = found;
    if meshes.is_empty()
        && clouds
            .iter()
            .all(|c| c.points.iter().all(|p| p.1.is_empty()))
    {
        return Err("no PolyMesh or Points with points in it".into());
    }
    // The key grid: every sample time of points and transforms.
    let mut times: Vec<f64> = meshes
        .iter()
        .map(|m| (&m.points, &m.xforms))
        .chain(clouds.iter().map(|c| (&c.points, &c.xforms)))
        .flat_map(|(points, xforms)| {
            points
                .iter()
                .map(|s| s.0)
                .chain(xforms.iter().flat_map(|x| x.samples.iter().map(|s| s.0)))
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
                    let world = world_matrix(&m.xforms, t);
                    nearest(&m.points, t)
                        .chunks(3)
                        .map(|c| placed(&world, c))
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
    let mut objects = objects;
    for cloud in &clouds {
        objects.extend(
            particles(cloud, start, rate, frames)
                .map_err(|e| format!("object `{}`: {e}", cloud.name.trim_start_matches('/')))?,
        );
    }
    Clip::read(name, rate, frames, objects)
}

#[cfg(test)]
mod tests {
    use super::*;
    use archive::DATA_BIT;

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
            "no PolyMesh or Points with points in it"
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
}
