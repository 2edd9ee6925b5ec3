//! The aerodynamic law as a leaf-file option: `[aero] law = "quadratic"`
//! with optional coefficient overrides; each law's fields are required or
//! rejected by name; the stability estimate and every integrator handle it.

use leafmagic::leaf::plates::square_card;
use leafmagic::leaf::{AeroSpec, LeafSpec, PROTOTYPE_A};
use leafmagic::physics::aero::quadratic;
use leafmagic::physics::aero::quadratic::QuadraticAero;
use leafmagic::physics::model::AeroLaw;
use leafmagic::physics::params::Integrator;
use leafmagic::physics::params::TimeStep;
use leafmagic::physics::stability;
use leafmagic::sim::drop::{DropParams, drop_leaf};

/// Prototype A with its `[aero]` table replaced by `aero` (TOML lines).
fn with_aero(aero: &str) -> String {
    crate::common::with_aero(PROTOTYPE_A, aero)
}

fn error(text: &str) -> String {
    LeafSpec::from_toml(text, "leaf.toml")
        .expect_err("must be rejected")
        .to_string()
}

#[test]
fn quadratic_law_reads_with_defaults_and_overrides() {
    let spec = LeafSpec::from_toml(&with_aero("law = \"quadratic\""), "leaf.toml").unwrap();
    let model = spec.model().unwrap();
    assert_eq!(model.aero, AeroLaw::Quadratic(QuadraticAero::default()));
    assert!(
        model
            .triangles
            .iter()
            .all(|t| t.alpha_n == 0.0 && t.alpha_t == 0.0)
    );
    let spec = LeafSpec::from_toml(
        &with_aero("law = \"quadratic\"\ncd_normal = 2.6\ncop_leading = 0.3\nair_density = 1.0"),
        "leaf.toml",
    )
    .unwrap();
    let AeroLaw::Quadratic(law) = spec.model().unwrap().aero else {
        panic!("not quadratic");
    };
    assert_eq!(
        (
            law.cd_normal,
            law.cop_leading,
            law.air_density,
            law.cd_parallel
        ),
        (2.6, 0.3, 1.0, quadratic::CD_PARALLEL)
    );
    // Round trip through TOML keeps the law.
    let again = LeafSpec::from_toml(&spec.to_toml(), "again").unwrap();
    assert_eq!(again, spec);
}

#[test]
fn each_law_rejects_the_other_laws_fields_by_name() {
    let msg = error(&with_aero("law = \"quadratic\"\nalpha_n = 0.47"));
    assert!(
        msg.starts_with("leaf.toml:")
            && msg.contains(": aero.alpha_n: ")
            && msg.contains("not used"),
        "{msg}"
    );
    let msg = error(&with_aero(
        "law = \"linear\"\nalpha_n = 0.47\nalpha_t = 0.047\ncd_normal = 2.0",
    ));
    assert!(
        msg.contains("aero.cd_normal") && msg.contains("quadratic"),
        "{msg}"
    );
    let msg = error(&with_aero("alpha_t = 0.047"));
    assert!(
        msg.contains("aero.alpha_n") && msg.contains("required"),
        "{msg}"
    );
    let msg = error(&with_aero("law = \"quadratic\"\ncd_parallel = -0.1"));
    assert!(
        msg.contains("aero.cd_parallel") && msg.contains("> 0"),
        "{msg}"
    );
    let msg = error(&with_aero("law = \"quadratic\"\ncl_amplitude = 2.0"));
    assert!(msg.contains("aero.cl_amplitude"), "{msg}");
    let msg = error(&with_aero("law = \"cubic\""));
    assert!(msg.contains("cubic") && msg.contains("quadratic"), "{msg}");
    // A per-triangle α under the quadratic law would be ignored: rejected.
    let text = with_aero("law = \"quadratic\"").replacen(
        "corners = [0, 1, 2]",
        "corners = [0, 1, 2]\nalpha_n = 0.3",
        1,
    );
    let msg = error(&text);
    assert!(msg.contains("triangle[0].alpha_n"), "{msg}");
}

/// The quadratic law's drag rate enters the estimate: it bounds the
/// implicit step (which treats the law explicitly), and drops at the auto
/// step stay finite with every integrator except forward Euler (unstable
/// on the undamped-enough spring modes by design).
#[test]
fn stability_estimate_accounts_for_the_quadratic_drag() {
    let linear = square_card(0.05, 0.08, AeroSpec::linear(0.47, 0.047))
        .model()
        .unwrap();
    let quad = square_card(0.05, 0.08, AeroSpec::quadratic())
        .model()
        .unwrap();
    let (el, eq) = (stability::estimate(&linear), stability::estimate(&quad));
    assert_eq!(el.dt_max(Integrator::Implicit), None);
    assert_eq!(el.explicit_drag_rate, 0.0);
    let rate = quadratic::drag_rate(&quad);
    assert!(rate > 0.0 && eq.explicit_drag_rate == rate && eq.drag_rate >= rate);
    let implicit = eq.dt_max(Integrator::Implicit).unwrap();
    assert!(
        (implicit * rate - 2.0).abs() < 1e-6,
        "{implicit} s at γ = {rate}"
    );
    for integrator in [
        Integrator::Symplectic,
        Integrator::Verlet,
        Integrator::Rk4,
        Integrator::Implicit,
    ] {
        let params = DropParams {
            integrator,
            dt: TimeStep::Auto,
            seconds: 3.0,
            ..Default::default()
        };
        let result = drop_leaf(&quad, &params).unwrap_or_else(|e| panic!("{integrator}: {e}"));
        let end = result.trajectory.position.last().unwrap();
        // Between the face-on (0.74 m/s) and edge-on (1.83 m/s) terminal speeds.
        assert!(end.z < -1.5 && end.z > -6.0, "{integrator}: z = {}", end.z);
    }
}

/// A scene takes its aerodynamic law from its leaves: a quadratic leaf
/// placed in a scene feels the same air force as dropped alone (summed
/// over its particles, which is translation invariant), and mixing laws
/// is an error that names the leaf.
#[test]
fn scenes_carry_the_leaves_law_and_reject_a_mix() {
    use leafmagic::physics::forces::triangle_aero;
    use leafmagic::sim::scene::Scene;
    use nalgebra::Vector3;
    let dir = std::env::temp_dir().join(format!("leafmagic-aero-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("q.toml"), with_aero("law = \"quadratic\"")).unwrap();
    let leaf = LeafSpec::read(&dir.join("q.toml"))
        .unwrap()
        .model()
        .unwrap();
    let header =
        "name = \"q\"\nduration = 1.0\nframe_rate = 60\nintegrator = \"verlet\"\ndt = \"auto\"\n";
    let one =
        format!("{header}[[leaf]]\nname = \"q\"\nleaf = \"q.toml\"\nposition = [0.0, 0.0, 2.0]\n");
    let scene = Scene::from_toml(&one, "q-scene.toml", &dir).unwrap();
    assert_eq!(scene.model.aero, leaf.aero);

    let total = |model: &leafmagic::physics::model::Model, x: &[Vector3<f64>]| {
        let v = vec![Vector3::new(0.1, 0.0, -0.8); x.len()];
        let mut f = vec![Vector3::zeros(); x.len()];
        triangle_aero(model, x, &v, None, &mut f);
        f.iter().sum::<Vector3<f64>>()
    };
    let alone = total(&leaf, &leaf.rest_position);
    let placed = total(&scene.model, &scene.initial.position);
    assert!(
        alone.z > 1e-4,
        "a falling quadratic leaf feels lift: {alone:?}"
    );
    assert!(
        (alone - placed).norm() <= 1e-12 * alone.norm(),
        "scene {placed:?} vs alone {alone:?}"
    );

    let mixed =
        format!("{one}[[leaf]]\nname = \"lin\"\nleaf = \"a\"\nposition = [1.0, 0.0, 2.0]\n");
    let err = Scene::from_toml(&mixed, "mixed.toml", &dir)
        .expect_err("two laws in one scene")
        .to_string();
    assert!(
        err.contains("mixed.toml") && err.contains("leaf[1].leaf") && err.contains("one law"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
