//! Where a directing table's error is reported: the file, and the field's
//! line found from its path ([`BadInput::in_toml`]).

use crate::util::bad_input::BadInput;

/// The file and its text (for line numbers).
pub struct Where<'a> {
    /// The file as named.
    pub file: &'a str,
    /// Its text.
    pub text: &'a str,
}

impl Where<'_> {
    /// `field` is refused for `reason`.
    pub fn err(&self, field: impl Into<String>, reason: impl Into<String>) -> BadInput {
        BadInput::in_toml(self.file, self.text, field, reason)
    }
}
