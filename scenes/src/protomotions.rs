//! Import of ProtoMotions path-follower scene JSON (the map description its
//! `obstacles_from_json` reads) into the PlaMo model. One file describes one 20 x 20 m
//! tile sampled at 0.1 m, origin at (0, 0). Accepted JSON (every key optional unless
//! marked; unknown keys are errors):
//!
//! ```json
//! {
//!   "segmentation": [ {"name": "tree", "cx": 4.0, "cy": 15.0, "radius": 2.0,
//!                      "goal_radius": 1.0, "color": "green"},
//!                     {"name": "grass", "cx": 0, "cy": 0} ],
//!   "terrain": [ {"type": "gravel", "start_x": 0, "start_y": 0, "end_x": 20, "end_y": 10,
//!                 "amplitude": 0.05},
//!                {"type": "sloped"}, {"type": "stairs"}, {"type": "mixed"} ],
//!   "static_obstacles": [ {"type": "box", "x": 8.0, "y": 8.0, "obs_size": 1.0,
//!                          "obs_height": 2.0} ],
//!   "top_obstacles": [ {"cx": 10.0, "cy": 5.0, "length": 2.0, "width": 3.0,
//!                       "z_bottom": 0.7} ],
//!   "dynamic_obstacles": [ {"start_x": 2, "start_y": 2, "velocity_x": 1.0,
//!                           "velocity_y": 0.0, "cycle": 5.0, "radius": 0.3} ]
//! }
//! ```
//!
//! Mapping: a segmentation entry with a `radius` becomes a circular landmark of
//! radius `goal_radius` (else `radius`); entries without one label the background
//! and are skipped. `gravel` adds value noise (seed 0) over its rectangle; `sloped`
//! is a ridge of slope 0.15 along X peaking at x = 10 m; `stairs` are 0.075 m x 0.5 m
//! steps along X, up to x = 10 m and down again; `mixed` is the slope on x < 10 m,
//! stairs coming down on x >= 10 m and gravel (0.04 m) on x < 10, y >= 10. Boxes have
//! their lower-left corner at (x, y), side `obs_size` (default 1) and height
//! `obs_height` (default 2). Top obstacles are centred at (cx, cy), `length` along X
//! and `width` along Y (default 1), underside at `z_bottom` (absolute), 0.2 m thick;
//! ProtoMotions' 1.5 m safety slack around them is not added. A dynamic obstacle
//! (a ball of `radius`, default 0.5) bounces between its start and
//! start + cycle * velocity at |velocity|.

use serde::Deserialize;

use crate::file_format::{
    Area, BlendMode, LandmarkSpec, RegionSpec, SceneFile, TerrainSpec, Tile, WallSpec,
};
use crate::generators::Generator;
use crate::{DynamicObstacle, Footprint, Motion, ObstacleShape, Scene, SceneError, TopObstacle};

/// Side of a ProtoMotions tile \[m\].
pub const TILE_SIZE: f64 = 20.0;
/// Its grid spacing \[m\].
pub const TILE_RESOLUTION: f64 = 0.1;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MapJson {
    #[serde(default)]
    segmentation: Vec<SegJson>,
    #[serde(default)]
    terrain: Vec<TerrainJson>,
    #[serde(default)]
    static_obstacles: Vec<BoxJson>,
    #[serde(default)]
    top_obstacles: Vec<TopJson>,
    #[serde(default)]
    dynamic_obstacles: Vec<DynJson>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)] // `color` is accepted and ignored.
struct SegJson {
    name: String,
    cx: f64,
    cy: f64,
    radius: Option<f64>,
    goal_radius: Option<f64>,
    color: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TerrainJson {
    #[serde(rename = "type")]
    kind: String,
    start_x: Option<f64>,
    start_y: Option<f64>,
    end_x: Option<f64>,
    end_y: Option<f64>,
    amplitude: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxJson {
    #[serde(rename = "type")]
    kind: String,
    x: f64,
    y: f64,
    obs_size: Option<f64>,
    obs_height: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TopJson {
    cx: f64,
    cy: f64,
    length: Option<f64>,
    width: Option<f64>,
    z_bottom: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DynJson {
    start_x: f64,
    start_y: f64,
    velocity_x: f64,
    velocity_y: f64,
    cycle: f64,
    radius: Option<f64>,
    name: Option<String>,
}

/// Import a ProtoMotions map description; `origin` names it in errors.
pub fn from_json_str(text: &str, origin: &str) -> Result<Scene, SceneError> {
    let de = &mut serde_json::Deserializer::from_str(text);
    let map: MapJson = serde_path_to_error::deserialize(de).map_err(|e| SceneError::Parse {
        origin: origin.to_string(),
        field: e.path().to_string(),
        message: e.into_inner().to_string(),
    })?;
    let whole = |t: &TerrainJson| Area {
        min: [t.start_x.unwrap_or(0.0), t.start_y.unwrap_or(0.0)],
        max: [t.end_x.unwrap_or(TILE_SIZE), t.end_y.unwrap_or(TILE_SIZE)],
    };
    let half = TILE_SIZE / 2.0;
    let slope_deg = 0.15f64.atan().to_degrees();
    let tile = |area: Option<Area>, generator| Tile {
        area,
        blend: BlendMode::Add,
        generator,
    };
    let stairs = |direction_deg, symmetric| Generator::Stairs {
        step_height: 0.075,
        step_depth: 0.5,
        direction_deg,
        steps: None,
        symmetric,
    };
    let mut tiles = Vec::new();
    for (k, t) in map.terrain.iter().enumerate() {
        match t.kind.as_str() {
            "gravel" => tiles.push(tile(
                Some(whole(t)),
                Generator::Rough {
                    amplitude: t.amplitude.unwrap_or(0.05),
                    seed: 0,
                    feature_size: TILE_RESOLUTION,
                },
            )),
            "sloped" => tiles.push(tile(
                None,
                Generator::Slope {
                    angle_deg: slope_deg,
                    direction_deg: 0.0,
                    symmetric: true,
                },
            )),
            "stairs" => tiles.push(tile(None, stairs(0.0, true))),
            "mixed" => {
                let left = Area {
                    min: [0.0, 0.0],
                    max: [half, TILE_SIZE],
                };
                let right = Area {
                    min: [half, 0.0],
                    max: [TILE_SIZE, TILE_SIZE],
                };
                tiles.push(tile(
                    Some(left),
                    Generator::Slope {
                        angle_deg: slope_deg,
                        direction_deg: 0.0,
                        symmetric: false,
                    },
                ));
                tiles.push(tile(Some(right), stairs(180.0, false)));
                tiles.push(tile(
                    Some(Area {
                        min: [0.0, half],
                        max: [half, TILE_SIZE],
                    }),
                    Generator::Rough {
                        amplitude: 0.04,
                        seed: 0,
                        feature_size: TILE_RESOLUTION,
                    },
                ));
            }
            other => {
                return Err(SceneError::invalid(
                    origin,
                    format!("terrain[{k}].type"),
                    other,
                    "one of gravel, sloped, stairs, mixed",
                ));
            }
        }
    }
    let mut walls = Vec::new();
    for (k, b) in map.static_obstacles.iter().enumerate() {
        if b.kind != "box" {
            return Err(SceneError::invalid(
                origin,
                format!("static_obstacles[{k}].type"),
                &b.kind,
                "box",
            ));
        }
        let s = b.obs_size.unwrap_or(1.0);
        walls.push(WallSpec {
            name: format!("box{k}"),
            center: [b.x + s / 2.0, b.y + s / 2.0],
            size: [s, s],
            yaw_deg: 0.0,
            height: b.obs_height.unwrap_or(2.0),
        });
    }
    let landmarks = map
        .segmentation
        .iter()
        .filter_map(|s| {
            let r = s.goal_radius.or(s.radius)?;
            Some(LandmarkSpec {
                name: s.name.to_lowercase(),
                region: RegionSpec::Circle {
                    center: [s.cx, s.cy],
                    radius: r,
                },
            })
        })
        .collect();
    let file = SceneFile {
        name: origin.to_string(),
        description: "imported from a ProtoMotions path-follower map".to_string(),
        terrain: TerrainSpec {
            size: Some([TILE_SIZE, TILE_SIZE]),
            origin: [0.0, 0.0],
            resolution: TILE_RESOLUTION,
            grid: None,
            tiles,
        },
        walls,
        tops: Vec::new(),
        dynamic: Vec::new(),
        landmarks,
    };
    let mut scene = crate::compile::build(&file, origin, std::path::Path::new("."))?;
    for (k, t) in map.top_obstacles.iter().enumerate() {
        scene.tops.push(TopObstacle {
            name: format!("top{k}"),
            footprint: Footprint::axis_aligned(
                [t.cx, t.cy],
                [t.length.unwrap_or(1.0) / 2.0, t.width.unwrap_or(1.0) / 2.0],
            ),
            z_bottom: t.z_bottom,
            z_top: t.z_bottom + 0.2,
        });
    }
    for (k, d) in map.dynamic_obstacles.iter().enumerate() {
        let radius = d.radius.unwrap_or(0.5);
        let speed = d.velocity_x.hypot(d.velocity_y);
        let from = [d.start_x, d.start_y, radius];
        let to = [
            d.start_x + d.cycle * d.velocity_x,
            d.start_y + d.cycle * d.velocity_y,
            radius,
        ];
        scene.dynamic.push(DynamicObstacle {
            name: d.name.clone().unwrap_or_else(|| format!("obstacle{k}")),
            shape: ObstacleShape::Sphere { radius },
            motion: Motion::Linear { from, to, speed },
        });
    }
    crate::validate::validate_named(&scene, origin)?;
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SAMPLE: &str = r#"{
      "segmentation": [
        {"name": "Grass", "cx": 0, "cy": 0},
        {"name": "Tree", "cx": 3.0, "cy": 16.0, "radius": 2.0, "goal_radius": 1.0, "color": "green"},
        {"name": "car", "cx": 16.0, "cy": 3.0, "radius": 1.5}
      ],
      "terrain": [ {"type": "gravel", "start_x": 0, "start_y": 0, "end_x": 8, "end_y": 8, "amplitude": 0.04} ],
      "static_obstacles": [ {"type": "box", "x": 9.0, "y": 9.0, "obs_size": 2.0, "obs_height": 1.5} ],
      "top_obstacles": [ {"cx": 10.0, "cy": 4.0, "length": 2.0, "width": 3.0, "z_bottom": 0.7} ],
      "dynamic_obstacles": [ {"start_x": 2, "start_y": 2, "velocity_x": 1.0, "velocity_y": 0.5, "cycle": 6.0} ]
    }"#;

    #[test]
    fn imports_landmarks_boxes_tops_and_dynamic_obstacles() {
        let s = from_json_str(SAMPLE, "map.json").unwrap();
        assert_eq!(s.landmark_names(), vec!["tree", "car"]);
        assert_eq!(s.terrain.nx, 201);
        assert!(
            matches!(s.landmark("tree").unwrap().region, Region::Circle { radius, .. } if radius == 1.0)
        );
        assert!(s.in_wall(10.0, 10.0) && !s.in_wall(8.9, 10.0));
        assert!((s.walls[0].z_max - 1.5).abs() < 1e-9);
        assert_eq!(s.ceiling_at(10.0, 4.0), Some(0.7));
        let b = s.obstacle_states_at(6.0)[0];
        assert!((b.position[0] - 8.0).abs() < 1e-9 && (b.position[1] - 5.0).abs() < 1e-9);
        let (lo, hi) = s.terrain.height_range();
        assert!(lo < 0.0 && hi > 0.0 && hi <= 0.04);
        assert_eq!(s.height_at(15.0, 15.0), 0.0);
    }

    #[test]
    fn terrain_types_follow_protomotions_shapes() {
        let ridge = from_json_str(r#"{"terrain": [{"type": "sloped"}]}"#, "m").unwrap();
        assert!((ridge.height_at(10.0, 5.0) - 1.5).abs() < 1e-9);
        assert!((ridge.height_at(4.0, 5.0) - 0.6).abs() < 1e-9);
        assert!((ridge.height_at(16.0, 5.0) - 0.6).abs() < 1e-9);
        let stairs = from_json_str(r#"{"terrain": [{"type": "stairs"}]}"#, "m").unwrap();
        assert!((stairs.height_at(10.0, 5.0) - 1.5).abs() < 1e-9);
        assert!((stairs.height_at(1.2, 5.0) - 0.15).abs() < 1e-9);
        let mixed = from_json_str(r#"{"terrain": [{"type": "mixed"}]}"#, "m").unwrap();
        assert!((mixed.height_at(10.0, 5.0) - 1.5).abs() < 1e-9);
        assert!((mixed.height_at(18.8, 5.0) - 0.15).abs() < 1e-9);
    }

    #[test]
    fn bad_json_names_the_field() {
        let e = from_json_str(
            r#"{"static_obstacles": [{"type": "box", "x": 1, "y": 1, "size": 2}]}"#,
            "m.json",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("m.json") && e.contains("static_obstacles[0]") && e.contains("size"),
            "{e}"
        );
        let e = from_json_str(r#"{"terrain": [{"type": "lava"}]}"#, "m.json")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("terrain[0].type") && e.contains("lava") && e.contains("gravel"),
            "{e}"
        );
        let e = from_json_str(
            r#"{"segmentation": [{"name": "a", "cx": 30, "cy": 1, "radius": 1}]}"#,
            "m.json",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("landmarks[0].region") && e.contains("inside the terrain"),
            "{e}"
        );
    }

    use crate::Region;
}
