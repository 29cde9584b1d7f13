//! Small scenes built in code, for tests, benches and examples that must not depend
//! on scene files: a flat yard with a wall and a low ceiling, a pyramid hill, a
//! slalom, a ball crossing a corridor, and a large random hilly grid.

use plamo_scenes::{
    DynamicObstacle, Footprint, HeightGrid, Landmark, Motion, ObstacleShape, Region, Scene,
    TopObstacle, Wall,
};

fn circle(name: &str, x: f64, y: f64, r: f64) -> Landmark {
    Landmark {
        name: name.into(),
        region: Region::Circle {
            center: [x, y],
            radius: r,
        },
    }
}

fn wall(name: &str, center: [f64; 2], half: [f64; 2]) -> Wall {
    Wall {
        name: name.into(),
        footprint: Footprint::axis_aligned(center, half),
        z_min: -1.0,
        z_max: 2.0,
    }
}

fn empty(name: &str, terrain: HeightGrid) -> Scene {
    Scene {
        name: name.into(),
        description: String::new(),
        terrain,
        walls: vec![],
        dynamic: vec![],
        tops: vec![],
        landmarks: vec![],
    }
}

/// 30 m x 20 m flat yard. A wall at x = 15 from y = 0 to 12 and, above it, a
/// ceiling at 0.9 m from y = 12 to 20: crossing means crouching under it. Landmarks
/// tree (3, 3), bench (25, 3), car (25, 15), swing (5, 17).
pub fn flat_scene() -> Scene {
    let mut s = empty("yard", HeightGrid::flat([0.0, 0.0], [30.0, 20.0], 0.1, 0.0));
    s.walls.push(wall("wall", [15.0, 6.0], [0.3, 6.0]));
    s.tops.push(TopObstacle {
        name: "low roof".into(),
        footprint: Footprint::axis_aligned([15.0, 16.0], [1.5, 4.0]),
        z_bottom: 0.9,
        z_top: 1.1,
    });
    s.landmarks = vec![
        circle("tree", 3.0, 3.0, 0.5),
        circle("bench", 25.0, 3.0, 0.5),
        circle("car", 25.0, 15.0, 0.8),
        circle("swing", 5.0, 17.0, 0.5),
    ];
    s
}

/// 40 m x 30 m with a square pyramid of `height` \[m\] and half-width 8 m centred at
/// (20, 15); landmarks west (6, 15) and east (34, 15).
pub fn pyramid_scene(height: f64) -> Scene {
    let mut g = HeightGrid::flat([0.0, 0.0], [40.0, 30.0], 0.1, 0.0);
    for j in 0..g.ny {
        for i in 0..g.nx {
            let [x, y] = g.position(i, j);
            let d = (x - 20.0).abs().max((y - 15.0).abs());
            g.heights[j * g.nx + i] = height * (1.0 - d / 8.0).max(0.0);
        }
    }
    let mut s = empty("pyramid", g);
    s.landmarks = vec![
        circle("west", 6.0, 15.0, 0.5),
        circle("east", 34.0, 15.0, 0.5),
    ];
    s
}

/// 44 m x 10 m corridor with four staggered walls at x = 8, 16, 24, 32 (alternately
/// from the bottom and from the top, leaving a 3.5 m gap): the path zig-zags.
/// Landmarks start (2, 5) and finish (42, 5).
pub fn slalom_scene() -> Scene {
    let mut s = empty(
        "slalom",
        HeightGrid::flat([0.0, 0.0], [44.0, 10.0], 0.1, 0.0),
    );
    for (k, x) in [8.0, 16.0, 24.0, 32.0].into_iter().enumerate() {
        let (cy, name) = if k % 2 == 0 {
            (3.25, "low")
        } else {
            (6.75, "high")
        };
        s.walls.push(wall(name, [x, cy], [0.2, 3.25]));
    }
    s.walls.push(wall("south", [22.0, -0.2], [22.0, 0.2]));
    s.walls.push(wall("north", [22.0, 10.2], [22.0, 0.2]));
    s.landmarks = vec![
        circle("start", 2.0, 5.0, 0.5),
        circle("finish", 42.0, 5.0, 0.5),
    ];
    s
}

/// 30 m x 10 m flat corridor; a ball of radius 0.3 m rolls across it (along +Y at
/// x = `ball_x`, 2 m/s, from y = 0 to 10 and back). Landmarks a (2, 5) and b (28, 5).
pub fn ball_scene(ball_x: f64) -> Scene {
    let mut s = empty("ball", HeightGrid::flat([0.0, 0.0], [30.0, 10.0], 0.1, 0.0));
    s.dynamic.push(DynamicObstacle {
        name: "ball".into(),
        shape: ObstacleShape::Sphere { radius: 0.3 },
        motion: Motion::Linear {
            from: [ball_x, 0.0, 0.3],
            to: [ball_x, 10.0, 0.3],
            speed: 2.0,
        },
    });
    s.landmarks = vec![circle("a", 2.0, 5.0, 0.5), circle("b", 28.0, 5.0, 0.5)];
    s
}

/// `n` x `n` cells at 0.1 m with smooth pseudo-random hills up to `amplitude` \[m\]
/// (a sum of sines, deterministic); landmarks sw and ne in opposite corners.
pub fn hills_scene(n: usize, amplitude: f64) -> Scene {
    let size = (n - 1) as f64 * 0.1;
    let mut g = HeightGrid::flat([0.0, 0.0], [size, size], 0.1, 0.0);
    for j in 0..g.ny {
        for i in 0..g.nx {
            let [x, y] = g.position(i, j);
            let h = (x * 0.21).sin() * (y * 0.17).cos()
                + 0.5 * (x * 0.05 + y * 0.11).sin()
                + 0.3 * ((x - y) * 0.3).cos();
            g.heights[j * g.nx + i] = amplitude * 0.5 * (h + 1.8) / 1.8;
        }
    }
    let mut s = empty("hills", g);
    s.landmarks = vec![
        circle("sw", 2.0, 2.0, 0.5),
        circle("ne", size - 2.0, size - 2.0, 0.5),
    ];
    s
}
