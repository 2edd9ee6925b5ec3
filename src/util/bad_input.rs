//! One way to name a bad input, for every kind of file leafmagic reads:
//! the file, the line when the file is text, the field as a path a user can
//! find in it (`particle[3].mass`, `rope[1].stiffness`) and the reason.

use super::toml_lines;

/// A file whose content is refused: `file:line: field: reason` (the line
/// and the field when known).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}{}: {}{}", .file, .line.map_or(String::new(), |l| format!(":{l}")), if .field.is_empty() { String::new() } else { format!("{}: ", .field) }, .reason)]
pub struct BadInput {
    /// The file (or embedded prototype) as the user named it.
    pub file: String,
    /// 1-based line of the field, when known.
    pub line: Option<usize>,
    /// The field, as a path in the file; empty for the file as a whole
    /// (it cannot be read).
    pub field: String,
    /// What is wrong.
    pub reason: String,
}

impl BadInput {
    /// The whole file is refused (it cannot be read, say).
    pub fn file(file: impl Into<String>, reason: impl Into<String>) -> BadInput {
        BadInput {
            file: file.into(),
            line: None,
            field: String::new(),
            reason: reason.into(),
        }
    }

    /// `field` of the TOML `text` is refused: its line is looked up (the
    /// line of its nearest enclosing table when the field is absent and a
    /// default was refused).
    pub fn in_toml(
        file: impl Into<String>,
        text: &str,
        field: impl Into<String>,
        reason: impl Into<String>,
    ) -> BadInput {
        let field = field.into();
        BadInput {
            file: file.into(),
            line: toml_lines::line_of_path(text, &field),
            field,
            reason: reason.into(),
        }
    }

    /// A TOML `text` that does not parse into what it should be, at the
    /// parser's line and field.
    pub fn toml_parse(file: impl Into<String>, text: &str, e: &toml::de::Error) -> BadInput {
        let (mut line, mut field) = match e.span() {
            Some(span) => (
                Some(toml_lines::line_of_offset(text, span.start)),
                toml_lines::path_at(text, span.start).unwrap_or_else(|| "(document)".into()),
            ),
            None => (None, "(document)".to_string()),
        };
        // Errors raised for a whole table (a key that does not apply to
        // its kind) name the key in backticks: point at that key.
        if let Some(key) = e.message().split('`').nth(1) {
            let path = if field == "(document)" {
                key.to_string()
            } else {
                format!("{field}.{key}")
            };
            if let Some(l) = toml_lines::line_of_present(text, &path) {
                (line, field) = (Some(l), path);
            }
        }
        BadInput {
            file: file.into(),
            line,
            field,
            reason: e.message().trim_end().to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_file_line_field_and_reason() {
        let text = "name = \"x\"\n\n[[particle]]\nmass = 1.0\n\n[[particle]]\nmass = -1.0\n";
        let e = BadInput::in_toml("leaf.toml", text, "particle[1].mass", "must be > 0");
        assert_eq!(e.to_string(), "leaf.toml:7: particle[1].mass: must be > 0");
        let e = BadInput::file("gone.toml", "cannot read: no such file");
        assert_eq!(e.to_string(), "gone.toml: cannot read: no such file");
        #[derive(serde::Deserialize, Debug)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct P {
            mass: f64,
        }
        #[derive(serde::Deserialize, Debug)]
        #[allow(dead_code)]
        struct L {
            particle: Vec<P>,
        }
        let text = "[[particle]]\nmass = 1.0\n\n[[particle]]\nmass = 1.0\nsize = 2\n";
        let e = BadInput::toml_parse("l.toml", text, &toml::from_str::<L>(text).unwrap_err());
        assert_eq!(e.line, Some(6), "{e}");
        assert!(e.to_string().starts_with("l.toml:6: particle[1]"), "{e}");
    }
}
