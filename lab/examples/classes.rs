//! The figures of docs/design/classes.md ("Floaters, spinners, lilters"), from
//! real runs (10 s drops, Verlet, auto dt):
//!
//! ```sh
//! cargo run --release --example classes
//! ```
//!
//! 1. the square card under the quadratic law as its density rises (class
//!    of each of eight releases, the most common one, I*);
//! 2. the paper's recipes (families of 16) under both laws;
//! 3. one round of genome variation of each prototype (200 variants);
//! 4. the table of one leaf per class.

use leafmagic::leaf::genome::{Genome, mutate};
use leafmagic::leaf::plates::{self, square_card};
use leafmagic::leaf::recipes::Recipe;
use leafmagic::leaf::{AeroSpec, LeafSpec};
use leafmagic::motion::classify::{Classification, MotionClass, classify};
use leafmagic::physics::aero::quadratic::AIR_DENSITY;
use leafmagic::sim::drop::{DropParams, drop_leaf};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;
use std::collections::BTreeMap;

const CARD_SIDE: f64 = 0.05;

fn fall(spec: &LeafSpec, tilt: [f64; 2]) -> Classification {
    let model = spec.model().unwrap();
    let params = DropParams {
        tilt_deg: tilt,
        ..Default::default()
    };
    classify(
        &drop_leaf(&model, &params).unwrap().trajectory,
        model.chord(),
    )
}

fn label(c: &Classification) -> String {
    format!("{}/{}", c.class, c.regime)
}

fn tally<'a>(labels: impl IntoIterator<Item = &'a String>) -> String {
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    for l in labels {
        *counts.entry(l.as_str()).or_default() += 1;
    }
    counts
        .iter()
        .map(|(k, v)| format!("{v} {k}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn letter(c: MotionClass) -> char {
    match c {
        MotionClass::Floater => 'F',
        MotionClass::Spinner => 'S',
        MotionClass::Lilter => 'L',
        MotionClass::Undetermined => '?',
    }
}

fn card_sweep() {
    println!("## 1. Square card, side {CARD_SIDE} m, quadratic law, eight releases each");
    println!("σ (kg/m²)  I* (model)  σ/(12ρL)  classes   most common");
    let sigmas = [
        0.01, 0.02, 0.03, 0.04, 0.05, 0.055, 0.06, 0.065, 0.07, 0.08, 0.1, 0.12, 0.14, 0.16, 0.18,
        0.2, 0.22, 0.25, 0.3, 0.4, 0.5,
    ];
    for sigma in sigmas {
        let card = square_card(CARD_SIDE, sigma, AeroSpec::quadratic());
        let model = card.model().unwrap();
        let classes: Vec<MotionClass> = plates::RELEASE_ATTITUDES
            .par_iter()
            .map(|&t| fall(&card, t).class)
            .collect();
        let mut best = (MotionClass::Undetermined, 0);
        for c in [
            MotionClass::Floater,
            MotionClass::Lilter,
            MotionClass::Spinner,
        ] {
            let n = classes.iter().filter(|&&x| x == c).count();
            if n > best.1 {
                best = (c, n);
            } else if n == best.1 {
                best = (MotionClass::Undetermined, n);
            }
        }
        println!(
            "{sigma:<10} {:<11.3} {:<9.3} {}  {} ({}/8)",
            plates::i_star(&model, CARD_SIDE, AIR_DENSITY),
            sigma / (12.0 * AIR_DENSITY * CARD_SIDE),
            classes.iter().map(|&c| letter(c)).collect::<String>(),
            if best.0 == MotionClass::Undetermined {
                "tie".to_string()
            } else {
                best.0.to_string()
            },
            best.1
        );
    }
}

fn recipes() {
    println!("\n## 2. The paper's recipes, 16 variants each");
    for recipe in [Recipe::Floater, Recipe::Spinner, Recipe::Lilter] {
        for (law, quadratic) in [("linear", false), ("quadratic", true)] {
            let with_law = |mut spec: LeafSpec| {
                if quadratic {
                    spec.aero = AeroSpec::quadratic();
                }
                spec
            };
            let own = fall(&with_law(recipe.leaf()), [10.0, 2.0]);
            let labels: Vec<String> = (1..=16u64)
                .into_par_iter()
                .map(|seed| {
                    let (spec, tilt) = recipe.variant(seed);
                    label(&fall(&with_law(spec), tilt))
                })
                .collect();
            println!(
                "{recipe:?} recipe, {law} law: leaf {}; family {}",
                label(&own),
                tally(&labels)
            );
        }
    }
}

fn genome_rounds() {
    println!("\n## 3. One round of genome variation, 200 variants, linear law, default release");
    for (proto, scale) in [("a", 1.0), ("a", 2.5), ("b", 1.0)] {
        let spec = LeafSpec::load(proto).unwrap();
        let start = Genome::of_prototype(&spec);
        let labels: Vec<String> = (0..200u64)
            .into_par_iter()
            .map(|seed| {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
                let g = mutate(&start, &spec.bounds, scale, &mut rng);
                label(&fall(&g.to_leaf(&spec), [10.0, 2.0]))
            })
            .collect();
        println!("prototype {proto}, scale {scale}: {}", tally(&labels));
    }
}

fn table() {
    println!("\n## 4. One leaf per class");
    println!("| class | regime | leaf | law | σ (g/m²) | I* | descent (m/s) | drift ratio |");
    println!("|---|---|---|---|---|---|---|---|");
    let fixture = |name: &str| {
        LeafSpec::read(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join(format!("../tests/fixtures/{name}")),
        )
        .unwrap()
    };
    let rows: Vec<(String, LeafSpec, f64)> = vec![
        ("prototype A".into(), LeafSpec::load("a").unwrap(), 0.0),
        ("fixture a-floater".into(), fixture("a-floater.toml"), 0.0),
        ("spinner recipe".into(), Recipe::Spinner.leaf(), 0.0),
        ("fixture a-spinner".into(), fixture("a-spinner.toml"), 0.0),
        ("fixture a-tumbler".into(), fixture("a-tumbler.toml"), 0.0),
        ("prototype B".into(), LeafSpec::load("b").unwrap(), 0.0),
        ("fixture a-lilter".into(), fixture("a-lilter.toml"), 0.0),
        (
            "card 20 g/m²".into(),
            square_card(CARD_SIDE, 0.02, AeroSpec::quadratic()),
            CARD_SIDE,
        ),
        (
            "card 100 g/m²".into(),
            square_card(CARD_SIDE, 0.1, AeroSpec::quadratic()),
            CARD_SIDE,
        ),
        (
            "card 300 g/m²".into(),
            square_card(CARD_SIDE, 0.3, AeroSpec::quadratic()),
            CARD_SIDE,
        ),
    ];
    for (name, spec, side) in rows {
        let model = spec.model().unwrap();
        let c = fall(&spec, [10.0, 2.0]);
        let length = if side > 0.0 { side } else { model.chord() };
        let law = if matches!(model.aero, leafmagic::physics::model::AeroLaw::Linear) {
            "linear"
        } else {
            "quadratic"
        };
        println!(
            "| {} | {} | {name} | {law} | {:.0} | {:.3} | {:.2} | {:.2} |",
            c.class,
            c.regime,
            plates::areal_density(&model) * 1e3,
            plates::i_star(&model, length, AIR_DENSITY),
            c.features.mean_descent_speed_m_s,
            c.features.drift_ratio
        );
    }
}

fn main() {
    leafmagic::util::pipe::quiet_broken_pipe();
    let start = std::time::Instant::now();
    card_sweep();
    recipes();
    genome_rounds();
    table();
    eprintln!("\n({:.1} s)", start.elapsed().as_secs_f64());
}
