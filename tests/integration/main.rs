//! Integration tests: one binary (one link on a 2-core machine), one module
//! per topic. Oracles are exact where docs/design/numerics.md, "Oracles", gives one.

mod accuracy;
mod aero_law;
mod alloc;
mod animation_falls;
mod batch;
mod bending;
mod blender;
mod breeding;
mod classes;
mod common;
mod contact;
// Shared with lab/examples/real_falls_classify.rs, which uses all of it.
#[allow(dead_code)]
mod corpus;
mod directing;
mod docs_links;
mod expectations;
mod export;
mod fuzz;
mod genome;
mod hostile;
mod hostile_gltf;
mod hostile_usd;
mod integrators;
mod invariants;
mod k8s;
mod law;
mod layers;
mod leaves;
mod like;
mod long_functions;
mod newcomer;
mod particles;
mod plate_cli;
mod real_falls;
mod resume;
mod rigid;
mod scene_files;
mod scenes;
mod shards;
mod skipping;
mod stability;
mod studio;
mod tearing;
mod unsteady;
mod usd;
mod validation;
