//! Recomputes `describe::SCALES`: the standard deviation of every motion
//! descriptor across a reference population of falls, 200 variants each of
//! prototypes A and B at variation scale 1 (seeded), 10 s drops. Falls
//! that are undetermined or diverge have no descriptors and are left out;
//! a period counts only where the fall has one.
//!
//! `cargo run --release --example descriptor_scales` (about 4 s on 2 cores).

use leafmagic::leaf::LeafSpec;
use leafmagic::leaf::genome::{Genome, mutate};
use leafmagic::motion::classify::classify;
use leafmagic::motion::describe::{Descriptors, NAMES, SCALES};
use leafmagic::sim::drop::{DropParams, drop_leaf};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;

fn main() {
    leafmagic::util::pipe::quiet_broken_pipe();
    let mut falls: Vec<Descriptors> = Vec::new();
    for (p, seed) in [("a", 11u64), ("b", 12)] {
        let proto = LeafSpec::load(p).unwrap();
        let g0 = Genome::of_prototype(&proto);
        let described: Vec<Option<Descriptors>> = (0..200u64)
            .into_par_iter()
            .map(|k| {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed * 1000 + k);
                let model = mutate(&g0, &proto.bounds, 1.0, &mut rng)
                    .model(&proto)
                    .ok()?;
                let fall = drop_leaf(&model, &DropParams::default()).ok()?;
                Descriptors::of(&classify(&fall.trajectory, model.chord())).ok()
            })
            .collect();
        falls.extend(described.into_iter().flatten());
    }
    println!("{} described falls", falls.len());
    println!(
        "{:<12} {:>10} {:>10} {:>10}",
        "descriptor", "std", "SCALES", "n"
    );
    for (k, name) in NAMES.iter().enumerate() {
        let v: Vec<f64> = falls
            .iter()
            .map(|d| d.values[k])
            .filter(|v| v.is_finite())
            .collect();
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let std = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        println!("{name:<12} {std:>10.3} {:>10.3} {:>10}", SCALES[k], v.len());
    }
}
