//! The studio: the paper's section 4.1 loop with a person as the eye. A
//! grid of candidates falls in the browser; the person picks the ones that
//! move well and the next generation is bred from the picks
//! ([`variation`]): variations at a shrinking scale, crossovers of two
//! picks and wild cards. A session ([`session`]) is a tree of generations
//! recorded in a run directory, with a collection of kept leaves that
//! [`collection`] exports; [`preference`] models the person's taste from
//! their picks, to order the grid; [`server`] is the local web server and
//! its page.
//!
//! May use: [`crate::output`], [`crate::breed`], [`crate::sim`],
//! [`crate::leaf`], [`crate::formats`], [`crate::motion`], [`crate::physics`],
//! [`crate::util`].

pub mod collection;
pub mod preference;
pub mod server;
pub mod session;
pub mod variation;

pub use collection::{ExportRequest, export_collection};
pub use server::Server;
pub use session::{Session, StudioError, StudioSettings};
