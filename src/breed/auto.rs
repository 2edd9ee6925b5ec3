//! `--prototype auto`: the embedded prototype to breed from, chosen from
//! what is bred toward. Issue 19 measured that the prototype matters more
//! than the optimizer: variants of prototype B find lilters and tumbling
//! spinners that variants of A rarely reach, and A's own neighbourhood is
//! where floaters (and autorotating spinners) live.

use crate::motion::classify::{MotionClass, Regime};

/// The name `--prototype` takes for the automatic choice.
pub const AUTO: &str = "auto";

/// The embedded prototype (`a` or `b`) for a target `class` (and, for an
/// example, its `regime`), with the reason in words. No class (descriptors
/// alone): A, the paper's first prototype.
pub fn choose(class: Option<MotionClass>, regime: Option<Regime>) -> (&'static str, &'static str) {
    match (class, regime) {
        (Some(MotionClass::Lilter), _) => (
            "b",
            "lilters are bred from prototype B, whose variants rock and flip far more often than A's",
        ),
        (Some(MotionClass::Spinner), Some(Regime::Tumble)) => (
            "b",
            "a tumbling spinner is bred from prototype B, whose variants tumble end over end far more often than A's",
        ),
        (Some(MotionClass::Spinner), _) => (
            "a",
            "an autorotating spinner is bred from prototype A, many of whose variants already autorotate",
        ),
        (Some(MotionClass::Floater), _) => (
            "a",
            "floaters are bred from prototype A, most of whose variants already float",
        ),
        _ => ("a", "no target class: prototype A, the paper's first leaf"),
    }
}
