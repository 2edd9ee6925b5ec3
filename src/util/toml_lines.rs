//! Line numbers for errors in TOML files (leaves, scenes): from a byte offset to the field path it
//! falls in, and from a field path (`leaf[2].count`) to its line.

use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// 1-based line of byte `offset` in `text`.
pub fn line_of_offset(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// The dotted path (`rope[1].stiffness`) of the deepest key or value whose
/// span contains `offset`, or `None` if the text does not parse or nothing
/// matches.
pub fn path_at(text: &str, offset: usize) -> Option<String> {
    let root = DeTable::parse(text).ok()?;
    find_in_table(root.get_ref(), offset, "")
}

fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

fn find_in_table(table: &DeTable<'_>, offset: usize, prefix: &str) -> Option<String> {
    for (key, value) in table.iter() {
        let path = join(prefix, key.get_ref());
        if key.span().contains(&offset) {
            return Some(path);
        }
        if let Some(found) = find_in_value(value, offset, &path) {
            return Some(found);
        }
    }
    None
}

fn find_in_value(value: &Spanned<DeValue<'_>>, offset: usize, path: &str) -> Option<String> {
    match value.get_ref() {
        DeValue::Table(t) => find_in_table(t, offset, path).or_else(|| {
            // A table's own span is its header (or its braces when inline).
            value.span().contains(&offset).then(|| path.to_string())
        }),
        DeValue::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                let indexed = format!("{path}[{i}]");
                if let Some(found) = find_in_value(item, offset, &indexed) {
                    return Some(found);
                }
            }
            value.span().contains(&offset).then(|| path.to_string())
        }
        _ => value.span().contains(&offset).then(|| path.to_string()),
    }
}

/// One step of a field path: a key, optionally indexed (`keys[3]`).
fn segments(path: &str) -> Vec<(&str, Vec<usize>)> {
    path.split('.')
        .map(|seg| {
            let mut parts = seg.split('[');
            let key = parts.next().unwrap_or("");
            let idx = parts
                .filter_map(|p| p.trim_end_matches(']').parse().ok())
                .collect();
            (key, idx)
        })
        .collect()
}

/// 1-based line of the field `path` in `text`; when the field itself is
/// absent (a default was used), the line of its nearest enclosing table.
pub fn line_of_path(text: &str, path: &str) -> Option<usize> {
    lookup(text, path).map(|(line, _)| line)
}

/// 1-based line of the field `path` only if it is present in `text`.
pub fn line_of_present(text: &str, path: &str) -> Option<usize> {
    lookup(text, path).and_then(|(line, exact)| exact.then_some(line))
}

/// The line of `path` (or of its nearest present ancestor) and whether the
/// path itself is present.
fn lookup(text: &str, path: &str) -> Option<(usize, bool)> {
    let root = DeTable::parse(text).ok()?;
    let mut table: &DeTable<'_> = root.get_ref();
    let mut best: Option<usize> = None;
    let steps = segments(path);
    let last = steps.len().saturating_sub(1);
    for (n, (key, indices)) in steps.into_iter().enumerate() {
        let Some((k, mut value)) = table.iter().find(|(k, _)| k.get_ref() == key) else {
            return best.map(|o| (line_of_offset(text, o), false));
        };
        best = Some(k.span().start);
        for i in indices {
            let item = match value.get_ref() {
                DeValue::Array(items) => items.get(i),
                _ => None,
            };
            let Some(item) = item else {
                return best.map(|o| (line_of_offset(text, o), false));
            };
            value = item;
            best = Some(item.span().start);
        }
        match value.get_ref() {
            DeValue::Table(t) => table = t,
            _ if n < last => return best.map(|o| (line_of_offset(text, o), false)),
            _ => {}
        }
    }
    best.map(|o| (line_of_offset(text, o), true))
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "name = \"x\"\nduration = 2.0\n\n[[leaf]]\nname = \"a\"\ncount = 3\n\n[[leaf]]\nname = \"b\"\nspread = [0.1, 0.2, 0.3]\n\n[ground]\nstatic_friction = 0.5\n";

    #[test]
    fn paths_and_lines_round_trip() {
        assert_eq!(line_of_path(TEXT, "duration"), Some(2));
        assert_eq!(line_of_path(TEXT, "leaf[0].count"), Some(6));
        assert_eq!(line_of_path(TEXT, "leaf[1].name"), Some(9));
        // Absent field: the line of its table's header.
        assert_eq!(line_of_path(TEXT, "leaf[1].count"), Some(8));
        assert_eq!(line_of_path(TEXT, "ground.restitution"), Some(12));
        assert_eq!(line_of_path(TEXT, "ground.static_friction"), Some(13));
        assert_eq!(line_of_present(TEXT, "leaf[1].count"), None);
        assert_eq!(line_of_present(TEXT, "leaf[0].count"), Some(6));
        assert_eq!(line_of_present(TEXT, "leaf[2].count"), None);
        let offset = TEXT.find("0.2").unwrap();
        assert_eq!(path_at(TEXT, offset).as_deref(), Some("leaf[1].spread[1]"));
        let offset = TEXT.find("count").unwrap();
        assert_eq!(path_at(TEXT, offset).as_deref(), Some("leaf[0].count"));
    }
}
