//! The one-dimensional signal tools the path and area features share:
//! velocities by a local linear fit, the noise of a record, detrending
//! and periodicity.

/// Velocity by a local linear fit over ±`h` samples (truncated at the
/// ends), per unit of `dt`.
pub(super) fn slope(x: &[f64], h: usize, dt: f64, out: &mut Vec<f64>) {
    let n = x.len();
    out.clear();
    for k in 0..n {
        let (a, b) = (k.saturating_sub(h), (k + h).min(n - 1));
        let mean_j = 0.5 * (a + b) as f64;
        let (mut num, mut den) = (0.0, 0.0);
        for (j, &xj) in x.iter().enumerate().take(b + 1).skip(a) {
            let d = j as f64 - mean_j;
            num += d * xj;
            den += d * d;
        }
        out.push(if den > 0.0 { num / (den * dt) } else { 0.0 });
    }
}

/// The spread of independent noise on `x`, from its second differences
/// (which white noise of spread σ gives a spread of σ√6, and a smooth
/// path sampled fast nearly none): their median absolute value / (0.6745
/// √6), robust to the odd outlier.
pub(super) fn noise(x: &[f64]) -> f64 {
    if x.len() < 3 {
        return 0.0;
    }
    let mut d: Vec<f64> = x
        .windows(3)
        .map(|w| (w[0] - 2.0 * w[1] + w[2]).abs())
        .collect();
    let mid = d.len() / 2;
    let median = *d.select_nth_unstable_by(mid, f64::total_cmp).1;
    median / (0.6745 * 6f64.sqrt())
}

/// `y` minus its least-squares line.
pub(super) fn detrended(y: &[f64]) -> Vec<f64> {
    let m = y.len();
    let mean_t = 0.5 * (m.max(1) - 1) as f64;
    let mean_y = y.iter().sum::<f64>() / m.max(1) as f64;
    let (mut num, mut den) = (0.0, 0.0);
    for (k, v) in y.iter().enumerate() {
        let d = k as f64 - mean_t;
        num += d * (v - mean_y);
        den += d * d;
    }
    let b = if den > 0.0 { num / den } else { 0.0 };
    y.iter()
        .enumerate()
        .map(|(k, v)| v - mean_y - b * (k as f64 - mean_t))
        .collect()
}

/// Normalised autocorrelation of `y` (zero mean) at its first local maximum
/// after it first goes below zero; 0 if there is none within half the
/// record.
pub(super) fn periodicity(y: &[f64]) -> f64 {
    let n = y.len();
    let var: f64 = y.iter().map(|v| v * v).sum();
    if var <= 0.0 {
        return 0.0;
    }
    let r = |lag: usize| -> f64 {
        let s: f64 = (0..n - lag).map(|i| y[i] * y[i + lag]).sum();
        s / var * n as f64 / (n - lag) as f64
    };
    let half = n / 2;
    let mut lag = 1;
    while lag < half && r(lag) > 0.0 {
        lag += 1;
    }
    // Down to the trough, then up to the peak.
    let mut now = r(lag);
    while lag + 1 < half && r(lag + 1) <= now {
        lag += 1;
        now = r(lag);
    }
    while lag + 1 < half {
        let next = r(lag + 1);
        if next < now {
            return now.clamp(-1.0, 1.0);
        }
        lag += 1;
        now = next;
    }
    0.0
}
