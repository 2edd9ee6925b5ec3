//! `export` and `preview`: a breeding run's leaves as leaf files (and their
//! falls as glTF or PC2), and a self-contained HTML page that plays a run,
//! a scene's output or a .glb file.

use super::args::{ExportArgs, PreviewArgs};
use super::report;
use anyhow::{Context, Result, bail};
use leafmagic::breed::{self, Run};
use leafmagic::output::export::{Clip, Format, glb, pc2};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `export`: writes the chosen individuals of the last generation as leaf
/// files, and with `--format` their falls.
pub fn export(args: ExportArgs) -> Result<()> {
    let run = Run::open(&args.run)?;
    let Some(cp) = &run.checkpoint else {
        bail!(
            "{}: the run has no completed generation yet",
            args.run.display()
        );
    };
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
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    breed::files::export_leaves(&run.proto, &chosen, &args.out)?;
    println!("{}", report::output::leaves(chosen.len(), &args.out));
    if let Some(format) = args.format {
        let started = Instant::now();
        let objects = leafmagic::output::export::drop_individuals(&run, &chosen, args.fps)?;
        let mut files = 0;
        for o in objects {
            let name = o.name.clone();
            let clip = leafmagic::output::export::side_by_side(&name, vec![o], args.fps, 0.0)?;
            files += write_clip(&clip, format, &args.out, &name)?.len();
        }
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

/// Writes `clip` into `dir` in `format` (`<stem>.glb`, or a `.pc2` and an
/// `.obj` per object); returns the paths.
pub fn write_clip(clip: &Clip, format: Format, dir: &Path, stem: &str) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    Ok(match format {
        Format::Glb => {
            let path = dir.join(format!("{stem}.glb"));
            glb::write_glb(clip, &path)?;
            vec![path]
        }
        Format::Pc2 => pc2::write_pc2(clip, dir)?,
    })
}

/// `preview`: writes the HTML page of a run, a scene's output or a .glb.
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
    let (clip, grid) = leafmagic::output::preview::load(&args.input, args.top, args.fps)?;
    let out = args.out.clone().unwrap_or_else(|| {
        if args.input.is_dir() {
            args.input.join("preview.html")
        } else {
            args.input.with_extension("html")
        }
    });
    let html = leafmagic::output::preview::html(&clip, grid)?;
    leafmagic::util::io::write_atomic(&out, html.as_bytes())
        .with_context(|| format!("cannot write {}", out.display()))?;
    println!(
        "{}",
        report::output::preview(&out, html.len(), &clip, started.elapsed().as_secs_f64())
    );
    Ok(())
}
