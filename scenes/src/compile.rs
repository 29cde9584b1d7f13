//! Scene file -> resolved [`Scene`]: builds the terrain from its grid and tiles, puts
//! walls and ceilings on the ground, and checks every field, naming it by its path
//! in the file (`walls[3].size`) when it is wrong.

use std::path::Path;

use crate::file_format::{Area, GridSpec, RegionSpec, SceneFile, TopSpec, WallSpec};
use crate::{
    DynamicObstacle, Footprint, HeightGrid, Landmark, Motion, ObstacleShape, Region, Scene,
    SceneError, TopObstacle, Wall,
};

/// Largest grid accepted (samples), so a typo cannot exhaust memory.
pub const MAX_SAMPLES: usize = 16_000_000;

/// Build the scene described by `file`; `origin` names it in errors and `base_dir`
/// is where relative paths (height-map PNGs) are looked up.
pub fn build(file: &SceneFile, origin: &str, base_dir: &Path) -> Result<Scene, SceneError> {
    let c = Ctx { origin };
    if file.name.trim().is_empty() {
        return Err(c.bad("name", &file.name, "a non-empty name"));
    }
    let terrain = c.terrain(file, base_dir)?;
    let mut scene = Scene {
        name: file.name.clone(),
        description: file.description.clone(),
        terrain,
        walls: Vec::new(),
        dynamic: Vec::new(),
        tops: Vec::new(),
        landmarks: Vec::new(),
    };
    for (k, w) in file.walls.iter().enumerate() {
        let wall = c.wall(&scene.terrain, w, &format!("walls[{k}]"))?;
        scene.walls.push(wall);
    }
    for (k, t) in file.tops.iter().enumerate() {
        let top = c.top(&scene.terrain, t, &format!("tops[{k}]"))?;
        scene.tops.push(top);
    }
    for (k, d) in file.dynamic.iter().enumerate() {
        let field = format!("dynamic[{k}]");
        if d.name.trim().is_empty() {
            return Err(c.bad(&format!("{field}.name"), &d.name, "a non-empty name"));
        }
        check_shape(origin, &format!("{field}.shape"), &d.shape)?;
        check_motion(
            origin,
            &format!("{field}.motion"),
            &d.motion,
            &scene.terrain,
        )?;
        scene.dynamic.push(DynamicObstacle {
            name: d.name.clone(),
            shape: d.shape,
            motion: d.motion.clone(),
        });
    }
    for (k, l) in file.landmarks.iter().enumerate() {
        let field = format!("landmarks[{k}]");
        let region = c.region(&scene.terrain, &l.region, &format!("{field}.region"))?;
        scene.landmarks.push(Landmark {
            name: l.name.clone(),
            region,
        });
    }
    crate::validate::validate_named(&scene, origin)?;
    Ok(scene)
}

struct Ctx<'a> {
    origin: &'a str,
}

impl Ctx<'_> {
    fn bad(&self, field: &str, value: impl std::fmt::Debug, allowed: &str) -> SceneError {
        SceneError::invalid(self.origin, field, value, allowed)
    }

    fn finite2(&self, field: &str, v: [f64; 2]) -> Result<(), SceneError> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(self.bad(field, v, "finite numbers [x, y] in metres"))
        }
    }

    fn size2(&self, field: &str, v: [f64; 2], max: f64) -> Result<(), SceneError> {
        if v.iter().all(|x| x.is_finite() && *x > 0.0 && *x <= max) {
            Ok(())
        } else {
            Err(self.bad(
                field,
                v,
                &format!("two sizes in metres, each > 0 and <= {max}"),
            ))
        }
    }

    fn positive(&self, field: &str, v: f64, max: f64) -> Result<(), SceneError> {
        if v.is_finite() && v > 0.0 && v <= max {
            Ok(())
        } else {
            Err(self.bad(field, v, &format!("a number > 0 and <= {max}")))
        }
    }

    fn terrain(&self, file: &SceneFile, base_dir: &Path) -> Result<HeightGrid, SceneError> {
        let t = &file.terrain;
        let res = t.resolution;
        if !(res.is_finite() && (0.02..=1.0).contains(&res)) {
            return Err(self.bad("terrain.resolution", res, "metres, 0.02 ..= 1"));
        }
        self.finite2("terrain.origin", t.origin)?;
        let mut grid = match &t.grid {
            Some(GridSpec::Inline { heights }) => self.inline_grid(heights, t.origin, res)?,
            Some(GridSpec::Png {
                path,
                scale,
                offset,
            }) => {
                if !scale.is_finite() || !offset.is_finite() {
                    return Err(self.bad(
                        "terrain.grid.scale",
                        (scale, offset),
                        "finite scale and offset (metres per grey level, metres)",
                    ));
                }
                let values = crate::height_png::read(self.origin, &base_dir.join(path))?;
                let (nx, ny, v) = values;
                HeightGrid {
                    origin: t.origin,
                    resolution: res,
                    nx,
                    ny,
                    heights: v.into_iter().map(|g| offset + scale * g as f64).collect(),
                }
            }
            None => {
                let Some(size) = t.size else {
                    return Err(self.bad(
                        "terrain.size",
                        "missing",
                        "[x, y] in metres (or a terrain.grid that gives the size)",
                    ));
                };
                self.size2("terrain.size", size, 2000.0)?;
                let n = (size[0] / res + 1.0) * (size[1] / res + 1.0);
                if n > MAX_SAMPLES as f64 {
                    return Err(self.bad(
                        "terrain.size",
                        size,
                        &format!("at most {MAX_SAMPLES} samples at this resolution"),
                    ));
                }
                HeightGrid::flat(t.origin, size, res, 0.0)
            }
        };
        if let (Some(_), Some(size)) = (&t.grid, t.size) {
            let (lo, hi) = grid.bounds();
            let have = [hi[0] - lo[0], hi[1] - lo[1]];
            if (have[0] - size[0]).abs() > res * 0.5 || (have[1] - size[1]).abs() > res * 0.5 {
                return Err(self.bad(
                    "terrain.size",
                    size,
                    &format!("the grid's own size {have:?} (or leave size out)"),
                ));
            }
        }
        if grid.nx < 2 || grid.ny < 2 {
            return Err(self.bad("terrain", (grid.nx, grid.ny), "at least 2 x 2 samples"));
        }
        for (k, tile) in t.tiles.iter().enumerate() {
            let field = format!("terrain.tiles[{k}]");
            if let Some(area) = &tile.area {
                self.area(&format!("{field}.area"), area)?;
            }
            tile.generator
                .check(self.origin, &format!("{field}.generator"))?;
            tile.generator
                .apply(&mut grid, tile.area.as_ref(), tile.blend);
        }
        Ok(grid)
    }

    fn inline_grid(
        &self,
        rows: &[Vec<f64>],
        origin: [f64; 2],
        res: f64,
    ) -> Result<HeightGrid, SceneError> {
        let ny = rows.len();
        let nx = rows.first().map_or(0, Vec::len);
        if ny < 2 || nx < 2 {
            return Err(self.bad(
                "terrain.grid.heights",
                (nx, ny),
                "at least 2 rows of at least 2 heights",
            ));
        }
        let mut heights = Vec::with_capacity(nx * ny);
        for (j, row) in rows.iter().enumerate() {
            if row.len() != nx {
                return Err(self.bad(
                    &format!("terrain.grid.heights[{j}]"),
                    format!("{} values", row.len()),
                    &format!("{nx} values, like row 0"),
                ));
            }
            for (i, &h) in row.iter().enumerate() {
                if !h.is_finite() {
                    return Err(self.bad(
                        &format!("terrain.grid.heights[{j}][{i}]"),
                        h,
                        "a finite height in metres",
                    ));
                }
                heights.push(h);
            }
        }
        Ok(HeightGrid {
            origin,
            resolution: res,
            nx,
            ny,
            heights,
        })
    }

    fn area(&self, field: &str, a: &Area) -> Result<(), SceneError> {
        self.finite2(&format!("{field}.min"), a.min)?;
        self.finite2(&format!("{field}.max"), a.max)?;
        if a.min[0] < a.max[0] && a.min[1] < a.max[1] {
            Ok(())
        } else {
            Err(self.bad(field, (a.min, a.max), "min < max along both X and Y"))
        }
    }

    fn footprint(
        &self,
        grid: &HeightGrid,
        field: &str,
        center: [f64; 2],
        size: [f64; 2],
        yaw_deg: f64,
    ) -> Result<Footprint, SceneError> {
        self.finite2(&format!("{field}.center"), center)?;
        self.size2(&format!("{field}.size"), size, 1000.0)?;
        if !yaw_deg.is_finite() {
            return Err(self.bad(
                &format!("{field}.yaw_deg"),
                yaw_deg,
                "a finite angle in degrees",
            ));
        }
        let fp = Footprint {
            center,
            half_extents: [size[0] / 2.0, size[1] / 2.0],
            yaw: yaw_deg.to_radians(),
        };
        inside_terrain(self.origin, grid, field, &fp.aabb())?;
        Ok(fp)
    }

    fn wall(&self, grid: &HeightGrid, w: &WallSpec, field: &str) -> Result<Wall, SceneError> {
        let fp = self.footprint(grid, field, w.center, w.size, w.yaw_deg)?;
        self.positive(&format!("{field}.height"), w.height, 100.0)?;
        let (lo, hi) = ground_range(grid, &fp);
        Ok(Wall {
            name: w.name.clone(),
            footprint: fp,
            z_min: lo - 0.1,
            z_max: hi + w.height,
        })
    }

    fn top(&self, grid: &HeightGrid, t: &TopSpec, field: &str) -> Result<TopObstacle, SceneError> {
        let fp = self.footprint(grid, field, t.center, t.size, t.yaw_deg)?;
        self.positive(&format!("{field}.clearance"), t.clearance, 20.0)?;
        self.positive(&format!("{field}.thickness"), t.thickness, 20.0)?;
        let (_, hi) = ground_range(grid, &fp);
        Ok(TopObstacle {
            name: t.name.clone(),
            footprint: fp,
            z_bottom: hi + t.clearance,
            z_top: hi + t.clearance + t.thickness,
        })
    }

    fn region(&self, grid: &HeightGrid, r: &RegionSpec, field: &str) -> Result<Region, SceneError> {
        match *r {
            RegionSpec::Circle { center, radius } => {
                self.finite2(&format!("{field}.center"), center)?;
                self.positive(&format!("{field}.radius"), radius, 1000.0)?;
                let region = Region::Circle { center, radius };
                inside_terrain(self.origin, grid, field, &region.aabb())?;
                Ok(region)
            }
            RegionSpec::Rect {
                center,
                size,
                yaw_deg,
            } => Ok(Region::Rect {
                footprint: self.footprint(grid, field, center, size, yaw_deg)?,
            }),
        }
    }
}

/// Error unless the box `(lo, hi)` lies within the terrain's bounds.
pub(crate) fn inside_terrain(
    origin: &str,
    grid: &HeightGrid,
    field: &str,
    aabb: &([f64; 2], [f64; 2]),
) -> Result<(), SceneError> {
    let (tlo, thi) = grid.bounds();
    let (lo, hi) = aabb;
    let eps = 1e-6;
    if lo[0] >= tlo[0] - eps
        && lo[1] >= tlo[1] - eps
        && hi[0] <= thi[0] + eps
        && hi[1] <= thi[1] + eps
    {
        Ok(())
    } else {
        Err(SceneError::invalid(
            origin,
            field,
            format!(
                "extends over x {:.2} ..= {:.2}, y {:.2} ..= {:.2}",
                lo[0], hi[0], lo[1], hi[1]
            ),
            format!(
                "inside the terrain: x {:.2} ..= {:.2}, y {:.2} ..= {:.2}",
                tlo[0], thi[0], tlo[1], thi[1]
            ),
        ))
    }
}

/// Lowest and highest ground under a footprint \[m\].
pub(crate) fn ground_range(grid: &HeightGrid, fp: &Footprint) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    let mut see = |h: f64| {
        lo = lo.min(h);
        hi = hi.max(h);
    };
    for c in fp.corners().iter().chain(std::iter::once(&fp.center)) {
        see(grid.height_at(c[0], c[1]));
    }
    let (alo, ahi) = fp.aabb();
    let r = grid.resolution;
    let i0 = ((alo[0] - grid.origin[0]) / r).floor().max(0.0) as usize;
    let j0 = ((alo[1] - grid.origin[1]) / r).floor().max(0.0) as usize;
    let i1 = (((ahi[0] - grid.origin[0]) / r).ceil().max(0.0) as usize).min(grid.nx - 1);
    let j1 = (((ahi[1] - grid.origin[1]) / r).ceil().max(0.0) as usize).min(grid.ny - 1);
    for j in j0..=j1 {
        for i in i0..=i1 {
            let [x, y] = grid.position(i, j);
            if fp.contains(x, y) {
                see(grid.heights[j * grid.nx + i]);
            }
        }
    }
    (lo, hi)
}

/// Check a dynamic obstacle's shape.
pub(crate) fn check_shape(origin: &str, field: &str, s: &ObstacleShape) -> Result<(), SceneError> {
    let ok = match *s {
        ObstacleShape::Sphere { radius } => radius.is_finite() && radius > 0.0 && radius <= 20.0,
        ObstacleShape::Box { half_extents } => half_extents
            .iter()
            .all(|h| h.is_finite() && *h > 0.0 && *h <= 20.0),
    };
    if ok {
        Ok(())
    } else {
        Err(SceneError::invalid(
            origin,
            field,
            s,
            "sphere radius or box half extents in metres, each > 0 and <= 20",
        ))
    }
}

/// Check a motion rule's parameters and that it starts over the terrain.
pub(crate) fn check_motion(
    origin: &str,
    field: &str,
    m: &Motion,
    grid: &HeightGrid,
) -> Result<(), SceneError> {
    let bad = |name: &str, v: &dyn std::fmt::Debug, allowed: &str| {
        SceneError::invalid(origin, format!("{field}.{name}"), v, allowed)
    };
    let finite3 = |name: &str, p: [f64; 3]| {
        if p.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(bad(name, &p, "finite [x, y, z] in metres"))
        }
    };
    let over = |name: &str, p: [f64; 3]| {
        inside_terrain(
            origin,
            grid,
            &format!("{field}.{name}"),
            &([p[0], p[1]], [p[0], p[1]]),
        )
    };
    let pos = |name: &str, v: f64, max: f64| {
        if v.is_finite() && v > 0.0 && v <= max {
            Ok(())
        } else {
            Err(bad(name, &v, &format!("a number > 0 and <= {max}")))
        }
    };
    match m {
        Motion::Linear { from, to, speed } => {
            finite3("from", *from)?;
            finite3("to", *to)?;
            over("from", *from)?;
            over("to", *to)?;
            pos("speed", *speed, 50.0)
        }
        Motion::Circle {
            center,
            radius,
            period,
            phase,
            ..
        } => {
            finite3("center", *center)?;
            pos("radius", *radius, 1000.0)?;
            pos("period", *period, 1e6)?;
            if !phase.is_finite() {
                return Err(bad("phase", phase, "a finite angle in radians"));
            }
            let c = *center;
            inside_terrain(
                origin,
                grid,
                field,
                &(
                    [c[0] - radius, c[1] - radius],
                    [c[0] + radius, c[1] + radius],
                ),
            )
        }
        Motion::Waypoints { points, speed } => {
            if points.len() < 2 {
                return Err(bad("points", &points.len(), "at least 2 points"));
            }
            for (k, p) in points.iter().enumerate() {
                finite3(&format!("points[{k}]"), *p)?;
                over(&format!("points[{k}]"), *p)?;
            }
            pos("speed", *speed, 50.0)
        }
        Motion::Ball {
            start,
            velocity,
            ground,
            restitution,
            horizontal_keep,
            gravity,
            period,
        } => {
            finite3("start", *start)?;
            over("start", *start)?;
            finite3("velocity", *velocity)?;
            if !ground.is_finite() {
                return Err(bad("ground", ground, "a finite height in metres"));
            }
            if !(restitution.is_finite() && (0.0..1.0).contains(restitution)) {
                return Err(bad("restitution", restitution, "0 <= e < 1"));
            }
            if !(horizontal_keep.is_finite() && (0.0..=1.0).contains(horizontal_keep)) {
                return Err(bad("horizontal_keep", horizontal_keep, "0 ..= 1"));
            }
            pos("gravity", *gravity, 100.0)?;
            if let Some(p) = period {
                pos("period", *p, 1e6)?;
            }
            Ok(())
        }
    }
}
