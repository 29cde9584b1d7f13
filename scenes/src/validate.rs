//! Whole-scene checks on a resolved [`Scene`]: finite numbers, everything inside the
//! terrain, landmarks apart from each other and from walls, and every landmark
//! reachable from the first (see [`crate::reach`]).

use crate::compile::{check_motion, check_shape, inside_terrain};
use crate::reach::{ReachRules, landmarks_connected};
use crate::{Footprint, Scene, SceneError};

/// Check a scene; errors name the scene and the field (`landmarks[2].region`).
pub fn validate(scene: &Scene) -> Result<(), SceneError> {
    validate_named(scene, &scene.name)
}

/// [`validate`], naming `origin` (a file) in errors.
pub(crate) fn validate_named(scene: &Scene, origin: &str) -> Result<(), SceneError> {
    let bad = |field: String, value: &dyn std::fmt::Debug, allowed: &str| {
        SceneError::invalid(origin, field, value, allowed)
    };
    let g = &scene.terrain;
    if !(g.resolution.is_finite() && g.resolution > 0.0) {
        return Err(bad(
            "terrain.resolution".into(),
            &g.resolution,
            "> 0 metres",
        ));
    }
    if g.nx < 2 || g.ny < 2 || g.heights.len() != g.nx * g.ny {
        return Err(bad(
            "terrain".into(),
            &(g.nx, g.ny, g.heights.len()),
            "nx, ny >= 2 and nx * ny heights",
        ));
    }
    if let Some(k) = g.heights.iter().position(|h| !h.is_finite()) {
        return Err(bad(
            format!("terrain.heights[{k}]"),
            &g.heights[k],
            "a finite height",
        ));
    }
    let footprint = |field: String, fp: &Footprint| -> Result<(), SceneError> {
        let ok = fp.center.iter().all(|v| v.is_finite())
            && fp.half_extents.iter().all(|v| v.is_finite() && *v > 0.0)
            && fp.yaw.is_finite();
        if !ok {
            return Err(bad(field, fp, "finite centre and yaw, half extents > 0"));
        }
        inside_terrain(origin, g, &field, &fp.aabb())
    };
    for (k, w) in scene.walls.iter().enumerate() {
        footprint(format!("walls[{k}]"), &w.footprint)?;
        if !(w.z_min.is_finite() && w.z_max.is_finite() && w.z_max > w.z_min) {
            return Err(bad(
                format!("walls[{k}].z_max"),
                &(w.z_min, w.z_max),
                "z_max > z_min, finite",
            ));
        }
    }
    for (k, t) in scene.tops.iter().enumerate() {
        footprint(format!("tops[{k}]"), &t.footprint)?;
        if !(t.z_bottom.is_finite() && t.z_top.is_finite() && t.z_top > t.z_bottom) {
            return Err(bad(
                format!("tops[{k}].z_top"),
                &(t.z_bottom, t.z_top),
                "z_top > z_bottom, finite",
            ));
        }
    }
    for (k, d) in scene.dynamic.iter().enumerate() {
        check_shape(origin, &format!("dynamic[{k}].shape"), &d.shape)?;
        check_motion(origin, &format!("dynamic[{k}].motion"), &d.motion, g)?;
    }
    let mut cells: Vec<Vec<(usize, usize)>> = Vec::new();
    for (k, l) in scene.landmarks.iter().enumerate() {
        let field = format!("landmarks[{k}]");
        if l.name.is_empty() || l.name.chars().any(char::is_whitespace) {
            return Err(bad(
                format!("{field}.name"),
                &l.name,
                "a non-empty name without spaces",
            ));
        }
        if let Some(j) = scene.landmarks[..k]
            .iter()
            .position(|o| o.name.eq_ignore_ascii_case(&l.name))
        {
            return Err(bad(
                format!("{field}.name"),
                &l.name,
                &format!("a name not used before (landmarks[{j}] has it)"),
            ));
        }
        let (lo, hi) = l.region.aabb();
        let size_ok =
            lo.iter().chain(hi.iter()).all(|v| v.is_finite()) && hi[0] > lo[0] && hi[1] > lo[1];
        if !size_ok {
            return Err(bad(
                format!("{field}.region"),
                &l.region,
                "finite, with a size > 0",
            ));
        }
        inside_terrain(origin, g, &format!("{field}.region"), &(lo, hi))?;
        let mine = scene.landmark_cells(l);
        if mine.is_empty() {
            return Err(bad(
                format!("{field}.region"),
                &l.region,
                &format!(
                    "a region that covers at least one grid cell ({} m apart)",
                    g.resolution
                ),
            ));
        }
        for (j, other) in cells.iter().enumerate() {
            if mine.iter().any(|c| other.contains(c)) {
                return Err(bad(
                    format!("{field}.region"),
                    &l.region,
                    &format!(
                        "a region apart from landmarks[{j}] ({:?}); they overlap",
                        scene.landmarks[j].name
                    ),
                ));
            }
        }
        for (w, wall) in scene.walls.iter().enumerate() {
            if mine.iter().any(|&(i, j)| {
                let [x, y] = g.position(i, j);
                wall.footprint.contains(x, y)
            }) {
                return Err(bad(
                    format!("{field}.region"),
                    &l.region,
                    &format!("a region outside every wall; it overlaps walls[{w}]"),
                ));
            }
        }
        cells.push(mine);
    }
    let rules = ReachRules::default();
    if let Err((from, to)) = landmarks_connected(scene, &rules) {
        return Err(SceneError::Unreachable {
            origin: origin.to_string(),
            from,
            from_name: scene.landmarks[from].name.clone(),
            to,
            to_name: scene.landmarks[to].name.clone(),
            min_headroom: rules.min_headroom,
            max_step: rules.max_step,
        });
    }
    Ok(())
}
