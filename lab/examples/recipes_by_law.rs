//! The paper's three recipes (section 4.1; `tests/integration/classes.rs`
//! holds them under the linear law), each as its family of 16 seeded
//! variants, classified under a chosen aerodynamic law: how many of 16 show
//! the recipe's class. Every drop is 10 s at the default settings.
//!
//! cargo run --release --example recipes_by_law [-- linear|quadratic|unsteady [KEY=VALUE ...]]
//!
//! `KEY=VALUE` sets a coefficient of the law's `[aero]` table (as in a leaf
//! file, e.g. `pressure_lag_gain=0`), to see which term makes a recipe hold
//! or fail.

use leafmagic::leaf::recipes::Recipe;
use leafmagic::leaf::{AeroLawName, AeroSpec, LeafSpec};
use leafmagic::motion::classify::{MotionClass, classify};
use leafmagic::physics::model::Model;
use leafmagic::sim::drop::{DropParams, drop_leaf};
use rayon::prelude::*;
use std::process::ExitCode;

/// The model of `spec` under `law` with the `[aero]` lines `extra` (the
/// linear law: unchanged; the others: no α), or the reason the lines or
/// the leaf they make are refused.
fn under(mut spec: LeafSpec, law: AeroLawName, extra: &[String]) -> Result<Model, String> {
    if law != AeroLawName::Linear {
        spec.aero = AeroSpec::named(law)
            .with_lines(extra)
            .map_err(|e| format!("bad [aero] key: {e}"))?;
        for t in &mut spec.triangles {
            t.alpha_n = None;
            t.alpha_t = None;
        }
    }
    spec.model()
        .map_err(|e| format!("the leaf under this law: {e}"))
}

fn main() -> ExitCode {
    leafmagic::util::pipe::quiet_broken_pipe();
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("recipes_by_law: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--").collect();
    let law: AeroLawName = args
        .first()
        .map_or("unsteady", String::as_str)
        .parse()
        .map_err(|e| format!("the law: {e}"))?;
    let extra = args.get(1..).unwrap_or_default();
    if !extra.is_empty() && law == AeroLawName::Linear {
        return Err(
            "the linear law's coefficients are each leaf's own α: no KEY=VALUE with it".into(),
        );
    }
    // Bad keys, and laws refused as a whole, stop here with one line
    // rather than in a worker thread.
    under(Recipe::Floater.variant(1).0, law, extra)?;
    println!(
        "the paper's recipes, 16 variants each, under law = \"{}\" {}",
        law.as_str(),
        extra.join(" ")
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
                let model = under(spec, law, extra)
                    .expect("the law is checked in run; a variant is a valid leaf");
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
    Ok(())
}
