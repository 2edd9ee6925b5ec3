//! A glTF document opened, checked and its arrays read without trusting
//! it: what the gltf crate (1.4) would refuse wrongly or panic on is
//! handled here, for the readers of [`super::read`]. Its buffers come from
//! a `.glb`'s binary chunk, data URIs or files beside a `.gltf`; required
//! extensions are decoded (KHR_mesh_quantization), left unread (looks
//! only) or refused by name; every accessor handed to the crate's readers
//! is checked first, since they meet a component type they do not expect
//! with `unreachable!`.

use super::error::ExportError;
use crate::util::confined::ReadScope;
use gltf::accessor::DataType::{F32, I8, I16, U8, U16};
use gltf::accessor::{DataType, Dimensions};
use gltf::animation::Property;
use std::path::Path;

/// The bytes of each buffer of a glTF document: the binary chunk of a
/// `.glb`, a `data:` URI (base64), or a file beside the `.gltf`, in its
/// folder `dir` and only where `scope` lets a reference reach
/// ([`ReadScope::read`]).
pub(super) fn buffer_data(
    gltf: &gltf::Gltf,
    files: Option<(&Path, &ReadScope)>,
) -> Result<Vec<Option<Vec<u8>>>, ExportError> {
    use base64::Engine as _;
    gltf.document
        .buffers()
        .map(|b| match b.source() {
            gltf::buffer::Source::Bin => Ok(gltf.blob.clone()),
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, data) = rest.split_once(";base64,").ok_or_else(|| {
                        ExportError::Data(format!(
                            "buffer {}: a data URI that is not base64",
                            b.index()
                        ))
                    })?;
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
pub(super) fn vec3s<'a, 's, F>(
    accessor: gltf::Accessor<'a>,
    get: F,
) -> Result<Vec<[f32; 3]>, ExportError>
where
    F: Clone + for<'b> Fn(gltf::Buffer<'b>) -> Option<&'s [u8]>,
{
    use gltf::accessor::Iter;
    check_accessor(
        &accessor,
        &[F32, I8, U8, I16, U16],
        Dimensions::Vec3,
        "positions",
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

/// Checks that an accessor is what the gltf crate's reader for it expects:
/// one of `types`, of `dims`, with elements no wider than its buffer
/// view's stride. The crate's readers meet any other component type with
/// `unreachable!` and a short stride with a failed assertion: a malformed
/// file would panic instead of being refused.
pub(super) fn check_accessor(
    accessor: &gltf::Accessor<'_>,
    types: &[DataType],
    dims: Dimensions,
    what: &str,
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
    let size = accessor.size();
    if let Some(stride) = accessor.view().and_then(|v| v.stride())
        && stride < size
    {
        return bad(format!(
            "a byte stride of {stride}, less than its {size}-byte elements"
        ));
    }
    Ok(())
}

/// [`check_accessor`] for an animation sampler: key times as floats, and
/// values of the kind its target property takes (glTF 2.0, "Animations").
pub(super) fn check_sampler(channel: &gltf::animation::Channel<'_>) -> Result<(), ExportError> {
    let sampler = channel.sampler();
    check_accessor(&sampler.input(), &[F32], Dimensions::Scalar, "key times")?;
    let (types, dims): (&[DataType], _) = match channel.target().property() {
        Property::Translation | Property::Scale => (&[F32], Dimensions::Vec3),
        Property::Rotation => (&[F32, I8, U8, I16, U16], Dimensions::Vec4),
        Property::MorphTargetWeights => (&[F32, I8, U8, I16, U16], Dimensions::Scalar),
    };
    check_accessor(&sampler.output(), types, dims, "key values")
}
