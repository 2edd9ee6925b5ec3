//! Experiments on the simulator: the paper's drop test ([`mod@drop`]), scene
//! files of its section 4.2 ([`scene`]), integration error against run time
//! ([`accuracy`]), the stiff and extreme matrix ([`stress`]) and the
//! real-falls experiment with paper squares ([`real_falls`]).
//!
//! May use: [`crate::physics`], [`crate::motion`], [`crate::leaf`], [`crate::util`].

pub mod accuracy;
pub mod drop;
pub mod real_falls;
pub mod scene;
pub mod stress;
