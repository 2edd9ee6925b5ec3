//! The MAP-Elites archive (Mouret & Clune 2015): the best leaf of every
//! cell of descent speed × rotation rate seen over a run.

use super::population::{ArchiveEntry, Individual};

/// Edges of the archive's descent-speed bins, m/s (log-spaced: gentle
/// floaters at 0.2–0.5 m/s, edge-on divers at 3–10 m/s).
pub const ARCHIVE_DESCENT_EDGES: [f64; 9] = [0.0, 0.25, 0.4, 0.6, 0.9, 1.4, 2.2, 3.5, 5.5];
/// Edges of the archive's rotation-rate bins, rad/s (steady floaters below
/// 0.5; autorotating spinners at 5–70, docs/design/falling-plates.md, "Folded
/// leaves under the linear law").
pub const ARCHIVE_SPIN_EDGES: [f64; 9] = [0.0, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0];

fn bin(edges: &[f64], value: f64) -> usize {
    edges.iter().rposition(|&e| value >= e).unwrap_or(0)
}

/// The archive cell (descent bin, rotation bin) of a fall of mean descent
/// `descent_m_s` and rotation rate `spin_rad_s`.
pub fn cell(descent_m_s: f64, spin_rad_s: f64) -> (usize, usize) {
    (
        bin(&ARCHIVE_DESCENT_EDGES, descent_m_s),
        bin(&ARCHIVE_SPIN_EDGES, spin_rad_s),
    )
}

/// Adds a generation's evaluated individuals to the archive: each cell keeps
/// the highest score (ties: the lower id). Diverged falls have no
/// descriptors and are not archived. Entries stay sorted by cell.
pub(crate) fn update_archive(
    archive: &mut Vec<ArchiveEntry>,
    generation: usize,
    population: &[Individual],
) {
    for (ind, fall) in population
        .iter()
        .filter(|i| !i.elite)
        .filter_map(|i| Some((i, i.eval.fall()?)))
    {
        let cell = cell(fall.descent_m_s, fall.spin_rad_s);
        let better = |e: &ArchiveEntry| {
            ind.eval.score > e.individual.eval.score
                || (ind.eval.score == e.individual.eval.score && ind.id < e.individual.id)
        };
        match archive.binary_search_by_key(&cell, |e| (e.descent_bin, e.spin_bin)) {
            Ok(k) if better(&archive[k]) => {
                archive[k] = ArchiveEntry {
                    descent_bin: cell.0,
                    spin_bin: cell.1,
                    generation,
                    individual: ind.clone(),
                }
            }
            Ok(_) => {}
            Err(k) => archive.insert(
                k,
                ArchiveEntry {
                    descent_bin: cell.0,
                    spin_bin: cell.1,
                    generation,
                    individual: ind.clone(),
                },
            ),
        }
    }
}
