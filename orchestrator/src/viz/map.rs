//! The top-down scene map.

use std::path::Path;

use anyhow::Context;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use plamo_scenes::{Footprint, Motion, ObstacleShape, Region, Scene};

use super::colors::{TERRAIN_COLORS, color_at};
use super::fonts::{FAMILY, ensure_registered};
use super::overlay::{ColorBar, MapOverlay};

const TITLE_H: u32 = 44;
const SIDE_W: u32 = 230;
const MARGIN: u32 = 12;
const X_LABEL_H: u32 = 44;
const Y_LABEL_W: u32 = 56;
const MIN_H: u32 = 470;

const WALL: RGBColor = RGBColor(45, 45, 50);
const CEILING: RGBColor = RGBColor(230, 110, 20);
const MOVER: RGBColor = RGBColor(20, 170, 40);
const LANDMARK: RGBColor = RGBColor(120, 30, 160);

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

/// Render `scene` from above with `overlay` on top into a PNG at `out_png`.
///
/// The picture keeps metres equal along X and Y (10 to 60 px per metre, chosen from
/// the scene's size) and always shows: terrain height shading (hill-shaded) with its
/// colour bar, walls (dark), low ceilings (hatched orange, labelled with their
/// clearance above the ground), moving obstacles (their shape at t = 0 and their
/// path dashed), landmark regions (outlined, named), a scale bar, axes in metres and
/// a legend. Overlay paths and markers are drawn last.
pub fn render_map(scene: &Scene, overlay: &MapOverlay, out_png: &Path) -> anyhow::Result<()> {
    ensure_registered()?;
    let (lo, hi) = scene.terrain.bounds();
    let (w_m, h_m) = (hi[0] - lo[0], hi[1] - lo[1]);
    let ppm = (1100.0 / w_m).min(850.0 / h_m).clamp(10.0, 60.0);
    let plot_w = (w_m * ppm).round() as u32;
    let plot_h = (h_m * ppm).round() as u32;
    let chart_w = plot_w + Y_LABEL_W + 2 * MARGIN;
    let chart_h = plot_h + X_LABEL_H + 2 * MARGIN;
    let width = chart_w + SIDE_W;
    let height = TITLE_H + chart_h.max(MIN_H);

    let root = BitMapBackend::new(out_png, (width, height)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, body) = root.split_vertically(TITLE_H);
    let title = if overlay.title.is_empty() {
        format!("{}: {}", scene.name, scene.description)
    } else {
        overlay.title.clone()
    };
    top.draw(&Text::new(
        title,
        (MARGIN as i32, 12),
        (FAMILY, 20)
            .into_font()
            .style(FontStyle::Bold)
            .color(&BLACK),
    ))?;
    let (left, side) = body.split_horizontally(chart_w);
    let (chart_area, _) = left.split_vertically(chart_h);

    let mut chart = ChartBuilder::on(&chart_area)
        .margin(MARGIN)
        .x_label_area_size(X_LABEL_H)
        .y_label_area_size(Y_LABEL_W)
        .build_cartesian_2d(lo[0]..hi[0], lo[1]..hi[1])?;
    let (zmin, zmax) = scene.terrain.height_range();
    draw_terrain(&mut chart, scene, zmin, zmax)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x [m]")
        .y_desc("y [m]")
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 15))
        .x_labels(((w_m / 5.0).ceil() as usize + 1).clamp(3, 12))
        .y_labels(((h_m / 5.0).ceil() as usize + 1).clamp(3, 12))
        .draw()?;

    let px = |p: [f64; 2]| chart.backend_coord(&(p[0], p[1]));
    let m2px = ppm;

    // Low ceilings: translucent fill, hatching, outline.
    for top in &scene.tops {
        let poly = corners_px(&top.footprint, &px);
        root.draw(&Polygon::new(poly.clone(), CEILING.mix(0.18).filled()))?;
        hatch(&root, &poly, 9.0, CEILING.mix(0.85))?;
        root.draw(&PathElement::new(closed(&poly), CEILING.stroke_width(2)))?;
    }
    // Walls.
    for wall in &scene.walls {
        let poly = corners_px(&wall.footprint, &px);
        root.draw(&Polygon::new(poly.clone(), WALL.filled()))?;
        root.draw(&PathElement::new(closed(&poly), BLACK.stroke_width(1)))?;
    }
    // Moving obstacles: path dashed, shape at t = 0.
    for d in &scene.dynamic {
        let path: Vec<(i32, i32)> = motion_path(&d.motion).into_iter().map(&px).collect();
        dashed(&root, &path, 10.0, 7.0, MOVER.stroke_width(2))?;
        let s = d.motion.state_at(0.0);
        let c = px([s.position[0], s.position[1]]);
        match d.shape {
            ObstacleShape::Sphere { radius } => {
                let r = ((radius * m2px).round() as i32).max(4);
                root.draw(&Circle::new(c, r, MOVER.filled()))?;
                root.draw(&Circle::new(c, r, BLACK.stroke_width(1)))?;
            }
            ObstacleShape::Box { half_extents } => {
                let (hx, hy) = (
                    (half_extents[0] * m2px) as i32,
                    (half_extents[1] * m2px) as i32,
                );
                root.draw(&Rectangle::new(
                    [
                        (c.0 - hx.max(3), c.1 - hy.max(3)),
                        (c.0 + hx.max(3), c.1 + hy.max(3)),
                    ],
                    MOVER.filled(),
                ))?;
            }
        }
        label(
            &root,
            (c.0 + 8, c.1 - 8),
            &d.name,
            13,
            MOVER,
            Pos::new(HPos::Left, VPos::Bottom),
        )?;
    }
    // Landmarks.
    for l in &scene.landmarks {
        match l.region {
            Region::Circle { center, radius } => {
                let r = (radius * m2px).round() as i32;
                root.draw(&Circle::new(px(center), r, LANDMARK.mix(0.12).filled()))?;
                root.draw(&Circle::new(px(center), r, LANDMARK.stroke_width(3)))?;
            }
            Region::Rect { footprint } => {
                let poly = corners_px(&footprint, &px);
                root.draw(&Polygon::new(poly.clone(), LANDMARK.mix(0.12).filled()))?;
                root.draw(&PathElement::new(closed(&poly), LANDMARK.stroke_width(3)))?;
            }
        }
        let c = px(l.region.center());
        label(
            &root,
            c,
            &l.name,
            16,
            LANDMARK,
            Pos::new(HPos::Center, VPos::Center),
        )?;
    }
    // Ceiling clearances, after landmarks so walls and regions do not hide them.
    for top in &scene.tops {
        let clearance = min_headroom(scene, &top.footprint).unwrap_or(top.z_bottom);
        let text = format!("ceiling {clearance:.2} m");
        label(
            &root,
            px(top.footprint.center),
            &text,
            13,
            CEILING,
            Pos::new(HPos::Center, VPos::Center),
        )?;
    }

    // Overlay paths and markers.
    for p in &overlay.paths {
        let pts: Vec<(i32, i32)> = p.points.iter().map(|q| px(*q)).collect();
        for (k, seg) in pts.windows(2).enumerate() {
            let style = rgb(p.color_of_segment(k)).stroke_width(p.width.max(1));
            if p.dashed {
                dashed(&root, seg, 10.0, 6.0, style)?;
            } else {
                root.draw(&PathElement::new(seg.to_vec(), style))?;
            }
        }
    }
    for m in &overlay.markers {
        let c = px(m.at);
        root.draw(&Circle::new(c, 7, rgb(m.color).filled()))?;
        root.draw(&Circle::new(c, 7, BLACK.stroke_width(2)))?;
        if let Some(text) = &m.label {
            label(
                &root,
                (c.0 + 10, c.1),
                text,
                14,
                BLACK,
                Pos::new(HPos::Left, VPos::Center),
            )?;
        }
    }

    // Scale bar, bottom left inside the map.
    let (plot_x, plot_y) = chart.plotting_area().get_pixel_range();
    scale_bar(&root, (plot_x.start + 14, plot_y.end - 18), ppm, w_m)?;

    // Side panel: colour bars and legend.
    let mut y = MARGIN as i32;
    let bar_h = 190;
    let terrain_bar = ColorBar {
        label: "terrain height [m]".to_string(),
        min: zmin,
        max: zmax,
        colors: TERRAIN_COLORS.to_vec(),
    };
    color_bar(&side, (14, y), bar_h, &terrain_bar)?;
    if let Some(bar) = &overlay.colorbar {
        color_bar(&side, (120, y), bar_h, bar)?;
    }
    y += bar_h + 48;
    legend(&side, y, scene, overlay)?;

    root.present()
        .with_context(|| format!("cannot write {}", out_png.display()))?;
    Ok(())
}

fn draw_terrain<DB: DrawingBackend>(
    chart: &mut ChartContext<
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    scene: &Scene,
    zmin: f64,
    zmax: f64,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let g = &scene.terrain;
    let r = g.resolution;
    let (lo, hi) = g.bounds();
    let span = zmax - zmin;
    // Light from the north-west, 45 degrees up.
    let light = [-0.5, 0.5, std::f64::consts::FRAC_1_SQRT_2];
    let mut cells = Vec::with_capacity(g.nx * g.ny);
    for j in 0..g.ny {
        for i in 0..g.nx {
            let [x, y] = g.position(i, j);
            let h = g.heights[j * g.nx + i];
            let t = if span > 1e-9 { (h - zmin) / span } else { 0.0 };
            let base = color_at(&TERRAIN_COLORS, t);
            let n = g.normal_at(x, y);
            let lit = n[0] * light[0] + n[1] * light[1] + n[2] * light[2];
            let shade = (0.55 + 0.45 * lit / light[2]).clamp(0.45, 1.15);
            let c = base.map(|v| (v as f64 * shade).round().clamp(0.0, 255.0) as u8);
            let x0 = (x - r / 2.0).max(lo[0]);
            let y0 = (y - r / 2.0).max(lo[1]);
            let x1 = (x + r / 2.0).min(hi[0]);
            let y1 = (y + r / 2.0).min(hi[1]);
            cells.push(Rectangle::new([(x0, y0), (x1, y1)], rgb(c).filled()));
        }
    }
    chart
        .draw_series(cells)
        .map_err(|e| anyhow::anyhow!("drawing the terrain: {e}"))?;
    Ok(())
}

fn corners_px(fp: &Footprint, px: &impl Fn([f64; 2]) -> (i32, i32)) -> Vec<(i32, i32)> {
    fp.corners().iter().map(|c| px(*c)).collect()
}

fn closed(poly: &[(i32, i32)]) -> Vec<(i32, i32)> {
    let mut v = poly.to_vec();
    if let Some(first) = poly.first() {
        v.push(*first);
    }
    v
}

/// Smallest free height under a ceiling's footprint \[m\].
fn min_headroom(scene: &Scene, fp: &Footprint) -> Option<f64> {
    let g = &scene.terrain;
    let (lo, hi) = fp.aabb();
    let mut best: Option<f64> = None;
    let n = 24;
    for a in 0..=n {
        for b in 0..=n {
            let x = lo[0] + (hi[0] - lo[0]) * a as f64 / n as f64;
            let y = lo[1] + (hi[1] - lo[1]) * b as f64 / n as f64;
            if !(fp.contains(x, y) && g.contains(x, y)) {
                continue;
            }
            if let Some(h) = scene.headroom_at(x, y) {
                best = Some(best.map_or(h, |m: f64| m.min(h)));
            }
        }
    }
    best
}

/// Points along an obstacle's path \[m\] (one period, or 12 s for open-ended throws).
fn motion_path(m: &Motion) -> Vec<[f64; 2]> {
    match m {
        Motion::Linear { from, to, .. } => vec![[from[0], from[1]], [to[0], to[1]]],
        Motion::Waypoints { points, .. } => {
            let mut v: Vec<[f64; 2]> = points.iter().map(|p| [p[0], p[1]]).collect();
            if let Some(p) = points.first() {
                v.push([p[0], p[1]]);
            }
            v
        }
        Motion::Circle { period, .. } => (0..=96)
            .map(|k| {
                let s = m.state_at(*period * k as f64 / 96.0);
                [s.position[0], s.position[1]]
            })
            .collect(),
        Motion::Ball { period, .. } => {
            let t_end = period.unwrap_or(12.0).min(12.0);
            (0..=200)
                .map(|k| {
                    let s = m.state_at(t_end * k as f64 / 200.0 * 0.999);
                    [s.position[0], s.position[1]]
                })
                .collect()
        }
    }
}

/// A dashed polyline in pixels.
fn dashed(
    area: &Area,
    pts: &[(i32, i32)],
    on: f64,
    off: f64,
    style: ShapeStyle,
) -> anyhow::Result<()> {
    let mut phase = 0.0;
    for seg in pts.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        let (dx, dy) = ((b.0 - a.0) as f64, (b.1 - a.1) as f64);
        let len = dx.hypot(dy);
        if len < 1e-9 {
            continue;
        }
        let mut s = 0.0;
        while s < len {
            let cycle = phase % (on + off);
            if cycle < on {
                let e = (s + on - cycle).min(len);
                let p = |t: f64| {
                    (
                        (a.0 as f64 + dx * t / len) as i32,
                        (a.1 as f64 + dy * t / len) as i32,
                    )
                };
                area.draw(&PathElement::new(vec![p(s), p(e)], style))?;
                phase += e - s;
                s = e;
            } else {
                let e = (s + on + off - cycle).min(len);
                phase += e - s;
                s = e;
            }
        }
    }
    Ok(())
}

/// Diagonal hatching clipped to a convex polygon (pixels).
fn hatch(area: &Area, poly: &[(i32, i32)], spacing: f64, color: RGBAColor) -> anyhow::Result<()> {
    let xs = poly.iter().map(|p| p.0);
    let ys = poly.iter().map(|p| p.1);
    let (x0, x1) = (xs.clone().min().unwrap_or(0), xs.max().unwrap_or(0));
    let (y0, y1) = (ys.clone().min().unwrap_or(0), ys.max().unwrap_or(0));
    // Lines x - y = c for c over the box.
    let mut c = (x0 - y1) as f64;
    while c <= (x1 - y0) as f64 {
        let a = [x0 as f64 - 1.0, x0 as f64 - 1.0 - c];
        let b = [x1 as f64 + 1.0, x1 as f64 + 1.0 - c];
        if let Some((p, q)) = clip_convex(poly, a, b) {
            area.draw(&PathElement::new(
                vec![(p[0] as i32, p[1] as i32), (q[0] as i32, q[1] as i32)],
                color.stroke_width(1),
            ))?;
        }
        c += spacing;
    }
    Ok(())
}

/// Cyrus-Beck: the part of segment a-b inside a convex polygon.
fn clip_convex(poly: &[(i32, i32)], a: [f64; 2], b: [f64; 2]) -> Option<([f64; 2], [f64; 2])> {
    let n = poly.len();
    // Orientation of the polygon.
    let area2: f64 = (0..n)
        .map(|k| {
            let (p, q) = (poly[k], poly[(k + 1) % n]);
            p.0 as f64 * q.1 as f64 - q.0 as f64 * p.1 as f64
        })
        .sum();
    let sign = if area2 >= 0.0 { 1.0 } else { -1.0 };
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    let d = [b[0] - a[0], b[1] - a[1]];
    for k in 0..n {
        let (p, q) = (poly[k], poly[(k + 1) % n]);
        let e = [(q.0 - p.0) as f64, (q.1 - p.1) as f64];
        // Inward normal.
        let nrm = [-e[1] * sign, e[0] * sign];
        let w = [a[0] - p.0 as f64, a[1] - p.1 as f64];
        let num = nrm[0] * w[0] + nrm[1] * w[1];
        let den = nrm[0] * d[0] + nrm[1] * d[1];
        if den.abs() < 1e-12 {
            if num < 0.0 {
                return None;
            }
        } else {
            let t = -num / den;
            if den > 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 < t1).then(|| {
        (
            [a[0] + d[0] * t0, a[1] + d[1] * t0],
            [a[0] + d[0] * t1, a[1] + d[1] * t1],
        )
    })
}

/// Text with a white box behind it.
fn label(
    area: &Area,
    at: (i32, i32),
    text: &str,
    size: u32,
    color: RGBColor,
    pos: Pos,
) -> anyhow::Result<()> {
    let font = TextStyle::from((FAMILY, size).into_font().style(FontStyle::Bold));
    let (w, h) = area.estimate_text_size(text, &font)?;
    let (w, h) = (w as i32, h as i32);
    let x0 = match pos.h_pos {
        HPos::Left => at.0,
        HPos::Center => at.0 - w / 2,
        HPos::Right => at.0 - w,
    };
    let y0 = match pos.v_pos {
        VPos::Top => at.1,
        VPos::Center => at.1 - h / 2,
        VPos::Bottom => at.1 - h,
    };
    area.draw(&Rectangle::new(
        [(x0 - 3, y0 - 2), (x0 + w + 3, y0 + h + 2)],
        WHITE.mix(0.85).filled(),
    ))?;
    area.draw(&Text::new(
        text.to_string(),
        (x0, y0),
        font.color(&color).pos(Pos::new(HPos::Left, VPos::Top)),
    ))?;
    Ok(())
}

/// A black-and-white scale bar of a round length (about a fifth of the map width).
fn scale_bar(area: &Area, at: (i32, i32), ppm: f64, width_m: f64) -> anyhow::Result<()> {
    let target = width_m / 5.0;
    let len = [1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0]
        .into_iter()
        .rev()
        .find(|&l| l <= target)
        .unwrap_or(1.0);
    let px_len = (len * ppm).round() as i32;
    let (x, y) = at;
    area.draw(&Rectangle::new(
        [(x - 6, y - 26), (x + px_len + 42, y + 10)],
        WHITE.mix(0.85).filled(),
    ))?;
    for k in 0..4 {
        let a = x + px_len * k / 4;
        let b = x + px_len * (k + 1) / 4;
        let fill = if k % 2 == 0 {
            BLACK.filled()
        } else {
            WHITE.filled()
        };
        area.draw(&Rectangle::new([(a, y - 6), (b, y + 2)], fill))?;
    }
    area.draw(&Rectangle::new(
        [(x, y - 6), (x + px_len, y + 2)],
        BLACK.stroke_width(1),
    ))?;
    area.draw(&Text::new(
        "0".to_string(),
        (x - 3, y - 22),
        (FAMILY, 12).into_font(),
    ))?;
    area.draw(&Text::new(
        format!("{len} m"),
        (x + px_len - 6, y - 22),
        (FAMILY, 12).into_font(),
    ))?;
    Ok(())
}

/// A vertical colour bar at `at` (pixels in `area`), `height` px tall.
fn color_bar(area: &Area, at: (i32, i32), height: i32, bar: &ColorBar) -> anyhow::Result<()> {
    let (x, y) = (at.0, at.1 + 22);
    area.draw(&Text::new(
        bar.label.clone(),
        (at.0, at.1),
        (FAMILY, 13).into_font(),
    ))?;
    let w = 22;
    for k in 0..height {
        let t = 1.0 - k as f64 / (height - 1) as f64;
        let c = color_at(&bar.colors, t);
        area.draw(&Rectangle::new(
            [(x, y + k), (x + w, y + k + 1)],
            rgb(c).filled(),
        ))?;
    }
    area.draw(&Rectangle::new(
        [(x, y), (x + w, y + height)],
        BLACK.stroke_width(1),
    ))?;
    let ticks = if bar.max > bar.min { 5 } else { 1 };
    for k in 0..ticks {
        let f = if ticks == 1 {
            0.0
        } else {
            k as f64 / (ticks - 1) as f64
        };
        let v = bar.min + (bar.max - bar.min) * f;
        let ty = y + height - 1 - ((height - 1) as f64 * f).round() as i32;
        area.draw(&PathElement::new(
            vec![(x + w, ty), (x + w + 5, ty)],
            BLACK.stroke_width(1),
        ))?;
        area.draw(&Text::new(
            format!("{v:.2}"),
            (x + w + 8, ty),
            TextStyle::from((FAMILY, 12).into_font()).pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
    }
    Ok(())
}

/// `text` split at spaces into lines at most `width` pixels wide in `font` (a single
/// word wider than that gets a line of its own).
fn wrap(area: &Area, text: &str, font: &TextStyle<'_>, width: i32) -> anyhow::Result<Vec<String>> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split_whitespace() {
        if let Some(last) = lines.last_mut() {
            let candidate = format!("{last} {word}");
            if area.estimate_text_size(&candidate, font)?.0 as i32 <= width {
                *last = candidate;
                continue;
            }
        }
        lines.push(word.to_string());
    }
    if lines.is_empty() {
        lines.push(String::new());
    }
    Ok(lines)
}

/// Legend entries for what the map shows.
fn legend(area: &Area, y0: i32, scene: &Scene, overlay: &MapOverlay) -> anyhow::Result<()> {
    let font = || (FAMILY, 13).into_font();
    let x = 14;
    let mut y = y0;
    let row = 24;
    area.draw(&Text::new(
        "legend".to_string(),
        (x, y),
        (FAMILY, 13).into_font().style(FontStyle::Bold),
    ))?;
    y += row;
    // Entries wrap at word boundaries to the panel's width; a wrapped entry pushes
    // the rows below it down.
    let text_w = area.dim_in_pixel().0 as i32 - (x + 36) - 6;
    let line_h = 15;
    let entry = |y: &mut i32, text: &str| -> anyhow::Result<()> {
        let lines = wrap(area, text, &font().into(), text_w)?;
        for (k, line) in lines.iter().enumerate() {
            let ly = *y - 7 + k as i32 * line_h;
            area.draw(&Text::new(line.clone(), (x + 36, ly), font()))?;
        }
        *y += (lines.len() as i32 - 1) * line_h;
        Ok(())
    };
    area.draw(&Rectangle::new(
        [(x, y - 8), (x + 26, y + 6)],
        WALL.filled(),
    ))?;
    entry(&mut y, "wall")?;
    y += row;
    let box_ = vec![(x, y - 8), (x + 26, y - 8), (x + 26, y + 6), (x, y + 6)];
    area.draw(&Polygon::new(box_.clone(), CEILING.mix(0.18).filled()))?;
    hatch(area, &box_, 6.0, CEILING.mix(0.85))?;
    area.draw(&PathElement::new(closed(&box_), CEILING.stroke_width(2)))?;
    entry(&mut y, "low ceiling (clearance)")?;
    y += row;
    dashed(
        area,
        &[(x, y), (x + 26, y)],
        6.0,
        4.0,
        MOVER.stroke_width(2),
    )?;
    area.draw(&Circle::new((x + 26, y), 4, MOVER.filled()))?;
    entry(&mut y, "moving obstacle, path")?;
    y += row;
    area.draw(&Rectangle::new(
        [(x, y - 8), (x + 26, y + 6)],
        LANDMARK.stroke_width(3),
    ))?;
    entry(&mut y, "landmark region")?;
    y += row;
    for p in &overlay.paths {
        if let Some(text) = &p.label {
            let style = rgb(p.color_of_segment(0)).stroke_width(p.width.max(1));
            if p.dashed {
                dashed(area, &[(x, y), (x + 26, y)], 6.0, 4.0, style)?;
            } else {
                area.draw(&PathElement::new(vec![(x, y), (x + 26, y)], style))?;
            }
            entry(&mut y, text)?;
            y += row;
        }
    }
    y += 8;
    let g = &scene.terrain;
    let (lo, hi) = g.bounds();
    let info = format!(
        "{:.0} x {:.0} m, grid {} m",
        hi[0] - lo[0],
        hi[1] - lo[1],
        g.resolution
    );
    area.draw(&Text::new(info, (x, y), font()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_keeps_the_inside_of_a_square() {
        let sq = [(0, 0), (10, 0), (10, 10), (0, 10)];
        let (p, q) = clip_convex(&sq, [-5.0, 5.0], [15.0, 5.0]).unwrap();
        assert!((p[0] - 0.0).abs() < 1e-9 && (q[0] - 10.0).abs() < 1e-9);
        assert!(clip_convex(&sq, [-5.0, 15.0], [15.0, 15.0]).is_none());
        // Clockwise order clips the same.
        let cw = [(0, 0), (0, 10), (10, 10), (10, 0)];
        let (p, q) = clip_convex(&cw, [5.0, -5.0], [5.0, 20.0]).unwrap();
        assert!((p[1] - 0.0).abs() < 1e-9 && (q[1] - 10.0).abs() < 1e-9);
    }

    #[test]
    fn renders_a_builtin_scene_with_an_overlay() {
        let scene = plamo_scenes::builtin("slalom").unwrap();
        let dir = std::env::temp_dir().join(format!("plamo-viz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("slalom.png");
        let overlay = MapOverlay {
            paths: vec![super::super::OverlayPath {
                points: vec![[2.5, 5.0], [8.0, 8.5], [12.0, 1.5], [28.0, 2.0]],
                colors: vec![[200, 0, 0], [0, 0, 200], [0, 160, 0]],
                width: 3,
                dashed: false,
                label: Some("plan".into()),
            }],
            markers: vec![super::super::OverlayMarker {
                at: [2.5, 5.0],
                color: [255, 255, 0],
                label: Some("start".into()),
            }],
            title: "slalom with a plan".into(),
            colorbar: Some(ColorBar {
                label: "speed [m/s]".into(),
                min: 0.0,
                max: 3.0,
                colors: vec![[0, 0, 200], [200, 0, 0]],
            }),
        };
        render_map(&scene, &overlay, &out).unwrap();
        let bytes = std::fs::read(&out).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        let decoder = png_header_size(&bytes);
        assert!(decoder.0 > 1000 && decoder.1 >= MIN_H, "{decoder:?}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Width and height from a PNG's IHDR chunk.
    fn png_header_size(b: &[u8]) -> (u32, u32) {
        let w = u32::from_be_bytes([b[16], b[17], b[18], b[19]]);
        let h = u32::from_be_bytes([b[20], b[21], b[22], b[23]]);
        (w, h)
    }
}
