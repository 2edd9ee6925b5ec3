//! How accurate a run is, and what accuracy costs: work-precision sweeps over
//! the time step (docs/design/numerics.md, "Error against work"), the error
//! estimate that breeding runs record ([`estimate`]), and, past the horizon
//! where pointwise error means nothing, statistics across time steps
//! ([`long`]).
//!
//! Its files, one job each: `run` (one run to T, measured, and the RK4
//! reference), `settings` (what a sweep runs), `cost` (what it will cost),
//! `sweep` (the sweep, what it found and accuracy.csv), `plot`
//! (accuracy.svg), `estimate` (the error a breeding run records), `long`
//! (statistics across steps past the horizon) and `error` (why a
//! computation could not be done); this file re-exports them.
//!
//! # The sweep
//!
//! A problem is a [`Model`] plus an initial [`State`] (a dropped leaf now; a
//! scene later) run for T seconds. For each integrator the step is swept over
//! h = T/2^j, so every run ends exactly at T. The error of a run is the RMS
//! over particles of |x_i(T) − x_i^ref(T)| divided by the model's chord
//! ([`Model::chord`]). Its work is the median wall time of
//! [`SweepSettings::runs`] identical runs (stepping only: building the
//! simulator, copying the initial state and all output are outside the clock)
//! and its force evaluations, which do not depend on the machine.
//!
//! **Reference.** RK4 at h_ref = T/2^J. It is validated by self-convergence:
//! the run at h_ref/2 must agree with it to [`REFERENCE_FACTOR`] × the
//! smallest error plotted. Where it does not (a law with kinks holds RK4 to
//! second order), the reference is halved until it does, reaches round-off
//! or 2^[`MAX_STEPS_LOG2`] steps ([`SweepSettings::refine_reference`]), and
//! every point measured again; still not valid, the report carries a
//! warning. Errors are measured against the finer of the two runs. Because RK4 is fourth order,
//! h_ref need not be below the first-order curves' smallest step (the rule
//! h_ref ≤ h_min/8 of docs/design/numerics.md, "Error against work", step 3, is for
//! a reference of the same order); the validation is what guarantees it is
//! good enough.
//!
//! **Events.** Spring breaking would limit every scheme to first order, so
//! the sweep runs on a copy of the model with breaking switched off
//! ([`smooth_model`]) and says how many springs it affected. The model has no
//! ground contact.
//!
//! **Divergence.** A run that the simulator stops (non-finite or runaway
//! state, failed implicit solve) is kept as a row with `diverged = true` and
//! no error. A run that reaches T ringing (its springs and hinges
//! oscillating step to step: [`EndRun::oscillating`]) is kept with
//! `oscillating = true` and no error: above the stable step the unstable
//! mode need not run away, the springs' nonlinearity can hold it at a
//! bounded amplitude for as long as the run lasts (docs/design/accuracy.md,
//! "Stable limits"). Between the largest stable and the smallest unstable
//! step of each explicit scheme, the step count n (h = T/n) is then
//! bisected, so the observed stability limit is located to about 1 % and
//! can be set against the estimate that `check` prints.
//!
//! **Observed order.** The least-squares slope of log error against log h
//! over the non-diverged points whose error lies between
//! [`FIT_FLOOR_FACTOR`] × the reference's self-difference (below that, the
//! reference's own error would bend the curve) and [`FIT_MAX_ERROR`] (above
//! that, the run is outside the asymptotic regime: near the stability limit
//! the error is of the order of the leaf itself). The pairwise orders
//! log₂(e(h)/e(h/2)) of those points are reported too.
//!
//! [`Model`]: crate::physics::model::Model
//! [`Model::chord`]: crate::physics::model::Model::chord
//! [`State`]: crate::physics::state::State

mod cost;
mod error;
pub mod estimate;
pub mod long;
pub mod plot;
mod run;
mod settings;
mod sweep;

pub use cost::*;
pub use error::*;
pub use estimate::{ErrorCache, ErrorEstimate, error_estimate};
pub use run::*;
pub use settings::*;
pub use sweep::*;
