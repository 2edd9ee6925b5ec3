//! Verdicts as JUnit XML, the test report a pipeline's CI (GitLab, Jenkins,
//! GitHub's test reporters) reads: one `<testcase>` per check, a
//! `<failure>` where it failed.
//!
//! The layout is the common denominator of those readers (Ant's JUnit
//! report: `testsuites` › `testsuite` › `testcase` › `failure`). XML 1.0
//! cannot hold every character a file's object names may carry: the five
//! markup characters are escaped, and the characters it forbids outright
//! (control characters other than tab, newline and return; lone
//! surrogates cannot occur in a Rust string) become U+FFFD, so a hostile
//! name cannot break the report.

use std::fmt::Write as _;

/// One check: its name, the group it belongs to, and why it failed (none
/// if it passed).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TestCase {
    /// What was checked (e.g. a fall's object name).
    pub name: String,
    /// The group readers sort it under (e.g. the file it came from).
    pub classname: String,
    /// Why it failed: the `<failure>` message; `None` for a pass.
    pub failure: Option<String>,
}

/// The JUnit XML document of `cases`, as one suite named `suite`.
pub fn junit_xml(suite: &str, cases: &[TestCase]) -> String {
    let failures = cases.iter().filter(|c| c.failure.is_some()).count();
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let counts = format!(
        "tests=\"{}\" failures=\"{failures}\" errors=\"0\" skipped=\"0\"",
        cases.len()
    );
    let _ = writeln!(out, "<testsuites {counts}>");
    let _ = writeln!(out, "  <testsuite name=\"{}\" {counts}>", escape(suite));
    for case in cases {
        let head = format!(
            "    <testcase classname=\"{}\" name=\"{}\"",
            escape(&case.classname),
            escape(&case.name)
        );
        match &case.failure {
            None => {
                let _ = writeln!(out, "{head}/>");
            }
            Some(message) => {
                let m = escape(message);
                let _ = writeln!(out, "{head}>");
                let _ = writeln!(out, "      <failure message=\"{m}\">{m}</failure>");
                let _ = writeln!(out, "    </testcase>");
            }
        }
    }
    out.push_str("  </testsuite>\n</testsuites>\n");
    out
}

/// `text` as XML character data or an attribute value (either quote).
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            // Kept as references: an attribute value's literal newlines and
            // tabs would be normalised to spaces by the reader.
            '\t' => out.push_str("&#9;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            // XML 1.0's Char production excludes these even as references.
            c if (c as u32) < 0x20 || c == '\u{FFFE}' || c == '\u{FFFF}' => out.push('\u{FFFD}'),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markup_and_forbidden_characters_are_escaped() {
        assert_eq!(
            escape("a<b>&\"c'\u{1}\u{FFFF}\n"),
            "a&lt;b&gt;&amp;&quot;c&apos;\u{FFFD}\u{FFFD}&#10;"
        );
    }

    #[test]
    fn counts_match_the_cases() {
        let case = |name: &str, failure: Option<&str>| TestCase {
            name: name.into(),
            classname: "f.abc".into(),
            failure: failure.map(String::from),
        };
        let xml = junit_xml(
            "s",
            &[case("a", None), case("b<", Some("x & y")), case("c", None)],
        );
        assert!(
            xml.contains("<testsuites tests=\"3\" failures=\"1\""),
            "{xml}"
        );
        assert_eq!(xml.matches("<testcase ").count(), 3);
        assert_eq!(xml.matches("<failure ").count(), 1);
        assert!(xml.contains("name=\"b&lt;\"") && xml.contains(">x &amp; y</failure>"));
    }
}
