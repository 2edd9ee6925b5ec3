//! glTF files written to hurt the reader (issue 58): node loops, a scene
//! naming one node 400,000 times, accessors whose counts run past their
//! bytes, indices past 32 bits, buffers outside the file's folder. Each is
//! built here, small, and must be refused with a message that names what
//! is wrong, or read with a warning that reaches the user; never a stack
//! overflow, a panic, or an allocation for bytes the file does not hold.

use base64::Engine as _;
use leafmagic::formats::{ExportError, fall::read_clip, gltf};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

fn scratch(name: &str) -> PathBuf {
    super::common::scratch("hostile", name)
}

/// Key times, 30 a second over 1 s.
const KEYS: usize = 31;

/// The buffer of [`falling`]: a triangle's three positions, the key
/// times, and a translation per key (a fall of 2 m, drifting).
fn buffer() -> Vec<u8> {
    let mut b = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 0.0, 0.05] {
        b.extend(v.to_le_bytes());
    }
    for k in 0..KEYS {
        b.extend((k as f32 / 30.0).to_le_bytes());
    }
    for k in 0..KEYS {
        let t = k as f32 / 30.0;
        for v in [0.1 * t, -2.0 * t, 0.0] {
            b.extend(v.to_le_bytes());
        }
    }
    b
}

/// A valid glTF document: node 0 holds a falling triangle (accessor 0
/// positions, 1 key times, 2 translations; animation 0 moves node 0), its
/// buffer a data URI.
fn falling() -> Value {
    let buf = buffer();
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&buf)
    );
    let times = 4 * KEYS;
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "leaf", "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": buf.len(), "uri": uri}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": times},
            {"buffer": 0, "byteOffset": 36 + times, "byteLength": 12 * KEYS},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [0.1, 0.0, 0.05]},
            {"bufferView": 1, "componentType": 5126, "count": KEYS, "type": "SCALAR",
             "min": [0.0], "max": [1.0]},
            {"bufferView": 2, "componentType": 5126, "count": KEYS, "type": "VEC3"},
        ],
        "animations": [{
            "name": "fall",
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
            "samplers": [{"input": 1, "output": 2}],
        }],
    })
}

/// `item` appended to the JSON array `list`.
fn push(list: &mut Value, item: Value) {
    list.as_array_mut().unwrap().push(item);
}

/// `doc` written as `dir/name`.
fn write(dir: &Path, name: &str, doc: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(doc).unwrap()).unwrap();
    path
}

/// Why reading `doc` (as a `.gltf` of its own folder) is refused, asserting
/// that it is and that it took under 5 s.
fn refused(name: &str, doc: &Value) -> String {
    let dir = scratch(name);
    let path = write(&dir, &format!("{name}.gltf"), doc);
    let start = Instant::now();
    let read = read_clip(&path, None);
    assert!(start.elapsed() < Duration::from_secs(5), "{name}: too slow");
    let err = read.expect_err(name).to_string();
    assert!(err.contains(&format!("{name}.gltf")), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
    err
}

/// What `leafmagic classify FILE` prints to stderr, asserting it fails
/// within 5 s, names the file and neither panics nor overflows.
fn cli_refuses(path: &Path) -> String {
    let start = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_leafmagic"))
        .arg("classify")
        .arg(path)
        .output()
        .unwrap();
    assert!(start.elapsed() < Duration::from_secs(5), "too slow");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "did not fail: {err}");
    assert_eq!(out.status.code(), Some(1), "not an error exit: {err}");
    let file = path.file_name().unwrap().to_string_lossy();
    assert!(err.contains(&*file), "{err}");
    for bad in ["panicked", "overflow"] {
        assert!(!err.contains(bad), "{err}");
    }
    err
}

#[test]
fn the_valid_base_file_reads() {
    let dir = scratch("valid");
    let path = write(&dir, "valid.gltf", &falling());
    let clip = read_clip(&path, None).unwrap();
    assert_eq!(clip.objects.len(), 1);
    assert_eq!(clip.frames, KEYS);
    assert!(clip.warnings.is_empty(), "{:?}", clip.warnings);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_node_that_is_its_own_child_is_named() {
    let mut doc = falling();
    doc["nodes"][0]["children"] = json!([0]);
    let err = refused("self-child", &doc);
    assert!(err.contains("node 0 is its own ancestor: 0 → 0"), "{err}");

    let dir = scratch("self-child-cli");
    let err = cli_refuses(&write(&dir, "self-child.gltf", &doc));
    assert!(err.contains("node 0 is its own ancestor"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_loop_of_two_and_three_nodes_is_named_with_its_path() {
    let mut doc = falling();
    doc["nodes"][0]["children"] = json!([1]);
    push(&mut doc["nodes"], json!({"children": [0]}));
    let err = refused("two-loop", &doc);
    assert!(
        err.contains("node 0 is its own ancestor: 0 → 1 → 0"),
        "{err}"
    );

    // A loop away from the scene's own tree is still no tree.
    let mut doc = falling();
    doc["nodes"] = json!([
        {"name": "leaf", "mesh": 0},
        {"children": [2]},
        {"children": [3]},
        {"children": [1]},
    ]);
    let err = refused("three-loop", &doc);
    assert!(err.contains("is its own ancestor"), "{err}");
    assert!(err.contains("1 → 2 → 3 → 1"), "{err}");
}

#[test]
fn skin_joints_in_a_loop_are_refused() {
    let mut doc = falling();
    doc["nodes"] = json!([
        {"name": "leaf", "mesh": 0, "skin": 0},
        {"name": "bone", "children": [2]},
        {"name": "tip", "children": [1]},
    ]);
    doc["skins"] = json!([{"joints": [1, 2]}]);
    let err = refused("joint-loop", &doc);
    assert!(err.contains("its own ancestor: 1 → 2 → 1"), "{err}");
}

#[test]
fn a_node_with_two_parents_or_reached_twice_is_named() {
    let mut doc = falling();
    doc["nodes"] = json!([
        {"name": "leaf", "mesh": 0},
        {"children": [0]},
        {"children": [0]},
    ]);
    doc["scenes"][0]["nodes"] = json!([1, 2]);
    let err = refused("two-parents", &doc);
    assert!(
        err.contains("node 0 is a child of both node 1 and node 2"),
        "{err}"
    );

    let mut doc = falling();
    doc["nodes"] = json!([{"name": "leaf", "mesh": 0}, {"children": [0]}]);
    doc["scenes"][0]["nodes"] = json!([1, 0]);
    let err = refused("reached-twice", &doc);
    assert!(
        err.contains("node 0 is reached twice from the scene: listed in it, and a child of node 1"),
        "{err}"
    );
}

#[test]
fn a_scene_naming_one_node_400000_times_is_refused_at_once() {
    let mut doc = falling();
    doc["scenes"][0]["nodes"] = Value::Array(vec![json!(0); 400_000]);
    let err = refused("crowd", &doc);
    assert!(err.contains("the scene lists node 0 400000 times"), "{err}");
}

/// Node 0 at the top of a chain of `n` nodes, the mesh at its bottom.
fn chain(n: usize) -> Value {
    let mut doc = falling();
    let mut nodes: Vec<Value> = (0..n - 1).map(|i| json!({"children": [i + 1]})).collect();
    nodes.push(json!({"name": "leaf", "mesh": 0}));
    doc["nodes"] = Value::Array(nodes);
    doc
}

#[test]
fn a_chain_of_100000_nodes_reads_without_recursion() {
    let dir = scratch("chain");
    let path = write(&dir, "chain.gltf", &chain(100_000));
    let start = Instant::now();
    let clip = read_clip(&path, None).unwrap();
    assert!(start.elapsed() < Duration::from_secs(5));
    assert_eq!(clip.objects.len(), 1);
    assert_eq!(clip.objects[0].name, "leaf");
    // Moved by the animated top of the chain: 2 m down over the clip.
    let (first, last) = (
        clip.objects[0].positions(0)[0],
        clip.objects[0].positions(clip.frames - 1)[0],
    );
    assert!((first.z - last.z - 2.0).abs() < 1e-4, "{first} {last}");

    // The same chain closed into a loop at its bottom.
    let mut doc = chain(100_000);
    doc["nodes"][99_999]["children"] = json!([0]);
    let path = write(&dir, "chain-loop.gltf", &doc);
    let err = cli_refuses(&path);
    assert!(err.contains("is its own ancestor"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn key_values_past_their_buffer_name_the_channel() {
    let mut doc = falling();
    doc["accessors"][2]["count"] = json!(2000);
    let err = refused("long-keys", &doc);
    assert!(
        err.contains(
            "animation 0 `fall`, channel 0 (node 0 `leaf`, translation), sampler 0: accessor 2 (key values): 2000 elements of 12 bytes"
        ),
        "{err}"
    );
    assert!(
        err.contains("run past the 372 bytes of its buffer view 2"),
        "{err}"
    );

    let dir = scratch("long-keys-cli");
    let err = cli_refuses(&write(&dir, "long-keys.gltf", &doc));
    assert!(err.contains("accessor 2 (key values)"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn offsets_strides_and_views_past_the_buffer_are_refused() {
    let mut doc = falling();
    doc["accessors"][0]["byteOffset"] = json!(1u64 << 62);
    let err = refused("far-offset", &doc);
    assert!(err.contains("accessor 0 (positions)"), "{err}");

    let mut doc = falling();
    doc["bufferViews"][0]["byteLength"] = json!(1u64 << 40);
    let err = refused("long-view", &doc);
    assert!(err.contains("its buffer view 0 runs from byte 0"), "{err}");

    let mut doc = falling();
    doc["accessors"][1]["count"] = json!(0);
    let err = refused("no-keys", &doc);
    assert!(err.contains("a count of 0"), "{err}");
}

#[test]
fn a_broken_channel_of_a_node_that_moves_nothing_read_is_a_warning() {
    let mut doc = falling();
    push(&mut doc["nodes"], json!({"name": "camera-rig"}));
    doc["scenes"][0]["nodes"] = json!([0, 1]);
    push(
        &mut doc["accessors"],
        json!({"bufferView": 2, "componentType": 5126, "count": 5000, "type": "VEC3"}),
    );
    push(
        &mut doc["animations"][0]["channels"],
        json!({"sampler": 1, "target": {"node": 1, "path": "translation"}}),
    );
    push(
        &mut doc["animations"][0]["samplers"],
        json!({"input": 1, "output": 3}),
    );
    let dir = scratch("side-warning");
    let path = write(&dir, "side.gltf", &doc);
    let clip = read_clip(&path, None).unwrap();
    assert_eq!(clip.warnings.len(), 1, "{:?}", clip.warnings);
    let w = &clip.warnings[0];
    assert!(
        w.contains("channel 1 (node 1 `camera-rig`, translation)")
            && w.contains("accessor 3 (key values)")
            && w.contains("left out"),
        "{w}"
    );
    // Printed on stderr by the text output, listed by --json.
    let out = Command::new(env!("CARGO_BIN_EXE_leafmagic"))
        .arg("classify")
        .arg(&path)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains(&format!("warning: {}: animation 0", path.display())),
        "{err}"
    );
    for all in [false, true] {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_leafmagic"));
        cmd.arg("classify").arg(&path).arg("--json");
        if all {
            cmd.arg("--all");
        }
        let out = cmd.output().unwrap();
        assert!(out.status.success());
        let v: Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(v["warnings"].as_array().map(Vec::len), Some(1), "{v}");
        assert!(v["warnings"][0].as_str().unwrap().contains("accessor 3"));
    }
    // On the node that moves the mesh, the same channel is an error.
    doc["animations"][0]["channels"][1]["target"]["node"] = json!(0);
    doc["animations"][0]["channels"][1]["target"]["path"] = json!("scale");
    let err = refused("main-broken", &doc);
    assert!(
        err.contains("channel 1 (node 0 `leaf`, scale), sampler 1: accessor 3 (key values)"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_strip_whose_faces_are_not_read_is_a_warning() {
    let mut doc = falling();
    // TRIANGLE_STRIP: its vertices move, its faces are not read.
    doc["meshes"][0]["primitives"][0]["mode"] = json!(5);
    let dir = scratch("strip");
    let clip = read_clip(&write(&dir, "strip.gltf", &doc), None).unwrap();
    assert_eq!(clip.warnings.len(), 1, "{:?}", clip.warnings);
    assert!(
        clip.warnings[0].contains("primitive 0 is drawn as TriangleStrip"),
        "{:?}",
        clip.warnings
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `doc` with morph target weights animated by accessor 3, a sparse
/// accessor of `count` zeros without a buffer view.
fn sparse_weights(count: u64, sparse_count: u64) -> Value {
    let mut doc = falling();
    doc["meshes"][0]["weights"] = json!([0.0]);
    doc["meshes"][0]["primitives"][0]["targets"] = json!([{"POSITION": 0}]);
    push(
        &mut doc["accessors"],
        json!({
            "componentType": 5126, "count": count, "type": "SCALAR",
            "sparse": {
                "count": sparse_count,
                "indices": {"bufferView": 1, "componentType": 5125},
                "values": {"bufferView": 1},
            },
        }),
    );
    push(
        &mut doc["animations"][0]["channels"],
        json!({"sampler": 1, "target": {"node": 0, "path": "weights"}}),
    );
    push(
        &mut doc["animations"][0]["samplers"],
        json!({"input": 1, "output": 3}),
    );
    doc
}

#[test]
fn a_sparse_accessor_of_four_billion_zeros_is_not_allocated() {
    let doc = sparse_weights((1 << 32) - 1, 1);
    let err = refused("sparse-huge", &doc);
    assert!(
        err.contains("accessor 3 (key values): its values would need 17179869180 bytes"),
        "{err}"
    );
    assert!(err.contains("memory budget"), "{err}");

    let dir = scratch("sparse-cli");
    let err = cli_refuses(&write(&dir, "sparse-huge.gltf", &doc));
    assert!(err.contains("memory budget"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);

    // More sparse values than the accessor holds, or more than their
    // buffer view holds.
    let err = refused("sparse-more", &sparse_weights(KEYS as u64, KEYS as u64 + 1));
    assert!(err.contains("32 sparse values"), "{err}");
    let err = refused("sparse-past", &sparse_weights(1 << 20, 1 << 20));
    assert!(err.contains("sparse indices: 1048576 elements"), "{err}");
}

#[test]
fn an_index_past_32_bits_is_not_wrapped() {
    let mut doc = falling();
    doc["nodes"][0]["mesh"] = json!(1u64 << 40);
    let err = refused("wide-mesh", &doc);
    assert!(
        err.contains("`nodes[0].mesh` holds the index 1099511627776"),
        "{err}"
    );
    let mut doc = falling();
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!((1u64 << 32) + 2);
    let err = refused("wide-attribute", &doc);
    assert!(err.contains("attributes.POSITION"), "{err}");
    let mut doc = falling();
    doc["animations"][0]["channels"][0]["target"]["node"] = json!(1u64 << 33);
    let err = refused("wide-target", &doc);
    assert!(err.contains("target.node"), "{err}");
}

#[test]
fn a_buffer_outside_the_folder_is_not_read() {
    let base = scratch("escape");
    let dir = base.join("shared");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(base.join("secret.bin"), buffer()).unwrap();
    let mut doc = falling();
    doc["buffers"][0]["uri"] = json!("../secret.bin");
    let path = write(&dir, "escape.gltf", &doc);
    let err = read_clip(&path, None).unwrap_err().to_string();
    assert!(err.contains("leads outside"), "{err}");
    let err = cli_refuses(&path);
    assert!(err.contains("`../secret.bin`, which is not read"), "{err}");
    assert!(err.contains("leads outside"), "{err}");
    let _ = std::fs::remove_dir_all(&base);
}

/// `doc` as the bytes of a `.glb`, its buffer 0 the binary chunk.
fn glb(doc: &Value) -> Vec<u8> {
    let mut doc = doc.clone();
    let bin = buffer();
    doc["buffers"][0] = json!({"byteLength": bin.len()});
    let mut json = serde_json::to_vec(&doc).unwrap();
    json.resize(json.len().div_ceil(4) * 4, b' ');
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(&bin);
    out
}

fn glb_error(bytes: &[u8]) -> String {
    match gltf::from_glb_bytes(bytes, "hostile", None, None) {
        Err(ExportError::Data(why)) => why,
        other => panic!("not refused as data: {other:?}"),
    }
}

#[test]
fn glb_bytes_are_checked_as_files_are() {
    // The valid file reads from bytes too.
    let clip = gltf::from_glb_bytes(&glb(&falling()), "ok", None, None).unwrap();
    assert_eq!(clip.objects.len(), 1);

    let mut doc = falling();
    doc["nodes"][0]["children"] = json!([0]);
    assert!(glb_error(&glb(&doc)).contains("node 0 is its own ancestor"));

    let why = glb_error(&glb(&sparse_weights((1 << 32) - 1, 1)));
    assert!(why.contains("memory budget"), "{why}");

    let mut doc = falling();
    doc["accessors"][0]["count"] = json!(1u64 << 40);
    let why = glb_error(&glb(&doc));
    assert!(why.contains("accessor 0 (positions)"), "{why}");

    // A header stating a length shorter than itself.
    let mut bytes = glb(&falling());
    bytes[8..12].copy_from_slice(&3u32.to_le_bytes());
    assert!(glb_error(&bytes).contains("less than the header's 12"));

    // A buffer that is a file: from bytes, there is no folder to read.
    let mut doc = falling();
    doc["buffers"][0]["uri"] = json!("leaf.bin");
    let why = match gltf::from_glb_bytes(&serde_json::to_vec(&doc).unwrap(), "x", None, None) {
        Err(ExportError::Data(why)) => why,
        other => panic!("{other:?}"),
    };
    assert!(why.contains("whose bytes are not read here"), "{why}");
}
