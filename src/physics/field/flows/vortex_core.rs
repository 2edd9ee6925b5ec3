//! Core models of a vortex. In a file of its own because two files name it:
//! the line vortex, which evaluates it, and the TOML keys (`core = "..."`),
//! which every flow kind reads.

use serde::{Deserialize, Serialize};

/// Core model of a line vortex, which removes the 1/ρ singularity on its axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VortexCore {
    /// Lamb–Oseen (viscous) core: v_θ = Γ/(2πρ)·(1 − e^{−ρ²/r_c²}); smooth
    /// everywhere, peak 0.6382·Γ/(2π r_c) at ρ = 1.1209 r_c. The default.
    #[default]
    LambOseen,
    /// Rankine core: solid-body rotation v_θ = Γρ/(2πR²) for ρ < R, free vortex
    /// Γ/(2πρ) outside; continuous, with a kink at ρ = R.
    Rankine,
}
