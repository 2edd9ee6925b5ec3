//! The linear law's keys (paper, eq. 9–10). Its coefficients αⁿ, αᵗ,
//! kg/(m²·s), belong to each triangle ([`crate::physics::model::Triangle`]):
//! the `[aero]` table gives the leaf's, which a triangle may override, and
//! both are required (no value fits every leaf; `prototypes/leaf-a.toml`
//! uses αⁿ = 0.47, αᵗ = 0.047).

use crate::physics::aero::keys::{AeroKeys, Key};
use crate::physics::model::error::ModelError;

/// αⁿ, the normal coefficient, and αᵗ, the tangential one.
pub const KEYS: &[Key] = &[Key::number("alpha_n"), Key::number("alpha_t")];

/// Both α set: the law has no default for them.
pub fn check_required(keys: &AeroKeys) -> Result<(), ModelError> {
    for key in KEYS {
        if keys.number(key.name).is_none() {
            return Err(ModelError {
                item: format!("aero.{}", key.name),
                reason: "required by law = \"linear\" (kg/(m²·s))".to_string(),
            });
        }
    }
    Ok(())
}
