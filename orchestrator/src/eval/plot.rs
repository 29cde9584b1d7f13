//! The experiments' charts: labelled scatter plots (the slalom Pareto plots) and bar
//! charts with confidence intervals.

use std::path::Path;

use plotters::prelude::*;

use crate::viz::{FAMILY, ensure_registered};

/// One series of a scatter plot.
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// Colour.
    pub color: RGBColor,
    /// Triangles instead of circles.
    pub triangles: bool,
    /// Join the points with a line (in the given order).
    pub line: bool,
    /// (x, y, label) per point.
    pub points: Vec<(f64, f64, String)>,
}

fn range(v: impl Iterator<Item = f64>, floor_zero: bool) -> std::ops::Range<f64> {
    let (lo, hi) = v
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    if !lo.is_finite() {
        return 0.0..1.0;
    }
    let lo = if floor_zero { lo.min(0.0) } else { lo };
    let pad = ((hi - lo) * 0.12).max(0.05 * hi.abs().max(1.0));
    (if floor_zero { lo } else { lo - pad })..(hi + pad)
}

/// A scatter plot of `series` into `path`; points with a non-finite coordinate are
/// left out (the markdown lists them).
pub fn scatter(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
) -> anyhow::Result<()> {
    ensure_registered()?;
    let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE)?;
    // Axes fit the points that are drawn.
    let all = || {
        series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|p| p.0.is_finite() && p.1.is_finite())
    };
    let xr = range(all().map(|p| p.0), false);
    let yr = range(all().map(|p| p.1), true);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FAMILY, 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(xr, yr)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .label_style((FAMILY, 14))
        .draw()?;
    for s in series {
        let c = s.color;
        let pts: Vec<(f64, f64, String)> = s
            .points
            .iter()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .cloned()
            .collect();
        if s.line && pts.len() > 1 {
            chart.draw_series(LineSeries::new(
                pts.iter().map(|p| (p.0, p.1)),
                c.stroke_width(1),
            ))?;
        }
        let tri = s.triangles;
        let anno = if tri {
            chart.draw_series(
                pts.iter()
                    .map(|p| TriangleMarker::new((p.0, p.1), 8, c.filled())),
            )?
        } else {
            chart.draw_series(pts.iter().map(|p| Circle::new((p.0, p.1), 6, c.filled())))?
        };
        anno.label(s.name.clone()).legend(move |(x, y)| {
            if tri {
                TriangleMarker::new((x + 5, y), 6, c.filled()).into_dyn()
            } else {
                Circle::new((x + 5, y), 5, c.filled()).into_dyn()
            }
        });
        chart.draw_series(pts.iter().map(|p| {
            EmptyElement::at((p.0, p.1))
                + Text::new(p.2.clone(), (8, -14), (FAMILY, 12).into_font())
        }))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FAMILY, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

/// One bar: label, value, optional (low, high) interval, colour.
pub struct Bar {
    /// Label under the bar.
    pub label: String,
    /// Height.
    pub value: f64,
    /// Confidence interval drawn as a whisker.
    pub interval: Option<(f64, f64)>,
    /// Fill colour.
    pub color: RGBColor,
}

/// A bar chart of `bars` into `path`, y from 0 to `y_max` (at least the tallest bar).
pub fn bars(
    path: &Path,
    title: &str,
    y_desc: &str,
    bars: &[Bar],
    y_max: f64,
) -> anyhow::Result<()> {
    ensure_registered()?;
    let root = BitMapBackend::new(path, (900, 520)).into_drawing_area();
    root.fill(&WHITE)?;
    let top = bars
        .iter()
        .map(|b| b.interval.map_or(b.value, |i| i.1).max(b.value))
        .filter(|v| v.is_finite())
        .fold(y_max, f64::max)
        * 1.08;
    let n = bars.len().max(1) as f64;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FAMILY, 20))
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..n, 0.0..top.max(1e-9))?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_desc(y_desc)
        .label_style((FAMILY, 14))
        .draw()?;
    for (i, b) in bars.iter().enumerate() {
        let x0 = i as f64 + 0.15;
        let x1 = i as f64 + 0.85;
        let v = if b.value.is_finite() { b.value } else { 0.0 };
        chart.draw_series(std::iter::once(Rectangle::new(
            [(x0, 0.0), (x1, v)],
            b.color.filled(),
        )))?;
        if let Some((lo, hi)) = b.interval {
            let xm = i as f64 + 0.5;
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(xm, lo), (xm, hi)],
                BLACK.stroke_width(2),
            )))?;
            for y in [lo, hi] {
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(xm - 0.1, y), (xm + 0.1, y)],
                    BLACK.stroke_width(2),
                )))?;
            }
        }
        chart.draw_series(std::iter::once(Text::new(
            format!("{v:.2}"),
            (x0 + 0.02, v + top * 0.02),
            (FAMILY, 13).into_font(),
        )))?;
        // Under the axis, in pixels: the chart area would clip it.
        let (px, py) = chart.backend_coord(&(x0, 0.0));
        root.draw(&Text::new(
            b.label.clone(),
            (px, py + 8),
            (FAMILY, 14).into_font(),
        ))?;
    }
    root.present()?;
    Ok(())
}
