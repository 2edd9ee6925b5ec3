//! `export` and `preview`: a breeding run's leaves as leaf files (and their
//! falls as glTF, PC2 or USD), and a self-contained HTML page that plays a
//! run, a scene's output or a .glb file.

use super::args::{ExportArgs, PreviewArgs};
use super::{input, report};
use anyhow::{Context, Result, bail};
use leafmagic::breed::{self, Run};
use leafmagic::formats::Format;
use leafmagic::formats::clip::Clip;
use leafmagic::formats::clip::render_mesh::{RenderMesh, read_obj};
use leafmagic::formats::{alembic, gltf, pc2, usd};
use nalgebra::Vector3;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `export`: writes the chosen individuals of the last generation as leaf
/// files, and with `--format` their falls. The output directory is written
/// as a whole: into a temporary sibling first, renamed into place when
/// complete, so a failure leaves what was there before.
pub fn export(args: ExportArgs) -> Result<()> {
    if args.run.join("summary.toml").is_file() {
        bail!(
            "{}: a scene's output (it holds summary.toml), not a breeding run; a scene is \
             exported as it runs: `leafmagic scene SCENE.toml --export glb|usd|pc2|abc`",
            args.run.display()
        );
    }
    let run = Run::open(&args.run)?;
    let Some(cp) = &run.checkpoint else {
        bail!(
            "{}: the run has no completed generation yet",
            args.run.display()
        );
    };
    if !(args.fps > 0.0 && args.fps.is_finite()) {
        bail!("--fps must be a positive number, got {}", args.fps);
    }
    if !(args.host_fps > 0.0 && args.host_fps.is_finite()) {
        bail!(
            "--host-fps must be a positive number, got {}",
            args.host_fps
        );
    }
    if !args.start_height.is_finite() {
        bail!("--start-height must be a finite number of metres");
    }
    let ranked = breed::selection::rank(&cp.population);
    let chosen: Vec<&breed::Individual> = match (&args.top, &args.ids) {
        (Some(k), None) => {
            if *k == 0 {
                bail!("--top must be at least 1");
            }
            ranked.into_iter().take(*k).collect()
        }
        (None, Some(ids)) => ids
            .iter()
            .map(|id| {
                cp.population.iter().find(|i| i.id == *id).ok_or_else(|| {
                    anyhow::anyhow!(
                        "--ids: individual {id} is not in the last generation ({})",
                        cp.generation
                    )
                })
            })
            .collect::<Result<_>>()?,
        _ => bail!("give either --top K or --ids ID,..."),
    };
    // The render mesh is bound once, to the prototype's rest shape; each
    // bred leaf carries the same binding on its own triangles.
    let render = match &args.render_mesh {
        None => None,
        Some(path) => {
            if args.format.is_none() {
                bail!("--render-mesh needs --format (it dresses the exported falls)");
            }
            let mesh = read_obj(path)?;
            let proto = run
                .proto
                .model()
                .with_context(|| format!("{}: the prototype", args.run.display()))?;
            let com = proto.centre_of_mass(&proto.rest_position);
            let rest: Vec<Vector3<f64>> = proto.rest_position.iter().map(|x| x - com).collect();
            let mut mesh = mesh;
            mesh.positions.iter_mut().for_each(|p| *p -= com);
            let triangles: Vec<[u32; 3]> = proto
                .triangles
                .iter()
                .map(|t| t.corners.map(|i| i as u32))
                .collect();
            Some(RenderMesh::bind(
                &path.display().to_string(),
                &mesh,
                &rest,
                &triangles,
            )?)
        }
    };
    let started = Instant::now();
    let out = &args.out;
    let staging = staging_dir(out)?;
    let result = (|| -> Result<Option<usize>> {
        breed::files::export_leaves(&run.proto, &chosen, &staging)?;
        let Some(format) = args.format else {
            return Ok(None);
        };
        let objects = leafmagic::output::export::drop_individuals(&run, &chosen, args.fps)?;
        let mut files = 0;
        for mut o in objects {
            o.translate(Vector3::new(0.0, 0.0, args.start_height));
            o.render = render.clone();
            let name = o.name.clone();
            let mut clip = leafmagic::output::export::side_by_side(&name, vec![o], args.fps, 0.0)?;
            clip.aero_law = run.proto.aero.law.as_str().to_string();
            files += write_clip(&clip, format, &staging, &name, args.host_fps)?.len();
        }
        Ok(Some(files))
    })();
    match result {
        Ok(files) => {
            replace_dir(&staging, out)?;
            println!("{}", report::output::leaves(chosen.len(), out));
            if let (Some(files), Some(format)) = (files, args.format) {
                println!(
                    "{}",
                    report::output::falls(
                        files,
                        format,
                        run.settings().seconds,
                        args.fps,
                        started.elapsed().as_secs_f64()
                    )
                );
            }
            Ok(())
        }
        Err(e) => {
            let _ = std::fs::remove_dir_all(&staging);
            Err(e.context(format!(
                "nothing was written to {} (it is as it was)",
                out.display()
            )))
        }
    }
}

/// A new, empty staging sibling of `out` to write into (staging folders
/// of killed exports are removed: [`leafmagic::util::io::staging_dir`]).
fn staging_dir(out: &Path) -> Result<PathBuf> {
    leafmagic::util::io::staging_dir(out).with_context(|| {
        format!(
            "--out {}: cannot create a staging folder beside it",
            out.display()
        )
    })
}

/// Puts the complete `staging` directory where `out` is, in one step where
/// the file system allows ([`leafmagic::util::io::swap_dir`]).
fn replace_dir(staging: &Path, out: &Path) -> Result<()> {
    leafmagic::util::io::swap_dir(staging, out).map_err(|e| {
        let _ = std::fs::remove_dir_all(staging);
        anyhow::Error::new(e).context(format!("cannot move the export into {}", out.display()))
    })
}

/// Writes `clip` into `dir` in `format` (`<stem>.glb`, `<stem>.usda`, `<stem>.abc`, or a `.pc2` and an `.obj` per object; USD's time
/// codes and the cache's samples spaced for a scene at `host_fps`); returns the paths.
pub fn write_clip(
    clip: &Clip,
    format: Format,
    dir: &Path,
    stem: &str,
    host_fps: f64,
) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    Ok(match format {
        Format::Glb => {
            let path = dir.join(format!("{stem}.glb"));
            gltf::write_glb(clip, &path)?;
            vec![path]
        }
        Format::Usd => {
            let path = dir.join(format!("{stem}.usda"));
            usd::write_usd(clip, &path, host_fps)?;
            vec![path]
        }
        Format::Pc2 => pc2::write_pc2(clip, dir, host_fps)?,
        Format::Abc => {
            let path = dir.join(format!("{stem}.abc"));
            alembic::write_abc(clip, &path)?;
            vec![path]
        }
    })
}

/// `preview`: writes the HTML page of a run, a scene's output, an
/// animation file or a fall record, or of several files side by side.
pub fn preview(args: PreviewArgs) -> Result<()> {
    if let Some(f) = args.fps
        && !(f > 0.0 && f.is_finite())
    {
        bail!("--fps must be a positive number, got {f}");
    }
    if args.top == 0 {
        bail!("--top must be at least 1");
    }
    let started = Instant::now();
    let first = &args.inputs[0];
    let (preview, out) = if let [input] = args.inputs.as_slice() {
        let out = args.out.clone().unwrap_or_else(|| {
            if input.is_dir() {
                input.join("preview.html")
            } else {
                input.with_extension("html")
            }
        });
        (preview_one(&args, input, true)?, out)
    } else {
        if let Some(dir) = args.inputs.iter().find(|p| p.is_dir()) {
            bail!(
                "{}: a directory; several inputs are compared as files (falls, animation files), one directory is previewed alone",
                dir.display()
            );
        }
        if let Some(flag) = record_flag(&args)
            && !args.inputs.iter().any(|p| is_record(p))
        {
            bail!("{flag} applies to a CSV record (a .csv fall); none of the inputs is one");
        }
        let mut parts: Vec<(String, leafmagic::output::preview::Preview)> = Vec::new();
        for input in &args.inputs {
            let stem = input
                .file_stem()
                .map_or("fall".to_string(), |s| s.to_string_lossy().into_owned());
            // Two inputs of one name (a/x.csv, b/x.csv) stay apart.
            let mut name = stem.clone();
            let mut k = 2;
            while parts.iter().any(|(n, _)| *n == name) {
                name = format!("{stem}-{k}");
                k += 1;
            }
            let mut part = preview_one(&args, input, false)?;
            if is_record(input) {
                // A record's fall is named as its input.
                part.clip.objects[0].name.clone_from(&name);
            }
            parts.push((name, part));
        }
        let out = args
            .out
            .clone()
            .unwrap_or_else(|| first.with_extension("compare.html"));
        (leafmagic::output::preview::together(parts, args.fps)?, out)
    };
    let html =
        leafmagic::output::preview::html_with(&preview.clip, preview.grid, preview.goals.as_ref())
            .map_err(|e| anyhow::anyhow!("{}: {e}", first.display()))?;
    leafmagic::util::io::write_atomic(&out, html.as_bytes())
        .with_context(|| format!("cannot write {}", out.display()))?;
    println!(
        "{}",
        report::output::preview(&out, html.len(), &preview, started.elapsed().as_secs_f64())
    );
    Ok(())
}

/// The first flag given that only a CSV record reads.
fn record_flag(args: &PreviewArgs) -> Option<&'static str> {
    [
        ("--size", args.size.is_some()),
        ("--up", args.up.is_some()),
        ("--frame-rate", args.frame_rate.is_some()),
    ]
    .into_iter()
    .find_map(|(flag, given)| given.then_some(flag))
}

/// Whether `path` is read as a fall record (a `.csv` file).
fn is_record(path: &Path) -> bool {
    path.is_file()
        && path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
}

/// The preview of one input; `alone`: the page's only one, where a flag
/// that does not apply to it is refused (among several, a flag applies to
/// the inputs it fits: --size to the records, --scale to the records and
/// Alembic archives).
fn preview_one(
    args: &PreviewArgs,
    input: &Path,
    alone: bool,
) -> Result<leafmagic::output::preview::Preview> {
    if is_record(input) {
        return preview_record(args, input, alone);
    }
    if let Some(flag) = record_flag(args).filter(|_| alone) {
        bail!(
            "{flag} applies to a CSV record (a .csv fall); {} is not one",
            input.display()
        );
    }
    let alembic = leafmagic::formats::fall::AnimationFormat::of(input)
        == Some(leafmagic::formats::fall::AnimationFormat::Alembic);
    Ok(leafmagic::output::preview::load(
        input,
        args.top,
        leafmagic::output::preview::FileOptions {
            fps: args.fps,
            animation: args.animation.as_deref(),
            scale: args.scale.filter(|_| alone || alembic),
            policy: Some(&args.reading.policy()),
        },
    )?)
}

/// `preview` of a CSV record: read and classified as `classify` reads and
/// classifies it (its notes on stderr), played as the plate or marker of
/// [`leafmagic::output::preview::from_record`], labelled with its class.
fn preview_record(
    args: &PreviewArgs,
    input: &Path,
    alone: bool,
) -> Result<leafmagic::output::preview::Preview> {
    if let Some(want) = args.animation.as_ref().filter(|_| alone) {
        bail!(
            "--animation {want}: {} is a CSV record, which holds one fall; --animation picks one of a glTF file's",
            input.display()
        );
    }
    let units = input::CsvUnits {
        up: args.up.unwrap_or(leafmagic::motion::trajectory::UpAxis::Z),
        scale: args.scale.unwrap_or(1.0),
        frame_rate: args.frame_rate,
    };
    let fall = input::read_fall(input, args.size, units, input::Pick::default())?;
    let name = input
        .file_stem()
        .map_or("fall".to_string(), |s| s.to_string_lossy().into_owned());
    let mut clip = leafmagic::output::preview::from_record(
        &name,
        &fall.record.trajectory,
        fall.size,
        args.fps,
    )
    .map_err(|e| anyhow::anyhow!("{}: {e}", input.display()))?;
    let object = &mut clip.objects[0];
    object.label = fall.classification.class.to_string();
    object.regime = fall.classification.regime.to_string();
    Ok(leafmagic::output::preview::Preview {
        clip,
        grid: false,
        classified: vec![0],
        goals: None,
    })
}

/// The hidden `compose-usd FILE [--root DIR]… [--parent PID] [--timeout-s
/// S]`: the flat layer of a USD stage, in JSON on stdout, for the parent
/// process that reads it
/// ([`leafmagic::formats::usd::compose_usd_stage`]). Its error, alone on
/// stderr, exit 1; a panic of the USD library is one too.
pub fn compose_usd(request: leafmagic::formats::usd::ComposeRequest) -> Result<()> {
    use std::io::Write;
    // Before anything can block: a child its parent no longer waits for,
    // or past its time, ends itself.
    leafmagic::formats::usd::watch_parent(request.parent, request.timeout);
    // This process exists to read one file; the parent reports what went
    // wrong, in its words, naming the file.
    std::panic::set_hook(Box::new(|_| {}));
    let composed =
        std::panic::catch_unwind(|| leafmagic::formats::usd::compose_usd_stage(&request))
            .unwrap_or_else(|panic| {
                let said = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_default();
                Err(format!("the USD library (openusd) failed on it: {said}"))
            });
    match composed {
        Ok(json) => {
            std::io::stdout()
                .write_all(json.as_bytes())
                .context("writing the composed layer")?;
            Ok(())
        }
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    }
}
