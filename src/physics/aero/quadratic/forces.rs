//! The quadratic law's forces on each triangle and its drag-rate bound for
//! the auto step (the equations: [`super`]).

use super::coefficients::QuadraticAero;
use crate::physics::aero::law::AeroLaw;
use crate::physics::aero::surfaces::surface;
use crate::physics::model::Model;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// Factor on the fastest steady fall (edge-on, [`edge_on_speed`]) that
/// bounds the relative air speed of any triangle for the stability
/// estimate: a spinning or rocking leaf's tips move faster than its centre,
/// and a release transient overshoots. Measured over 45 drops under this
/// law (the card at 10–1000 g/m² from three releases, eight variants of
/// each recipe): the fastest triangle never exceeded 1.02 × the edge-on
/// speed, so 2 leaves a factor-two margin.
pub const SPEED_MARGIN: f64 = 2.0;

/// Adds the quadratic law's force on every triangle of `model` that is not
/// torn (`torn[t]`; an empty mask tears none; see the module docs). `wind`
/// holds G at every particle, or is `None` in still air.
pub fn quadratic_forces(
    law: &QuadraticAero,
    model: &Model,
    x: &[V3],
    v: &[V3],
    wind: Option<&[V3]>,
    torn: &[bool],
    force: &mut [V3],
) {
    let half_rho = 0.5 * law.air_density;
    let k_normal = law.cd_normal - law.cd_parallel - 2.0 * law.cl_amplitude;
    let offset_at_zero = 1.0 - law.cop_leading;
    for (t, tri) in model.triangles.iter().enumerate() {
        let Some((big_n, n2)) = surface(t, tri, x, torn) else {
            continue;
        };
        let [a, b, c] = tri.corners;
        let (e1, e2) = (x[b] - x[a], x[c] - x[a]);
        let doubled_area = n2.sqrt();
        let n = big_n / doubled_area;
        let area = 0.5 * doubled_area;
        let third = 1.0 / 3.0;
        let mut v_rel = -(v[a] + v[b] + v[c]) * third;
        if let Some(g) = wind {
            v_rel += (g[a] + g[b] + g[c]) * third;
        }
        let u2 = v_rel.norm_squared();
        if u2 <= f64::MIN_POSITIVE {
            continue;
        }
        let u = u2.sqrt();
        let q = v_rel.dot(&n);
        let f = (v_rel * (law.cd_parallel + k_normal * q * q / u2)
            + n * (2.0 * law.cl_amplitude * q))
            * (half_rho * area * u);

        // Centre of pressure: p = centroid + s d, d upstream in the plane.
        let v_plane = v_rel - n * q;
        let w_plane = v_plane.norm();
        let mut weights = [third; 3];
        if law.rotational_lift != 0.0 {
            // In-plane angular velocity from the turning of the normal:
            // ω_in = n × ṅ, ṅ = (Ṅ − n (n·Ṅ)) / |N|.
            let n_dot = (v[b] - v[a]).cross(&e2) + e1.cross(&(v[c] - v[a]));
            let omega_in = n.cross(&(n_dot - n * n.dot(&n_dot))) / doubled_area;
            let w2 = omega_in.norm_squared();
            if w2 > f64::MIN_POSITIVE {
                // Chord across the rotation axis.
                let across = n.cross(&omega_in) / w2.sqrt();
                let proj = [a, b, c].map(|i| x[i].dot(&across));
                let chord = proj[0].max(proj[1]).max(proj[2]) - proj[0].min(proj[1]).min(proj[2]);
                let magnus =
                    v_rel.cross(&omega_in) * (half_rho * law.rotational_lift * chord * area);
                for &i in &tri.corners {
                    force[i] += magnus * third;
                }
            }
        }
        if w_plane > 1e-12 * u {
            let d = -v_plane / w_plane;
            let alpha = q.abs().atan2(w_plane);
            let centroid = (x[a] + x[b] + x[c]) * third;
            let proj = [a, b, c].map(|i| (x[i] - centroid).dot(&d));
            let lead = proj[0].max(proj[1]).max(proj[2]);
            let trail = proj[0].min(proj[1]).min(proj[2]);
            // Quarter chord behind the leading edge at α = 0:
            // lead − f (lead − trail) = (1 − f) lead + f trail.
            let at_zero = offset_at_zero * lead + law.cop_leading * trail;
            let s = at_zero * (1.0 - alpha * std::f64::consts::FRAC_2_PI);
            // Barycentric coordinates of centroid + s d: the gradient of the
            // coordinate of corner b is (e2 × N)·/|N|², of c (N × e1)/|N|².
            let shift = d * s;
            let wb = shift.dot(&e2.cross(&big_n)) / n2;
            let wc = shift.dot(&big_n.cross(&e1)) / n2;
            weights = [third - wb - wc, third + wb, third + wc];
        }
        for (&i, w) in tri.corners.iter().zip(weights) {
            force[i] += f * w;
        }
    }
}

/// Fastest steady fall of `model` under `law`: edge-on, where all its weight
/// is carried by in-plane drag, M g = ½ ρ A C_D∥ V², m/s.
pub fn edge_on_speed(law: &QuadraticAero, model: &Model) -> f64 {
    let area = model.surface_area();
    if area <= 0.0 {
        return 0.0;
    }
    (2.0 * model.total_mass() * model.gravity.norm() / (law.air_density * area * law.cd_parallel))
        .sqrt()
}

/// Largest drag rate γ = Σⱼ ‖∂F_i/∂v_j‖ / m_i of any free particle under
/// the quadratic law at the reference relative speed
/// v_ref = wind bound + [`SPEED_MARGIN`] × [`edge_on_speed`], 1/s (0 for the
/// linear law): a Gershgorin bound on the drag's rate, from
/// [`QuadraticAero::corner_rate_bound`] for each corner of each triangle at
/// the rest shape; the rotational lift, a third on each corner, adds at most
/// ½ ρ C_R A c (v_ref/h_min + ω_ref) with c ≤ 2 r_max and ω_ref = v_ref/h_min.
pub fn drag_rate(model: &Model) -> f64 {
    let AeroLaw::Quadratic(law) = &model.aero else {
        return 0.0;
    };
    let v_ref = model.wind.speed_bound() + SPEED_MARGIN * edge_on_speed(law, model);
    let half_rho = 0.5 * law.air_density;
    let x = &model.rest_position;
    let mut rate = vec![0.0; model.len()];
    for tri in &model.triangles {
        let [a, b, c] = tri.corners;
        let doubled = (x[b] - x[a]).cross(&(x[c] - x[a])).norm();
        if doubled == 0.0 {
            continue;
        }
        let area = 0.5 * doubled;
        let centroid = (x[a] + x[b] + x[c]) / 3.0;
        let r_max = [a, b, c]
            .iter()
            .map(|&i| (x[i] - centroid).norm())
            .fold(0.0, f64::max);
        let heights: [f64; 3] = std::array::from_fn(|k| {
            let (j, l) = (tri.corners[(k + 1) % 3], tri.corners[(k + 2) % 3]);
            doubled / (x[l] - x[j]).norm()
        });
        let h_min = heights.iter().copied().fold(f64::INFINITY, f64::min);
        let rotational =
            half_rho * law.rotational_lift.abs() * area * 2.0 * r_max * 2.0 * v_ref / h_min / 3.0;
        for (k, &i) in tri.corners.iter().enumerate() {
            rate[i] +=
                half_rho * area * v_ref * law.corner_rate_bound(r_max / heights[k]) + rotational;
        }
    }
    (0..model.len())
        .filter(|&i| !model.fixed[i])
        .map(|i| rate[i] / model.mass[i])
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::aero::quadratic::{AIR_DENSITY, APW_ROTATIONAL_LIFT};
    use crate::physics::model::{ModelParts, Triangle};

    fn plate(law: QuadraticAero) -> Model {
        Model::new(ModelParts {
            mass: vec![1e-5; 3],
            fixed: vec![false; 3],
            rest_position: vec![
                V3::new(0.0, 0.0, 0.0),
                V3::new(0.03, 0.0, 0.0),
                V3::new(0.0, 0.02, 0.0),
            ],
            triangles: vec![Triangle {
                corners: [0, 1, 2],
                alpha_n: 0.0,
                alpha_t: 0.0,
            }],
            aero: AeroLaw::Quadratic(law),
            gravity: V3::new(0.0, 0.0, -crate::physics::model::STANDARD_GRAVITY),
            ..Default::default()
        })
        .unwrap()
    }

    fn force_and_moment(model: &Model, vel: V3) -> (V3, V3) {
        let x = model.rest_position.clone();
        let v = vec![vel; 3];
        let mut f = vec![V3::zeros(); 3];
        let AeroLaw::Quadratic(law) = &model.aero else {
            unreachable!()
        };
        quadratic_forces(law, model, &x, &v, None, &[], &mut f);
        let centroid = (x[0] + x[1] + x[2]) / 3.0;
        let total: V3 = f.iter().sum();
        let moment: V3 = x.iter().zip(&f).map(|(p, f)| (p - centroid).cross(f)).sum();
        (total, moment)
    }

    /// Face-on and edge-on forces are pure drag with C_D⊥ and C_D∥; at 45°
    /// the drag and lift components equal ½ρAu² (1.4, 1.2).
    #[test]
    fn force_follows_the_coefficients() {
        let law = QuadraticAero::default();
        let model = plate(law);
        let area = model.surface_area();
        let q = |u: f64| 0.5 * AIR_DENSITY * area * u * u;
        // Falling face-down at 0.7 m/s: the air pushes up with C_D = 2.4.
        let (f, _) = force_and_moment(&model, V3::new(0.0, 0.0, -0.7));
        assert!((f - V3::new(0.0, 0.0, 2.4 * q(0.7))).norm() < 1e-15, "{f}");
        // Sliding edge-on along x at 2 m/s: C_D = 0.4, no lift.
        let (f, _) = force_and_moment(&model, V3::new(2.0, 0.0, 0.0));
        assert!((f - V3::new(-0.4 * q(2.0), 0.0, 0.0)).norm() < 1e-15, "{f}");
        // Moving along (1, 0, −1)/√2: α = 45°, C_D = 1.4, C_L = 1.2.
        let dir = V3::new(1.0, 0.0, -1.0).normalize();
        let (f, _) = force_and_moment(&model, dir);
        let drag = -f.dot(&dir);
        let lift = (f + dir * drag).norm();
        assert!((drag - 1.4 * q(1.0)).abs() < 1e-12 * q(1.0), "{drag}");
        assert!((lift - 1.2 * q(1.0)).abs() < 1e-12 * q(1.0), "{lift}");
        // Lift pushes up (the air comes from below) and does no work.
        assert!(f.z > 0.0);
        let (cd, cl) = law.coefficients(std::f64::consts::FRAC_PI_4);
        assert!((cd - 1.4).abs() < 1e-15 && (cl - 1.2).abs() < 1e-15);
    }

    /// Edge-on flow puts the centre of pressure a quarter chord behind the
    /// leading edge; face-on flow at the centroid.
    #[test]
    fn centre_of_pressure_moves_from_quarter_chord_to_centroid() {
        let model = plate(QuadraticAero::default());
        let cop = |vel: V3| {
            let (f, m) = force_and_moment(&model, vel);
            // m = r × f with r in the plane (z = 0): r = (f × m)/|f|² + k f.
            let f_plane = V3::new(f.x, f.y, 0.0);
            (f, m, f_plane)
        };
        // Nearly edge-on flow along −x (plate moving +x, leading edge at
        // x = 0.03), tiny normal component so the force has a normal part.
        let eps = 1e-3;
        let (f, m, _) = cop(V3::new(1.0, 0.0, -eps));
        // Moment about the centroid from the normal force F_z at arm r_x:
        // m_y = −r_x F_z (r × F with r = (r_x, 0, 0)).
        let r_x = -m.y / f.z;
        // Chord along x: corners at x = 0, 0.03, 0 → centroid x = 0.01,
        // lead = 0.02, trail = −0.01, quarter chord at 0.02 − 0.0075.
        let expect = (0.02 - 0.25 * 0.03) * (1.0 - eps.atan() * std::f64::consts::FRAC_2_PI);
        assert!((r_x - expect).abs() < 1e-12, "{r_x} vs {expect}");
        // Face-on: no moment.
        let (_, m, _) = cop(V3::new(0.0, 0.0, -1.0));
        assert!(m.norm() < 1e-18, "{m}");
        // At 45° halfway.
        let (f, m, _) = cop(V3::new(1.0, 0.0, -1.0));
        // The in-plane force component has no arm about y for r along x.
        let r_x = -m.y / f.z;
        assert!((r_x - 0.5 * 0.0125).abs() < 1e-12, "{r_x}");
    }

    /// A plate falling face-down while turning about x (ω = +x) feels a
    /// Magnus force along v_rel × ω = (+z) × (+x) = +y, doing no work.
    #[test]
    fn rotational_lift_is_magnus_like_and_does_no_work() {
        let law = QuadraticAero {
            rotational_lift: APW_ROTATIONAL_LIFT,
            ..Default::default()
        };
        let model = plate(law);
        let x = model.rest_position.clone();
        let centroid = (x[0] + x[1] + x[2]) / 3.0;
        let omega = V3::new(3.0, 0.0, 0.0);
        let fall = V3::new(0.0, 0.0, -0.8);
        let v: Vec<V3> = x
            .iter()
            .map(|p| fall + omega.cross(&(p - centroid)))
            .collect();
        let total = |law: &QuadraticAero| {
            let mut f = vec![V3::zeros(); 3];
            quadratic_forces(law, &model, &x, &v, None, &[], &mut f);
            f.iter().sum::<V3>()
        };
        let magnus = total(&law) - total(&QuadraticAero::default());
        // |F| = ½ ρ C_R c A |v| |ω|, c = 0.02 (extent along y, across x).
        let area = model.surface_area();
        let expect = 0.5 * AIR_DENSITY * APW_ROTATIONAL_LIFT * 0.02 * area * 0.8 * 3.0;
        assert!(
            (magnus - V3::new(0.0, expect, 0.0)).norm() < 1e-9 * expect,
            "{magnus}"
        );
        let mut f = vec![V3::zeros(); 3];
        quadratic_forces(&law, &model, &x, &v, None, &[], &mut f);
        let mut g = vec![V3::zeros(); 3];
        quadratic_forces(&QuadraticAero::default(), &model, &x, &v, None, &[], &mut g);
        let power: f64 = (0..3).map(|i| (f[i] - g[i]).dot(&v[i])).sum();
        assert!(power.abs() < 1e-9 * expect * 0.8, "{power}");
    }

    /// The drag-rate bound holds: ‖∂F_i/∂v_j‖ summed over j, over m_i,
    /// measured by finite differences at random velocities up to v_ref.
    #[test]
    fn drag_rate_bounds_the_measured_jacobian() {
        use rand::{RngExt, SeedableRng};
        let law = QuadraticAero {
            rotational_lift: APW_ROTATIONAL_LIFT,
            ..Default::default()
        };
        let model = plate(law);
        let bound = drag_rate(&model);
        let v_ref = SPEED_MARGIN * edge_on_speed(&law, &model);
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(3);
        let x = model.rest_position.clone();
        let mut worst: f64 = 0.0;
        for _ in 0..200 {
            let v: Vec<V3> = (0..3)
                .map(|_| V3::from_fn(|_, _| rng.random_range(-1.0..1.0)) * (v_ref / 3f64.sqrt()))
                .collect();
            let eval = |v: &[V3]| {
                let mut f = vec![V3::zeros(); 3];
                quadratic_forces(&law, &model, &x, v, None, &[], &mut f);
                f
            };
            let h = 1e-7;
            for i in 0..3 {
                let mut row = 0.0;
                for j in 0..3 {
                    // Frobenius norm of the 3 × 3 block bounds its spectral norm.
                    let mut block = 0.0;
                    for k in 0..3 {
                        let mut plus = v.clone();
                        let mut minus = v.clone();
                        plus[j][k] += h;
                        minus[j][k] -= h;
                        let d = (eval(&plus)[i] - eval(&minus)[i]) / (2.0 * h);
                        block += d.norm_squared();
                    }
                    row += block.sqrt();
                }
                worst = worst.max(row / model.mass[i]);
            }
        }
        println!("drag rate: measured {worst:.1} 1/s, bound {bound:.1} 1/s");
        assert!(
            worst > 0.1 * bound,
            "bound {bound} far above measured {worst}"
        );
        assert!(worst <= bound, "measured {worst} exceeds the bound {bound}");
    }

    #[test]
    fn bad_coefficients_are_named() {
        let mut law = QuadraticAero {
            cd_parallel: 0.0,
            ..Default::default()
        };
        assert_eq!(law.validate().unwrap_err().item, "aero.cd_parallel");
        law = QuadraticAero {
            cl_amplitude: 1.3,
            ..Default::default()
        };
        assert_eq!(law.validate().unwrap_err().item, "aero.cl_amplitude");
        law = QuadraticAero {
            air_density: f64::NAN,
            ..Default::default()
        };
        assert_eq!(law.validate().unwrap_err().item, "aero.air_density");
        law = QuadraticAero {
            cop_leading: 0.6,
            ..Default::default()
        };
        assert_eq!(law.validate().unwrap_err().item, "aero.cop_leading");
        assert!(QuadraticAero::default().validate().is_ok());
    }
}
