//! How much of a file a reader samples: the limits every reader of another
//! tool's keys (glTF, USD, Alembic) holds, so that a corrupt or mis-scaled
//! file is refused with its reason instead of asking for more frames or
//! memory than any machine has, and the rate a file's own keys are read at.

use crate::formats::clip::frame_count;

/// Highest rate a file's keys are sampled at, Hz (a glTF file read at its
/// own keys, a USD stage's time codes, an Alembic archive's samples): keys closer than this (a
/// duplicated key, a bake at a solver's substep) are not worth a frame each;
/// ten times a 98 fps camera, twice the 240 Hz `drop` records at, still
/// resolves every fall leafmagic classifies.
pub const MAX_KEY_RATE_HZ: f64 = 1000.0;

/// Most frames a clip is read at: 1000 s of keys at [`MAX_KEY_RATE_HZ`],
/// or 11 hours at 24 fps; key times past it are in the wrong unit or
/// corrupt, and would otherwise ask for more memory than any machine has.
pub const MAX_FRAMES: usize = 1_000_000;

/// Most vertex positions a deforming clip is read with (its frames times
/// its vertices): 1.2 GB of them.
pub const MAX_SAMPLED_POINTS: usize = 50_000_000;

/// How many frames sample `start..=end` (s) at `fps`, or why not: at most
/// [`MAX_FRAMES`].
pub(crate) fn sampled_frames(start: f64, end: f64, fps: f64) -> Result<usize, String> {
    let span = (end - start) * fps;
    if !(span.is_finite() && span < MAX_FRAMES as f64) {
        return Err(format!(
            "its keys run from {start} s to {end} s, {span:.0} frames at {fps} Hz: more than the {MAX_FRAMES} this reader samples (are its times in seconds?)"
        ));
    }
    Ok(frame_count(start, end, fps))
}

/// Checks that `frames` frames of `vertices` vertices each stay within
/// [`MAX_SAMPLED_POINTS`].
pub(crate) fn check_points(object: &str, frames: usize, vertices: usize) -> Result<(), String> {
    if frames.saturating_mul(vertices) > MAX_SAMPLED_POINTS {
        return Err(format!(
            "`{object}`: {vertices} vertices at {frames} frames are more than the {MAX_SAMPLED_POINTS} positions this reader holds"
        ));
    }
    Ok(())
}

/// The rate to sample keys at whose shortest interval (between consecutive
/// keys of any channel) is `shortest` seconds: its reciprocal, at most
/// [`MAX_KEY_RATE_HZ`], rounded to 1e-3 Hz (glTF stores times as f32, which
/// keeps 7 digits: 1/24 s reads back as 0.041666668, whose reciprocal is
/// 23.99999..), and at least 0.001 Hz; `None` without an interval (no key,
/// or one).
pub(crate) fn key_rate(shortest: f64) -> Option<f64> {
    if !(shortest.is_finite() && shortest > 0.0) {
        return None;
    }
    let rate = (1.0 / shortest).min(MAX_KEY_RATE_HZ);
    // Keys over 1000 s apart round to 0.001 Hz, not to 0.
    Some(((rate * 1000.0).round() / 1000.0).max(1e-3))
}
