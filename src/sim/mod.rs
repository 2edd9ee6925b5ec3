//! Experiments on the simulator: the paper's drop test ([`mod@drop`]), scene
//! files of its section 4.2 ([`scene`]), integration error against run time
//! ([`accuracy`]), the stiff and extreme matrix ([`stress`]), the
//! real-falls experiment with paper squares ([`real_falls`]) and the
//! strips' scaling law ([`strips`]).
//!
//! May use: [`crate::physics`], [`crate::motion`], [`crate::leaf`], [`crate::util`].

pub mod accuracy;
pub mod drop;
pub mod real_falls;
pub mod scene;
pub mod stress;
pub mod strips;
