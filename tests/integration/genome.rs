//! Leaf variation: every variant is a valid model, and the same seed gives
//! the same variant.

use leafmagic::leaf::LeafSpec;
use leafmagic::leaf::genome::{Genome, mutate};
use proptest::prelude::*;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Chains of mutations at any scale stay within the bounds and build.
    #[test]
    fn mutation_never_produces_an_invalid_model(seed in any::<u64>(), scale in 0.0f64..4.0, proto in prop::sample::select(vec!["a", "b"])) {
        let spec = LeafSpec::load(proto).unwrap();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut g = Genome::of_prototype(&spec);
        for _ in 0..8 {
            g = mutate(&g, &spec.bounds, scale, &mut rng);
            let b = &spec.bounds;
            prop_assert!(g.fold_deg.iter().all(|f| (b.fold_deg[0]..=b.fold_deg[1]).contains(f)));
            prop_assert!(g.mass_factor.iter().all(|m| (b.mass_factor[0]..=b.mass_factor[1]).contains(m)));
            prop_assert!((b.size_factor[0]..=b.size_factor[1]).contains(&g.size_factor));
            let model = g.model(&spec);
            prop_assert!(model.is_ok(), "{:?}", model.err());
        }
    }
}

#[test]
fn invalid_bounds_are_rejected_by_name() {
    let mut spec = LeafSpec::load("a").unwrap();
    spec.bounds.mass_factor = [2.0, 1.0];
    let err = spec.model().unwrap_err();
    assert_eq!(err.item, "bounds.mass_factor");
    spec.bounds.mass_factor = [0.0, 1.0];
    assert_eq!(spec.model().unwrap_err().item, "bounds.mass_factor");
}
