//! Breeding: the paper's section 4.1 loop, automated. A prototype is copied
//! into a population of variants ([`crate::leaf::genome`]), each is dropped in
//! still air ([`crate::sim::drop::drop_leaf`]) on the rayon pool, every fall is
//! classified ([`crate::motion::classify`]), the best are kept and the next
//! generation is bred from them with a variation scale that shrinks as the
//! population converges.
//!
//! Reproducibility: every random draw comes from a stream seeded by
//! (seed, generation, id) or (seed, generation, "selection"), never from a
//! shared generator, and results are gathered in id order; so the same seed
//! gives the same bytes whatever the number of threads. Every file is
//! written atomically, and a checkpoint after each generation lets
//! `--resume` finish a killed run with the same bytes as an uninterrupted one.

//!
//! Files: [`settings`] and [`population`] are the data; [`mod@evaluate`] drops
//! and scores one individual; [`selection`] ranks, selects and varies
//! (with [`strategy`], [`cmaes`] and [`least_squares`]);
//! [`archive`] is the MAP-Elites archive; [`novelty`] scores the leaves
//! that hold the target class by how differently they fall; [`run`] is the driver and the run
//! directory ([`files`] its tables, [`plot`] its plots); [`shard`],
//! [`worker`] and [`executor`] spread a generation over processes and
//! machines; [`verify`] checks a run directory before it is used again.
//!
//! May use: [`crate::sim`], [`crate::leaf`], [`crate::motion`],
//! [`crate::physics`], [`crate::util`].

pub mod archive;
pub mod auto;
pub mod boundary;
pub mod cmaes;
pub mod evaluate;
pub mod executor;
pub mod files;
pub mod least_squares;
pub mod novelty;
pub mod plot;
pub mod population;
pub mod robust;
pub mod run;
pub mod selection;
pub mod settings;
pub mod shard;
pub mod strategy;
pub mod verify;
pub mod worker;

pub use evaluate::{evaluate, like_score, score};
pub use population::{
    ArchiveEntry, BreedError, Checkpoint, Child, Evaluation, GenerationSummary, Individual, Job,
    Plan, Progress, Quiet,
};
pub use run::{ERROR_ESTIMATE_SECONDS, Run, StartLeaves, start_leaves};
pub use settings::BreedSettings;
