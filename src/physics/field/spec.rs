//! TOML glue shared by every table of the field: a flow's keys, a bound's
//! shape, a front.
//!
//! Each table is one flat serde struct of optional keys (the tagged-enum
//! alternative cannot combine `deny_unknown_fields` with the `#[serde(flatten)]`
//! the shared keys would need). Which keys a `kind` or `shape` takes is then
//! checked here, on conversion: a key it needs and lacks ([`required`]), a key
//! that means nothing for it ([`reject_extra`]).

use std::fmt;

/// Takes a key the kind requires.
pub(super) fn required<T>(
    value: Option<T>,
    key: &str,
    owner: &dyn fmt::Display,
) -> Result<T, String> {
    value.ok_or_else(|| format!("{owner} requires `{key}`"))
}

/// Rejects keys that are present but mean nothing for this kind.
pub(super) fn reject_extra(
    present: &[(&str, bool)],
    allowed: &[&str],
    owner: &dyn fmt::Display,
) -> Result<(), String> {
    match present
        .iter()
        .find(|(key, here)| *here && !allowed.contains(key))
    {
        Some((key, _)) => Err(format!("`{key}` does not apply to {owner}")),
        None => Ok(()),
    }
}
