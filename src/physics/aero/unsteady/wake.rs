//! The wake's rocking couple on a plate that falls face-on (opt-in:
//! `wake_couple`, default 0).
//!
//! # Why
//!
//! Real paper squares let go flat leave their flat fall 0.13–0.37 s after
//! release, about three to four times the time the air takes to cross the
//! plate at every size; the law's face-on fall, let go at 1–5°, only rocks
//! about face-on at the Munk couple's period and takes 0.76–1.05 s at every
//! size (docs/lab/real-falls.md, "When a flat release departs"). No coefficient
//! of the quasi-steady terms changes that. A bluff plate's wake does: it
//! sheds vortices from alternate edges at a Strouhal frequency
//! f = St |u| / c (St ≈ 0.15 for plates normal to a stream; Roshko 1954,
//! NACA TN 3169), and the uneven pressure rocks the plate.
//!
//! # The term
//!
//! Each plate p carries a wake phase φ_p that turns at ω_p = 2π St U_p / c_p
//! (U_p the area-weighted mean relative air speed over its intact
//! triangles, c_p its largest chord), from φ = π/2 at release. Each intact
//! triangle t of the plate gets the normal force
//!
//! f_t = C_W · ½ ρ U_p² · sin φ_p · sin⁴α_t · A_t · (d_t / c_p) · n_t,
//!
//! d_t the distance of its centroid from the plate's area centre along an
//! axis fixed in the plate (its first intact triangle's first edge): a
//! couple about the in-plane axis across that one, whose net force vanishes
//! on a plate of uniform sin⁴α. The sin⁴α keeps it to the face-on fall
//! (broadside flow sheds a bluff wake; a gliding or edge-on plate's flow is
//! attached). It is a forcing that follows the flow, not a wake that
//! answers the plate's motion (no coupling back, as wake-oscillator models
//! of vortex-induced vibration add): the least that tests whether a wake's
//! timing explains the departure. The stability estimate leaves it out: its
//! size is that of the face-on drag, and its own rate ω_p is far below 1/dt.
//!
//! φ is state, carried by [`super::PressureLag`]: an evaluation a time Δ
//! after the committed state reads φ + ½(ω₀ + ω) Δ, ω₀ the committed rate
//! and ω its own (the trapezoid rule, second order as Verlet is), and each
//! step commits its last evaluation's.

use crate::physics::model::Model;

/// One plate's wake: its phase and the rate it turns at.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct WakePhase {
    /// φ at the committed state, rad.
    pub(super) phase: f64,
    /// ω at the committed state, rad/s (NaN before any evaluation).
    rate: f64,
    /// ω of the last evaluation since the commit (NaN: none).
    pub(super) pending: f64,
    /// The plate's largest chord c_p, m.
    pub(super) chord: f64,
}

impl WakePhase {
    /// Every plate of `model` at φ = π/2 (`plates` entries, one per plate
    /// index).
    pub(super) fn for_model(model: &Model, plates: usize) -> Vec<WakePhase> {
        let mut out = vec![
            WakePhase {
                phase: std::f64::consts::FRAC_PI_2,
                rate: f64::NAN,
                pending: f64::NAN,
                chord: 0.0,
            };
            plates
        ];
        for g in &model.surfaces {
            let c = g.chords.iter().copied().fold(0.0, f64::max);
            out[g.plate].chord = out[g.plate].chord.max(c);
        }
        out
    }

    /// φ a time `elapsed` after the committed state, where the plate's
    /// wake turns at `rate`.
    pub(super) fn phase_at(&self, elapsed: f64, rate: f64) -> f64 {
        let from = if self.rate.is_nan() { rate } else { self.rate };
        self.phase + 0.5 * (from + rate) * elapsed
    }

    /// Commits the step of `h` s: from the committed rate to the last
    /// evaluation's (`evaluated`), or at the committed rate.
    pub(super) fn advance(&mut self, h: f64, evaluated: bool) {
        let to = if evaluated && !self.pending.is_nan() {
            self.pending
        } else {
            self.rate
        };
        if to.is_nan() {
            return;
        }
        self.phase = self.phase_at(h, to);
        self.rate = to;
        self.pending = f64::NAN;
    }
}
