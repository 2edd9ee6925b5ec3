//! The human reports of recorded falls: a classification (`classify`, and
//! the end of `drop`), one fall's descriptors (`describe`) and two falls'
//! descriptors side by side (`compare`).

use super::text;
use leafmagic::motion::class::MotionClass;
use leafmagic::motion::classify::Classification;
use leafmagic::motion::describe::{self, Descriptors};
use leafmagic::motion::path::PathFeatures;
use std::fmt::Write as _;
use std::path::Path;

/// A classification's class, regime and reason, and the features behind it.
pub fn class(c: &Classification) -> String {
    let f = &c.features;
    text(|out| {
        writeln!(out, "class           {} ({})", c.class, c.regime)?;
        if let Some(reason) = &c.reason {
            writeln!(out, "reason          {reason}")?;
        }
        if let Some(p) = &c.path {
            return path_lines(out, c, p);
        }
        writeln!(
            out,
            "descent         {:.3} m/s mean, drift ratio {:.2}, {:.1} chords in the window {:.2}–{:.2} s",
            f.mean_descent_speed_m_s, f.drift_ratio, f.descent_chords, f.t_start_s, f.t_end_s
        )?;
        writeln!(
            out,
            "rotation        {:.2} net turns, {} reversals, {} flips, {:.2} yaw turns, tilt {:.1}° ± {:.1}°",
            f.net_turns, f.reversals, f.normal_flips, f.yaw_turns, f.tilt_mean_deg, f.tilt_std_deg
        )
    })
}

/// The lines of a decision from the path (and areas): the inputs, and the
/// features behind it.
fn path_lines(out: &mut String, c: &Classification, p: &PathFeatures) -> std::fmt::Result {
    writeln!(out, "inputs          {}", c.inputs.describe())?;
    // A record refused before it was measured (too short, too slow) has
    // nothing more to show.
    if p.t_end_s <= p.t_start_s {
        return Ok(());
    }
    writeln!(
        out,
        "record          {:.1} Hz, window {:.2}–{:.2} s, {} gaps ({:.3} s missing, longest {:.3} s)",
        p.sample_rate_hz, p.t_start_s, p.t_end_s, p.gaps, p.interpolated_s, p.longest_gap_s
    )?;
    // Refused before the path was measured (too gappy).
    if p.samples == 0 {
        return Ok(());
    }
    writeln!(
        out,
        "noise           {:.1} mm vertical, {:.1} mm horizontal (estimated), {} samples on the grid",
        1e3 * p.position_noise_m,
        1e3 * p.horizontal_noise_m,
        p.samples
    )?;
    writeln!(
        out,
        "descent         {:.3} m/s mean (Froude {:.2}), modulation {:.2}, {:.1} chords",
        p.mean_descent_speed_m_s, p.froude_number, p.descent_speed_cv, p.descent_chords
    )?;
    writeln!(
        out,
        "path            drift ratio {:.2} ({:.0}° from vertical), straightness {:.2}, {} reversals, {:.2} turns",
        p.drift_ratio, p.glide_angle_deg, p.straightness, p.reversals, p.path_turns
    )?;
    if let (Some(m), Some(w), Some(r)) = (
        p.area_maxima_per_s,
        p.area_turn_rate_rad_s,
        p.area_periodicity,
    ) {
        writeln!(
            out,
            "areas           {} signals, {m:.1} maxima per second (≈ {w:.1} rad/s about a horizontal axis), periodicity {r:.2}",
            p.area_signals
        )?;
    }
    Ok(())
}

/// `classify`: the file, its length in samples, and its classification.
pub fn classified(path: &Path, samples: usize, c: &Classification) -> String {
    text(|out| {
        writeln!(
            out,
            "trajectory      {} ({samples} samples)",
            path.display()
        )?;
        out.push_str(&class(c));
        Ok(())
    })
}

/// `classify --all`: the file, then each fall of it on a line (its name,
/// when it lives, its class and regime), then the tally and what was left
/// out.
pub fn classified_each(
    path: &Path,
    clip: &leafmagic::formats::clip::Clip,
    classes: &[Option<Classification>],
) -> String {
    text(|out| {
        writeln!(
            out,
            "file            {} ({} objects, {} keys at {} Hz)",
            path.display(),
            clip.objects.len(),
            clip.frames,
            clip.fps
        )?;
        let width = clip
            .objects
            .iter()
            .zip(classes)
            .filter(|(_, c)| c.is_some())
            .map(|(o, _)| o.name.chars().count())
            .max()
            .unwrap_or(0)
            .max("object".len());
        writeln!(
            out,
            "{:width$}  {:>13}  class (regime)",
            "object", "life (s)"
        )?;
        for (o, c) in clip.objects.iter().zip(classes) {
            let Some(c) = c else { continue };
            let (first, last) = o.life_s(clip.fps);
            writeln!(
                out,
                "{:width$}  {:>13}  {} ({})",
                o.name,
                format!("{first:.2}–{last:.2}"),
                c.class,
                c.regime
            )?;
        }
        let tally = super::output::class_tally(classes.iter().flatten().map(|c| c.class.as_str()));
        writeln!(
            out,
            "classified      {}",
            if tally.is_empty() { "none" } else { &tally }
        )?;
        let left = classes.iter().filter(|c| c.is_none()).count();
        if left > 0 {
            writeln!(
                out,
                "left out        {left} object{} that {} not fall (still, a rope or a prop)",
                if left == 1 { "" } else { "s" },
                if left == 1 { "does" } else { "do" }
            )?;
        }
        Ok(())
    })
}

/// Classes in words, as `--expect` lists them: `floater`, `floater or
/// spinner`, `floater, spinner or lilter`.
pub fn either(classes: &[MotionClass]) -> String {
    let names: Vec<&str> = classes.iter().map(|c| c.as_str()).collect();
    match names.split_last() {
        None => String::new(),
        Some((last, [])) => (*last).to_string(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
    }
}

/// `classify --expect`: the expected classes, how many of the `falls`
/// falls have one, and each that does not (its name, class and regime).
pub fn verdicts(
    expected: &[MotionClass],
    falls: usize,
    wrong: &[&(String, &Classification)],
) -> String {
    text(|out| {
        writeln!(out, "expected        {}", either(expected))?;
        writeln!(
            out,
            "as expected     {} of {falls} fall{}",
            falls - wrong.len(),
            if falls == 1 { "" } else { "s" }
        )?;
        for (name, c) in wrong {
            writeln!(out, "not expected    {name}: {} ({})", c.class, c.regime)?;
        }
        Ok(())
    })
}

/// `describe`: the file, its class (with the inputs and reason), and each
/// descriptor with its unit, its scale in distances and what it measures,
/// or why the record could not give it.
pub fn described(
    path: &Path,
    samples: usize,
    c: &Classification,
    d: Option<&Descriptors>,
) -> String {
    text(|out| {
        writeln!(
            out,
            "fall            {} ({samples} samples)",
            path.display()
        )?;
        writeln!(out, "class           {} ({})", c.class, c.regime)?;
        writeln!(out, "inputs          {}", c.inputs.describe())?;
        let Some(d) = d else {
            // Undetermined: its reason is all there is.
            if let Some(reason) = &c.reason {
                writeln!(out, "reason          {reason}")?;
            }
            return writeln!(out, "descriptors     none (an undetermined fall has none)");
        };
        writeln!(out)?;
        writeln!(
            out,
            "{:<18} {:>12} {:>7}  what it measures",
            "descriptor", "value", "scale"
        )?;
        for k in 0..describe::NAMES.len() {
            let label = describe::label(k);
            let v = d.values[k];
            let (cell, meaning) = if !d.measured[k] {
                (
                    "—".to_string(),
                    format!("not measured: {}", describe::unmeasured_because(k)),
                )
            } else if c.path.is_some() && describe::NAMES[k] == "tumble" {
                // Without orientation the turn rate comes from the areas.
                (
                    format!("{v:.3}"),
                    "rotation rate about a horizontal axis, π × area maxima per second".to_string(),
                )
            } else if v.is_finite() {
                (format!("{v:.3}"), describe::MEANINGS[k].to_string())
            } else {
                ("none".to_string(), describe::MEANINGS[k].to_string())
            };
            writeln!(
                out,
                "{label:<18} {cell:>12} {:>7}  {meaning}",
                describe::SCALES[k]
            )?;
        }
        let measured = d.measured.iter().filter(|&&m| m).count();
        writeln!(
            out,
            "\nmeasured        {measured} of {}; a distance to this fall (`compare`, `breed --like`) uses those {measured}, each in units of its scale",
            describe::NAMES.len()
        )
    })
}

/// `compare`: the two files, their descriptors as a table, and their
/// distance (infinite between different classes).
pub fn comparison(
    (path_a, a): (&Path, &Descriptors),
    (path_b, b): (&Path, &Descriptors),
    distance: f64,
) -> String {
    text(|out| {
        writeln!(out, "a: {}\nb: {}\n", path_a.display(), path_b.display())?;
        out.push_str(&describe::table(&[("a", a), ("b", b)]));
        if distance.is_finite() {
            writeln!(
                out,
                "\ndistance    {distance:.4} (RMS over descriptors, each in units of its reference spread)"
            )
        } else {
            writeln!(
                out,
                "\ndistance    ∞: different classes ({} vs {}) are never close",
                a.class, b.class
            )
        }
    })
}
