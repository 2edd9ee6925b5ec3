//! The lagged centre of pressure (module docs of [`super`], "Lagged
//! centre of pressure"): the state the simulator carries from step to step
//! ([`PressureLag`]) and its exponential time differencing.

use super::wake;
use crate::physics::aero::law::AeroLaw;
use crate::physics::model::Model;

/// The lagged angle of attack α_L of every triangle: the state of the
/// law's lagged centre of pressure, carried by the simulator from step to
/// step (module docs, "Lagged centre of pressure").
///
/// A force evaluation a time Δ after the committed state reads α_L at its
/// own time: dα_L/dt = r (α − α_L), r = 1/τ, solved exactly with α taken
/// linear between the committed α and the evaluation's own, and r their
/// mean (exponential time differencing; Cox & Matthews 2002, J. Comput.
/// Phys. 176): with x = r Δ and φ = (1 − e^(−x))/x,
/// α_L(Δ) = e^(−x) α_L + (φ − e^(−x)) α₀ + (1 − φ) α, a convex combination
/// (α_L stays between the angles it follows, at any step) and second order
/// in Δ. So Verlet's end-of-step evaluation, whose acceleration it carries
/// into the next step, sees the lag at that step's end, and the term keeps
/// Verlet second order (a test measures it). RK4 under this law is not
/// fourth order, with the term or without it (docs/lab/real-falls.md).
/// [`Self::advance`] then commits the step's last evaluation. The same
/// state carries each plate's wake phase when the opt-in wake term is on
/// (module docs, "Wake"), read and committed the same way.
#[derive(Clone, Debug, PartialEq)]
pub struct PressureLag {
    /// Committed α_L per triangle, rad; NaN until the triangle has met the
    /// air.
    pub(super) lagged: Vec<f64>,
    /// Committed α and lag rate r = |u|/(k c∥) of each triangle (α NaN: no
    /// flow over it then; rate ∞: broadside, no lag).
    pub(super) alpha: Vec<f64>,
    pub(super) rate: Vec<f64>,
    /// The last evaluation's α_L, α and r, not yet committed.
    pub(super) pending_lagged: Vec<f64>,
    pub(super) pending_alpha: Vec<f64>,
    pub(super) pending_rate: Vec<f64>,
    /// The angle the flow over each triangle starts at where it had none
    /// at the committed state ([`seed_flow_start`](super::seed_flow_start); NaN: not known).
    pub(super) start: Vec<f64>,
    /// Whether some triangle has not yet met the air (α_L NaN).
    waiting: bool,
    /// Whether a force evaluation has run since the last commit.
    pub(super) evaluated: bool,
    /// Time of the committed state, s (NaN before the first evaluation),
    /// and the next (or last) evaluation's time after it, Δ.
    time: f64,
    pub(super) elapsed: f64,
    /// Whether the lag term is on (`pressure_lag_gain > 0`); the state also
    /// carries the wake's phases ([`wake`]) when only that term is on.
    lag_on: bool,
    /// Each plate's wake ([`wake::WakePhase`]); empty with the term off.
    pub(super) wake: Vec<wake::WakePhase>,
}

impl PressureLag {
    /// The state for `model`, all triangles unlagged and every plate's wake
    /// at its start; `None` unless its law is the unsteady one with a lag
    /// term (`pressure_lag_gain > 0`) or a wake (`wake_couple > 0`).
    pub fn for_model(model: &Model) -> Option<PressureLag> {
        let AeroLaw::Unsteady(law) = &model.aero else {
            return None;
        };
        let lag_on = law.pressure_lag_gain > 0.0;
        (lag_on || law.wake_couple > 0.0).then(|| {
            let n = model.triangles.len();
            PressureLag {
                lagged: vec![f64::NAN; n],
                alpha: vec![f64::NAN; n],
                rate: vec![f64::NAN; n],
                pending_lagged: vec![f64::NAN; n],
                pending_alpha: vec![f64::NAN; n],
                pending_rate: vec![f64::NAN; n],
                start: vec![f64::NAN; n],
                waiting: lag_on && n > 0,
                evaluated: false,
                time: f64::NAN,
                elapsed: 0.0,
                lag_on,
                wake: if law.wake_couple > 0.0 {
                    wake::WakePhase::for_model(model, model.plate_count())
                } else {
                    Vec::new()
                },
            }
        })
    }

    /// Plate `p`'s wake phase φ at the committed state, rad (NaN without
    /// the wake term or such a plate).
    pub fn wake_phase(&self, p: usize) -> f64 {
        self.wake.get(p).map_or(f64::NAN, |w| w.phase)
    }

    /// The committed lagged angle of attack of triangle `t`, rad (NaN
    /// before it has met the air).
    pub fn lagged(&self, t: usize) -> f64 {
        self.lagged[t]
    }

    /// Whether the evaluation just placed is at the committed time and a
    /// triangle there has not met the air: then the flow's start angles
    /// are wanted ([`seed_flow_start`](super::seed_flow_start)).
    pub fn wants_start(&self) -> bool {
        self.waiting && self.elapsed <= 0.0
    }

    /// Places the next force evaluation at time `t`, s: Δ = t − the
    /// committed state's time (the first evaluation fixes that time).
    pub fn evaluate_at(&mut self, t: f64) {
        if self.time.is_nan() {
            self.time = t;
        }
        self.elapsed = (t - self.time).max(0.0);
    }

    /// Commits the last evaluation and carries it to `h` s after the
    /// committed state (the step just taken): from the evaluation's time
    /// to the step's end with α and r held, α_L ← α + (α_L − α) e^(−r h′),
    /// h′ = h − Δ (none after an end-of-step evaluation; the whole step
    /// after Euler's, at its start). Without an evaluation since the last
    /// commit, the committed α and r are held over the whole of `h`. A
    /// triangle meeting the air for the first time starts from the angle
    /// its flow started at ([`seed_flow_start`](super::seed_flow_start)) where that is known, and
    /// unlagged (α_L = α) where not; one with no flow keeps α_L.
    pub fn advance(&mut self, h: f64) {
        // After an end-of-step evaluation Δ is h up to the clock's
        // round-off: nothing is left to carry.
        let rest = if self.evaluated {
            let rest = h - self.elapsed;
            if rest > 1e-9 * h { rest } else { 0.0 }
        } else {
            h
        };
        for t in 0..self.lagged.len() {
            let (lagged, alpha, rate) = if self.evaluated {
                let pending = (
                    self.pending_lagged[t],
                    self.pending_alpha[t],
                    self.pending_rate[t],
                );
                self.pending_alpha[t] = f64::NAN;
                pending
            } else {
                (self.lagged[t], self.alpha[t], self.rate[t])
            };
            if alpha.is_nan() {
                continue;
            }
            self.lagged[t] = if lagged.is_nan() || rate == f64::INFINITY {
                alpha
            } else if rest > 0.0 {
                alpha + (lagged - alpha) * (-rest * rate).exp()
            } else {
                lagged
            };
            self.alpha[t] = alpha;
            self.rate[t] = rate;
            self.start[t] = f64::NAN;
        }
        self.waiting = self.lag_on && self.lagged.iter().any(|l| l.is_nan());
        for w in &mut self.wake {
            w.advance(h, self.evaluated);
        }
        if !self.time.is_nan() {
            self.time += h;
        }
        self.evaluated = false;
        self.elapsed = 0.0;
    }
}

/// α_L a time `elapsed` after the committed state (α_L, α₀, r₀) =
/// `committed`, where the angle of attack is `alpha` and the lag rate
/// `rate` ([`PressureLag`]: exponential time differencing).
#[inline]
pub(super) fn lag_at(committed: (f64, f64, f64), elapsed: f64, alpha: f64, rate: f64) -> f64 {
    let (lagged, alpha0, rate0) = committed;
    if lagged.is_nan() || rate == f64::INFINITY || rate0 == f64::INFINITY {
        return if lagged.is_nan() || elapsed > 0.0 {
            alpha
        } else {
            lagged
        };
    }
    if elapsed <= 0.0 {
        return lagged;
    }
    // No committed flow: α held at the evaluation's over the interval.
    let (alpha0, rate0) = if alpha0.is_nan() {
        (alpha, rate)
    } else {
        (alpha0, rate0)
    };
    let x = 0.5 * (rate0 + rate) * elapsed;
    let em1 = (-x).exp_m1();
    let decay = 1.0 + em1;
    let phi = if x > 0.0 { -em1 / x } else { 1.0 };
    decay * lagged + (phi - decay) * alpha0 + (1.0 - phi) * alpha
}

/// The angle of attack α = asin(|u·n|/|u|) of a flow of normal part `qn`
/// and speed `speed` > 0, rad (min 1: round-off).
#[inline]
pub(super) fn angle_of_attack(qn: f64, speed: f64) -> f64 {
    (qn.abs() / speed).min(1.0).asin()
}

/// The centre of pressure's offset upstream of mid-chord in steady flow,
/// in chords: a quarter chord at α = 0 (thin-aerofoil theory), none
/// broadside, linear between (module docs).
#[inline]
pub fn pressure_offset(alpha: f64) -> f64 {
    0.25 * (1.0 - alpha * std::f64::consts::FRAC_2_PI)
}

/// What the lagged centre of pressure does on a triangle in an evaluation
/// (the passes of `lagged_pressure` in triangle_forces.rs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) enum LagCouple {
    /// No flow over it, or broadside: no lag rate, no couple.
    #[default]
    None,
    /// Its lag starts at this evaluation: α_L follows, no couple yet.
    Follows,
    /// α_L lags α and the couple acts.
    Acts,
}
