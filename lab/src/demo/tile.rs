//! Tiles (the unit of work) and the work counted while rendering.

use super::Camera;

/// A rectangle of pixels: the unit of work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Tile {
    /// The whole image of a camera.
    #[must_use]
    pub fn all(camera: &Camera) -> Self {
        Tile {
            x: 0,
            y: 0,
            width: camera.width(),
            height: camera.height(),
        }
    }

    /// Number of pixels.
    #[must_use]
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

/// The tiles of size `tile_width × tile_height` (smaller at the right and bottom edges) that
/// cover a `width × height` image, row by row. Widths that are multiples of the lane count
/// waste no lanes.
pub fn tiles(
    width: u32,
    height: u32,
    tile_width: u32,
    tile_height: u32,
) -> impl Iterator<Item = Tile> {
    let (tw, th) = (tile_width.max(1), tile_height.max(1));
    (0..height.div_ceil(th)).flat_map(move |j| {
        (0..width.div_ceil(tw)).map(move |i| {
            let (x, y) = (i * tw, j * th);
            Tile {
                x,
                y,
                width: tw.min(width - x),
                height: th.min(height - y),
            }
        })
    })
}

/// Work counted while rendering, per ray lane (see the [module docs](super)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Primary rays (pixels).
    pub rays: u64,
    /// Ray–sphere tests.
    pub sphere_tests: u64,
    /// Ray–plane tests.
    pub plane_tests: u64,
    /// Ray–bounding-sphere tests of mesh parts.
    pub bound_tests: u64,
    /// Ray–triangle tests run.
    pub triangle_tests: u64,
    /// Ray–triangle tests skipped because a packet missed a part's bounding sphere.
    pub triangle_tests_saved: u64,
}

impl Stats {
    /// Every ray–primitive test run (spheres, planes, bounding spheres, triangles).
    #[must_use]
    pub fn tests(&self) -> u64 {
        self.sphere_tests + self.plane_tests + self.bound_tests + self.triangle_tests
    }

    /// Adds `o` to `self`.
    pub fn add(&mut self, o: &Stats) {
        self.rays += o.rays;
        self.sphere_tests += o.sphere_tests;
        self.plane_tests += o.plane_tests;
        self.bound_tests += o.bound_tests;
        self.triangle_tests += o.triangle_tests;
        self.triangle_tests_saved += o.triangle_tests_saved;
    }
}
