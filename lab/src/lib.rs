//! leafmagic's lab: research experiments built on the simulator that no
//! command of the tool uses, kept apart from the product (the tool does not
//! depend on this crate). Their results are checked by this crate's tests
//! (`lab/tests/`), which `cargo test` at the workspace's root runs, and
//! their history is written up in `docs/lab/`.
//!
//! - [`real_falls`]: Howison, Hughes & Iida's real-falls experiment redone
//!   in the simulator and scored against their tracked paper squares.
//! - [`strips`]: the strips' tumbling-rate scaling law.
//!
//! The experiments' commands are this crate's examples
//! (`cargo run --release -p leafmagic-lab --example real_falls`, and
//! `plate_regimes`, `recipes_by_law`, `descriptor_scales`, `classes`,
//! `real_falls_classify`).
#![warn(missing_docs)]

pub mod real_falls;
pub mod strips;
