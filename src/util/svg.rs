//! What every SVG plot shares (plotters' SVG backend): the size, the legend
//! and finite ranges. Text goes into the file as `<text>` elements for the
//! viewer to render, so no font files are read and none need be installed
//! (plotters is built without its `ttf` feature; text extents are
//! estimated). The plots themselves live with what they show:
//! [`crate::sim::accuracy::plot`], [`crate::breed::plot`].

use plotters::prelude::*;

/// A plot that plotters could not draw (it draws into memory, so only a bug
/// or an impossible range gets here).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct PlotError(pub String);

impl PlotError {
    /// Wraps what plotters reports.
    pub fn of(e: impl std::fmt::Display) -> PlotError {
        PlotError(e.to_string())
    }
}

/// Plot size, pixels.
pub const SIZE: (u32, u32) = (960, 640);

/// The smallest and largest finite value, if any.
pub fn min_max(values: &[f64]) -> Option<(f64, f64)> {
    let lo = values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .reduce(f64::min)?;
    let hi = values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .reduce(f64::max)?;
    Some((lo, hi))
}

/// The legend box of the generation and example plots.
pub fn legend<'a, 'b: 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, SVGBackend<'b>, CT>,
    position: SeriesLabelPosition,
) -> Result<(), PlotError> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(PlotError::of)
}

/// A legend entry's mark: a short line in the series' colour and width.
pub fn legend_mark(colour: RGBColor, width: u32) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(width))
}
