//! The stable-step estimate against the dense eigenvalue problem, and the
//! auto step in use (docs/numerics.md, "Stable-step estimate" and "Auto
//! step").

use leafmagic::leaf::LeafSpec;
use leafmagic::physics::model::Model;
use leafmagic::physics::params::Integrator;
use leafmagic::physics::stability;
use nalgebra::DMatrix;

/// Dense M^-1/2 K M^-1/2 at the rest shape: springs and hinges.
fn dense_spectrum(model: &Model) -> Vec<f64> {
    let n = model.len();
    let mut k = DMatrix::<f64>::zeros(3 * n, 3 * n);
    for s in &model.springs {
        let d = model.rest_position[s.i] - model.rest_position[s.j];
        let dir = d / d.norm();
        let block = dir * dir.transpose() * s.stiffness;
        for (a, b, sign) in [
            (s.i, s.i, 1.0),
            (s.j, s.j, 1.0),
            (s.i, s.j, -1.0),
            (s.j, s.i, -1.0),
        ] {
            for r in 0..3 {
                for c in 0..3 {
                    k[(3 * a + r, 3 * b + c)] += sign * block[(r, c)];
                }
            }
        }
    }
    // Hinges: k_b g gᵀ with g the fold angle's gradient (Gauss–Newton part).
    for h in &model.hinges {
        let (_, g) = leafmagic::physics::forces::dihedral(&model.rest_position, h).unwrap();
        let ids = [h.edge[0], h.edge[1], h.apexes[0], h.apexes[1]];
        for (pa, &a) in ids.iter().enumerate() {
            for (pb, &b) in ids.iter().enumerate() {
                for r in 0..3 {
                    for c in 0..3 {
                        k[(3 * a + r, 3 * b + c)] += h.stiffness * g[pa][r] * g[pb][c];
                    }
                }
            }
        }
    }
    for a in 0..3 * n {
        for b in 0..3 * n {
            k[(a, b)] /= (model.mass[a / 3] * model.mass[b / 3]).sqrt();
        }
    }
    let mut eig: Vec<f64> = k.symmetric_eigenvalues().iter().copied().collect();
    eig.sort_by(f64::total_cmp);
    eig
}

#[test]
fn power_iteration_finds_the_top_mode_within_the_bounds() {
    for p in ["a", "b"] {
        let model = LeafSpec::load(p).unwrap().model().unwrap();
        let est = stability::estimate(&model);
        let eig = dense_spectrum(&model);
        let top = eig.last().unwrap().sqrt();
        assert!(est.power_converged, "prototype {p}");
        assert!(
            (est.omega_max - top).abs() < 1e-6 * top,
            "prototype {p}: {} vs dense {top}",
            est.omega_max
        );
        assert!(est.omega_lower <= top * (1.0 + 1e-12) && top <= est.omega_upper * (1.0 + 1e-12));
    }
}

/// The prototypes are rigid networks: exactly six zero modes (three
/// translations, three rotations), no floppy mechanism.
#[test]
fn prototypes_have_exactly_six_zero_modes() {
    for p in ["a", "b"] {
        let model = LeafSpec::load(p).unwrap().model().unwrap();
        let eig = dense_spectrum(&model);
        let top = *eig.last().unwrap();
        let zero = eig.iter().filter(|&&e| e.abs() < 1e-8 * top).count();
        assert_eq!(zero, 6, "prototype {p}: spectrum {eig:?}");
    }
}

/// The auto step is below the estimated limit, divides the output frame, and
/// is what drop uses.
#[test]
fn auto_step_is_safe_and_divides_the_frame() {
    let model = LeafSpec::load("a").unwrap().model().unwrap();
    let est = stability::estimate(&model);
    let frame = 1.0 / 240.0;
    for integrator in [Integrator::Symplectic, Integrator::Verlet, Integrator::Rk4] {
        let dt = est.auto_dt(integrator, frame).unwrap();
        let limit = est.dt_max(integrator).unwrap();
        assert!(dt <= stability::AUTO_SAFETY * limit + 1e-15);
        let per_frame = frame / dt;
        assert!((per_frame - per_frame.round()).abs() < 1e-9);
    }
    // Forward Euler is stable on the leaf only because air and dashpots damp
    // every spring mode; its limit is far below the others.
    let euler = est.dt_max(Integrator::Euler).unwrap();
    assert!(euler > 0.0 && euler < 0.5 * est.dt_max(Integrator::Symplectic).unwrap());
}

/// Stiff and extreme set-ups are flagged with the item named.
#[test]
fn warnings_name_the_light_particle_and_stiff_spring() {
    let mut spec = LeafSpec::load("a").unwrap();
    spec.particles[4].mass *= 1e-5;
    spec.springs[7].stiffness = 1e4;
    let est = stability::estimate(&spec.model().unwrap());
    assert_eq!(est.lightest_particle, 4);
    assert!(
        est.warnings
            .iter()
            .any(|w| w.starts_with("particle[4]") && w.contains("mass ratio")),
        "{:?}",
        est.warnings
    );
    assert!(
        est.warnings.iter().any(|w| w.starts_with("spring[")),
        "{:?}",
        est.warnings
    );
    assert!(
        stability::estimate(&LeafSpec::load("a").unwrap().model().unwrap())
            .warnings
            .is_empty()
    );
}

/// A strongly overdamped top mode (ζ ≈ 11–17, as a 1e-4 light particle or
/// 1e-9 kg masses in air give) still has a Verlet limit: about 1/c, where
/// c = 2ζω is the mode's damping rate (for drag alone Verlet is stable for
/// h c < 1). Unbalanced, the (x, v, a) step matrix lost that root to
/// round-off and the estimate read "no stable step".
#[test]
fn overdamped_modes_keep_a_verlet_limit() {
    for zeta in [3.0, 11.0, 17.0] {
        let w: f64 = 7e4;
        let c = 2.0 * zeta * w;
        let limit = stability::largest_stable_step(Integrator::Verlet, w * w, c).unwrap();
        assert!(limit > 0.0, "ζ = {zeta}");
        assert!(
            (limit * c - 1.0).abs() < 0.1,
            "ζ = {zeta}: h c = {}",
            limit * c
        );
        // The simulator agrees: below the limit a run stays finite, above it diverges.
        let model = crate::common::oscillator(1.0, w * w, c);
        for (factor, stable) in [(0.9, true), (1.2, false)] {
            let mut s = leafmagic::physics::state::State::at_rest(&model);
            s.position[1].x += 1e-3;
            let mut sim = leafmagic::physics::integrate::Simulator::new(&model, Integrator::Verlet);
            let h = factor * limit;
            let failed = (0..20_000).any(|_| sim.step(&model, &mut s, h).is_err());
            assert_eq!(!failed, stable, "ζ = {zeta}, h = {factor} × limit");
        }
    }
}
