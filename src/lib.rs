//! leafmagic: design the motion of falling leaves by breeding them in a
//! physically based simulator (after Haumann et al., "An Application of
//! Motion Design and Control for Physically-Based Animation").
//!
//! The folders are the layers; each imports only the layers above it in
//! this list (a test, `layers`, holds the rule):
//!
//! - [`util`]: atomic file writes, CSV of particle positions, SVG plot
//!   helpers. Imports nothing of leafmagic.
//! - [`physics`]: the simulator of the paper's section 2: the model and its
//!   parts, the state, the wind field, the force terms, contact, rigid
//!   bodies, stability, the integrators and the frame loops.
//! - [`motion`]: trajectories and what they show: classification into the
//!   paper's floaters, spinners and lilters, and motion descriptors. Knows
//!   nothing of physics: it reads poses, from leafmagic or anywhere else.
//! - [`formats`]: the files of other tools, read and written: the clip
//!   every format shares, glTF, USD, Alembic, PC2 + OBJ, and the one entry
//!   point that turns any supported file into a fall.
//! - [`leaf`]: leaf files, the paper's prototypes, the genome that varies
//!   them, recipes and flat plates.
//! - [`sim`]: experiments built on the simulator: the drop test, scenes,
//!   accuracy sweeps, the stress matrix.
//! - [`breed`]: the paper's section 4.1 loop, automated: populations,
//!   evaluation, selection, the run directory, shards and executors.
//! - [`direct`]: directing leaves: a scene's goals and free parameters, and
//!   the search (CMA-ES against a random baseline) that meets the goals.
//! - [`output`]: what leaves leafmagic: clips of its own drops and scene
//!   runs (written through [`formats`]) and the HTML preview.
//! - [`studio`]: choosing leaves by eye in the browser: a session of
//!   generations bred from a person's picks, and its local web server.
//!
//! The command line (`src/cli/`) sits on top, in the binary. The research
//! experiments (real falls, strips) are the workspace's `lab` crate, built
//! on this library; nothing here depends on them.
#![warn(missing_docs)]

pub mod breed;
pub mod direct;
pub mod formats;
pub mod leaf;
pub mod motion;
pub mod output;
pub mod physics;
pub mod sim;
pub mod studio;
pub mod util;
