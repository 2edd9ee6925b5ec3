//! Experiments on the simulator: the paper's drop test ([`mod@drop`]), scene
//! files of its section 4.2 ([`scene`]), integration error against run time
//! ([`accuracy`]), and the stiff and extreme matrix ([`stress`]). The
//! research experiments (real falls, strips) live in the workspace's `lab`
//! crate, which this one does not depend on.
//!
//! May use: [`crate::physics`], [`crate::motion`], [`crate::leaf`], [`crate::util`].

pub mod accuracy;
pub mod drop;
pub mod scene;
pub mod stress;
