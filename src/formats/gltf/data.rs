//! A glTF document opened, checked and its arrays read without trusting
//! it: what the gltf crate (1.4) would refuse wrongly or panic on is
//! handled here, for the readers of [`super::read`]. Its buffers come from
//! a `.glb`'s binary chunk, data URIs or files beside a `.gltf`; required
//! extensions are decoded (KHR_mesh_quantization), left unread (looks
//! only) or refused by name; every accessor handed to the crate's readers
//! is checked first, since they meet a component type they do not expect
//! with `unreachable!`.

use crate::formats::error::ExportError;
use crate::util::confined::ReadScope;
use gltf::accessor::DataType::{F32, I8, I16, U8, U16};
use gltf::accessor::{DataType, Dimensions};
use gltf::animation::Property;
use std::path::Path;

/// The bytes of each buffer of a glTF document: the binary chunk of a
/// `.glb`, a `data:` URI (base64), or a file beside the `.gltf`, in its
/// folder `dir` and only where `scope` lets a reference reach
/// ([`ReadScope::read`]). Every buffer is charged to `budget` (the
/// scope's, or a scope of its own for a read without files).
pub(super) fn buffer_data(
    gltf: &gltf::Gltf,
    files: Option<(&Path, &ReadScope)>,
    budget: &ReadScope,
) -> Result<Vec<Option<Vec<u8>>>, ExportError> {
    use base64::Engine as _;
    let charge = |bytes: usize, b: usize| {
        budget
            .charge(bytes as u64, &format!("buffer {b}"))
            .map_err(ExportError::Data)
    };
    gltf.document
        .buffers()
        .map(|b| match b.source() {
            gltf::buffer::Source::Bin => {
                if let Some(blob) = &gltf.blob {
                    charge(blob.len(), b.index())?;
                }
                Ok(gltf.blob.clone())
            }
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, data) = rest.split_once(";base64,").ok_or_else(|| {
                        ExportError::Data(format!(
                            "buffer {}: a data URI that is not base64",
                            b.index()
                        ))
                    })?;
                    // What it decodes to, at most: 3 bytes per 4 characters.
                    charge(data.len() / 4 * 3 + 3, b.index())?;
                    return base64::engine::general_purpose::STANDARD
                        .decode(data)
                        .map(Some)
                        .map_err(|e| {
                            ExportError::Data(format!(
                                "buffer {}: its base64 data URI does not decode: {e}",
                                b.index()
                            ))
                        });
                }
                let Some((dir, scope)) = files else {
                    return Ok(None);
                };
                scope.read(dir, uri).map(Some).map_err(|why| {
                    ExportError::Data(format!(
                        "buffer {} refers to the file `{uri}`, which is not read: {why}",
                        b.index(),
                    ))
                })
            }
        })
        .collect()
}

/// A glTF document's buffers as read, and the budget its decoding is
/// charged to: what every accessor is checked against before it is read.
pub(super) struct Reading<'s> {
    /// Each buffer's bytes ([`buffer_data`]); `None` where not read.
    pub buffers: &'s [Option<Vec<u8>>],
    /// The memory budget of the read.
    pub budget: &'s ReadScope,
}

impl<'s> Reading<'s> {
    /// The buffer data getter the gltf crate's readers take.
    pub fn get(&self) -> impl Clone + for<'b> Fn(gltf::Buffer<'b>) -> Option<&'s [u8]> + 's {
        let buffers = self.buffers;
        move |b: gltf::Buffer<'_>| buffers.get(b.index()).and_then(|d| d.as_deref())
    }
}

/// Keys of glTF 2.0 JSON whose numbers are indices into the document's
/// arrays (`attributes` and morph `targets` hold them as values).
const INDEX_KEYS: [&str; 21] = [
    "scene",
    "nodes",
    "children",
    "mesh",
    "skin",
    "camera",
    "attributes",
    "targets",
    "indices",
    "material",
    "joints",
    "skeleton",
    "inverseBindMatrices",
    "sampler",
    "node",
    "input",
    "output",
    "bufferView",
    "buffer",
    "source",
    "index",
];

/// Refuses an index past what gltf-json 1.4 keeps: it reads an index as
/// a u64 and truncates it to 32 bits (`as u32`), so that mesh 2^40 would
/// read as mesh 0. Walks the JSON without recursion (its nesting is the
/// file's); `extras` are the author's own and left alone.
fn check_index_widths(json: &serde_json::Value) -> Result<(), ExportError> {
    use serde_json::Value;
    let too_wide = |v: &Value| v.as_u64().is_some_and(|n| n > u64::from(u32::MAX));
    let mut stack: Vec<(String, &Value)> = vec![(String::new(), json)];
    while let Some((path, value)) = stack.pop() {
        let children: Vec<(String, &Value)> = match value {
            // Only containers are walked into: a scalar is checked
            // where its key is seen, and needs no path of its own.
            Value::Object(map) => map
                .iter()
                .filter(|(k, v)| *k != "extras" && (v.is_object() || v.is_array()))
                .map(|(k, v)| (format!("{path}.{k}"), v))
                .collect(),
            Value::Array(items) => items
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_object() || v.is_array())
                .map(|(i, v)| (format!("{path}[{i}]"), v))
                .collect(),
            _ => continue,
        };
        if let Value::Object(map) = value {
            for (key, v) in map.iter().filter(|(k, _)| INDEX_KEYS.contains(&k.as_str())) {
                // The index itself or a list of them; a primitive's
                // attributes and morph targets map names to them.
                let maps = matches!(key.as_str(), "attributes" | "targets");
                let mut found: Vec<(String, &Value)> = vec![(String::new(), v)];
                if let Some(items) = v.as_array() {
                    found.extend(items.iter().enumerate().map(|(i, x)| (format!("[{i}]"), x)));
                }
                if maps {
                    let mut inner: Vec<(String, &Value)> = Vec::new();
                    for (at, x) in &found {
                        for (k, y) in x.as_object().into_iter().flatten() {
                            inner.push((format!("{at}.{k}"), y));
                        }
                    }
                    found.extend(inner);
                }
                if let Some((at, n)) = found.into_iter().find(|(_, x)| too_wide(x)) {
                    let field = format!("{path}.{key}{at}");
                    return Err(ExportError::Data(format!(
                        "`{}` holds the index {n}, past any array a glTF file can hold (indices are below 2^32)",
                        field.trim_start_matches('.')
                    )));
                }
            }
        }
        stack.extend(children);
    }
    Ok(())
}

/// Required extensions that change neither where a mesh's vertices are nor
/// how it moves (materials, textures, lights, material variants): a reader
/// of falls may leave them unread, as a viewer without them would draw the
/// same motion with plainer looks.
const LOOKS_ONLY: [&str; 5] = [
    "KHR_materials_",
    "KHR_texture_",
    "EXT_texture_",
    "MSFT_texture_",
    "KHR_lights_punctual",
];

/// Parses a glTF document and checks it as the gltf crate does, except
/// for the extensions it requires: KHR_mesh_quantization is decoded here
/// ([`vec3s`]), extensions of looks alone ([`LOOKS_ONLY`]) are left
/// unread, and any other is refused by name: compressed geometry (Draco,
/// meshopt) with how to write the file without it.
pub(super) fn open_gltf(bytes: &[u8]) -> Result<gltf::Gltf, ExportError> {
    use gltf::json::validation::Validate;
    let invalid = |e: gltf::Error| ExportError::Data(format!("not a valid glTF file: {e}"));
    // gltf 1.4 subtracts the 12-byte header from the length a `.glb`
    // states without checking that it is at least that.
    if let Some(length) = bytes
        .strip_prefix(b"glTF")
        .and_then(|rest| rest.get(4..8))
        .map(|l| u32::from_le_bytes([l[0], l[1], l[2], l[3]]))
        && length < 12
    {
        return Err(ExportError::Data(format!(
            "not a valid glTF file: its header states a length of {length} bytes, less than the header's 12"
        )));
    }
    let json: serde_json::Value = if bytes.starts_with(b"glTF") {
        let glb = gltf::binary::Glb::from_slice(bytes).map_err(invalid)?;
        serde_json::from_slice(&glb.json)
    } else {
        serde_json::from_slice(bytes)
    }
    .map_err(|e| invalid(gltf::Error::Deserialize(e)))?;
    check_index_widths(&json)?;
    drop(json);
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(invalid)?;
    for ext in gltf.document.extensions_required() {
        let refuse = |what: &str, fix: &str| {
            Err(ExportError::Data(format!(
                "the file requires the glTF extension {ext} ({what}), which leafmagic does not decode: {fix}"
            )))
        };
        match ext {
            "KHR_mesh_quantization" => {}
            e if LOOKS_ONLY.iter().any(|p| e.starts_with(p)) => {}
            "KHR_draco_mesh_compression" => {
                return refuse(
                    "Draco-compressed geometry",
                    "write it without Draco compression (Blender's glTF export: Data › Compression off)",
                );
            }
            "EXT_meshopt_compression" | "KHR_meshopt_compression" => {
                return refuse(
                    "meshopt-compressed buffers",
                    "write it without them (gltfpack: leave out -c and -cc; its quantisation alone is read)",
                );
            }
            _ => {
                return Err(ExportError::Data(format!(
                    "the file requires the glTF extension {ext}, which leafmagic does not read (it reads KHR_mesh_quantization, and leaves extensions of materials, textures and lights unread)"
                )));
            }
        }
    }
    let root = gltf.document.as_json();
    // gltf-json 1.4's own check of a primitive reads its POSITION accessor
    // unchecked, and panics on an index past the accessors: check it first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (k, prim) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(i) = prim.attributes.get(&position)
                && i.value() >= root.accessors.len()
            {
                return Err(invalid(gltf::Error::Validation(vec![(
                    gltf::json::Path::new()
                        .field("meshes")
                        .index(m)
                        .field("primitives")
                        .index(k)
                        .field("attributes")
                        .key("POSITION"),
                    gltf::json::validation::Error::IndexOutOfBounds,
                )])));
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path();
        if !path.as_str().starts_with("extensionsRequired") {
            errors.push((path, error));
        }
    });
    // gltf-json 1.4 checks a channel's sampler index but not its target,
    // whose reader then unwraps a missing node or an unknown path.
    for (i, anim) in root.animations.iter().enumerate() {
        for (c, channel) in anim.channels.iter().enumerate() {
            let at = |field: &str| {
                gltf::json::Path::new()
                    .field("animations")
                    .index(i)
                    .field("channels")
                    .index(c)
                    .field("target")
                    .field(field)
            };
            use gltf::json::validation::Error::{IndexOutOfBounds, Invalid};
            if channel.target.node.value() >= root.nodes.len() {
                errors.push((at("node"), IndexOutOfBounds));
            }
            if matches!(
                channel.target.path,
                gltf::json::validation::Checked::Invalid
            ) {
                errors.push((at("path"), Invalid));
            }
        }
    }
    if errors.is_empty() {
        Ok(gltf)
    } else {
        Err(invalid(gltf::Error::Validation(errors)))
    }
}

/// The three-component values of `accessor` (positions, morph target
/// displacements) as f32: floats, or the 8- and 16-bit integers
/// KHR_mesh_quantization allows, normalised where the accessor says so as
/// glTF 2.0 defines it ("Animations", normalised integers: c/127 and
/// c/32767 clamped at −1, c/255, c/65535) and taken as they are where not
/// (the node's transform then scales them, as gltfpack writes them).
pub(super) fn vec3s(
    accessor: gltf::Accessor<'_>,
    data: &Reading<'_>,
) -> Result<Vec<[f32; 3]>, ExportError> {
    use gltf::accessor::Iter;
    check_accessor(
        &accessor,
        &[F32, I8, U8, I16, U16],
        Dimensions::Vec3,
        "positions",
        data,
    )?;
    let (normalized, index) = (accessor.normalized(), accessor.index());
    fn read<'a, 's, T, F>(
        accessor: gltf::Accessor<'a>,
        get: F,
        scale: impl Fn(T) -> f32,
    ) -> Option<Vec<[f32; 3]>>
    where
        T: gltf::accessor::Item + Copy,
        [T; 3]: gltf::accessor::Item,
        F: Clone + for<'b> Fn(gltf::Buffer<'b>) -> Option<&'s [u8]>,
    {
        Iter::<[T; 3]>::new(accessor, get).map(|it| it.map(|v| v.map(&scale)).collect())
    }
    let get = data.get();
    let values = match accessor.data_type() {
        DataType::F32 => read(accessor, get, |c: f32| c),
        DataType::I8 if normalized => read(accessor, get, |c: i8| (c as f32 / 127.0).max(-1.0)),
        DataType::I8 => read(accessor, get, |c: i8| c as f32),
        DataType::U8 if normalized => read(accessor, get, |c: u8| c as f32 / 255.0),
        DataType::U8 => read(accessor, get, |c: u8| c as f32),
        DataType::I16 if normalized => read(accessor, get, |c: i16| (c as f32 / 32767.0).max(-1.0)),
        DataType::I16 => read(accessor, get, |c: i16| c as f32),
        DataType::U16 if normalized => read(accessor, get, |c: u16| c as f32 / 65535.0),
        DataType::U16 => read(accessor, get, |c: u16| c as f32),
        DataType::U32 => None,
    };
    values.ok_or_else(|| {
        ExportError::Data(format!(
            "accessor {index} (positions): its data lies outside its buffer"
        ))
    })
}

/// Checks that an accessor is what the gltf crate's reader for it expects,
/// and that its data is in the file, before anything is allocated for it:
/// one of `types`, of `dims`, with elements no wider than its buffer
/// view's stride, every element (and every sparse index and value) inside
/// its buffer view and every view inside the bytes of its buffer, and the
/// values it decodes to within the read's memory budget. The crate's
/// readers meet any other component type with `unreachable!`, a short
/// stride with a failed assertion, and allocate for the count an accessor
/// states (a sparse one without a buffer view: 2^32−1 zeros) before
/// reading a byte: a malformed file would panic or exhaust memory
/// instead of being refused.
pub(super) fn check_accessor(
    accessor: &gltf::Accessor<'_>,
    types: &[DataType],
    dims: Dimensions,
    what: &str,
    data: &Reading<'_>,
) -> Result<(), ExportError> {
    let bad = |why: String| {
        Err(ExportError::Data(format!(
            "accessor {} ({what}): {why}",
            accessor.index()
        )))
    };
    if !types.contains(&accessor.data_type()) {
        return bad(format!(
            "component type {:?}, where glTF allows {types:?}",
            accessor.data_type()
        ));
    }
    if accessor.dimensions() != dims {
        return bad(format!(
            "type {:?}, where glTF asks for {dims:?}",
            accessor.dimensions()
        ));
    }
    let (size, count) = (accessor.size(), accessor.count());
    if let Some(stride) = accessor.view().and_then(|v| v.stride())
        && stride < size
    {
        return bad(format!(
            "a byte stride of {stride}, less than its {size}-byte elements"
        ));
    }
    if count == 0 {
        return bad("a count of 0 (glTF asks for at least 1)".into());
    }
    match (accessor.view(), accessor.sparse()) {
        (Some(view), _) => {
            let stride = view.stride().unwrap_or(size);
            elements_fit(&view, accessor.offset(), stride, count, size, data).or_else(bad)?;
        }
        (None, None) => {
            return bad("neither a buffer view nor sparse values: it holds no data".into());
        }
        (None, Some(_)) => {}
    }
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        if n == 0 || n > count {
            return bad(format!(
                "{n} sparse values, where glTF asks for 1 to its count of {count}"
            ));
        }
        let indices = sparse.indices();
        let index_size = indices.index_type().size();
        let view = indices.view();
        if view.stride().is_some_and(|s| s < index_size) {
            return bad("sparse indices with a byte stride shorter than an index".into());
        }
        let stride = view.stride().unwrap_or(index_size);
        elements_fit(&view, indices.offset(), stride, n, index_size, data)
            .or_else(|why| bad(format!("sparse indices: {why}")))?;
        let view = sparse.values().view();
        if view.stride().is_some_and(|s| s < size) {
            return bad("sparse values with a byte stride shorter than a value".into());
        }
        let stride = view.stride().unwrap_or(size);
        elements_fit(&view, sparse.values().offset(), stride, n, size, data)
            .or_else(|why| bad(format!("sparse values: {why}")))?;
    }
    // The values as read: components of at most 4 bytes, decoded to f32
    // or u32 (4 bytes each) by every reader here.
    let decoded = (count as u64).saturating_mul(dims.multiplicity() as u64 * 4);
    data.budget.charge(decoded, "its values").or_else(bad)
}

/// Checks that `count` elements of `size` bytes, `stride` apart from byte
/// `offset` of `view`, lie inside it, and it inside its buffer's bytes.
fn elements_fit(
    view: &gltf::buffer::View<'_>,
    offset: usize,
    stride: usize,
    count: usize,
    size: usize,
    data: &Reading<'_>,
) -> Result<(), String> {
    let b = view.buffer().index();
    let Some(Some(buffer)) = data.buffers.get(b) else {
        return Err(format!(
            "its buffer view {} is in buffer {b}, whose bytes are not read here (a file beside a .glb, or no folder to read it from)",
            view.index()
        ));
    };
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|end| end > buffer.len()) {
        return Err(format!(
            "its buffer view {} runs from byte {} for {} bytes, past the {} bytes of buffer {b}",
            view.index(),
            view.offset(),
            view.length(),
            buffer.len()
        ));
    }
    let end = stride
        .checked_mul(count - 1)
        .and_then(|x| x.checked_add(offset))
        .and_then(|x| x.checked_add(size));
    if end.is_none_or(|end| end > view.length()) {
        return Err(format!(
            "{count} elements of {size} bytes, {stride} bytes apart from byte {offset}, run past the {} bytes of its buffer view {}",
            view.length(),
            view.index()
        ));
    }
    Ok(())
}

/// [`check_accessor`] for an animation sampler: key times as floats, and
/// values of the kind its target property takes (glTF 2.0, "Animations").
pub(super) fn check_sampler(
    channel: &gltf::animation::Channel<'_>,
    data: &Reading<'_>,
) -> Result<(), ExportError> {
    let sampler = channel.sampler();
    check_accessor(
        &sampler.input(),
        &[F32],
        Dimensions::Scalar,
        "key times",
        data,
    )?;
    let (types, dims): (&[DataType], _) = match channel.target().property() {
        Property::Translation | Property::Scale => (&[F32], Dimensions::Vec3),
        Property::Rotation => (&[F32, I8, U8, I16, U16], Dimensions::Vec4),
        Property::MorphTargetWeights => (&[F32, I8, U8, I16, U16], Dimensions::Scalar),
    };
    check_accessor(&sampler.output(), types, dims, "key values", data)
}
