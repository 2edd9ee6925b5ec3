//! The paper's three kinds of fall (section 4.1: floaters, spinners,
//! lilters) from leafmagic's own leaves: the paper's recipes under its
//! linear law, variants found by varying prototype A's genome (kept as
//! fixtures), and a flat square card under the quadratic law as its areal
//! density rises (Field et al. 1997 order). Every drop is 10 s at the
//! default settings (Verlet, auto dt); a prototype drop costs ~5 ms.

use leafmagic::leaf::genome::{Genome, mutate};
use leafmagic::leaf::plates::{self, square_card};
use leafmagic::leaf::recipes::Recipe;
use leafmagic::leaf::{AeroSpec, LeafSpec};
use leafmagic::motion::classify::{Classification, MotionClass, Regime, classify};
use leafmagic::sim::drop::{DropParams, drop_leaf};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;
use std::path::Path;

/// Drops `spec` released at `tilt` (degrees) and classifies the fall.
fn fall(spec: &LeafSpec, tilt: [f64; 2]) -> Classification {
    let model = spec.model().unwrap();
    let params = DropParams {
        tilt_deg: tilt,
        ..Default::default()
    };
    let result = drop_leaf(&model, &params).unwrap();
    classify(&result.trajectory, model.chord())
}

/// Classes of the recipe's seeded family (seeds 1–16, each with its own
/// release).
fn family(recipe: Recipe) -> Vec<(MotionClass, Regime)> {
    (1..=16u64)
        .into_par_iter()
        .map(|seed| {
            let (spec, tilt) = recipe.variant(seed);
            let c = fall(&spec, tilt);
            (c.class, c.regime)
        })
        .collect()
}

fn count(classes: &[(MotionClass, Regime)], class: MotionClass) -> usize {
    classes.iter().filter(|c| c.0 == class).count()
}

/// Two thirds of a family of 16 must show the recipe's class.
const FAMILY_MAJORITY: usize = 11;

/// Topology A, flaps 1, 2, 3 folded up, centre of gravity near the centre:
/// "usually floaters". The recipe leaf is prototype A (20° up, uniform
/// 80 g/m²). Measured: 16 of 16 variants float (9 steady, 7 glide).
#[test]
fn paper_floaters_flaps_up_centre_of_gravity_central() {
    let c = fall(&Recipe::Floater.leaf(), DropParams::default().tilt_deg);
    assert_eq!(c.class, MotionClass::Floater, "{c:#?}");
    let classes = family(Recipe::Floater);
    let floaters = count(&classes, MotionClass::Floater);
    println!("recipe A floater: {floaters} of 16 floaters: {classes:?}");
    assert!(floaters >= FAMILY_MAJORITY, "{classes:?}");
}

/// Topology A, flaps 1 and 3 folded in opposite directions, centre of
/// gravity off to one side: "spinners". The recipe leaf (±30°, a quarter of
/// the mass on the tip of flap 2) spins about the vertical (autorotation,
/// its plane steep), as leafmagic's predecessor found (docs/design/falling-plates.md,
/// "Folded leaves under the linear law"). Measured: 13 of 16 variants spin (12
/// about the vertical, 1 tumbles), 2 lilt, 1 floats.
#[test]
fn paper_spinners_flaps_opposed_centre_of_gravity_aside() {
    let c = fall(&Recipe::Spinner.leaf(), DropParams::default().tilt_deg);
    assert_eq!(
        (c.class, c.regime),
        (MotionClass::Spinner, Regime::Autorotation),
        "{c:#?}"
    );
    assert!(c.features.vertical_spin_share > 0.9, "{:#?}", c.features);
    let classes = family(Recipe::Spinner);
    let spinners = count(&classes, MotionClass::Spinner);
    println!("recipe A spinner: {spinners} of 16 spinners: {classes:?}");
    assert!(spinners >= FAMILY_MAJORITY, "{classes:?}");
}

/// Topology B, flap 1 folded up and flaps 2 and 3 down: the film's
/// "lilted motion" (alternately rocks, then turns end over end). The recipe
/// leaf is prototype B (retuned: flap 1 +35°, flaps 2, 3 −40°). Measured:
/// 16 of 16 variants lilt.
#[test]
fn paper_lilters_topology_b_flap_1_up_2_and_3_down() {
    let b = Recipe::Lilter.leaf();
    let angle = |flap: u8| {
        b.folds
            .iter()
            .find(|f| f.flap == Some(flap))
            .unwrap()
            .angle_deg
    };
    assert!(angle(1) > 0.0 && angle(2) < 0.0 && angle(3) < 0.0);
    let c = fall(&b, DropParams::default().tilt_deg);
    assert_eq!(c.class, MotionClass::Lilter, "{c:#?}");
    // It rocks (pitch reversals) and flips over, more than once each.
    assert!(
        c.features.reversals >= 4 && c.features.normal_flips >= 4,
        "{:#?}",
        c.features
    );
    let classes = family(Recipe::Lilter);
    let lilters = count(&classes, MotionClass::Lilter);
    println!("recipe B lilter: {lilters} of 16 lilters: {classes:?}");
    assert!(lilters >= FAMILY_MAJORITY, "{classes:?}");
}

/// One round of variation of prototype A's genome (genome::mutate at scale
/// 2.5, seeds 0, 1, 2, …, default release) finds all three classes. Under
/// the paper's law; measured: first spinner at seed 0, floater at seed 2,
/// lilter at seed 70 (29 before the size step was widened to a quarter, issue
/// 19: the draws of later genes moved).
#[test]
fn varying_prototype_a_finds_every_class() {
    let proto = LeafSpec::load("a").unwrap();
    let start = Genome::of_prototype(&proto);
    let classes: Vec<(u64, MotionClass)> = (0..120u64)
        .into_par_iter()
        .map(|seed| {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
            let genome = mutate(&start, &proto.bounds, 2.5, &mut rng);
            let c = fall(&genome.to_leaf(&proto), DropParams::default().tilt_deg);
            (seed, c.class)
        })
        .collect();
    for class in [
        MotionClass::Floater,
        MotionClass::Spinner,
        MotionClass::Lilter,
    ] {
        let first = classes.iter().find(|c| c.1 == class);
        println!("first {class}: seed {:?}", first.map(|c| c.0));
        assert!(first.is_some(), "no {class} among {classes:?}");
    }
}

/// The variants kept from such searches (tests/fixtures/a-*.toml, seeds in
/// their headers) keep their class, at the default release and at two
/// others.
#[test]
fn fixtures_from_varying_prototype_a_keep_their_class() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let cases = [
        ("a-floater.toml", MotionClass::Floater, Regime::Glide),
        ("a-spinner.toml", MotionClass::Spinner, Regime::Autorotation),
        ("a-tumbler.toml", MotionClass::Spinner, Regime::Tumble),
        ("a-lilter.toml", MotionClass::Lilter, Regime::Chaotic),
    ];
    cases.par_iter().for_each(|&(file, class, regime)| {
        let spec = LeafSpec::read(&dir.join(file)).unwrap();
        // The fixtures are variants of A: same topology, linear law.
        let a = LeafSpec::load("a").unwrap();
        assert_eq!(spec.triangles, a.triangles);
        assert_eq!(spec.aero, a.aero);
        for tilt in [[10.0, 2.0], [0.0, 0.0], [-15.0, 0.0]] {
            let c = fall(&spec, tilt);
            println!(
                "{file} at {tilt:?}: {} / {}, {:.2} m/s, margin {:.2}",
                c.class, c.regime, c.features.mean_descent_speed_m_s, c.features.margin
            );
            assert_eq!((c.class, c.regime), (class, regime), "{file} {tilt:?}");
        }
    });
}

/// Under the paper's linear law a flat, uniform card has no pitching
/// moment (docs/design/falling-plates.md, "Linear law: no pitching moment"):
/// whatever its density it keeps its release attitude
/// exactly and slides down along it — a floater, never a flutterer,
/// tumbler or lilter. (Released 45° steep it would glide steeply, which the
/// classifier leaves undetermined.)
#[test]
fn flat_card_only_floats_under_the_linear_law() {
    [0.02, 0.1, 0.5].par_iter().for_each(|&sigma| {
        let card = square_card(0.05, sigma, AeroSpec::linear(0.47, 0.047));
        for tilt in [[10.0, 2.0], [0.0, 20.0]] {
            let c = fall(&card, tilt);
            let f = &c.features;
            let released = (tilt[0].to_radians().cos() * tilt[1].to_radians().cos())
                .acos()
                .to_degrees();
            assert_eq!(c.class, MotionClass::Floater, "σ = {sigma}: {c:#?}");
            assert!(
                (f.tilt_mean_deg - released).abs() < 0.1 && f.tilt_std_deg < 0.1,
                "σ = {sigma}, {tilt:?}: tilt {} ± {} vs {released}",
                f.tilt_mean_deg,
                f.tilt_std_deg
            );
        }
    });
}

/// A flat card released level under the quadratic law falls face-down at
/// V = √(2 σ g / (ρ C_D⊥)) (0.74 m/s at 80 g/m²): the law's terminal speed.
#[test]
fn flat_card_falls_at_the_quadratic_terminal_speed() {
    let sigma = 0.08;
    let model = square_card(0.05, sigma, AeroSpec::quadratic())
        .model()
        .unwrap();
    let params = DropParams {
        seconds: 2.0,
        tilt_deg: [0.0, 0.0],
        ..Default::default()
    };
    let traj = drop_leaf(&model, &params).unwrap().trajectory;
    let n = traj.len();
    let vz = (traj.position[n - 1].z - traj.position[n - 121].z)
        / (traj.time[n - 1] - traj.time[n - 121]);
    let expect = (2.0 * sigma * leafmagic::physics::model::STANDARD_GRAVITY
        / (leafmagic::physics::aero::quadratic::AIR_DENSITY
            * leafmagic::physics::aero::quadratic::CD_NORMAL))
        .sqrt();
    assert!((-vz - expect).abs() < 1e-6 * expect, "{} vs {expect}", -vz);
}

/// The card as its areal density rises, under the quadratic law: floaters
/// (flutter) at low density, lilters between, spinners (tumble) at high
/// density — the order Field et al. (1997, Nature 388, 252) report. Each
/// density
/// is named by the most common class of eight release attitudes.
/// Measured: 8/8, 8/8 floaters; 5/8, 5/8 lilters; 7/8, 7/8 spinners (the
/// diagonal release [20°, 20°] floats at 0.1–0.14 and lilts at 0.3–0.5).
#[test]
fn card_classes_follow_density_floater_lilter_spinner() {
    let side = 0.05;
    let attitudes = plates::RELEASE_ATTITUDES;
    let sweep = [
        (0.02, MotionClass::Floater),
        (0.04, MotionClass::Floater),
        (0.1, MotionClass::Lilter),
        (0.14, MotionClass::Lilter),
        (0.3, MotionClass::Spinner),
        (0.5, MotionClass::Spinner),
    ];
    let runs: Vec<(usize, MotionClass)> = (0..sweep.len() * attitudes.len())
        .into_par_iter()
        .map(|k| {
            let (sigma, _) = sweep[k / attitudes.len()];
            let card = square_card(side, sigma, AeroSpec::quadratic());
            (
                k / attitudes.len(),
                fall(&card, attitudes[k % attitudes.len()]).class,
            )
        })
        .collect();
    for (i, &(sigma, want)) in sweep.iter().enumerate() {
        let classes: Vec<MotionClass> = runs.iter().filter(|r| r.0 == i).map(|r| r.1).collect();
        let model = square_card(side, sigma, AeroSpec::quadratic())
            .model()
            .unwrap();
        let i_star = plates::i_star(
            &model,
            side,
            leafmagic::physics::aero::quadratic::AIR_DENSITY,
        );
        let n = |c| classes.iter().filter(|&&x| x == c).count();
        println!(
            "σ = {sigma} kg/m², I* = {i_star:.3}: {} floaters, {} lilters, {} spinners, {} undetermined",
            n(MotionClass::Floater),
            n(MotionClass::Lilter),
            n(MotionClass::Spinner),
            n(MotionClass::Undetermined)
        );
        assert!(
            n(want) > classes.len() / 2,
            "σ = {sigma}: expected mostly {want}, got {classes:?}"
        );
    }
}
