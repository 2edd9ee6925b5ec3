//! Levenberg–Marquardt steps toward a motion target, from the population
//! itself: the hybrid's third way of breeding children (after the GA's and
//! CMA-ES's) in runs bred toward descriptors (`--like`,
//! `--target-features`).
//!
//! # Why
//!
//! The distance to an example is the root mean square of the scaled
//! descriptor differences r (`MotionTarget::residuals`), so breeding
//! toward it is a nonlinear least-squares problem, min ‖r(x)‖², over the
//! genes x. CMA-ES sees only the one number ‖r‖ and ranks; it learns the
//! shape of the valley over many generations (its covariance learning rate
//! is about μ_eff/n², some 70 generations for 16 genes and 24 samples).
//! The residual vector says much more: with its Jacobian J a Gauss–Newton
//! step solves the linearised problem at once. Measured on the spinner
//! example of the breeding benchmark (docs/design/breeding.md), forward-difference
//! Levenberg–Marquardt from the hybrid's best leaf at 364 leaves (distance
//! 0.021) reached 0.0057 in 18 drops and its floor, 0.0051, in 35; the
//! hybrid without them reached 0.0056 on that seed only after 1,804 leaves.
//!
//! # The step
//!
//! No extra drops are spent on derivatives. J is fitted by ridge
//! regression to the members of the evaluated population that have
//! residuals (those inside the target's class gate), as differences from
//! the best member b: with ΔX the gene differences (columns, in the unit
//! box of [`crate::leaf::genome::Genome::coordinates`], varied genes only)
//! and ΔR the residual differences,
//!
//!   J = ΔR ΔXᵀ (ΔX ΔXᵀ + ε I)⁻¹,  ε = [`RIDGE`] × tr(ΔX ΔXᵀ) / n,
//!
//! the least-squares linear model through b (CMA-ES's samples around its
//! mean give the spread this needs). Then for each damping λ of
//! [`DAMPING`] (Levenberg 1944, Marquardt 1963; scaled by diag JᵀJ as
//! Marquardt did, so that genes of any unit weigh alike):
//!
//!   (JᵀJ + λ diag(JᵀJ) + δ I) Δx = −Jᵀ r_b,  child = clamp(x_b + Δx, 0, 1).
//!
//! Small λ is the Gauss–Newton step, large λ a short step down the
//! gradient: the ladder spans both, one child each, so no line search (and
//! no state between generations) is needed. Everything is a function of
//! the evaluated population, so a resumed run and every shard worker
//! derive the same children, to the bit: the linear algebra is written out
//! here (Cholesky on at most a few dozen genes), not left to a library
//! whose kernels may choose their order by the CPU.

use super::population::Individual;
use crate::leaf::Bounds;
use crate::leaf::genome::Genome;

/// The damping ladder λ of the children of one generation, relative to
/// diag JᵀJ: from nearly Gauss–Newton to a short gradient step.
pub const DAMPING: [f64; 4] = [1e-3, 1e-2, 1e-1, 1.0];

/// How many children a generation gets from these steps: one per damping.
pub const STEPS: usize = DAMPING.len();

/// Ridge of the Jacobian's regression, relative to the mean squared gene
/// difference: keeps J defined when the members span fewer directions than
/// there are genes (J is then zero along the missing ones).
pub const RIDGE: f64 = 1e-6;

/// Fewest members besides the best with residuals for a fit.
pub const MIN_NEIGHBOURS: usize = 3;

/// Longest step, in the unit box (Euclidean, over the varied genes); a
/// step is also no longer than the farthest member the model was fitted
/// to: a linear model is not trusted beyond its data.
pub const MAX_STEP: f64 = 0.25;

/// The model is fitted to the nearest members, this many per varied gene.
pub const NEIGHBOURS_PER_GENE: usize = 2;

/// The children of one generation's Levenberg–Marquardt steps (module
/// docs), one per [`DAMPING`], from `population` (evaluated) within
/// `bounds`; empty when no member has residuals or too few neighbours do.
/// `template` gives the genome's shape (any genome of the prototype).
/// Also returns the member the steps start from (the best with residuals).
pub fn steps<'a>(
    population: &'a [Individual],
    bounds: &Bounds,
    template: &Genome,
) -> (Option<&'a Individual>, Vec<Genome>) {
    let Some(best) = population
        .iter()
        .filter(|i| !i.eval.residuals.is_empty())
        .min_by(|a, c| c.eval.score.total_cmp(&a.eval.score).then(a.id.cmp(&c.id)))
    else {
        return (None, Vec::new());
    };
    let varied: Vec<usize> = template
        .coordinate_sds(bounds)
        .iter()
        .enumerate()
        .filter(|(_, sd)| **sd > 0.0)
        .map(|(k, _)| k)
        .collect();
    let x_best = best.genome.coordinates(bounds);
    let r_best = &best.eval.residuals;
    let (n, m) = (varied.len(), r_best.len());
    // Differences from the best (varied genes only) of every other member
    // with residuals, nearest first.
    let norm = |d: &[f64]| d.iter().map(|v| v * v).sum::<f64>().sqrt();
    let mut near: Vec<(f64, Vec<f64>, Vec<f64>)> = population
        .iter()
        .filter(|i| i.id != best.id && i.eval.residuals.len() == m)
        .filter_map(|i| {
            let x = i.genome.coordinates(bounds);
            let d: Vec<f64> = varied.iter().map(|&k| x[k] - x_best[k]).collect();
            let r = i.eval.residuals.iter().zip(r_best).map(|(a, b)| a - b);
            let far = norm(&d);
            (far > 0.0).then(|| (far, d, r.collect()))
        })
        .collect();
    if n == 0 || near.len() < MIN_NEIGHBOURS {
        return (Some(best), Vec::new());
    }
    // The nearest members only: the linear model is local, and members of
    // other regions (the GA's children of other parents) would bend it.
    // (A stable sort: ties keep population order.)
    near.sort_by(|p, q| p.0.total_cmp(&q.0));
    near.truncate((NEIGHBOURS_PER_GENE * n).max(MIN_NEIGHBOURS));
    let reach = near.last().map_or(0.0, |p| p.0);
    let (dx, dr): (Vec<Vec<f64>>, Vec<Vec<f64>>) = near.into_iter().map(|(_, d, r)| (d, r)).unzip();
    let max_step = reach.min(MAX_STEP);
    let Some(jacobian) = fit_jacobian(&dx, &dr, n, m) else {
        return (Some(best), Vec::new());
    };
    // Normal equations of the linearised problem: A = JᵀJ, g = Jᵀ r_b.
    let mut a = vec![vec![0.0; n]; n];
    let mut g = vec![0.0; n];
    for p in 0..n {
        for q in 0..n {
            a[p][q] = (0..m).map(|row| jacobian[row][p] * jacobian[row][q]).sum();
        }
        g[p] = (0..m).map(|row| jacobian[row][p] * r_best[row]).sum();
    }
    let largest = (0..n).map(|p| a[p][p]).fold(0.0, f64::max);
    if largest <= 0.0 || !largest.is_finite() {
        return (Some(best), Vec::new());
    }
    let mut children = Vec::with_capacity(STEPS);
    for lambda in DAMPING {
        let mut damped = a.clone();
        for (p, row) in damped.iter_mut().enumerate() {
            row[p] += lambda * a[p][p] + 1e-12 * largest;
        }
        let Some(step) = cholesky(damped).and_then(|l| solve(&l, g.iter().map(|v| -v).collect()))
        else {
            return (Some(best), Vec::new());
        };
        let length = norm(&step);
        let shrink = if length > max_step {
            max_step / length
        } else {
            1.0
        };
        let mut x = x_best.clone();
        for (&k, s) in varied.iter().zip(&step) {
            x[k] = (x[k] + s * shrink).clamp(0.0, 1.0);
        }
        children.push(best.genome.with_coordinates(bounds, &x));
    }
    (Some(best), children)
}

/// J (m × n) = ΔR ΔXᵀ (ΔX ΔXᵀ + ε I)⁻¹ from the differences (one row of
/// `dx` and of `dr` per member).
fn fit_jacobian(dx: &[Vec<f64>], dr: &[Vec<f64>], n: usize, m: usize) -> Option<Vec<Vec<f64>>> {
    let mut gram = vec![vec![0.0; n]; n];
    for d in dx {
        for p in 0..n {
            for q in 0..n {
                gram[p][q] += d[p] * d[q];
            }
        }
    }
    let trace: f64 = (0..n).map(|p| gram[p][p]).sum();
    if trace <= 0.0 || !trace.is_finite() {
        return None;
    }
    let ridge = RIDGE * trace / n as f64;
    for (p, row) in gram.iter_mut().enumerate() {
        row[p] += ridge;
    }
    // Each row of J solves gram · jᵀ = ΔX · (that residual's differences):
    // one factorisation for all of them.
    let l = cholesky(gram)?;
    (0..m)
        .map(|row| {
            let rhs: Vec<f64> = (0..n)
                .map(|p| dx.iter().zip(dr).map(|(d, r)| d[p] * r[row]).sum())
                .collect();
            solve(&l, rhs)
        })
        .collect()
}

/// The Cholesky factor L (lower triangle, a = L Lᵀ) of symmetric positive
/// definite `a`, in place; `None` if it is not (numerically) positive
/// definite.
fn cholesky(mut a: Vec<Vec<f64>>) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    for j in 0..n {
        let d = a[j][j] - a[j][..j].iter().map(|v| v * v).sum::<f64>();
        if d <= 0.0 || !d.is_finite() {
            return None;
        }
        let d = d.sqrt();
        a[j][j] = d;
        for i in j + 1..n {
            let dot: f64 = a[i][..j].iter().zip(&a[j][..j]).map(|(p, q)| p * q).sum();
            a[i][j] = (a[i][j] - dot) / d;
        }
    }
    Some(a)
}

/// Solves L Lᵀ x = b with the factor of [`cholesky`]; `None` if the result
/// is not finite.
fn solve(l: &[Vec<f64>], mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    // L y = b, then Lᵀ x = y.
    for i in 0..n {
        for k in 0..i {
            b[i] -= l[i][k] * b[k];
        }
        b[i] /= l[i][i];
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            b[i] -= l[k][i] * b[k];
        }
        b[i] /= l[i][i];
    }
    b.iter().all(|v| v.is_finite()).then_some(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::breed::population::{Evaluation, Outcome};
    use crate::leaf::LeafSpec;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// A population of prototype A's genomes whose residuals are exactly
    /// linear in the unit coordinates, r = J (x − x*), with the optimum x*
    /// inside the box: the least-damped step lands on x* (Gauss–Newton is
    /// exact on a linear problem), and every step is closer than the best.
    #[test]
    fn on_linear_residuals_the_gauss_newton_step_lands_on_the_optimum() {
        let proto = LeafSpec::load("a").unwrap();
        let template = Genome::of_prototype(&proto);
        let bounds = proto.bounds.clone();
        let sds = template.coordinate_sds(&bounds);
        let varied: Vec<usize> = (0..sds.len()).filter(|&k| sds[k] > 0.0).collect();
        let n = sds.len();
        let optimum: Vec<f64> = (0..n)
            .map(|k| 0.3 + 0.4 * ((k as f64) * 0.37).sin().abs())
            .collect();
        // 24 residuals (more than genes, so x* is the only zero), each a
        // fixed mix of the varied genes.
        let jac = |row: usize, col: usize| {
            ((row * 7 + col * 3) as f64 * 0.61).sin() + if row == col { 2.0 } else { 0.0 }
        };
        let residual = |x: &[f64]| -> Vec<f64> {
            (0..24)
                .map(|row| {
                    varied
                        .iter()
                        .enumerate()
                        .map(|(c, &k)| jac(row, c) * (x[k] - optimum[k]))
                        .sum()
                })
                .collect()
        };
        let member = |id: u64, x: Vec<f64>| {
            let r = residual(&x);
            let d = (r.iter().map(|v| v * v).sum::<f64>() / r.len() as f64).sqrt();
            Individual {
                id,
                parent: None,
                elite: false,
                genome: template.with_coordinates(&bounds, &x),
                eval: Evaluation {
                    outcome: Outcome::Diverged(String::new()),
                    score: 1.0 + 1.0 / (1.0 + d),
                    distance: Some(d),
                    releases: 1,
                    kept: 1,
                    release_deg: [0.0; 2],
                    residuals: r,
                    spread: [0.0; 3],
                },
            }
        };
        // The best 0.01 from the optimum along every gene; the others
        // scattered 0.02 about it.
        let start: Vec<f64> = optimum.iter().map(|v| v + 0.01).collect();
        let mut population = vec![member(0, start.clone())];
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
        for id in 1..40u64 {
            let x: Vec<f64> = start
                .iter()
                .map(|v| v + 0.02 * rng.random_range(-1.0..1.0))
                .collect();
            population.push(member(id, x));
        }
        // Make member 0 the best: the others are farther only by chance.
        let best_score = population[0].eval.score;
        for i in &mut population[1..] {
            i.eval.score = i.eval.score.min(best_score - 1e-9);
        }
        let (from, children) = steps(&population, &bounds, &template);
        assert_eq!(from.unwrap().id, 0);
        assert_eq!(children.len(), STEPS);
        let gn = children[0].coordinates(&bounds);
        for &k in &varied {
            assert!(
                (gn[k] - optimum[k]).abs() < 1e-3,
                "gene {k}: {} against {}",
                gn[k],
                optimum[k]
            );
        }
        let norm = |r: Vec<f64>| r.iter().map(|v| v * v).sum::<f64>();
        let at_best = norm(residual(&start));
        for c in &children {
            assert!(norm(residual(&c.coordinates(&bounds))) < at_best);
        }
    }

    #[test]
    fn cholesky_solves_a_known_system() {
        let a = vec![
            vec![4.0, 2.0, 0.4],
            vec![2.0, 5.0, 1.0],
            vec![0.4, 1.0, 3.0],
        ];
        let x = [1.0, -2.0, 0.5];
        let b: Vec<f64> = a
            .iter()
            .map(|row| row.iter().zip(&x).map(|(p, q)| p * q).sum())
            .collect();
        let got = cholesky(a).and_then(|l| solve(&l, b)).unwrap();
        for (g, e) in got.iter().zip(x) {
            assert!((g - e).abs() < 1e-12, "{got:?}");
        }
        assert!(cholesky(vec![vec![1.0, 2.0], vec![2.0, 1.0]]).is_none());
    }

    /// On exactly linear residuals the regression recovers J, and the
    /// least-damped step lands on the least-squares solution.
    #[test]
    fn the_fit_recovers_a_linear_model() {
        let j = [
            [1.0, 0.5, 0.0],
            [0.0, 2.0, -1.0],
            [0.3, 0.0, 1.0],
            [1.0, 1.0, 1.0],
        ];
        let apply = |d: &[f64]| -> Vec<f64> {
            j.iter()
                .map(|row| row.iter().zip(d).map(|(p, q)| p * q).sum())
                .collect()
        };
        let dx: Vec<Vec<f64>> = (0..9)
            .map(|k| {
                let k = k as f64;
                vec![
                    (k * 0.7).sin() * 0.01,
                    (k * 1.3).cos() * 0.01,
                    (k * 0.4 + 1.0).sin() * 0.01,
                ]
            })
            .collect();
        let dr: Vec<Vec<f64>> = dx.iter().map(|d| apply(d)).collect();
        let fit = fit_jacobian(&dx, &dr, 3, 4).unwrap();
        for (row, expected) in fit.iter().zip(j) {
            for (g, e) in row.iter().zip(expected) {
                assert!((g - e).abs() < 1e-4, "{fit:?}");
            }
        }
    }
}
