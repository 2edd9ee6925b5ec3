//! The human reports of `export` and `preview`: what was written, and where.

use leafmagic::formats::Format;
use leafmagic::output::preview::Preview;
use std::collections::BTreeMap;
use std::path::Path;

/// `export`: the leaf files and index.csv (one line, without its newline).
pub fn leaves(count: usize, dir: &Path) -> String {
    format!("wrote {count} leaves and index.csv to {}", dir.display())
}

/// `export --format`: the fall files, re-dropped for `seconds` at `fps`, in
/// `elapsed_s` (one line, without its newline).
pub fn falls(files: usize, format: Format, seconds: f64, fps: f64, elapsed_s: f64) -> String {
    format!(
        "wrote {files} {format} files of their falls (re-dropped for {seconds} s, {fps} fps) in {elapsed_s:.2} s"
    )
}

/// `preview`: the page, its size, what it plays and, of a file, the
/// classes it labelled its falls with (one line, without its newline).
pub fn preview(page: &Path, bytes: usize, preview: &Preview, elapsed_s: f64) -> String {
    let clip = &preview.clip;
    let partial = clip
        .objects
        .iter()
        .filter(|o| !o.lives_whole(clip.frames) && o.kind != leafmagic::output::preview::TRAIL)
        .count();
    let lives = if partial > 0 {
        format!(", {partial} of them over a part of it")
    } else {
        String::new()
    };
    format!(
        "wrote {} ({:.2} MB: {} object{}{lives}, {} frames at {} fps{}) in {elapsed_s:.2} s",
        page.display(),
        bytes as f64 / 1e6,
        clip.objects.len(),
        if clip.objects.len() == 1 { "" } else { "s" },
        clip.frames,
        clip.fps,
        classified(preview),
    )
}

/// "; classified K falls: N floater, …" when the preview labelled any
/// falls of a file by their class ([`class_tally`]).
fn classified(preview: &Preview) -> String {
    let objects = &preview.clip.objects;
    let tally = class_tally(
        preview
            .classified
            .iter()
            .map(|&k| objects[k].label.as_str()),
    );
    if tally.is_empty() {
        String::new()
    } else {
        format!("; classified {tally}")
    }
}

/// "K falls: N floater, M spinner, …" of the classes given, the most
/// frequent first; empty for none.
pub fn class_tally<'a>(classes: impl IntoIterator<Item = &'a str>) -> String {
    let mut tally: BTreeMap<&str, usize> = BTreeMap::new();
    let mut n = 0;
    for c in classes {
        *tally.entry(c).or_default() += 1;
        n += 1;
    }
    if n == 0 {
        return String::new();
    }
    let mut classes: Vec<(&str, usize)> = tally.into_iter().collect();
    classes.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(b.0)));
    let list: Vec<String> = classes.iter().map(|(c, n)| format!("{n} {c}")).collect();
    format!(
        "{n} fall{}: {}",
        if n == 1 { "" } else { "s" },
        list.join(", ")
    )
}
