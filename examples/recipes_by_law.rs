//! The paper's three recipes (section 4.1; `tests/integration/classes.rs`
//! holds them under the linear law), each as its family of 16 seeded
//! variants, classified under a chosen aerodynamic law: how many of 16 show
//! the recipe's class. Every drop is 10 s at the default settings.
//!
//! cargo run --release --example recipes_by_law [-- linear|quadratic|unsteady]

use leafmagic::leaf::recipes::Recipe;
use leafmagic::leaf::{AeroLawName, AeroSpec, LeafSpec};
use leafmagic::motion::classify::{MotionClass, classify};
use leafmagic::sim::drop::{DropParams, drop_leaf};
use rayon::prelude::*;

/// `spec` under `law` (the linear law: unchanged; the others: no α).
fn under(mut spec: LeafSpec, law: AeroLawName) -> LeafSpec {
    if law != AeroLawName::Linear {
        spec.aero = AeroSpec::named(law);
        for t in &mut spec.triangles {
            t.alpha_n = None;
            t.alpha_t = None;
        }
    }
    spec
}

fn main() {
    let law: AeroLawName = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "unsteady".to_string())
        .parse()
        .expect("a law: linear, quadratic or unsteady");
    println!(
        "the paper's recipes, 16 variants each, under law = \"{}\"",
        law.as_str()
    );
    for (recipe, class) in [
        (Recipe::Floater, MotionClass::Floater),
        (Recipe::Spinner, MotionClass::Spinner),
        (Recipe::Lilter, MotionClass::Lilter),
    ] {
        let classes: Vec<MotionClass> = (1..=16u64)
            .into_par_iter()
            .map(|seed| {
                let (spec, tilt) = recipe.variant(seed);
                let model = under(spec, law).model().expect("a valid leaf");
                assert_eq!(model.aero.name(), law.as_str());
                let params = DropParams {
                    tilt_deg: tilt,
                    ..Default::default()
                };
                let result = drop_leaf(&model, &params).expect("the drop runs");
                classify(&result.trajectory, model.chord()).class
            })
            .collect();
        let hits = classes.iter().filter(|&&c| c == class).count();
        let others: Vec<String> = [
            MotionClass::Floater,
            MotionClass::Spinner,
            MotionClass::Lilter,
        ]
        .iter()
        .map(|k| format!("{k:?} {}", classes.iter().filter(|&c| c == k).count()))
        .collect();
        println!(
            "{recipe:?}: {hits} of 16 show the class {class:?} ({})",
            others.join(", ")
        );
    }
}
