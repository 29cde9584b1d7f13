//! Speed and head-height profiles over distance (the planner's output along a route).

use std::path::Path;

use plotters::prelude::*;

use super::fonts::{FAMILY, ensure_registered};

/// One instruction's share of a profile: samples over arc length.
#[derive(Debug, Clone, Default)]
pub struct ProfileSegment {
    /// Label drawn at the segment's start ("run to the car").
    pub label: String,
    /// Distance from the route's start \[m\].
    pub distance: Vec<f64>,
    /// Planned speed \[m/s\].
    pub speed: Vec<f64>,
    /// Speed cap before the optimisation (locomotion, head height, slope, lateral) \[m/s\].
    pub speed_cap: Vec<f64>,
    /// Head height above the terrain \[m\].
    pub head_height: Vec<f64>,
    /// Headroom (ceiling minus terrain) where there is a ceiling \[m\].
    pub headroom: Vec<Option<f64>>,
}

/// Draw two stacked plots sharing the distance axis: speed (with its cap, dashed)
/// and head height (with the headroom under ceilings), instruction boundaries as
/// vertical lines. Writes a PNG at `out_png`.
pub fn render_profile(
    title: &str,
    segments: &[ProfileSegment],
    out_png: &Path,
) -> anyhow::Result<()> {
    ensure_registered()?;
    let d_max = segments
        .iter()
        .filter_map(|s| s.distance.last().copied())
        .fold(1.0f64, f64::max);
    let v_max = segments
        .iter()
        .flat_map(|s| {
            s.speed
                .iter()
                .chain(s.speed_cap.iter().filter(|v| v.is_finite()))
        })
        .fold(1.0f64, |a, &b| a.max(b))
        * 1.1;
    let root = BitMapBackend::new(out_png, (1200, 800)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, rest) = root.split_vertically(40);
    top.draw(&Text::new(
        title.to_string(),
        (12, 10),
        (FAMILY, 20).into_font().color(&BLACK),
    ))?;
    let (upper, lower) = rest.split_vertically(380);
    let speed_color = RGBColor(200, 40, 40);
    let cap_color = RGBColor(150, 150, 150);
    let head_color = RGBColor(30, 90, 200);
    let ceiling_color = RGBColor(230, 140, 20);

    let mut ch = ChartBuilder::on(&upper)
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .build_cartesian_2d(0.0..d_max, 0.0..v_max)?;
    ch.configure_mesh()
        .x_desc("distance [m]")
        .y_desc("speed [m/s]")
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 15))
        .draw()?;
    for (k, seg) in segments.iter().enumerate() {
        let cap: Vec<(f64, f64)> = seg
            .distance
            .iter()
            .zip(&seg.speed_cap)
            .map(|(&d, &v)| (d, v.min(v_max)))
            .collect();
        let s = ch.draw_series(DashedLineSeries::new(cap, 4, 3, cap_color.stroke_width(1)))?;
        if k == 0 {
            s.label("speed cap (locomotion, height, slope, lateral)")
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], cap_color));
        }
        let pts: Vec<(f64, f64)> = seg
            .distance
            .iter()
            .copied()
            .zip(seg.speed.iter().copied())
            .collect();
        let s = ch.draw_series(LineSeries::new(pts, speed_color.stroke_width(2)))?;
        if k == 0 {
            s.label("planned speed (QP)").legend(move |(x, y)| {
                PathElement::new([(x, y), (x + 20, y)], speed_color.stroke_width(2))
            });
        }
        if let Some(&d0) = seg.distance.first() {
            ch.draw_series(std::iter::once(PathElement::new(
                [(d0, 0.0), (d0, v_max)],
                BLACK.mix(0.4),
            )))?;
            ch.draw_series(std::iter::once(Text::new(
                seg.label.clone(),
                (d0 + 0.01 * d_max, v_max * 0.97),
                (FAMILY, 13).into_font(),
            )))?;
        }
    }
    ch.configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .label_font((FAMILY, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .draw()?;

    let h_max = segments
        .iter()
        .flat_map(|s| s.head_height.iter())
        .fold(1.6f64, |a, &b| a.max(b))
        * 1.1;
    let mut ch = ChartBuilder::on(&lower)
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .build_cartesian_2d(0.0..d_max, 0.0..h_max)?;
    ch.configure_mesh()
        .x_desc("distance [m]")
        .y_desc("head height above terrain [m]")
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 15))
        .draw()?;
    let mut roof_labelled = false;
    for (k, seg) in segments.iter().enumerate() {
        // Headroom under ceilings, as bars from the top of the plot.
        let bars: Vec<_> = seg
            .distance
            .windows(2)
            .zip(&seg.headroom)
            .filter_map(|(d, h)| {
                h.map(|h| {
                    Rectangle::new(
                        [(d[0], h.min(h_max)), (d[1], h_max)],
                        ceiling_color.mix(0.5).filled(),
                    )
                })
            })
            .collect();
        let any_roof = !bars.is_empty();
        let s = ch.draw_series(bars)?;
        if any_roof && !roof_labelled {
            roof_labelled = true;
            s.label("ceiling (headroom)").legend(move |(x, y)| {
                Rectangle::new(
                    [(x, y - 5), (x + 20, y + 5)],
                    ceiling_color.mix(0.5).filled(),
                )
            });
        }
        let pts: Vec<(f64, f64)> = seg
            .distance
            .iter()
            .copied()
            .zip(seg.head_height.iter().copied())
            .collect();
        let s = ch.draw_series(LineSeries::new(pts, head_color.stroke_width(2)))?;
        if k == 0 {
            s.label("planned head height").legend(move |(x, y)| {
                PathElement::new([(x, y), (x + 20, y)], head_color.stroke_width(2))
            });
        }
        if let Some(&d0) = seg.distance.first() {
            ch.draw_series(std::iter::once(PathElement::new(
                [(d0, 0.0), (d0, h_max)],
                BLACK.mix(0.4),
            )))?;
        }
    }
    ch.configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .label_font((FAMILY, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .draw()?;
    root.present()?;
    Ok(())
}
