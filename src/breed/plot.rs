//! The plots of a breeding run: class counts per generation, and the
//! example's fall against the best leaf's.

use super::population::{GenerationSummary, OutcomeKind};
use crate::motion::trajectory::Trajectory;
use crate::util::svg::{PlotError, legend, legend_mark};
use plotters::prelude::*;

/// The SVG text of a breeding run's class counts per generation: one line
/// per outcome (floater, spinner, lilter, undetermined, diverged).
///
/// # Errors
/// A message if plotters fails (it writes to memory, so only on a bug).
pub fn generations_svg(history: &[GenerationSummary], title: &str) -> Result<String, PlotError> {
    // In OutcomeKind::ALL's order.
    const COLOURS: [RGBColor; 5] = [
        RGBColor(0, 114, 178),
        RGBColor(213, 94, 0),
        RGBColor(0, 158, 115),
        RGBColor(120, 120, 120),
        RGBColor(0, 0, 0),
    ];
    let last = history.last().map_or(1, |h| h.generation.max(1));
    let top = history
        .iter()
        .map(|h| h.counts.max())
        .max()
        .unwrap_or(1)
        .max(1);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(PlotError::of)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(16)
            .x_label_area_size(44)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..last as f64, 0.0..(top as f64 * 1.1))
            .map_err(PlotError::of)?;
        chart
            .configure_mesh()
            .x_desc("generation")
            .y_desc("individuals")
            .x_labels(last + 1)
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_label_formatter(&|v| format!("{v:.0}"))
            .light_line_style(WHITE.mix(0.0))
            .axis_desc_style(("sans-serif", 16))
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(PlotError::of)?;
        for (kind, colour) in OutcomeKind::ALL.into_iter().zip(COLOURS) {
            if history.iter().all(|h| h.counts[kind] == 0) {
                continue;
            }
            let points: Vec<(f64, f64)> = history
                .iter()
                .map(|h| (h.generation as f64, h.counts[kind] as f64))
                .collect();
            chart
                .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
                .map_err(PlotError::of)?
                .label(kind.name())
                .legend(legend_mark(colour, 2));
            chart
                .draw_series(
                    points
                        .into_iter()
                        .map(|p| Circle::new(p, 3, colour.filled())),
                )
                .map_err(PlotError::of)?;
        }
        legend(&mut chart, SeriesLabelPosition::MiddleRight)?;
        root.present().map_err(PlotError::of)?;
    }
    Ok(svg)
}

/// Rotation rates of a fall, rad/s, averaged over 0.1 s windows: (time,
/// rate about the vertical, rate about the horizontal axes). From the
/// world-frame rotation between successive orientations, ω ≈ log(q₁ q₀⁻¹)/Δt.
fn rotation_rates(fall: &Trajectory) -> Vec<(f64, f64, f64)> {
    let mut out = Vec::new();
    // A record without orientation (video of a real fall) has no rates.
    if !fall.has_orientation() {
        return out;
    }
    let mut k = 0;
    while k + 1 < fall.len() {
        let t0 = fall.time[k];
        let mut j = k + 1;
        while j + 1 < fall.len() && fall.time[j] - t0 < 0.1 {
            j += 1;
        }
        let (mut vertical, mut horizontal) = (0.0, 0.0);
        for i in k..j {
            let w = (fall.orientation[i + 1] * fall.orientation[i].inverse()).scaled_axis();
            vertical += w.z;
            horizontal += w.xy().norm();
        }
        let span = (fall.time[j] - t0).max(f64::MIN_POSITIVE);
        out.push((
            0.5 * (t0 + fall.time[j]),
            vertical / span,
            horizontal / span,
        ));
        k = j;
    }
    out
}

/// A chart of something against time, s, with the axes drawn.
fn time_panel<'a, 'b>(
    area: &'a DrawingArea<SVGBackend<'b>, plotters::coord::Shift>,
    t_max: f64,
    y: std::ops::Range<f64>,
    y_desc: &str,
) -> Result<
    ChartContext<
        'a,
        SVGBackend<'b>,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    PlotError,
> {
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t_max, y)
        .map_err(PlotError::of)?;
    chart
        .configure_mesh()
        .x_desc("time, s")
        .y_desc(y_desc)
        .light_line_style(WHITE.mix(0.0))
        .axis_desc_style(("sans-serif", 16))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(PlotError::of)?;
    Ok(chart)
}

/// The SVG text overlaying an example fall and the best bred leaf's fall:
/// height against time (each from its own start) above, and the rotation
/// rates about the vertical and the horizontal axes below.
///
/// # Errors
/// A message if plotters fails (it writes to memory, so only on a bug).
pub fn like_svg(
    example: Option<&Trajectory>,
    best: &Trajectory,
    title: &str,
) -> Result<String, PlotError> {
    const EXAMPLE: RGBColor = RGBColor(213, 94, 0);
    const BEST: RGBColor = RGBColor(0, 114, 178);
    let falls: Vec<(&str, RGBColor, &Trajectory)> = example
        .map(|e| ("example", EXAMPLE, e))
        .into_iter()
        .chain([("best leaf", BEST, best)])
        .collect();
    let heights: Vec<Vec<(f64, f64)>> = falls
        .iter()
        .map(|(_, _, f)| {
            let z0 = f.position.first().map_or(0.0, |p| p.z);
            f.time
                .iter()
                .zip(&f.position)
                .map(|(&t, p)| (t, p.z - z0))
                .collect()
        })
        .collect();
    let rates: Vec<Vec<(f64, f64, f64)>> =
        falls.iter().map(|(_, _, f)| rotation_rates(f)).collect();
    let t_max = falls
        .iter()
        .filter_map(|(_, _, f)| f.time.last().copied())
        .fold(1e-3, f64::max);
    let z_min = heights.iter().flatten().map(|p| p.1).fold(-1e-3, f64::min);
    let (r_min, r_max) = rates
        .iter()
        .flatten()
        .fold((0.0f64, 1e-3f64), |(lo, hi), r| {
            (lo.min(r.1).min(r.2), hi.max(r.1).max(r.2))
        });
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 720)).into_drawing_area();
        root.fill(&WHITE).map_err(PlotError::of)?;
        let root = root
            .titled(title, ("sans-serif", 20))
            .map_err(PlotError::of)?;
        let (upper, lower) = root.split_vertically(330);
        let mut chart = time_panel(&upper, t_max, (z_min * 1.05)..0.0, "height fallen, m")?;
        for ((name, colour, _), points) in falls.iter().zip(&heights) {
            let colour = *colour;
            chart
                .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
                .map_err(PlotError::of)?
                .label(*name)
                .legend(legend_mark(colour, 2));
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;

        // Headroom above the rates for the four-line legend, so it covers
        // none of them.
        let pad = 0.05 * (r_max - r_min);
        let mut chart = time_panel(
            &lower,
            t_max,
            (r_min - pad)..(r_max + 14.0 * pad),
            "rotation rate, rad/s (0.1 s means)",
        )?;
        for ((name, colour, _), r) in falls.iter().zip(&rates) {
            let colour = *colour;
            let vertical: Vec<(f64, f64)> = r.iter().map(|p| (p.0, p.1)).collect();
            let horizontal: Vec<(f64, f64)> = r.iter().map(|p| (p.0, p.2)).collect();
            chart
                .draw_series(LineSeries::new(vertical, colour.stroke_width(2)))
                .map_err(PlotError::of)?
                .label(format!("{name}: about the vertical"))
                .legend(legend_mark(colour, 2));
            chart
                .draw_series(DashedLineSeries::new(
                    horizontal,
                    6,
                    4,
                    colour.stroke_width(1),
                ))
                .map_err(PlotError::of)?
                .label(format!("{name}: about the horizontal (|ω_h|)"))
                .legend(legend_mark(colour, 1));
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        root.present().map_err(PlotError::of)?;
    }
    Ok(svg)
}
