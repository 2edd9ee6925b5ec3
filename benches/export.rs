//! Export speed (issues 5 and 21): a 10 s, 100-leaf scene exported at 30 fps
//! (100 deforming leaves × 301 frames) as .glb, as USD (.usda), as PC2 +
//! OBJ, and as the preview page. The scene is simulated once, outside the timing; each
//! iteration resamples the recorded frames into a clip and writes it.
//! The target is under a second per export.

use criterion::{Criterion, criterion_group, criterion_main};
use leafmagic::formats::{gltf, pc2, usd};
use leafmagic::output::export;
use leafmagic::sim::scene::Scene;
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

const SCENE: &str = include_str!("hundred-leaves.toml");

fn bench(c: &mut Criterion) {
    let scene = Scene::from_toml(SCENE, "benches/hundred-leaves.toml", Path::new("benches"))
        .expect("the benchmark scene compiles");
    let run = scene.run(None).expect("the benchmark scene runs");
    let clip = export::from_scene_run(&scene, &run, 30.0).unwrap();
    let dir = std::env::temp_dir().join(format!("leafmagic-bench-export-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let glb_size = gltf::glb_bytes(&clip).unwrap().len();
    let usd_size = usd::usd_bytes(&clip, clip.fps).unwrap().len();
    let page_size = leafmagic::output::preview::html(&clip, false)
        .unwrap()
        .len();
    eprintln!(
        "scene: {} objects, {} frames at 30 fps; .glb {:.1} MB, .usda {:.1} MB, page {:.2} MB",
        clip.objects.len(),
        clip.frames,
        glb_size as f64 / 1e6,
        usd_size as f64 / 1e6,
        page_size as f64 / 1e6
    );
    let mut g = c.benchmark_group("export_100_leaves_10s_30fps");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    g.bench_function("clip (resample 60 -> 30 fps)", |b| {
        b.iter(|| export::from_scene_run(&scene, black_box(&run), 30.0).unwrap())
    });
    g.bench_function("glb (clip + write file)", |b| {
        b.iter(|| {
            let clip = export::from_scene_run(&scene, black_box(&run), 30.0).unwrap();
            gltf::write_glb(&clip, &dir.join("scene.glb")).unwrap()
        })
    });
    g.bench_function("usd (clip + write .usda)", |b| {
        b.iter(|| {
            let clip = export::from_scene_run(&scene, black_box(&run), 30.0).unwrap();
            usd::write_usd(&clip, &dir.join("scene.usda"), clip.fps).unwrap()
        })
    });
    g.bench_function("pc2 + obj (clip + write 200 files)", |b| {
        b.iter(|| {
            let clip = export::from_scene_run(&scene, black_box(&run), 30.0).unwrap();
            pc2::write_pc2(&clip, &dir.join("pc2"), 30.0).unwrap()
        })
    });
    g.bench_function("preview page (clip + html)", |b| {
        b.iter(|| {
            let clip = export::from_scene_run(&scene, black_box(&run), 30.0).unwrap();
            leafmagic::output::preview::html(&clip, false)
                .unwrap()
                .len()
        })
    });
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench);
criterion_main!(benches);
