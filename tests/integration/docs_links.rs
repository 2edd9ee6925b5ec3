//! Every relative link in the repository's Markdown reaches something: the
//! file or folder it names exists, and a `#fragment` into a Markdown file
//! names one of its headings (GitHub's anchors: lower case, punctuation
//! dropped, spaces as hyphens). Moving a page (the docs' guide, reference,
//! design and lab split) cannot leave a reader at a dead link.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The Markdown files a reader reaches: the README, `docs/` and the
/// format READMEs (not `target/` or `runs/`).
fn pages() -> Vec<PathBuf> {
    let root = root();
    let mut out = vec![
        root.join("README.md"),
        root.join("prototypes/README.md"),
        root.join("scenes/README.md"),
    ];
    let mut stack = vec![root.join("docs")];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "md") {
                out.push(p);
            }
        }
    }
    out.retain(|p| p.is_file());
    out.sort();
    out
}

/// The text outside fenced code blocks.
fn prose(text: &str) -> String {
    let mut out = String::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if !fenced {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | ' '))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

fn anchors(page: &Path) -> BTreeSet<String> {
    prose(&std::fs::read_to_string(page).unwrap())
        .lines()
        .filter(|l| l.starts_with('#'))
        .map(|l| anchor(&l.trim_start_matches('#').replace(['`', '*'], "")))
        .collect()
}

/// Every `](target)` of `text`.
fn links(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("](") {
        rest = &rest[i + 2..];
        if let Some(end) = rest.find([')', ' ', '\n']) {
            if rest.as_bytes()[end] == b')' {
                out.push(rest[..end].to_string());
            }
            rest = &rest[end..];
        }
    }
    out
}

#[test]
fn every_relative_link_in_the_docs_reaches_its_file_and_heading() {
    let pages = pages();
    assert!(pages.len() >= 15, "found only {pages:?}");
    let (mut checked, mut dead) = (0, Vec::new());
    for page in &pages {
        let text = prose(&std::fs::read_to_string(page).unwrap());
        for target in links(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            checked += 1;
            let (path, fragment) = target.split_once('#').unwrap_or((&target, ""));
            let file = if path.is_empty() {
                page.clone()
            } else {
                page.parent().unwrap().join(path)
            };
            let shown = page.strip_prefix(root()).unwrap().display();
            if !file.exists() {
                dead.push(format!("{shown}: {target} (no such file)"));
            } else if !fragment.is_empty()
                && file.extension().is_some_and(|x| x == "md")
                && !anchors(&file).contains(fragment)
            {
                dead.push(format!("{shown}: {target} (no such heading)"));
            }
        }
    }
    assert!(
        checked > 100,
        "only {checked} links found: the scan is broken"
    );
    assert!(dead.is_empty(), "dead links:\n{}", dead.join("\n"));
}

#[test]
fn the_link_check_tells_a_dead_link() {
    assert_eq!(
        links("see [a](b.md#c) and [d](e f) [g](h)"),
        ["b.md#c", "h"]
    );
    assert_eq!(anchor("Into the clients"), "into-the-clients");
    assert_eq!(anchor("`leafmagic` — what it is"), "leafmagic--what-it-is");
}
