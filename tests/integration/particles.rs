//! Particles baked to Alembic `Points` as Blender writes them
//! (`tests/data/particles/`, made by its `make.py` with Blender's Python
//! module): each particle read on its own path over its own life, against
//! where Blender's particle system holds it at every frame, through births
//! and deaths that make Blender's exporter renumber the living ones.

use leafmagic::formats::alembic::DEFAULT_POINT_WIDTH_M;
use leafmagic::formats::clip::POINT_KIND;
use leafmagic::formats::fall;
use nalgebra::Vector3;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

type V3 = Vector3<f64>;

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/particles")
        .join(rel)
}

fn leafmagic() -> Command {
    Command::new(env!("CARGO_BIN_EXE_leafmagic"))
}

/// One particle as Blender holds it: (frame, place in world metres z up,
/// size) at each frame it lives, by its own index.
type Truth = BTreeMap<u64, Vec<(usize, V3, f64)>>;

fn blender_truth(csv: &str) -> Truth {
    let mut out = Truth::new();
    let text = std::fs::read_to_string(data(csv)).unwrap();
    for line in text.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        out.entry(v[1] as u64)
            .or_default()
            .push((v[0] as usize, V3::new(v[2], v[3], v[4]), v[5]));
    }
    out
}

/// Every particle of both files is read where Blender's particle system
/// holds it at every frame of its life, sized as Blender sizes it: in
/// `dying.abc` particles die from frame 11 on, one in the very frame
/// another is born, and Blender's exporter numbers the living 0, 1, … at
/// each frame, so the reader follows them by motion. Read by the file's
/// numbers instead, `dying`'s 12 particles would be 5 paths, each jumping
/// to a neighbour's at every death (at frame 11 number 1 is particle 2,
/// 0.2 m from particle 1): this test then fails.
#[test]
fn blender_particles_are_read_each_on_its_own_path_through_births_and_deaths() {
    for (file, count) in [("leaves", 6), ("dying", 12)] {
        let truth = blender_truth(&format!("{file}.blender.csv"));
        assert_eq!(truth.len(), count);
        let clip = fall::read_clip(&data(&format!("{file}.abc")), None).unwrap();
        assert_eq!(clip.fps, 24.0);
        let points: BTreeMap<u64, _> = clip
            .objects
            .iter()
            .filter(|o| o.kind == POINT_KIND)
            .map(|o| {
                let id = o.name.strip_prefix("tree/leaves/").unwrap();
                (id.parse::<u64>().unwrap(), o)
            })
            .collect();
        assert_eq!(
            points.keys().collect::<Vec<_>>(),
            truth.keys().collect::<Vec<_>>(),
            "{file}"
        );
        let mut worst: f64 = 0.0;
        for (id, life) in &truth {
            let o = points[id];
            // The archive's first sample is Blender's frame 1.
            assert_eq!(o.first_frame, life[0].0 - 1, "{file} {id}: born");
            assert_eq!(o.frame_count(), life.len(), "{file} {id}: lives");
            for (k, (_, at, _)) in life.iter().enumerate() {
                worst = worst.max((o.centre(k) - at).norm());
            }
            // Its width is its size (float32 in the file).
            let width = fall::chord(&o.positions(0));
            assert!((width - life[0].2).abs() <= 1e-6 * life[0].2, "{file} {id}");
            assert!(width != DEFAULT_POINT_WIDTH_M);
        }
        // float32 in the file, under a float32 matrix per frame.
        assert!(worst < 1e-5, "{file}: {worst} m off Blender's particles");
    }
}

/// `classify` reads a particle's path by `--object`, as a path without
/// attitude sized by its width, and says so; the whole file lists every
/// particle with its life.
#[test]
fn classify_reads_a_particle_as_a_path_sized_by_its_width() {
    let file = data("dying.abc");
    let o = leafmagic().arg("classify").arg(&file).output().unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("13 objects move in it")
            && err.contains("`tree/leaves/11` (point, 0.92–1.29 s of 1.46 s)"),
        "{err}"
    );
    let o = leafmagic()
        .args(["classify", data("leaves.abc").to_str().unwrap(), "--object"])
        .arg("tree/leaves/4")
        .arg("--json")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("`tree/leaves/4` is a point (a particle), with no attitude")
            && err.contains("30 keys at 24 Hz, chord 0.0479 m"),
        "{err}"
    );
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["inputs"], "path", "{v}");
    assert!(v["features"]["descent_m"].as_f64().unwrap() > 1.0, "{v}");
}

/// `classify --all` names every fall of a file as `classify --object`
/// names each, with the tally, and leaves out what does not fall (a
/// glTF's ground); flags that do not apply are refused by name.
#[test]
fn classify_all_names_every_fall_of_a_file_as_classify_object_does() {
    let class_of = |file: &Path, object: &str| {
        let o = leafmagic()
            .arg("classify")
            .arg(file)
            .args(["--object", object, "--json"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: Value = serde_json::from_slice(&o.stdout).unwrap();
        v["class"].as_str().unwrap().to_string()
    };
    let ground = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/blender/tumble_thick_with_ground.glb");
    for (file, falls, left_out) in [(data("leaves.abc"), 7, 0), (ground, 1, 1)] {
        let o = leafmagic()
            .arg("classify")
            .arg(&file)
            .args(["--all", "--json"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: Value = serde_json::from_slice(&o.stdout).unwrap();
        let objects = v["objects"].as_array().unwrap();
        assert_eq!(objects.len(), falls, "{v}");
        assert_eq!(v["left_out"].as_array().unwrap().len(), left_out, "{v}");
        for o in objects {
            let name = o["object"].as_str().unwrap();
            assert_eq!(
                o["class"],
                class_of(&file, name),
                "{}: {name}",
                file.display()
            );
        }
        // The table: a line per fall and the tally.
        let o = leafmagic()
            .arg("classify")
            .arg(&file)
            .arg("--all")
            .output()
            .unwrap();
        let table = String::from_utf8_lossy(&o.stdout);
        assert!(
            table.contains(&format!("classified      {falls} fall")),
            "{table}"
        );
        for o in objects {
            let line = table
                .lines()
                .find(|l| l.starts_with(o["object"].as_str().unwrap()))
                .unwrap();
            assert!(line.contains(o["class"].as_str().unwrap()), "{line}");
        }
    }
    let csv =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real-falls/squares/square_003.csv");
    let abc = data("leaves.abc");
    let glb = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/blender/tumble_thick.glb");
    for (file, more, want) in [
        (&csv, vec![], "a CSV record holds one fall"),
        (&abc, vec!["--object", "tree/leaves/1"], "--object"),
        (
            &abc,
            vec!["--up", "y"],
            "--up and --frame-rate apply to a CSV record",
        ),
        (
            &glb,
            vec!["--scale", "0.01"],
            "--scale applies to a CSV record or an Alembic archive",
        ),
        (
            &abc,
            vec!["--size", "0"],
            "--size must be a positive number",
        ),
    ] {
        let o = leafmagic()
            .arg("classify")
            .arg(file)
            .arg("--all")
            .args(&more)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(want), "{more:?}: {err}");
    }
}
