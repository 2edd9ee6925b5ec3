//! The work-precision plot of an accuracy sweep.

use super::sweep::{SweepReport, TOLERANCES};
use crate::physics::params::Integrator;
use crate::util::svg::{PlotError, SIZE, min_max};
use plotters::prelude::*;

/// One colour per integrator (colour-blind-safe Okabe–Ito hues).
fn colour(integrator: Integrator) -> RGBColor {
    match integrator {
        Integrator::Euler => RGBColor(213, 94, 0),
        Integrator::Symplectic => RGBColor(230, 159, 0),
        Integrator::Verlet => RGBColor(0, 114, 178),
        Integrator::Rk4 => RGBColor(0, 158, 115),
        Integrator::Implicit => RGBColor(204, 121, 167),
    }
}

/// The SVG text of the work-precision plot of `report`: log error (RMS
/// position error at T over the chord) against log wall time, one curve per
/// integrator; diverged runs are crosses along the top edge at their wall
/// time (they have no error); dashed lines mark the tolerances of the table
/// and the reference's self-difference (the noise floor).
///
/// # Errors
/// A message if plotters fails (it writes to memory, so only on a bug).
pub fn work_precision_svg(report: &SweepReport, title: &str) -> Result<String, PlotError> {
    let finite: Vec<(f64, f64)> = report
        .rows
        .iter()
        .filter_map(|r| r.error.map(|e| (r.wall_s, e)))
        .filter(|&(w, e)| w > 0.0 && e > 0.0)
        .collect();
    let walls = report
        .rows
        .iter()
        .map(|r| r.wall_s)
        .filter(|&w| w > 0.0)
        .collect::<Vec<_>>();
    let (w_min, w_max) = min_max(&walls).unwrap_or((1e-6, 1.0));
    let floor = report.reference.self_difference.max(1e-300);
    let errors: Vec<f64> = finite.iter().map(|p| p.1).chain([floor]).collect();
    let (e_min, e_max) = min_max(&errors).unwrap_or((1e-12, 1.0));
    let x_range = (w_min / 2.0)..(w_max * 2.0);
    // Room above the largest error for the row of diverged markers.
    let y_top = (e_max * 30.0).max(TOLERANCES[0] * 10.0);
    let y_range = (e_min / 3.0)..y_top;
    let x_desc = format!(
        "wall time per run, s (median of {} timed runs, stepping only)",
        report.runs
    );
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(PlotError::of)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d(x_range.log_scale(), y_range.log_scale())
            .map_err(PlotError::of)?;
        chart
            .configure_mesh()
            .x_desc(x_desc.as_str())
            .y_desc("RMS particle position error at T / chord")
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .light_line_style(WHITE.mix(0.0))
            .axis_desc_style(("sans-serif", 17))
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(PlotError::of)?;
        let grey = RGBColor(120, 120, 120);
        let (x0, x1) = (w_min / 2.0, w_max * 2.0);
        for (level, label) in TOLERANCES
            .iter()
            .map(|&t| (t, format!("{t:.0e}")))
            .map(|(t, l)| (t, format!("error {l}")))
            .chain([(floor, "reference self-difference".to_string())])
        {
            chart
                .draw_series(DashedLineSeries::new(
                    [(x0, level), (x1, level)],
                    6,
                    4,
                    grey.stroke_width(1),
                ))
                .map_err(PlotError::of)?;
            chart
                .draw_series([Text::new(
                    label,
                    (x0 * 1.15, level * 1.8),
                    ("sans-serif", 15).into_font().color(&grey),
                )])
                .map_err(PlotError::of)?;
        }
        let diverged_y = y_top / 2.0;
        for integrator in Integrator::ALL {
            let c = colour(integrator);
            let rows: Vec<_> = report
                .rows
                .iter()
                .filter(|r| r.integrator == integrator)
                .collect();
            if rows.is_empty() {
                continue;
            }
            let curve: Vec<(f64, f64)> = rows
                .iter()
                .filter_map(|r| r.error.map(|e| (r.wall_s, e)))
                .filter(|&(w, e)| w > 0.0 && e > 0.0)
                .collect();
            chart
                .draw_series(LineSeries::new(curve.clone(), c.stroke_width(2)))
                .map_err(PlotError::of)?
                .label(integrator.name())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(2))
                });
            chart
                .draw_series(curve.iter().map(|&p| Circle::new(p, 3, c.filled())))
                .map_err(PlotError::of)?;
            chart
                .draw_series(
                    rows.iter()
                        .filter(|r| r.unstable() && r.wall_s > 0.0)
                        .map(|r| Cross::new((r.wall_s, diverged_y), 5, c.stroke_width(2))),
                )
                .map_err(PlotError::of)?;
        }
        // A legend entry for the crosses (they have no error to plot).
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(PlotError::of)?
            .label("unstable (stopped, or ringing at T)")
            .legend(|(x, y)| Cross::new((x + 12, y), 5, BLACK.stroke_width(2)));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font(("sans-serif", 16))
            .draw()
            .map_err(PlotError::of)?;
        root.present().map_err(PlotError::of)?;
    }
    Ok(svg)
}
