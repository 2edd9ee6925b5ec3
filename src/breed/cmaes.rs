//! CMA-ES, the covariance matrix adaptation evolution strategy, written
//! against Hansen, "The CMA Evolution Strategy: A Tutorial" (2016,
//! arXiv:1604.00772; equation numbers below are the tutorial's): a normal
//! search distribution N(m, σ² C) over the unit box of the genome
//! ([`crate::leaf::genome::Genome::coordinates`]) whose mean, step size and
//! covariance (per-gene step sizes and their correlations) are learned from
//! the ranking of each generation's samples.
//!
//! Own code rather than a crate: the strategy's whole state must go into the
//! run's checkpoint and be checked on resume, every sample must come from
//! the individual's own seeded stream (same bytes for any thread count), and
//! the update is some forty lines; nalgebra (already a dependency) does the
//! eigendecomposition.
//!
//! **Bounds.** A sample outside the box is mirrored back into it
//! (reflection at each face, [`reflect`]), and the mirrored point is what is
//! evaluated and what the update learns from: the genome always lies within
//! the prototype's bounds, and the distribution follows the points that
//! were actually judged. Only positive recombination weights are used (no
//! active CMA).

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// Smallest and largest step size σ in the unit box: below 1e-9 no gene
/// moves, above 1 every sample is a uniform draw over the bounds anyway.
pub const SIGMA_RANGE: [f64; 2] = [1e-9, 1.0];
/// Smallest standard deviation of a coordinate when the distribution
/// starts (a gene with no spread would make C singular).
const MIN_START_SD: f64 = 1e-4;

/// The whole state of the strategy: what the checkpoint holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CmaState {
    /// Samples per generation, λ.
    pub lambda: usize,
    /// The mean m, in unit-box coordinates.
    pub mean: Vec<f64>,
    /// The step size σ.
    pub sigma: f64,
    /// The covariance C, n × n, row-major.
    pub covariance: Vec<f64>,
    /// The evolution path of σ, p_σ.
    pub path_sigma: Vec<f64>,
    /// The evolution path of C, p_c.
    pub path_c: Vec<f64>,
    /// Updates made (the tutorial's generation counter g).
    pub updates: u64,
}

/// The strategy parameters of the tutorial's Table 1 for dimension `n` and
/// `lambda` samples, positive weights only.
struct Parameters {
    weights: Vec<f64>,
    mu_eff: f64,
    c_sigma: f64,
    d_sigma: f64,
    c_c: f64,
    c_1: f64,
    c_mu: f64,
    /// E‖N(0, I)‖ ≈ √n (1 − 1/(4n) + 1/(21n²)).
    chi_n: f64,
}

impl Parameters {
    fn new(n: usize, lambda: usize) -> Parameters {
        let nf = n as f64;
        let mu = (lambda / 2).max(1);
        let raw: Vec<f64> = (1..=mu)
            .map(|i| ((lambda as f64 + 1.0) / 2.0).ln() - (i as f64).ln())
            .collect();
        let sum: f64 = raw.iter().sum();
        let weights: Vec<f64> = raw.iter().map(|w| w / sum).collect();
        let mu_eff = 1.0 / weights.iter().map(|w| w * w).sum::<f64>();
        let c_sigma = (mu_eff + 2.0) / (nf + mu_eff + 5.0);
        let d_sigma = 1.0 + 2.0 * (((mu_eff - 1.0) / (nf + 1.0)).sqrt() - 1.0).max(0.0) + c_sigma;
        let c_c = (4.0 + mu_eff / nf) / (nf + 4.0 + 2.0 * mu_eff / nf);
        let c_1 = 2.0 / ((nf + 1.3).powi(2) + mu_eff);
        let c_mu =
            (1.0 - c_1).min(2.0 * (mu_eff - 2.0 + 1.0 / mu_eff) / ((nf + 2.0).powi(2) + mu_eff));
        Parameters {
            weights,
            mu_eff,
            c_sigma,
            d_sigma,
            c_c,
            c_1,
            c_mu: c_mu.max(0.0),
            chi_n: nf.sqrt() * (1.0 - 1.0 / (4.0 * nf) + 1.0 / (21.0 * nf * nf)),
        }
    }
}

/// `x` mirrored into [0, 1] at each face (periodic reflection, so any real
/// number lands in the box).
pub fn reflect(x: f64) -> f64 {
    if !x.is_finite() {
        return 0.5;
    }
    let t = x.rem_euclid(2.0);
    if t > 1.0 { 2.0 - t } else { t }
}

/// A state that cannot be resumed: what is wrong with it.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {reason}")]
pub struct CmaError {
    /// The field.
    pub field: String,
    /// Why.
    pub reason: String,
}

impl CmaState {
    /// A distribution centred on `mean` with per-coordinate standard
    /// deviations `sds` × `scale`: C = diag(sds²) / s̄², σ = `scale` s̄ with s̄
    /// the root mean square of `sds`, so σ carries the overall step and C
    /// the shape (the tutorial's choice of a diagonal C₀).
    pub fn start(mean: Vec<f64>, sds: &[f64], scale: f64, lambda: usize) -> CmaState {
        let n = mean.len();
        let sds: Vec<f64> = sds.iter().map(|s| s.max(MIN_START_SD)).collect();
        let rms = (sds.iter().map(|s| s * s).sum::<f64>() / n.max(1) as f64).sqrt();
        let mut covariance = vec![0.0; n * n];
        for (k, s) in sds.iter().enumerate() {
            covariance[k * n + k] = (s / rms).powi(2);
        }
        CmaState {
            lambda: lambda.max(2),
            mean: mean.into_iter().map(reflect).collect(),
            sigma: (scale * rms).clamp(SIGMA_RANGE[0], SIGMA_RANGE[1]),
            covariance,
            path_sigma: vec![0.0; n],
            path_c: vec![0.0; n],
            updates: 0,
        }
    }

    fn dim(&self) -> usize {
        self.mean.len()
    }

    fn c(&self) -> DMatrix<f64> {
        let n = self.dim();
        DMatrix::from_row_slice(n, n, &self.covariance)
    }

    /// B and D of C = B D² Bᵀ (eq. 10), eigenvalues floored at 0.
    fn eigen(&self) -> (DMatrix<f64>, DVector<f64>) {
        let e = SymmetricEigen::new(self.c());
        let d = e.eigenvalues.map(|v| v.max(0.0).sqrt());
        (e.eigenvectors, d)
    }

    /// One sample x = m + σ B D z, z ~ N(0, I) drawn from `rng` (eq. 38–40),
    /// mirrored into the unit box.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64> {
        let n = self.dim();
        let (b, d) = self.eigen();
        let z = DVector::from_iterator(n, (0..n).map(|_| StandardNormal.sample(rng)));
        let y = &b * d.component_mul(&z);
        (0..n)
            .map(|k| reflect(self.mean[k] + self.sigma * y[k]))
            .collect()
    }

    /// The update from one generation's samples, best first (eq. 41–47):
    /// mean, step-size path and σ (cumulative step-size adaptation),
    /// covariance path and the rank-one and rank-μ updates of C.
    pub fn update(&mut self, ranked: &[Vec<f64>]) {
        let n = self.dim();
        if ranked.is_empty() || n == 0 {
            return;
        }
        let p = Parameters::new(n, ranked.len());
        let m = DVector::from_column_slice(&self.mean);
        let ys: Vec<DVector<f64>> = ranked
            .iter()
            .take(p.weights.len())
            .map(|x| (DVector::from_column_slice(x) - &m) / self.sigma)
            .collect();
        let y_w = ys
            .iter()
            .zip(&p.weights)
            .fold(DVector::zeros(n), |acc, (y, w)| acc + y * *w);
        let new_mean = &m + &y_w * self.sigma;
        // C^{-1/2} = B D⁻¹ Bᵀ.
        let (b, d) = self.eigen();
        let d_inv = d.map(|v| if v > 0.0 { 1.0 / v } else { 0.0 });
        let c_inv_sqrt = &b * DMatrix::from_diagonal(&d_inv) * b.transpose();
        let ps = DVector::from_column_slice(&self.path_sigma) * (1.0 - p.c_sigma)
            + &c_inv_sqrt * &y_w * (p.c_sigma * (2.0 - p.c_sigma) * p.mu_eff).sqrt();
        let ps_norm = ps.norm();
        let g = (self.updates + 1) as f64;
        let h_sigma = ps_norm / (1.0 - (1.0 - p.c_sigma).powf(2.0 * g)).sqrt()
            < (1.4 + 2.0 / (n as f64 + 1.0)) * p.chi_n;
        let h = if h_sigma { 1.0 } else { 0.0 };
        let pc = DVector::from_column_slice(&self.path_c) * (1.0 - p.c_c)
            + &y_w * (h * (p.c_c * (2.0 - p.c_c) * p.mu_eff).sqrt());
        let delta_h = (1.0 - h) * p.c_c * (2.0 - p.c_c);
        let mut c =
            self.c() * (1.0 + p.c_1 * delta_h - p.c_1 - p.c_mu) + &pc * pc.transpose() * p.c_1;
        for (y, w) in ys.iter().zip(&p.weights) {
            c += y * y.transpose() * (p.c_mu * w);
        }
        // Symmetric by construction; rounding is made symmetric exactly.
        let c = (&c + c.transpose()) * 0.5;
        self.sigma = (self.sigma * ((p.c_sigma / p.d_sigma) * (ps_norm / p.chi_n - 1.0)).exp())
            .clamp(SIGMA_RANGE[0], SIGMA_RANGE[1]);
        self.mean = new_mean.iter().map(|&x| x.clamp(0.0, 1.0)).collect();
        self.path_sigma = ps.iter().copied().collect();
        self.path_c = pc.iter().copied().collect();
        self.covariance = c.transpose().iter().copied().collect();
        self.updates += 1;
    }

    /// Checks a state read back from a checkpoint for dimension `n`: sizes,
    /// finite numbers, σ in [`SIGMA_RANGE`], the mean in the box, C
    /// symmetric with a positive diagonal.
    ///
    /// # Errors
    /// The first field that fails, with the reason.
    pub fn check(&self, n: usize) -> Result<(), CmaError> {
        let fail = |field: &str, reason: String| {
            Err(CmaError {
                field: field.to_string(),
                reason,
            })
        };
        for (field, len, want) in [
            ("mean", self.mean.len(), n),
            ("path_sigma", self.path_sigma.len(), n),
            ("path_c", self.path_c.len(), n),
            ("covariance", self.covariance.len(), n * n),
        ] {
            if len != want {
                return fail(field, format!("{len} numbers, but the genome needs {want}"));
            }
        }
        if self.lambda < 2 {
            return fail("lambda", format!("{} samples; at least 2", self.lambda));
        }
        if !(SIGMA_RANGE[0] <= self.sigma && self.sigma <= SIGMA_RANGE[1]) {
            return fail(
                "sigma",
                format!(
                    "{} is outside [{}, {}]",
                    self.sigma, SIGMA_RANGE[0], SIGMA_RANGE[1]
                ),
            );
        }
        let all = self
            .mean
            .iter()
            .chain(&self.path_sigma)
            .chain(&self.path_c)
            .chain(&self.covariance);
        if all.clone().any(|v| !v.is_finite()) {
            return fail("(numbers)", "a number is not finite".to_string());
        }
        if self.mean.iter().any(|x| !(0.0..=1.0).contains(x)) {
            return fail("mean", "a coordinate is outside the unit box".to_string());
        }
        for i in 0..n {
            if self.covariance[i * n + i] <= 0.0 {
                return fail("covariance", format!("diagonal entry {i} is not positive"));
            }
            for j in 0..i {
                if self.covariance[i * n + j] != self.covariance[j * n + i] {
                    return fail("covariance", format!("not symmetric at ({i}, {j})"));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    #[test]
    fn reflection_lands_in_the_box_and_is_the_identity_inside() {
        assert_eq!(reflect(0.25), 0.25);
        assert!((reflect(1.25) - 0.75).abs() < 1e-15);
        assert!((reflect(-0.25) - 0.25).abs() < 1e-15);
        assert!((reflect(2.25) - 0.25).abs() < 1e-15);
        assert_eq!(reflect(f64::NAN), 0.5);
    }

    /// The exact oracle of an evolution strategy: on a convex quadratic
    /// with a badly scaled, rotated Hessian CMA-ES converges linearly to
    /// its minimum, learning C ∝ H⁻¹.
    #[test]
    fn it_finds_the_minimum_of_an_ill_conditioned_rotated_ellipsoid() {
        let n = 6;
        let centre: Vec<f64> = (0..n).map(|k| 0.3 + 0.07 * k as f64).collect();
        // f(x) = Σ 10^(3k/(n−1)) ((R(x − c))_k)², R a fixed rotation.
        let r = {
            let a = DMatrix::from_fn(n, n, |i, j| {
                ((i * 7 + j * 3) % 5) as f64 - 2.0 + (i == j) as u8 as f64 * 3.0
            });
            a.qr().q()
        };
        let f = |x: &[f64]| {
            let d = DVector::from_iterator(n, x.iter().zip(&centre).map(|(a, b)| a - b));
            let y = &r * d;
            (0..n)
                .map(|k| 10f64.powf(3.0 * k as f64 / (n - 1) as f64) * y[k] * y[k])
                .sum::<f64>()
        };
        let mut state = CmaState::start(vec![0.5; n], &[0.1; 6], 2.0, 12);
        for g in 0..300u64 {
            let mut samples: Vec<Vec<f64>> = (0..state.lambda as u64)
                .map(|i| state.sample(&mut Xoshiro256PlusPlus::seed_from_u64(g * 1000 + i)))
                .collect();
            samples.sort_by(|a, b| f(a).total_cmp(&f(b)));
            state.update(&samples);
            assert_eq!(state.check(n), Ok(()));
        }
        assert!(f(&state.mean) < 1e-12, "f(m) = {}", f(&state.mean));
        // Same draws, same state: the update is deterministic.
        let a = CmaState::start(vec![0.5; n], &[0.1; 6], 1.0, 8);
        let mut b = a.clone();
        let mut c = a.clone();
        let s: Vec<Vec<f64>> = (0..8)
            .map(|i| a.sample(&mut Xoshiro256PlusPlus::seed_from_u64(i)))
            .collect();
        b.update(&s);
        c.update(&s);
        assert_eq!(b, c);
    }

    #[test]
    fn a_damaged_state_names_its_field() {
        let s = CmaState::start(vec![0.5; 3], &[0.1; 3], 1.0, 6);
        assert_eq!(s.check(3), Ok(()));
        assert_eq!(s.check(4).unwrap_err().field, "mean");
        let mut bad = s.clone();
        bad.sigma = 0.0;
        assert_eq!(bad.check(3).unwrap_err().field, "sigma");
        let mut bad = s.clone();
        bad.covariance[1] = 0.5;
        assert_eq!(bad.check(3).unwrap_err().field, "covariance");
        let mut bad = s;
        bad.path_c[0] = f64::NAN;
        assert!(bad.check(3).is_err());
    }
}
