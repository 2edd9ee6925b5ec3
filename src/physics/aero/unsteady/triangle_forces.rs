//! The unsteady law's forces on every triangle (module docs of [`super`]
//! give the equations and their sources).

use super::coefficients::UnsteadyAero;
use super::lag::{LagCouple, PressureLag, angle_of_attack, lag_at, pressure_offset};
use crate::physics::aero::law::AeroLaw;
use crate::physics::aero::surfaces::surface;
use crate::physics::model::{Model, SurfaceGeometry};
use nalgebra::{Matrix3, Vector3};

/// A vector in space.
pub(super) type V3 = Vector3<f64>;

/// Laminar skin friction on one face, 1.328/√Re (Blasius).
pub const BLASIUS: f64 = 1.328;

/// Reynolds numbers below this are taken as this in the skin-friction
/// coefficient (Blasius' law is for Re ≫ 1; below, the force is already
/// negligible).
pub const MIN_REYNOLDS: f64 = 1.0;

/// Factor on the fastest steady fall ([`edge_on_speed`](super::edge_on_speed)) that bounds the
/// air speed of any triangle for the stability estimate (as the quadratic
/// law's [`crate::physics::aero::quadratic::SPEED_MARGIN`]).
pub const SPEED_MARGIN: f64 = 2.0;

/// Edge-on drag coefficient C_D∥ at in-plane relative speed `speed` along
/// a chord `chord`: form drag plus skin friction on both faces.
#[inline]
pub fn cd_parallel(law: &UnsteadyAero, speed: f64, chord: f64) -> f64 {
    let friction = if law.kinematic_viscosity > 0.0 && law.skin_friction > 0.0 {
        let re = (speed * chord / law.kinematic_viscosity).max(MIN_REYNOLDS);
        2.0 * BLASIUS * law.skin_friction / re.sqrt()
    } else {
        0.0
    };
    law.cd_parallel + friction
}

/// Adds the unsteady law's velocity-dependent forces on every triangle of
/// `model` that is not torn (`torn[t]`; an empty mask tears none), and
/// each corner's added-mass tensor m_k n nᵀ into `added` (which the caller
/// zeroes; an empty slice skips them, for callers that read only the
/// forces). `wind` holds G at every particle, or is `None` in still air.
/// `lag` is the simulator's lagged centre of pressure: read, and each
/// triangle's angle of attack recorded for [`PressureLag::advance`]
/// (`None`, or `pressure_lag_gain = 0`, leaves that term out). See the
/// module docs for the equations.
#[allow(clippy::too_many_arguments)]
pub fn unsteady_forces(
    law: &UnsteadyAero,
    model: &Model,
    x: &[V3],
    v: &[V3],
    wind: Option<&[V3]>,
    torn: &[bool],
    force: &mut [V3],
    added: &mut [Matrix3<f64>],
    mut lag: Option<&mut PressureLag>,
) {
    SCRATCH.with_borrow_mut(|scratch| {
        scratch.measure(law, model, x, v, wind, torn);
        let Scratch {
            triangles,
            plates,
            flows,
            wake,
        } = scratch;
        flow_coefficients(law, model, flows);
        if let Some(lag) = lag.as_deref_mut().filter(|_| law.pressure_lag_gain > 0.0) {
            lagged_pressure(law, triangles, flows, lag);
        }
        per_triangle(law, model, v, wind, triangles, flows, force, added);
        if let Some(lag) = lag.filter(|_| law.wake_couple > 0.0) {
            wake_couples(law, model, x, triangles, plates, flows, lag, wake, force);
        }
    });
    if law.buoyancy {
        let lift = -model.gravity * (law.air_density / law.solid_density);
        for (fi, &m) in force.iter_mut().zip(&model.mass) {
            *fi += lift * m;
        }
    }
}

/// The lagged centre of pressure's couple on every intact triangle with
/// flow over it, as its in-plane arm in `flows` (which [`per_triangle`]
/// applies with the Munk couple's), and each triangle's α and lag rate
/// recorded in `lag` (module docs): the normal force ½ ρ A C_D⊥ |u| (u·n) n
/// moved G c∥ (f(α_L) − f(α)) cos α upstream along the in-plane flow (the
/// cos α, |u∥|/|u|, takes the couple through zero where the in-plane flow
/// reverses, instead of through a jump).
fn lagged_pressure(
    law: &UnsteadyAero,
    triangles: &[Option<TriangleMotion>],
    flows: &mut [Flow],
    lag: &mut PressureLag,
) {
    lag.evaluated = true;
    // The angles first, back to back: each arcsine is a long chain of
    // its own, and independent ones overlap (as in `flow_coefficients`).
    for ((alpha, flow), tm) in lag
        .pending_alpha
        .iter_mut()
        .zip(flows.iter())
        .zip(triangles)
    {
        *alpha = if tm.is_some() && flow.u2 > f64::MIN_POSITIVE {
            angle_of_attack(flow.qn, flow.speed)
        } else {
            f64::NAN
        };
    }
    // Then the lag rates, each a division; then α_L at the evaluation,
    // each an exponential and a division; then the couples. Passes of
    // their own for the same reason: one triangle's chain (arcsine, rate,
    // exponential, quotient, couple) filled the reorder window, so no two
    // triangles' chains overlapped (perf). Same operations per triangle,
    // same bits.
    for (t, (flow, tm)) in flows.iter_mut().zip(triangles).enumerate() {
        flow.lag = LagCouple::None;
        let alpha = lag.pending_alpha[t];
        if tm.is_none() || alpha.is_nan() {
            continue;
        }
        // Broadside (no in-plane flow) there is no upstream and no chord
        // along the flow: α_L still follows α, no couple acts.
        if flow.along2 <= f64::MIN_POSITIVE {
            lag.pending_rate[t] = f64::INFINITY;
            lag.pending_lagged[t] = alpha;
            continue;
        }
        let rate = flow.speed / (law.pressure_lag * flow.along_chord);
        let mut fresh = lag.lagged[t].is_nan();
        if fresh && lag.elapsed <= 0.0 {
            // Met at the committed time: that is where its lag starts, so
            // later evaluations of the step integrate from it.
            (lag.lagged[t], lag.alpha[t], lag.rate[t]) = (alpha, alpha, rate);
        } else if fresh && !lag.start[t].is_nan() {
            // The flow began at the committed time, from none, at the
            // angle `seed_flow_start` found and at rate |u|/(k c) = 0: the
            // lag starts there (started at this evaluation's α instead, it
            // begins O(h) late, an error of first order in every fall from
            // rest: small under Verlet's own, but RK4's whole error).
            let start = lag.start[t];
            (lag.lagged[t], lag.alpha[t], lag.rate[t]) = (start, start, 0.0);
            fresh = false;
        }
        lag.pending_rate[t] = rate;
        flow.lag = if fresh {
            LagCouple::Follows
        } else {
            LagCouple::Acts
        };
    }
    let elapsed = lag.elapsed;
    for (((((pending, flow), &alpha), &rate), &lagged), (&alpha0, &rate0)) in lag
        .pending_lagged
        .iter_mut()
        .zip(flows.iter())
        .zip(&lag.pending_alpha)
        .zip(&lag.pending_rate)
        .zip(&lag.lagged)
        .zip(lag.alpha.iter().zip(&lag.rate))
    {
        if flow.lag != LagCouple::None {
            *pending = lag_at((lagged, alpha0, rate0), elapsed, alpha, rate);
        }
    }
    let half_rho = 0.5 * law.air_density;
    for (((flow, tm), &alpha), &lagged) in flows
        .iter_mut()
        .zip(triangles)
        .zip(&lag.pending_alpha)
        .zip(&lag.pending_lagged)
    {
        let Some(tm) = tm.as_ref().filter(|_| flow.lag == LagCouple::Acts) else {
            continue;
        };
        let shift = law.pressure_lag_gain
            * flow.along_chord
            * (pressure_offset(lagged) - pressure_offset(alpha));
        let normal_force = half_rho * tm.area * law.cd_normal * flow.speed * flow.qn;
        // Offset −e s upstream of the force F n, along e = u∥/|u| (the
        // in-plane flow's direction times cos α): couple C = −s F e × n,
        // so n × C = −s F e. With the unit direction u∥/|u∥| instead, the
        // couple reversed in a jump whenever the in-plane flow passed
        // through zero (a plate rocking through face-on with α_L behind
        // α), and a 5 cm plate's fall converged erratically, its Verlet
        // error at 0.25 s 60× the smooth law's (docs/lab/real-falls.md,
        // "A couple without a jump").
        let along_flow = (flow.u - tm.n * flow.qn) / flow.speed;
        flow.lag_arm = along_flow * (-shift * normal_force);
    }
}

/// Records in `lag` the angle of attack at which the flow over each
/// triangle starts where it has none at the committed state (a release
/// from rest in still air): `acc` holds the particles' accelerations
/// there. The relative flow u is linear in the particles' velocities at
/// fixed positions (the corners' mean, less the plate's rotation), so
/// where they are all zero it grows as u(t) ≈ t L(a): its direction, and
/// so α(0⁺), is the flow's own formula read with the accelerations for
/// the velocities. Call after an evaluation at the committed time
/// ([`PressureLag::wants_start`]); still air only (in wind the flow's
/// start would need the wind's rate of change too, and a triangle falls
/// back to starting unlagged).
pub fn seed_flow_start(model: &Model, x: &[V3], acc: &[V3], torn: &[bool], lag: &mut PressureLag) {
    let AeroLaw::Unsteady(law) = &model.aero else {
        return;
    };
    SCRATCH.with_borrow_mut(|scratch| {
        scratch.measure(law, model, x, acc, None, torn);
        let Scratch {
            triangles, flows, ..
        } = scratch;
        for (t, (flow, tm)) in flows.iter().zip(triangles.iter()).enumerate() {
            let unmet = lag.lagged[t].is_nan() && lag.pending_alpha[t].is_nan();
            if unmet && tm.is_some() && flow.u2 > f64::MIN_POSITIVE {
                lag.start[t] = angle_of_attack(flow.qn, flow.u2.sqrt());
            }
        }
    });
}

/// What drag and translational lift remove from a triangle's velocity: its
/// plate's rotation about the plate's centre (area-weighted means over the
/// plate's intact triangles).
#[derive(Clone, Copy, Debug, Default)]
struct PlateMotion {
    area: f64,
    /// Σ A c, then the centre.
    centre: V3,
    /// Σ A ω, then the mean in-plane angular velocity n × ṅ.
    omega: V3,
}

/// One intact triangle's shape and turning, measured once per evaluation
/// and read by both passes ([`plate_motions`], [`per_triangle`]).
#[derive(Clone, Copy, Debug)]
struct TriangleMotion {
    /// N = e₁ × e₂ and |N|².
    big_n: V3,
    n2: f64,
    /// n = N/|N| and the area |N|/2.
    n: V3,
    area: f64,
    /// ṅ = (Ṅ − n (n·Ṅ))/|N|.
    n_dot: V3,
    /// x_a + x_b + x_c (three times the centroid).
    corner_sum: V3,
}

/// Per-thread scratch of [`unsteady_forces`], kept so that the step loop
/// does not allocate (tests/integration/alloc.rs) without widening the
/// force kernels' signatures.
#[derive(Default)]
struct Scratch {
    /// One per triangle; `None` for a torn or degenerate one.
    triangles: Vec<Option<TriangleMotion>>,
    plates: Vec<PlateMotion>,
    /// One per triangle, as `triangles`; read only where that is `Some`.
    flows: Vec<Flow>,
    /// One per plate, for the wake's couple (empty with it off).
    wake: Vec<WakeSums>,
}

impl Scratch {
    /// The first passes of an evaluation at (x, v): each triangle's shape
    /// and turning, each plate's motion, each triangle's relative flow.
    fn measure(
        &mut self,
        law: &UnsteadyAero,
        model: &Model,
        x: &[V3],
        v: &[V3],
        wind: Option<&[V3]>,
        torn: &[bool],
    ) {
        triangle_motions(model, x, v, torn, &mut self.triangles);
        plate_motions(law, model, &self.triangles, &mut self.plates);
        relative_flows(
            law,
            model,
            x,
            v,
            wind,
            &self.triangles,
            &self.plates,
            &mut self.flows,
        );
    }
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
}

/// Fills `out` with every triangle's [`TriangleMotion`] (`None` where
/// [`surface`] finds it torn or degenerate).
fn triangle_motions(
    model: &Model,
    x: &[V3],
    v: &[V3],
    torn: &[bool],
    out: &mut Vec<Option<TriangleMotion>>,
) {
    out.clear();
    out.extend(model.triangles.iter().enumerate().map(|(t, tri)| {
        let (big_n, n2) = surface(t, tri, x, torn)?;
        let [a, b, c] = tri.corners;
        let (e1, e2) = (x[b] - x[a], x[c] - x[a]);
        let doubled = n2.sqrt();
        // One division, then products: the law's kernel is bound by its
        // divider (perf), and six divisions by |N| cost five more than one.
        let inv_doubled = 1.0 / doubled;
        let n = big_n * inv_doubled;
        let n_dot_raw = (v[b] - v[a]).cross(&e2) + e1.cross(&(v[c] - v[a]));
        Some(TriangleMotion {
            big_n,
            n2,
            n,
            area: 0.5 * doubled,
            n_dot: (n_dot_raw - n * n.dot(&n_dot_raw)) * inv_doubled,
            corner_sum: x[a] + x[b] + x[c],
        })
    }));
}

/// Adds the wake's couple (module docs, "Wake") on every plate of `model` to
/// `force`, from the evaluation's triangle motions, plate motions (area and
/// centre, [`plate_motions`]) and flows, and records each plate's rate in
/// `lag`.
#[allow(clippy::too_many_arguments)]
fn wake_couples(
    law: &UnsteadyAero,
    model: &Model,
    x: &[V3],
    triangles: &[Option<TriangleMotion>],
    plates: &[PlateMotion],
    flows: &[Flow],
    lag: &mut PressureLag,
    sums: &mut Vec<WakeSums>,
    force: &mut [V3],
) {
    lag.evaluated = true;
    let elapsed = lag.elapsed;
    sums.clear();
    sums.resize(lag.wake.len(), WakeSums::default());
    for ((tm, flow), (geom, tri)) in triangles
        .iter()
        .zip(flows)
        .zip(model.surfaces.iter().zip(&model.triangles))
    {
        let Some(tm) = tm else {
            continue;
        };
        let sum = &mut sums[geom.plate];
        sum.speed += tm.area * flow.speed;
        if sum.axis.is_none() {
            let [a, b, _] = tri.corners;
            sum.axis = Some((x[b] - x[a]).normalize());
        }
    }
    // Each plate's pressure scale ½ ρ U² sin φ / c at this evaluation.
    for ((sum, w), p) in sums.iter_mut().zip(lag.wake.iter_mut()).zip(plates) {
        if p.area <= 0.0 || w.chord <= 0.0 {
            continue;
        }
        let u = sum.speed / p.area;
        let rate = std::f64::consts::TAU * law.wake_strouhal * u / w.chord;
        w.pending = rate;
        let phase = w.phase_at(elapsed, rate);
        sum.scale = law.wake_couple * 0.5 * law.air_density * u * u * phase.sin() / w.chord;
    }
    for ((tm, flow), (geom, tri)) in triangles
        .iter()
        .zip(flows)
        .zip(model.surfaces.iter().zip(&model.triangles))
    {
        let sum = &sums[geom.plate];
        let (Some(tm), Some(e)) = (tm, sum.axis) else {
            continue;
        };
        if flow.u2 <= f64::MIN_POSITIVE {
            continue;
        }
        let sin2 = flow.qn * flow.qn / flow.u2;
        let d = (tm.corner_sum / 3.0 - plates[geom.plate].centre).dot(&e);
        let f = tm.n * (sum.scale * sin2 * sin2 * tm.area * d / 3.0);
        for &i in &tri.corners {
            force[i] += f;
        }
    }
}

/// One plate's sums for [`wake_couples`]: Σ A |u|, its axis, and its
/// pressure scale ½ ρ U² sin φ / c times C_W.
#[derive(Clone, Copy, Debug, Default)]
struct WakeSums {
    speed: f64,
    axis: Option<V3>,
    scale: f64,
}

/// Fills `plates` with each plate's [`PlateMotion`]; left empty when no
/// term reads them: the law keeps the whole rotation in drag
/// (`rotation_drag = 1`) and has no wake.
fn plate_motions(
    law: &UnsteadyAero,
    model: &Model,
    triangles: &[Option<TriangleMotion>],
    plates: &mut Vec<PlateMotion>,
) {
    plates.clear();
    if law.rotation_drag >= 1.0 && law.wake_couple <= 0.0 {
        return;
    }
    plates.resize(model.plate_count(), PlateMotion::default());
    for (tm, geom) in triangles.iter().zip(&model.surfaces) {
        let Some(tm) = tm else {
            continue;
        };
        let p = &mut plates[geom.plate];
        p.area += tm.area;
        p.centre += tm.corner_sum * (tm.area / 3.0);
        p.omega += tm.n.cross(&tm.n_dot) * tm.area;
    }
    for p in plates.iter_mut().filter(|p| p.area > 0.0) {
        p.centre /= p.area;
        p.omega /= p.area;
    }
}

/// The air's flow over one intact triangle, in the two passes that precede
/// [`per_triangle`]: [`relative_flows`] fills the vectors and the
/// projections the chord look-ups read, [`flow_coefficients`] the square
/// roots, chords and quotients. They are apart so that the look-ups and
/// their chains of divisions and square roots, a third of the law's time
/// when each waited for its own triangle's (perf), run back to back over
/// all triangles and overlap. Every value is the expression the single
/// pass computed, in the same order, so the forces keep their bits.
#[derive(Clone, Copy, Debug, Default)]
struct Flow {
    /// The dual basis ∇β_b, ∇β_c of the corners.
    grad_b: V3,
    grad_c: V3,
    /// The air's velocity relative to the triangle (module docs), |u|² and
    /// its normal part u·n.
    u: V3,
    u2: f64,
    qn: f64,
    /// |u∥|² and u∥ on ∇β_b, ∇β_c (the chord along the flow).
    along2: f64,
    along_on: [f64; 2],
    /// ω = n × ṅ, |ω|², n × ω, and both on ∇β_b, ∇β_c (the chord across
    /// the rotation axis and the span along it).
    omega: V3,
    w2: f64,
    across: V3,
    across_on: [f64; 2],
    omega_on: [f64; 2],
    /// Then: |u|, the chord along u∥ (0 with no in-plane flow), C_D∥ (with
    /// skin friction), the chord across the axis and the finite-span
    /// factor.
    speed: f64,
    along_chord: f64,
    cd_par: f64,
    chord: f64,
    finite: f64,
    /// The lagged centre of pressure's share of the couples' in-plane arm
    /// (n × C; zero without the term), added with the Munk couple's.
    lag_arm: V3,
    /// What the lag does on the triangle in this evaluation.
    lag: LagCouple,
}

/// Whether the law's rotational terms act on a triangle turning at |ω|² =
/// `w2`.
#[inline]
fn turning(law: &UnsteadyAero, w2: f64) -> bool {
    w2 > f64::MIN_POSITIVE && (law.rotational_lift != 0.0 || damped(law))
}

/// Whether the law damps rotation at all.
#[inline]
fn damped(law: &UnsteadyAero) -> bool {
    law.rotational_damping != 0.0 || law.rotational_damping_quadratic != 0.0
}

/// First pass of the per-triangle terms: each intact triangle's [`Flow`]
/// vectors and projections.
#[allow(clippy::too_many_arguments)]
fn relative_flows(
    law: &UnsteadyAero,
    model: &Model,
    x: &[V3],
    v: &[V3],
    wind: Option<&[V3]>,
    triangles: &[Option<TriangleMotion>],
    plates: &[PlateMotion],
    flows: &mut Vec<Flow>,
) {
    let third = 1.0 / 3.0;
    flows.resize(triangles.len(), Flow::default());
    for (((tri, tm), geom), flow) in model
        .triangles
        .iter()
        .zip(triangles)
        .zip(&model.surfaces)
        .zip(flows.iter_mut())
    {
        let Some(tm) = tm else {
            continue;
        };
        let TriangleMotion {
            big_n,
            n2,
            n,
            n_dot,
            corner_sum,
            ..
        } = *tm;
        let [a, b, c] = tri.corners;
        let (e1, e2) = (x[b] - x[a], x[c] - x[a]);
        let w = corner_velocities(tri.corners, v, wind);
        let inv_n2 = 1.0 / n2;
        let grad_b = e2.cross(&big_n) * inv_n2;
        let grad_c = big_n.cross(&e1) * inv_n2;
        // Less the share (1 − rotation_drag) of what the plate's rotation
        // gives the triangle.
        let mut u = -(w[0] + w[1] + w[2]) * third;
        if let Some(p) = plates
            .get(geom.plate)
            .filter(|p| p.area > 0.0 && law.rotation_drag < 1.0)
        {
            let r = corner_sum * third - p.centre;
            u += p.omega.cross(&r) * (1.0 - law.rotation_drag);
        }
        let u2 = u.norm_squared();
        let qn = u.dot(&n);
        let u_plane = u - n * qn;
        let omega = n.cross(&n_dot);
        // Directions for `chord` unnormalised: it reads only their direction.
        let across = n.cross(&omega);
        *flow = Flow {
            grad_b,
            grad_c,
            u,
            u2,
            qn,
            along2: u_plane.norm_squared(),
            along_on: [u_plane.dot(&grad_b), u_plane.dot(&grad_c)],
            omega,
            w2: omega.norm_squared(),
            across,
            across_on: [across.dot(&grad_b), across.dot(&grad_c)],
            omega_on: [omega.dot(&grad_b), omega.dot(&grad_c)],
            ..Flow::default()
        };
    }
}

/// Second pass: each intact triangle's square roots, chord look-ups and
/// the coefficients they give ([`Flow`]).
fn flow_coefficients(law: &UnsteadyAero, model: &Model, flows: &mut [Flow]) {
    for (flow, geom) in flows.iter_mut().zip(&model.surfaces) {
        flow.speed = flow.u2.sqrt();
        let along = flow.along2.sqrt();
        // `chord` reads a direction, whatever its length: no division.
        (flow.along_chord, flow.cd_par) = if along > 0.0 {
            let chord = geom.chord(flow.along_on[0], flow.along_on[1]);
            (chord, cd_parallel(law, along, chord))
        } else {
            (0.0, law.cd_parallel)
        };
    }
    for (flow, geom) in flows.iter_mut().zip(&model.surfaces) {
        if turning(law, flow.w2) {
            flow.chord = geom.chord(flow.across_on[0], flow.across_on[1]);
            if law.rotational_lift != 0.0 {
                // A plate of finite span s along the axis sheds tip
                // vortices: Prandtl's lifting line scales a wing's
                // circulation by AR/(AR + 2), AR = s/c (→ 1 in 2-D).
                let span = geom.chord(flow.omega_on[0], flow.omega_on[1]);
                flow.finite = span / (span + 2.0 * flow.chord);
            }
        }
    }
}

/// Each corner's velocity relative to the air (`wind` at the particles, or
/// still air).
#[inline(always)]
fn corner_velocities(corners: [usize; 3], v: &[V3], wind: Option<&[V3]>) -> [V3; 3] {
    let [a, b, c] = corners;
    match wind {
        Some(g) => [v[a] - g[a], v[b] - g[b], v[c] - g[c]],
        None => [v[a], v[b], v[c]],
    }
}

/// The per-triangle terms of [`unsteady_forces`], from each intact
/// triangle's [`Flow`].
#[allow(clippy::too_many_arguments)]
fn per_triangle(
    law: &UnsteadyAero,
    model: &Model,
    v: &[V3],
    wind: Option<&[V3]>,
    triangles: &[Option<TriangleMotion>],
    flows: &[Flow],
    force: &mut [V3],
    added: &mut [Matrix3<f64>],
) {
    let rho = law.air_density;
    let half_rho = 0.5 * rho;
    let rho_added = rho * law.added_mass;
    let third = 1.0 / 3.0;
    let half_pi_rho = std::f64::consts::FRAC_PI_2 * rho;
    let damped = damped(law);
    for (((tri, tm), geom), flow) in model
        .triangles
        .iter()
        .zip(triangles)
        .zip(&model.surfaces)
        .zip(flows)
    {
        let Some(tm) = tm else {
            continue;
        };
        let geom: &SurfaceGeometry = geom;
        let TriangleMotion { n, area, n_dot, .. } = *tm;
        let Flow {
            grad_b,
            grad_c,
            u,
            u2,
            qn,
            omega,
            w2,
            across,
            speed,
            cd_par,
            chord,
            finite,
            ..
        } = *flow;
        let corners = tri.corners;
        let w = corner_velocities(corners, v, wind);
        let grads = [-(grad_b + grad_c), grad_b, grad_c];
        let mut f = [V3::zeros(); 3];
        // In-plane vector whose projection on the corner gradients gives
        // the normal forces of the triangle's couples (n × C).
        let mut couple_arm = flow.lag_arm;

        if rho_added > 0.0 {
            let mut q = V3::zeros();
            for k in 0..3 {
                let m = rho_added * geom.added_mass[k];
                let wn = n.dot(&w[k]);
                f[k] -= (n * n_dot.dot(&w[k]) + n_dot * wn) * m;
                q += w[k] * (m * wn);
            }
            // Munk couple C = −Q × n: n × C = −Q∥; relieved near
            // broadside where the flow has separated (module docs, "Munk
            // relief").
            let munk = q - n * n.dot(&q);
            if law.munk_relief > 0.0 && u2 > f64::MIN_POSITIVE {
                let sin2 = qn * qn / u2;
                couple_arm -= munk * (1.0 - law.munk_relief * sin2 * sin2 * sin2);
            } else {
                couple_arm -= munk;
            }
        }

        if u2 > f64::MIN_POSITIVE {
            let k_normal = law.cd_normal - cd_par - 2.0 * law.translational_lift;
            let drag = (u * (cd_par + k_normal * qn * qn / u2)
                + n * (2.0 * law.translational_lift * qn))
                * (half_rho * area * speed * third);
            for fk in &mut f {
                *fk += drag;
            }
        }

        if turning(law, w2) {
            if law.rotational_lift != 0.0 {
                let lift = u.cross(&omega)
                    * (half_rho * law.rotational_lift * finite * chord * area * third);
                for fk in &mut f {
                    *fk += lift;
                }
            }
            if damped {
                // τ = −(π/2) ρ A a² (μ₁|u| + μ₂ a |ω|) ω, a = c/2: n × τ.
                let half = 0.5 * chord;
                let quadratic = if law.rotational_damping_quadratic != 0.0 {
                    law.rotational_damping_quadratic * half * w2.sqrt()
                } else {
                    0.0
                };
                let rate =
                    half_pi_rho * area * half * half * (law.rotational_damping * speed + quadratic);
                couple_arm -= across * rate;
            }
        }

        for k in 0..3 {
            force[corners[k]] += f[k] + n * grads[k].dot(&couple_arm);
        }
    }
    // The added-mass tensors in a pass of their own (the same sums in the
    // same order): interleaved with the forces, the read-modify-write of
    // each corner's 3 × 3 tensor stalled the loop (perf).
    if rho_added > 0.0 && !added.is_empty() {
        added_mass_tensors(rho_added, model, triangles, added);
    }
}

/// Adds each intact triangle's m_k n nᵀ to its corners' tensors in `added`
/// (m_k its corner's share of the plate's added mass times `rho_added`).
fn added_mass_tensors(
    rho_added: f64,
    model: &Model,
    triangles: &[Option<TriangleMotion>],
    added: &mut [Matrix3<f64>],
) {
    for ((tri, tm), geom) in model.triangles.iter().zip(triangles).zip(&model.surfaces) {
        let Some(tm) = tm else {
            continue;
        };
        let nn = tm.n * tm.n.transpose();
        for (&i, &share) in tri.corners.iter().zip(&geom.added_mass) {
            added[i] += nn * (rho_added * share);
        }
    }
}

/// The flow's kinetic energy T = ½ Σ m_k (n·w_k)² of every intact triangle's
/// added mass, J (w relative to `wind`, or to still air): with the body's
/// own kinetic energy, what the added-mass forces conserve.
pub fn added_mass_energy(model: &Model, x: &[V3], v: &[V3], wind: Option<&[V3]>) -> f64 {
    let AeroLaw::Unsteady(law) = &model.aero else {
        return 0.0;
    };
    let rho_added = law.air_density * law.added_mass;
    let mut energy = 0.0;
    for (t, tri) in model.triangles.iter().enumerate() {
        let Some((big_n, n2)) = surface(t, tri, x, &[]) else {
            continue;
        };
        let n = big_n / n2.sqrt();
        for (k, &i) in tri.corners.iter().enumerate() {
            let w = match wind {
                Some(g) => v[i] - g[i],
                None => v[i],
            };
            energy += 0.5 * rho_added * model.surfaces[t].added_mass[k] * n.dot(&w).powi(2);
        }
    }
    energy
}

/// The plate's added mass at rest per plate (the sum of its corners'
/// shares, times ρ and the law's factor), kg, in the order of
/// [`crate::physics::model::plates`]; empty under the other laws.
pub fn plate_added_masses(model: &Model) -> Vec<f64> {
    let AeroLaw::Unsteady(law) = &model.aero else {
        return Vec::new();
    };
    let corners: Vec<[usize; 3]> = model.triangles.iter().map(|t| t.corners).collect();
    crate::physics::model::plates(&corners)
        .iter()
        .map(|plate| {
            plate
                .iter()
                .map(|&t| model.surfaces[t].added_mass.iter().sum::<f64>())
                .sum::<f64>()
                * law.air_density
                * law.added_mass
        })
        .collect()
}
