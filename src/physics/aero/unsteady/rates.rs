//! The unsteady law's rates for the stability estimate and `--dt auto`:
//! the fastest steady falls that bound the air speed, and the rate at
//! which the law's velocity-dependent forces act, measured on the free
//! particles and on each rigid body ([`drag_rate`]).

use super::coefficients::UnsteadyAero;
use super::triangle_forces::{SPEED_MARGIN, V3, cd_parallel, unsteady_forces};
use crate::physics::aero::law::AeroLaw;
use crate::physics::model::{Model, SurfaceGeometry};
use nalgebra::Matrix3;
use std::ops::AddAssign;

/// Fastest steady fall of `model` under `law`: edge-on, its weight carried
/// by in-plane drag alone, M g = ½ ρ A C_D∥(V) V², on the longest chord of
/// any triangle (the least skin friction), m/s.
pub fn edge_on_speed(law: &UnsteadyAero, model: &Model) -> f64 {
    let area = model.surface_area();
    if area <= 0.0 {
        return 0.0;
    }
    let chord = model
        .surfaces
        .iter()
        .flat_map(|g| g.chords.iter().copied())
        .fold(0.0, f64::max);
    let weight = model.total_mass() * model.gravity.norm();
    let drag =
        |speed: f64| 0.5 * law.air_density * area * cd_parallel(law, speed, chord) * speed * speed;
    // Drag grows without bound with speed (at least as V^1.5): bisect.
    let (mut lo, mut hi) = (0.0, 1.0);
    while drag(hi) < weight && hi < 1e6 {
        hi *= 2.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if drag(mid) < weight {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// Per-triangle bounds shared by the particle and rigid-body rates, at
/// relative speed `v_ref` and rotation rate `omega_ref` (module docs for
/// the terms).
struct TriangleBounds {
    /// ‖∂F/∂u‖ of drag, translational lift and skin friction, N·s/m.
    drag: f64,
    /// Rotational lift ½ρ C_R c A: multiplies (ω, |u|) in its derivatives.
    rot_lift: f64,
    /// Rotational damping (π/2) ρ A a²: its couple's scale, with a = c/2.
    damping: f64,
    /// a = half the longest chord, m.
    half_chord: f64,
    /// Each corner's added mass, kg.
    added: [f64; 3],
}

fn triangle_bounds(
    law: &UnsteadyAero,
    geom: &SurfaceGeometry,
    area: f64,
    u_ref: f64,
    q_ref: f64,
) -> TriangleBounds {
    let rho = law.air_density;
    let chord_max = geom.chords.iter().copied().fold(0.0, f64::max);
    let chord_min = geom
        .chords
        .iter()
        .copied()
        .filter(|&c| c > 0.0)
        .fold(f64::INFINITY, f64::min)
        .min(chord_max)
        .max(1e-12);
    // F = ½ρA [C_D∥ |u| u + k q² u/|u| + 2 C_T |u| q n], k = C_D⊥ − C_D∥ − 2C_T:
    // ‖∂‖ ≤ ½ρA [(2 C_D∥ + 1.5 C_f) |u| + 4 |k| |q| + 2 C_T (|u| + |q|)]
    // (skin friction C_f ∝ |u|^−½, so its force grows as |u|^1.5), with
    // |u| ≤ u_ref and the normal part |q| ≤ q_ref.
    let cf = cd_parallel(law, u_ref, chord_min) - law.cd_parallel;
    let k = (law.cd_normal - law.cd_parallel - 2.0 * law.translational_lift).abs() + cf;
    TriangleBounds {
        drag: 0.5
            * rho
            * area
            * ((2.0 * law.cd_parallel + 1.5 * cf) * u_ref
                + 4.0 * k * q_ref
                + 2.0 * law.translational_lift * (u_ref + q_ref)),
        rot_lift: 0.5 * rho * law.rotational_lift * chord_max * area,
        damping: std::f64::consts::FRAC_PI_2 * rho * area * (0.5 * chord_max).powi(2),
        half_chord: 0.5 * chord_max,
        added: std::array::from_fn(|k| rho * law.added_mass * geom.added_mass[k]),
    }
}

/// Fastest rate at which a plate of `model` can tumble, 1/s (0 under the
/// other laws): Ω = 2 U / c with U the [`face_on_speed`] and c the
/// narrowest plate's width (the largest, over its triangles, of the
/// shortest chord through a triangle's centroid: a strip's width, a
/// square's side, a disk's diameter). A tumbling plate's edges move at
/// about its fall speed or slower (Ω c/2 ≲ U; Mahadevan, Ryu & Samuel
/// 1999): measured at the defaults, real and simulated squares turn at
/// 0.6–0.7 of it and a narrow heavy strip at 0.2 (docs/lab/real-falls.md), so this is a bound,
/// not an estimate.
pub fn tumbling_rate(model: &Model) -> f64 {
    let AeroLaw::Unsteady(law) = &model.aero else {
        return 0.0;
    };
    let mut width = vec![0.0f64; model.plate_count()];
    for g in &model.surfaces {
        let shortest = g
            .chords
            .iter()
            .copied()
            .filter(|&c| c > 0.0)
            .fold(f64::INFINITY, f64::min);
        if shortest.is_finite() {
            width[g.plate] = width[g.plate].max(shortest);
        }
    }
    let narrowest = width
        .into_iter()
        .filter(|&w| w > 0.0)
        .fold(f64::INFINITY, f64::min);
    if narrowest.is_finite() {
        2.0 * face_on_speed(law, model) / narrowest
    } else {
        0.0
    }
}

/// Fastest face-on fall of `model` under `law`, M g = ½ ρ A C_D⊥ V², m/s:
/// what bounds the normal part of the air's relative velocity.
pub fn face_on_speed(law: &UnsteadyAero, model: &Model) -> f64 {
    let area = model.surface_area();
    if area <= 0.0 {
        return 0.0;
    }
    (2.0 * model.total_mass() * model.gravity.norm() / (law.air_density * area * law.cd_normal))
        .sqrt()
}

/// Largest rate of the explicit part of the unsteady law, 1/s (0 under the
/// other laws): a Gershgorin bound at the rest shape, every relative speed
/// up to v_ref = wind bound + [`SPEED_MARGIN`] × [`edge_on_speed`].
///
/// - A particle of no rigid body: ‖(m_i I + M_i)⁻¹ Σⱼ ∂f_i/∂v_j‖, term by
///   term with every corner moving independently (|ṅ| ≤ v_ref Σ 1/h_j);
///   forces along a triangle's normal are divided by the particle's
///   effective mass along it, |(m I + M)⁻¹ n| (M its rest added-mass
///   tensor, which a rigid motion only turns), in-plane ones by m — the
///   added mass these terms scale with also slows the particle they push,
///   so a very light leaf's rate stays bounded.
/// - A rigid body: its members cannot move apart, so corner-by-corner
///   bounds would be far too pessimistic (a fine plate's triangles are
///   small, its rotation slow); its rate is measured instead
///   ([`rigid_body_rate`]).
///
/// The normal part of any triangle's relative velocity is bounded by
/// q_ref = wind bound + [`SPEED_MARGIN`] × [`face_on_speed`]: faster, the
/// face-on drag exceeds the weight several times and brakes it within
/// V/g (a test measures it in falls of plates and the recipes).
pub fn drag_rate(model: &Model) -> f64 {
    let (particles, bodies) = drag_rate_parts(model);
    particles.max(bodies)
}

/// Each particle's added-mass tensor M_i = Σ m_k n nᵀ at the rest shape
/// (the sum over the triangles at it, m_k its corner's share times ρ and
/// the law's factor), kg: what [`crate::physics::forces::Forces::acceleration`] solves with
/// at a shape where every triangle lies as at rest.
pub fn rest_added_mass_tensors(law: &UnsteadyAero, model: &Model) -> Vec<Matrix3<f64>> {
    let x = &model.rest_position;
    let mut tensor = vec![Matrix3::<f64>::zeros(); model.len()];
    for (t, tri) in model.triangles.iter().enumerate() {
        let [a, b, c] = tri.corners;
        let nrm = (x[b] - x[a]).cross(&(x[c] - x[a])).normalize();
        for (k, &i) in tri.corners.iter().enumerate() {
            tensor[i] += nrm
                * nrm.transpose()
                * (law.air_density * law.added_mass * model.surfaces[t].added_mass[k]);
        }
    }
    tensor
}

/// [`drag_rate`] split: (free particles, rigid bodies).
pub fn drag_rate_parts(model: &Model) -> (f64, f64) {
    let AeroLaw::Unsteady(law) = &model.aero else {
        return (0.0, 0.0);
    };
    let wind = model.wind.speed_bound();
    let v_ref = wind + SPEED_MARGIN * edge_on_speed(law, model);
    let q_ref = wind + SPEED_MARGIN * face_on_speed(law, model);
    let x = &model.rest_position;
    let n = model.len();
    let body_of = model.body_of();
    let tensor = rest_added_mass_tensors(law, model);
    let mut normal_rate = vec![0.0; n];
    let mut plane_rate = vec![0.0; n];
    for (t, tri) in model.triangles.iter().enumerate() {
        let geom = &model.surfaces[t];
        let [a, b, c] = tri.corners;
        let big_n = (x[b] - x[a]).cross(&(x[c] - x[a]));
        let doubled = big_n.norm();
        let nrm = big_n / doubled;
        let area = 0.5 * doubled;
        let tb = triangle_bounds(law, geom, area, v_ref, q_ref);
        let m_sum: f64 = tb.added.iter().sum();
        let rigid = tri
            .corners
            .iter()
            .map(|&i| body_of[i])
            .reduce(|p, q| if p == q { p } else { None })
            .flatten();
        if rigid.is_some() {
            continue;
        }
        let heights: [f64; 3] = std::array::from_fn(|k| {
            let (j, l) = (tri.corners[(k + 1) % 3], tri.corners[(k + 2) % 3]);
            doubled / (x[l] - x[j]).norm()
        });
        let s: f64 = heights.iter().map(|h| 1.0 / h).sum();
        // |ṅ| ≤ Σⱼ |n·w_j|/h_j with every corner at v_ref.
        let omega_ref = v_ref * s;
        // A third of drag and rotational lift on each corner, each corner
        // velocity a third of u: summed over the corners, a third of the
        // triangle's rate.
        let drag = tb.drag / 3.0;
        let rot_lift = tb.rot_lift * (omega_ref + v_ref * s) / 3.0;
        let tau = tb.damping
            * (law.rotational_damping * (omega_ref + v_ref * s)
                + 2.0 * law.rotational_damping_quadratic * tb.half_chord * omega_ref * s);
        for (k, &i) in tri.corners.iter().enumerate() {
            let h = heights[k];
            // −m_k (ṅ·w_k) n (normal) and −m_k (n·w_k) ṅ (in-plane), each
            // ≤ m_k (v_ref s + ω_ref); the Munk couple's λ_k = ∇β_k·Q∥ with
            // ‖∂Q/∂w_j‖ ≤ 2 m_j v_ref.
            let gyro = tb.added[k] * (v_ref * s + omega_ref);
            let munk = 2.0 * v_ref * m_sum / h;
            let along_n = (model.mass[i] * Matrix3::identity() + tensor[i])
                .try_inverse()
                .map_or(1.0 / model.mass[i], |inv| (inv * nrm).norm());
            normal_rate[i] += (gyro + munk + tau / h) * along_n;
            plane_rate[i] += (gyro + drag + rot_lift) / model.mass[i];
        }
    }
    let bound = (0..n)
        .filter(|&i| !model.fixed[i] && body_of[i].is_none())
        .map(|i| normal_rate[i] + plane_rate[i])
        .fold(0.0, f64::max);
    let particles = if bound > 0.0 {
        let free: Vec<bool> = (0..n)
            .map(|i| !model.fixed[i] && body_of[i].is_none())
            .collect();
        bound.min(MEASURED_MARGIN * free_particle_rate(law, model, &free, &tensor, v_ref, q_ref))
    } else {
        bound
    };
    let index = PlateIndex::of(model);
    let bodies = (0..model.rigid.len())
        .map(|b| body_rate(law, &body_alone(model, &index, b), v_ref, q_ref))
        .fold(0.0, f64::max);
    (particles, bodies)
}

/// Factor on the measured rate of the free particles ([`free_particle_rate`])
/// before it replaces the corner-by-corner bound: the measurement samples
/// states, so it is kept with a margin.
pub const MEASURED_MARGIN: f64 = 1.5;

/// Power iterations per sampled state in [`free_particle_rate`]. On
/// prototype A the largest rate after 12 agrees with 24 to 1e-4 (168.88
/// against 168.89 1/s). Complex pairs settle slowly elsewhere: over the
/// recipes' 120 variants (40 of each, under this law) the rate after 12
/// lies within 0.92–1.07 of the rate after 32 (rms 2 %; after 8,
/// 0.91–1.21, and 2 of the 120 auto steps change), well inside the
/// [`MEASURED_MARGIN`] the estimate keeps on top.
const POWER_ITERATIONS: usize = 12;

/// The rate of the free particles (`free[i]`) under the unsteady law, 1/s:
/// the spectral radius of K⁻¹ ∂f/∂v (K_i = m_i I + M_i, the rest
/// added-mass tensors `tensor`), by power iteration on forward-difference
/// products ∂f/∂v · y at the rest shape (relative error about 1e-6, the
/// step's, against a margin of 1.5; central differences cost twice), for the relative velocities of
/// [`rigid_body_rate`] (speeds q_ref and v_ref along nine directions of the
/// leaf's best-fit frame, with and without a rotation of rate
/// 2 v_ref / (its extent across that axis) about each in-plane axis,
/// `tumbling_rates`). The corner-by-corner bound
/// of [`drag_rate`] lets every corner move independently at v_ref and is
/// far above what a leaf's motion reaches (60× on prototype A); this is a
/// measurement, not a bound, which `--dt auto` keeps with
/// [`MEASURED_MARGIN`] and its safety factor, and a test checks drops at
/// the auto step against half of it.
pub fn free_particle_rate(
    law: &UnsteadyAero,
    model: &Model,
    free: &[bool],
    tensor: &[Matrix3<f64>],
    v_ref: f64,
    q_ref: f64,
) -> f64 {
    let x = &model.rest_position;
    let n = model.len();
    let members: Vec<usize> = (0..n).filter(|&i| free[i]).collect();
    if members.is_empty() {
        return 0.0;
    }
    let centre = members.iter().map(|&i| x[i]).sum::<V3>() / members.len() as f64;
    let mut cov = Matrix3::zeros();
    for &i in &members {
        let r = x[i] - centre;
        cov += r * r.transpose();
    }
    let eig = cov.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    // Largest spread first: the normal (least spread) is axes[2].
    order.sort_by(|&p, &q| eig.eigenvalues[q].total_cmp(&eig.eigenvalues[p]));
    let axes: [V3; 3] = order.map(|k| eig.eigenvectors.column(k).into());
    let omega_ref = tumbling_rates(&axes, members.iter().map(|&i| x[i]), v_ref);
    let inverse: Vec<Matrix3<f64>> = (0..n)
        .map(|i| {
            (Matrix3::identity() * model.mass[i] + tensor[i])
                .try_inverse()
                .unwrap_or_else(Matrix3::zeros)
        })
        .collect();
    let mut f_plus = vec![V3::zeros(); n];
    let mut f_base = vec![V3::zeros(); n];
    let mut v = vec![V3::zeros(); n];
    let mut worst: f64 = 0.0;
    for (vel, spin) in sampled_motions(&axes, v_ref, q_ref, omega_ref) {
        let base: Vec<V3> = (0..n).map(|i| vel + spin.cross(&(x[i] - centre))).collect();
        f_base.fill(V3::zeros());
        unsteady_forces(law, model, x, &base, None, &[], &mut f_base, &mut [], None);
        // A deterministic start with every component.
        let mut y: Vec<V3> = (0..n)
            .map(|i| {
                if free[i] {
                    let k = i as f64;
                    V3::new(1.0 + 0.37 * k, -0.6 + 0.11 * k, 0.8 - 0.23 * k)
                } else {
                    V3::zeros()
                }
            })
            .collect();
        let norm = |y: &[V3]| y.iter().map(|a| a.norm_squared()).sum::<f64>().sqrt();
        let mut log_growth = Vec::with_capacity(POWER_ITERATIONS);
        for _ in 0..POWER_ITERATIONS {
            let size = norm(&y);
            if size <= 0.0 || !size.is_finite() {
                break;
            }
            let eps = 1e-6 * v_ref.max(1e-9) / size;
            for i in 0..n {
                v[i] = base[i] + y[i] * eps;
            }
            f_plus.fill(V3::zeros());
            unsteady_forces(law, model, x, &v, None, &[], &mut f_plus, &mut [], None);
            for i in 0..n {
                y[i] = if free[i] {
                    inverse[i] * (f_plus[i] - f_base[i]) / eps
                } else {
                    V3::zeros()
                };
            }
            log_growth.push((norm(&y) / size).ln());
        }
        // The mean growth over the second half: the spectral radius
        // (a complex pair makes single ratios oscillate).
        let tail = &log_growth[log_growth.len() / 2..];
        if !tail.is_empty() {
            let rate = (tail.iter().sum::<f64>() / tail.len() as f64).exp();
            if rate.is_finite() {
                worst = worst.max(rate);
            }
        }
    }
    worst
}

/// The rates 2 v_ref / c at which a plate tumbling about `axes[0]` and
/// about `axes[1]` turns, c the extent of `points` across that axis (along
/// the other in-plane axis): a tumbling plate's edges move at about its
/// fall speed (Ω ≈ 2U/c; Mahadevan, Ryu & Samuel 1999), so a strip turns
/// about its long axis at 2 v_ref over its width, not over its length.
fn tumbling_rates(
    axes: &[V3; 3],
    points: impl Iterator<Item = V3> + Clone,
    v_ref: f64,
) -> [f64; 2] {
    let extent = |a: &V3| {
        let (lo, hi) = points
            .clone()
            .map(|p| p.dot(a))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
                (lo.min(d), hi.max(d))
            });
        (hi - lo).max(f64::MIN_POSITIVE)
    };
    [
        2.0 * v_ref / extent(&axes[1]),
        2.0 * v_ref / extent(&axes[0]),
    ]
}

/// The relative motions at which the measured rates are taken: a velocity
/// of speed q_ref or v_ref along each of [`RATE_DIRECTIONS`] (in the frame
/// `axes`, its normal part along `axes[2]` capped at q_ref, as in a fall),
/// each without rotation and with rate `omega_ref` about either in-plane axis.
/// A motion that capping makes equal to one already listed (along the
/// normal, v_ref capped is q_ref) is listed once: the rate is a maximum
/// over them, and each costs a dozen force evaluations.
fn sampled_motions(axes: &[V3; 3], v_ref: f64, q_ref: f64, omega_ref: [f64; 2]) -> Vec<(V3, V3)> {
    let to_world = |d: [f64; 3]| axes[0] * d[0] + axes[1] * d[1] + axes[2] * d[2];
    let mut motions = Vec::with_capacity(RATE_DIRECTIONS.len() * 6);
    for d in RATE_DIRECTIONS {
        let dir = to_world(d).normalize();
        for speed in [q_ref, v_ref] {
            let mut vel = dir * speed;
            let normal = vel.dot(&axes[2]);
            if normal.abs() > q_ref {
                vel -= axes[2] * (normal - q_ref * normal.signum());
            }
            for spin in [V3::zeros(), axes[0] * omega_ref[0], axes[1] * omega_ref[1]] {
                if !motions.contains(&(vel, spin)) {
                    motions.push((vel, spin));
                }
            }
        }
    }
    motions
}

/// Directions of the relative velocity, in the body frame of the rest
/// shape, at which [`rigid_body_rate`] measures: along each axis and the
/// diagonals between the plate's plane and its normal.
const RATE_DIRECTIONS: [[f64; 3]; 9] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, 1.0, -1.0],
    [1.0, 1.0, 1.0],
    [1.0, -1.0, 0.3],
];

/// The rate of rigid body `b` under the unsteady law, 1/s: the largest
/// |eigenvalue| of M_g⁻¹ ∂(F, τ)/∂(V, ω), with M_g the body's generalised
/// mass (its own and added, the 6 × 6 of [`crate::physics::rigid`]),
/// measured by forward differences at the rest shape for relative speeds
/// |V| ∈ {q_ref, v_ref} along nine directions (the normal part of
/// the larger capped at q_ref, as in a fall: see [`drag_rate`]), each with
/// and without a rotation of rate 2 v_ref / (the body's extent across that
/// axis) about each in-plane axis (`tumbling_rates`).
/// A measurement at sampled states, not a bound; `--dt auto` keeps
/// [`crate::physics::stability::AUTO_SAFETY`] below it and a test checks
/// drops at the auto step against half of it.
pub fn rigid_body_rate(law: &UnsteadyAero, model: &Model, b: usize, v_ref: f64, q_ref: f64) -> f64 {
    // Each of the hundreds of force evaluations below would otherwise
    // measure every triangle of the model, when only the body's plates act
    // on its members: a scene of N plates paid N² (400 rigid 5 cm squares
    // did not finish `scene --explain` in 10 minutes).
    let alone = body_alone(model, &PlateIndex::of(model), b);
    body_rate(law, &alone, v_ref, q_ref)
}

/// The triangles that touch each particle and the triangles of each plate,
/// built once per model so that taking each rigid body out alone
/// ([`body_alone`]) costs the body's size, not the model's: a scene of N
/// plates would otherwise pay N² again, in bookkeeping.
struct PlateIndex {
    /// `touching[i]`: the triangles with particle i as a corner.
    touching: Vec<Vec<usize>>,
    /// `plate_triangles[p]`: plate p's triangles, in the model's order.
    plate_triangles: Vec<Vec<usize>>,
}

impl PlateIndex {
    fn of(model: &Model) -> PlateIndex {
        let mut touching = vec![Vec::new(); model.len()];
        let mut plate_triangles = vec![Vec::new(); model.plate_count()];
        for (t, (tri, geom)) in model.triangles.iter().zip(&model.surfaces).enumerate() {
            for &i in &tri.corners {
                touching[i].push(t);
            }
            plate_triangles[geom.plate].push(t);
        }
        PlateIndex {
            touching,
            plate_triangles,
        }
    }
}

/// Rigid body `b` of `model` as a model of its own (body 0 there): the
/// triangles of every plate that one of its members is a corner of, the
/// particles they and the members use (in the model's order, at their rest
/// positions and masses), no springs, hinges, ground or wind, and the
/// triangles' surface geometry with their plates renumbered in order. Under
/// the unsteady law the forces on the members come from the triangles that
/// touch them, all kept with the whole of their plates, whose sums run over
/// their own triangles; so with the other particles at rest the members'
/// forces and added mass are the same, to the bit, as in the whole model:
/// the same triangles, in the same order.
fn body_alone(model: &Model, index: &PlateIndex, b: usize) -> Model {
    let body = &model.rigid[b];
    let mut plates: Vec<usize> = body
        .members
        .iter()
        .flat_map(|&i| &index.touching[i])
        .map(|&t| model.surfaces[t].plate)
        .collect();
    plates.sort_unstable();
    plates.dedup();
    let mut kept: Vec<usize> = plates
        .iter()
        .flat_map(|&p| index.plate_triangles[p].iter().copied())
        .collect();
    kept.sort_unstable();
    let mut old = body.members.clone();
    old.extend(kept.iter().flat_map(|&t| model.triangles[t].corners));
    old.sort_unstable();
    old.dedup();
    // `old` is sorted: a particle's new index is its place in it.
    let new_index = |i: usize| old.binary_search(&i).expect("a kept particle");
    // Plates numbered as their first triangle comes in the model's order.
    let mut plate_index = vec![usize::MAX; plates.len()];
    let mut count = 0;
    for &t in &kept {
        let slot = plates
            .binary_search(&model.surfaces[t].plate)
            .expect("a kept plate");
        if plate_index[slot] == usize::MAX {
            plate_index[slot] = count;
            count += 1;
        }
    }
    let renumbered = |p: usize| plate_index[plates.binary_search(&p).expect("a kept plate")];
    let pick = |values: &[f64]| old.iter().map(|&i| values[i]).collect::<Vec<f64>>();
    Model {
        mass: pick(&model.mass),
        inv_mass: pick(&model.inv_mass),
        fixed: old.iter().map(|&i| model.fixed[i]).collect(),
        particle_drag: pick(&model.particle_drag),
        rest_position: old.iter().map(|&i| model.rest_position[i]).collect(),
        springs: Vec::new(),
        triangles: kept
            .iter()
            .map(|&t| {
                let mut tri = model.triangles[t];
                tri.corners = tri.corners.map(new_index);
                tri
            })
            .collect(),
        hinges: Vec::new(),
        aero: model.aero,
        wind: crate::physics::field::WindField::still(),
        gravity: model.gravity,
        ground: None,
        rigid: vec![crate::physics::model::RigidBody {
            members: body.members.iter().map(|&i| new_index(i)).collect(),
            ..body.clone()
        }],
        surfaces: kept
            .iter()
            .map(|&t| SurfaceGeometry {
                plate: renumbered(model.surfaces[t].plate),
                ..model.surfaces[t]
            })
            .collect(),
    }
}

/// [`rigid_body_rate`] of body 0 of `model`, which [`body_alone`] made.
fn body_rate(law: &UnsteadyAero, model: &Model, v_ref: f64, q_ref: f64) -> f64 {
    let body = &model.rigid[0];
    let x = &model.rest_position;
    let centre = body
        .members
        .iter()
        .zip(&body.member_mass)
        .map(|(&i, &m)| x[i] * m)
        .sum::<V3>()
        / body.mass;
    // The body's frame: its principal axes (the plate normal has the largest moment).
    let eig = body.inertia.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&p, &q| eig.eigenvalues[p].total_cmp(&eig.eigenvalues[q]));
    let axes: [V3; 3] = order.map(|k| eig.eigenvectors.column(k).into());
    let omega_ref = tumbling_rates(&axes, body.members.iter().map(|&i| x[i]), v_ref);
    let n = model.len();
    let mut v = vec![V3::zeros(); n];
    let mut f = vec![V3::zeros(); n];
    let mut added = vec![Matrix3::zeros(); n];
    let mut load = |vel: V3, omega: V3, added: &mut Vec<Matrix3<f64>>| -> (V3, V3) {
        for &i in &body.members {
            v[i] = vel + omega.cross(&(x[i] - centre));
        }
        f.fill(V3::zeros());
        added.fill(Matrix3::zeros());
        unsteady_forces(law, model, x, &v, None, &[], &mut f, added, None);
        let mut total = (V3::zeros(), V3::zeros());
        for &i in &body.members {
            total.0 += f[i];
            total.1 += (x[i] - centre).cross(&f[i]);
        }
        total
    };
    // Generalised mass at rest.
    load(V3::zeros(), V3::zeros(), &mut added);
    let mut mass = nalgebra::Matrix6::<f64>::zeros();
    for (&i, &m) in body.members.iter().zip(&body.member_mass) {
        let r = x[i] - centre;
        let k = Matrix3::identity() * m + added[i];
        let rx = Matrix3::new(0.0, -r.z, r.y, r.z, 0.0, -r.x, -r.y, r.x, 0.0);
        let blocks = [k, -(k * rx), rx * k, -(rx * k * rx)];
        for (q, blk) in blocks.iter().enumerate() {
            mass.fixed_view_mut::<3, 3>(3 * (q / 2), 3 * (q % 2))
                .add_assign(blk);
        }
    }
    let Some(inverse) = mass.try_inverse() else {
        return f64::INFINITY;
    };
    let mut worst: f64 = 0.0;
    for (vel, spin) in sampled_motions(&axes, v_ref, q_ref, omega_ref) {
        let mut jac = nalgebra::Matrix6::<f64>::zeros();
        let hv = 1e-6 * v_ref.max(1e-9);
        let hw = 1e-6 * omega_ref[0].max(omega_ref[1]).max(1e-9);
        // Forward differences: 7 loads per state instead of central
        // differences' 12, for a relative error of about 1e-6.
        let (f0, t0) = load(vel, spin, &mut added);
        for col in 0..6 {
            let mut e = nalgebra::Vector6::<f64>::zeros();
            e[col] = if col < 3 { hv } else { hw };
            let dv = V3::new(e[0], e[1], e[2]);
            let dw = V3::new(e[3], e[4], e[5]);
            let (fp, tp) = load(vel + dv, spin + dw, &mut added);
            for row in 0..3 {
                jac[(row, col)] = (fp[row] - f0[row]) / e[col];
                jac[(row + 3, col)] = (tp[row] - t0[row]) / e[col];
            }
        }
        let map = inverse * jac;
        // A force that overflowed (gravity or a mass near f64's limit makes
        // the reference speeds infinite) leaves inf or NaN here, on which
        // the Schur iteration never settles: the rate is unbounded, and the
        // estimate's check refuses it.
        if !map.iter().all(|v| v.is_finite()) {
            return f64::INFINITY;
        }
        let rate = map
            .complex_eigenvalues()
            .iter()
            .map(|z| z.norm())
            .fold(0.0, f64::max);
        worst = worst.max(rate);
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::model::{ModelParts, RigidGroup, Triangle};

    /// Appends a flat square of `cells` × `cells` cells (two triangles
    /// each, side `side`) at `origin` to `parts`, tilted by `tilt` about x,
    /// with particle masses growing along the list (no two bodies alike);
    /// returns its particles.
    fn square(
        parts: &mut ModelParts,
        origin: V3,
        side: f64,
        cells: usize,
        tilt: f64,
    ) -> Vec<usize> {
        let first = parts.mass.len();
        let h = side / cells as f64;
        for j in 0..=cells {
            for i in 0..=cells {
                let (y, z) = (j as f64 * h * tilt.cos(), j as f64 * h * tilt.sin());
                parts
                    .rest_position
                    .push(origin + V3::new(i as f64 * h, y, z));
                parts
                    .mass
                    .push(1e-5 * (1.0 + 0.01 * parts.mass.len() as f64));
                parts.fixed.push(false);
            }
        }
        let id = |i: usize, j: usize| first + j * (cells + 1) + i;
        for j in 0..cells {
            for i in 0..cells {
                for corners in [
                    [id(i, j), id(i + 1, j), id(i + 1, j + 1)],
                    [id(i, j), id(i + 1, j + 1), id(i, j + 1)],
                ] {
                    parts.triangles.push(Triangle {
                        corners,
                        alpha_n: 0.0,
                        alpha_t: 0.0,
                    });
                }
            }
        }
        (first..parts.mass.len()).collect()
    }

    /// Three squares and a free one, bodies listed in `order`.
    fn scene(order: [usize; 3]) -> Model {
        let mut parts = ModelParts {
            aero: AeroLaw::Unsteady(UnsteadyAero::default()),
            gravity: V3::new(0.0, 0.0, -9.81),
            ..Default::default()
        };
        square(&mut parts, V3::new(-0.3, 0.0, 0.0), 0.04, 3, 0.0);
        let bodies = [
            square(&mut parts, V3::new(0.0, 0.0, 0.0), 0.05, 4, 0.0),
            square(&mut parts, V3::new(0.2, 0.1, 0.0), 0.03, 2, 0.4),
            square(&mut parts, V3::new(0.5, 0.0, 0.2), 0.06, 3, 1.1),
        ];
        parts.rigid = order
            .iter()
            .map(|&k| RigidGroup {
                members: bodies[k].clone(),
            })
            .collect();
        Model::new(parts).unwrap()
    }

    /// [`rigid_body_rate`] measures a body on its own plates
    /// ([`body_alone`]); the whole model's forces, which it measured on
    /// before, give the same rate to the bit, for every body of a model
    /// with another body before and after it and a free plate first.
    #[test]
    fn a_body_measured_alone_has_the_whole_models_rate() {
        let model = scene([0, 1, 2]);
        let AeroLaw::Unsteady(law) = model.aero else {
            unreachable!()
        };
        assert_eq!(model.plate_count(), 4);
        for (b, order) in [(0, [0, 1, 2]), (1, [1, 0, 2]), (2, [2, 1, 0])] {
            // The whole model with body b listed first: what body_rate
            // measures when it is given the whole model.
            let whole = scene(order);
            for (v_ref, q_ref) in [(1.2, 0.4), (3.0, 3.0)] {
                let alone = rigid_body_rate(&law, &model, b, v_ref, q_ref);
                let reference = body_rate(&law, &whole, v_ref, q_ref);
                assert!(alone.is_finite() && alone > 0.0);
                assert_eq!(
                    alone.to_bits(),
                    reference.to_bits(),
                    "body {b}: {alone} against {reference}"
                );
            }
        }
    }
}
