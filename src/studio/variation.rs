//! The next generation from a person's picks: variations of the picks at
//! the session's (shrinking) scale, crossovers between two picks, and a
//! few wild cards so the grid does not collapse onto one lineage (the
//! known failure of interactive evolution: docs/guide/studio.md).
//!
//! Wild cards from the archive's empty cells: the session's archive is
//! breed's MAP-Elites archive (Mouret & Clune 2015) over every candidate
//! evaluated so far: per cell of descent speed × rotation rate
//! ([`crate::breed::archive::cell`]) the best-scoring leaf that fell into
//! it. A cell the grid has not shown lately is one that no candidate of
//! the generation bred from occupies (so none of the picks either). The
//! rule, simple and deterministic: when such cells exist, the first wild
//! card of a grid is a variation of the elite of one of them, the
//! `index mod n`-th of the n such cells in cell order for generation
//! `index` (a choice that moves with the index and the set, with no
//! memory to forbid a cell twice running); the other wild cards stay
//! uniform draws. It offers the person a kind of fall the
//! tree found once and the grid has since left, which a uniform draw
//! rarely hits (MAP-Elites' point: illumination keeps the stepping stones).
//!
//! Mutation and uniform draws are breeding's own
//! ([`crate::leaf::genome::mutate`], [`crate::breed::selection::uniform`]);
//! what is new here is only who the parents are and how many of each kind
//! a grid gets.

use crate::breed::selection::{plan, stream_seed, uniform};
use crate::breed::settings::BreedSettings;
use crate::leaf::LeafSpec;
use crate::leaf::genome::{Genome, mutate};
use rand::RngExt;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};

/// How a candidate was made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Origin {
    /// Generation 0: a varied copy of the prototype.
    Prototype,
    /// Generation 0: a uniform draw over the prototype's bounds.
    Uniform,
    /// A variation of one pick.
    Variation,
    /// A crossover of two picks, then varied.
    Crossover,
    /// A wild card: a uniform draw over the bounds, no parent.
    Wild,
    /// A wild card from the archive: a variation of the elite of a cell
    /// the grid has not shown lately (its one parent).
    Archive,
}

/// Wild cards in a grid of `grid`: one in a small grid, two from 10 on
/// (a sixth to a tenth of the grid: enough to offer a way out of a
/// lineage, few enough to leave the picks' children the room).
pub fn wild_cards(grid: usize) -> usize {
    if grid >= 10 { 2 } else { 1 }
}

/// Crossovers in a grid of `grid` bred from `picks` picks: none from one
/// pick, else a quarter of the grid (at least one).
pub fn crossovers(grid: usize, picks: usize) -> usize {
    if picks < 2 { 0 } else { (grid / 4).max(1) }
}

/// Generation 0 of a session: breed's own generation 0 (half varied
/// copies of the prototype, half uniform draws), `settings.population`
/// of them.
pub fn first_generation(settings: &BreedSettings, proto: &LeafSpec) -> Vec<Child> {
    let copies = crate::breed::selection::initial_copies(settings);
    plan(settings, proto, None)
        .children
        .into_iter()
        .map(|c| Child {
            origin: if (c.id as usize) < copies {
                Origin::Prototype
            } else {
                Origin::Uniform
            },
            id: c.id,
            parents: Vec::new(),
            genome: c.genome,
        })
        .collect()
}

/// The `grid` children of `picks` (id and genome; at least one): [`crossovers`] of them
/// crossovers of pairs of picks (every pair in turn), [`wild_cards`] wild
/// cards last, the rest variations of the picks in turn; ids from
/// `first_id`; with an `archive` elite (id and genome), the first wild card
/// is a variation of it. Every child draws from its own stream of
/// (`seed`, id), so the same picks and seed give the same children.
pub fn children_of(
    picks: &[(u64, &Genome)],
    archive: Option<(u64, &Genome)>,
    proto: &LeafSpec,
    grid: usize,
    scale: f64,
    seed: u64,
    first_id: u64,
) -> Vec<Child> {
    assert!(!picks.is_empty(), "at least one pick");
    let bounds = &proto.bounds;
    let wild = wild_cards(grid);
    let cross = crossovers(grid, picks.len());
    let varied = grid - wild - cross;
    let pairs: Vec<(usize, usize)> = (0..picks.len())
        .flat_map(|a| (a + 1..picks.len()).map(move |b| (a, b)))
        .collect();
    (0..grid)
        .map(|k| {
            let id = first_id + k as u64;
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(seed, 0, id));
            if k < varied {
                let (parent, genome) = picks[k % picks.len()];
                Child {
                    id,
                    origin: Origin::Variation,
                    parents: vec![parent],
                    genome: mutate(genome, bounds, scale, &mut rng),
                }
            } else if k < varied + cross {
                let (a, b) = pairs[(k - varied) % pairs.len()];
                let (a, b) = (picks[a], picks[b]);
                let mixed = crossover(a.1, b.1, proto, &mut rng);
                Child {
                    id,
                    origin: Origin::Crossover,
                    parents: vec![a.0, b.0],
                    genome: mutate(&mixed, bounds, scale, &mut rng),
                }
            } else if let Some((elite, genome)) = archive.filter(|_| k == varied + cross) {
                Child {
                    id,
                    origin: Origin::Archive,
                    parents: vec![elite],
                    genome: mutate(genome, bounds, scale, &mut rng),
                }
            } else {
                Child {
                    id,
                    origin: Origin::Wild,
                    parents: Vec::new(),
                    genome: uniform(&Genome::of_prototype(proto), bounds, &mut rng),
                }
            }
        })
        .collect()
}

/// Uniform crossover in the unit box of the prototype's bounds: every gene
/// from one parent or the other, half and half (Sims 1991's mating of two
/// picks). In coordinates, so the child is within the bounds whatever the
/// parents are.
pub fn crossover<R: rand::Rng + ?Sized>(
    a: &Genome,
    b: &Genome,
    proto: &LeafSpec,
    rng: &mut R,
) -> Genome {
    let bounds = &proto.bounds;
    let (ua, ub) = (a.coordinates(bounds), b.coordinates(bounds));
    let u: Vec<f64> = ua
        .iter()
        .zip(&ub)
        .map(|(x, y)| if rng.random_bool(0.5) { *x } else { *y })
        .collect();
    a.with_coordinates(bounds, &u)
}

/// The elite the first wild card of generation `index` varies: of the
/// `archive` cells (sorted by cell) that none of `shown` (the cells of the
/// generation bred from) is, the `index mod n`-th; none if every cell was
/// shown.
pub fn archive_elite<'a>(
    archive: &'a [crate::breed::population::ArchiveEntry],
    shown: &[(usize, usize)],
    index: usize,
) -> Option<&'a crate::breed::population::Individual> {
    let unshown: Vec<_> = archive
        .iter()
        .filter(|e| !shown.contains(&(e.descent_bin, e.spin_bin)))
        .collect();
    (!unshown.is_empty()).then(|| &unshown[index % unshown.len()].individual)
}

/// A child before evaluation.
#[derive(Clone, Debug, PartialEq)]
pub struct Child {
    /// Its id.
    pub id: u64,
    /// How it was made.
    pub origin: Origin,
    /// Its parents' ids.
    pub parents: Vec<u64>,
    /// Its genome.
    pub genome: Genome,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_is_variations_crossovers_and_wild_cards() {
        assert_eq!((wild_cards(4), wild_cards(12), wild_cards(20)), (1, 2, 2));
        assert_eq!(crossovers(12, 1), 0);
        assert_eq!(crossovers(12, 2), 3);
        assert_eq!(crossovers(4, 3), 1);
    }

    #[test]
    fn crossover_takes_every_gene_from_a_parent() {
        let proto = LeafSpec::load("a").unwrap();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        let a = Genome::of_prototype(&proto);
        let b = uniform(&a, &proto.bounds, &mut rng);
        let c = crossover(&a, &b, &proto, &mut rng);
        let (ua, ub, uc) = (
            a.coordinates(&proto.bounds),
            b.coordinates(&proto.bounds),
            c.coordinates(&proto.bounds),
        );
        for ((x, y), z) in ua.iter().zip(&ub).zip(&uc) {
            assert!((z - x).abs() < 1e-9 || (z - y).abs() < 1e-9, "{x} {y} {z}");
        }
        assert!(c.check(&proto).is_ok());
    }
}
