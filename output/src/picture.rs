//! Pictures of a world without a window: the particles seen along z (a 3D world projected
//! onto x-y, far particles drawn first), each a disc of the particle spacing coloured by a
//! field, as RGB pixels; PNG frames and animated GIFs of them.

use mpm_gimp::{Boundary, Dimension, Face, ParticlesView, Real, Vec3, World};
use std::io::{self, Write};

/// What colours the particles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Colour {
    /// Speed `|v|`, m/s.
    Speed,
    /// Pressure `-tr(sigma) / 3` (Cauchy stress), Pa.
    Pressure,
    /// Temperature, K (grey where heat is not declared).
    Temperature,
    /// Material id.
    Material,
}

/// An RGB picture, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Picture {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// `3 * width * height` bytes, red, green, blue per pixel.
    pub rgb: Vec<u8>,
}

/// The colour of the pixels no particle or wall covers.
pub const BACKGROUND: [u8; 3] = [246, 246, 242];

/// The colour map of [`render`], perceptually ordered (dark blue, teal, green, yellow), at `t`
/// in [0, 1] (clamped; 0 where not finite): what a legend draws.
pub fn colour_map(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (STOPS.len() - 1) as f64;
    let k = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - k as f64;
    core::array::from_fn(|c| (STOPS[k][c] + f * (STOPS[k + 1][c] - STOPS[k][c])).round() as u8)
}

/// The value `colour` gives particle `i` of the view `v` (`density` by material id).
fn value(v: &ParticlesView<'_>, colour: Colour, i: usize, density: &[f64]) -> f64 {
    let d = if v.dimension == Dimension::ThreeD {
        3
    } else {
        2
    };
    match colour {
        Colour::Speed => (0..d)
            .map(|a| (v.velocity[a][i] as f64).powi(2))
            .sum::<f64>()
            .sqrt(),
        Colour::Pressure => {
            // Stored components: 2D xx, yy, xy, zz; 3D xx, yy, zz, xy, xz, yz.
            let diagonal: [usize; 3] = if d == 2 { [0, 1, 3] } else { [0, 1, 2] };
            let rho0 = density.get(v.material[i] as usize).copied().unwrap_or(0.0);
            let trace: f64 = diagonal.iter().map(|&k| v.stress[k][i] as f64).sum();
            -trace * rho0 / (3.0 * v.jacobian(i) as f64)
        }
        Colour::Temperature => v.temperature.get(i).map_or(f64::NAN, |&t| t as f64),
        Colour::Material => v.material[i] as f64,
    }
}

/// The colliders' solids under the particles: every pixel whose centre is inside one (3D: in
/// the grid's middle plane along z), in one grey; `rgb` is the picture's `width` (from
/// `scale`) by `height` pixels. Each collider is asked for its distance only at the pixels
/// of the box that holds it ([`World::collider_bounds`]; all of them for a half-space).
fn draw_colliders(world: &World, scale: f64, height: u32, rgb: &mut [u8]) {
    let def = world.def();
    let w = rgb.len() / 3 / height.max(1) as usize;
    let z = def.origin.z as f64 + 0.5 * def.cells[2] as f64 * def.cell_size as f64;
    let solid = [120u8, 110, 100];
    // Pixel x of world x, and pixel row of world y (rows top to bottom).
    let column = |x: f64| (x - def.origin.x as f64) * scale - 0.5;
    let row = |y: f64| height as f64 - (y - def.origin.y as f64) * scale - 0.5;
    for id in 0..world.collider_count() as u32 {
        let Ok(bounds) = world.collider_bounds(id) else {
            continue;
        };
        // The pixels whose centres may lie inside: the box's and one more around it (a centre
        // on the box's face, rounded either way), clamped to the picture.
        let (x0, x1, y0, y1) = match bounds {
            Some((lo, hi)) => (
                (column(lo.x as f64).ceil() - 1.0).max(0.0) as usize,
                (column(hi.x as f64).floor() + 2.0).clamp(0.0, w as f64) as usize,
                (row(hi.y as f64).ceil() - 1.0).max(0.0) as usize,
                (row(lo.y as f64).floor() + 2.0).clamp(0.0, height as f64) as usize,
            ),
            None => (0, w, 0, height as usize),
        };
        for y in y0..y1 {
            let wy = def.origin.y as f64 + (height as f64 - y as f64 - 0.5) / scale;
            for x in x0..x1 {
                let wx = def.origin.x as f64 + (x as f64 + 0.5) / scale;
                let p = Vec3::new(wx as Real, wy as Real, z as Real);
                if world.collider_distance(id, p).is_ok_and(|d| d <= 0.0) {
                    let at = 3 * (y * w + x);
                    rgb[at..at + 3].copy_from_slice(&solid);
                }
            }
        }
    }
}

/// Renders the world's active particles over the grid's box, `width` pixels wide (the height
/// follows the box), coloured by `colour` from `range.0` (dark) to `range.1` (light), over
/// the colliders' solids.
pub fn render(world: &World, colour: Colour, range: (f64, f64), width: u32) -> Picture {
    let def = world.def();
    let d = def.axes();
    let (w, h) = (width.max(1), def.cells[1]);
    let scale = w as f64 / (def.cells[0] as f64 * def.cell_size as f64);
    let height = ((h as f64 * def.cell_size as f64) * scale).round().max(1.0) as u32;
    let mut rgb = Vec::with_capacity(3 * (w * height) as usize);
    for _ in 0..w * height {
        rgb.extend_from_slice(&BACKGROUND);
    }
    draw_colliders(world, scale, height, &mut rgb);
    let v = world.particles();
    let density = crate::densities(world);
    // Far particles first (3D), so that near ones cover them.
    let mut order: Vec<usize> = (0..v.count).filter(|&i| v.status[i] == 0).collect();
    if d == 3 {
        order.sort_by(|&a, &b| v.position[2][a].total_cmp(&v.position[2][b]));
    }
    let spacing = def.cell_size as f64 / def.particles_per_cell as f64;
    // Discs that cover the lattice's diagonal gaps (`spacing / sqrt 2`).
    let radius = (0.75 * spacing * scale).max(0.75);
    let (lo, hi) = range;
    let span = if hi > lo { hi - lo } else { 1.0 };
    let origin = [def.origin.x as f64, def.origin.y as f64];
    for i in order {
        let value = value(&v, colour, i, &density);
        let c = if value.is_nan() {
            [160, 160, 160]
        } else {
            colour_map((value - lo) / span)
        };
        let px = (v.position[0][i] as f64 - origin[0]) * scale;
        let py = height as f64 - (v.position[1][i] as f64 - origin[1]) * scale;
        let (x0, x1) = ((px - radius).floor() as i64, (px + radius).ceil() as i64);
        let (y0, y1) = ((py - radius).floor() as i64, (py + radius).ceil() as i64);
        for y in y0.max(0)..y1.min(height as i64) {
            for x in x0.max(0)..x1.min(w as i64) {
                let (dx, dy) = (x as f64 + 0.5 - px, y as f64 + 0.5 - py);
                if dx * dx + dy * dy <= radius * radius {
                    let at = 3 * (y as usize * w as usize + x as usize);
                    rgb[at..at + 3].copy_from_slice(&c);
                }
            }
        }
    }
    // The walls (faces that are not open), on their planes `margin` cells inside the grid.
    let margin = def.shape.margin_cells() as f64 * def.cell_size as f64 * scale;
    let wall = [90u8, 90, 90];
    let mut line = |x0: f64, y0: f64, x1: f64, y1: f64| {
        let (xa, xb) = (x0.min(x1).floor() as i64, x0.max(x1).ceil() as i64);
        let (ya, yb) = (y0.min(y1).floor() as i64, y0.max(y1).ceil() as i64);
        for y in ya.max(0)..=yb.min(height as i64 - 1) {
            for x in xa.max(0)..=xb.min(w as i64 - 1) {
                let at = 3 * (y as usize * w as usize + x as usize);
                rgb[at..at + 3].copy_from_slice(&wall);
            }
        }
    };
    let (left, right) = (margin, w as f64 - 1.0 - margin);
    let (top, bottom) = (margin, height as f64 - 1.0 - margin);
    let walled = |f: Face| def.faces[f as usize] != Boundary::Open;
    if walled(Face::XMin) {
        line(left, top, left, bottom);
    }
    if walled(Face::XMax) {
        line(right, top, right, bottom);
    }
    if walled(Face::YMin) {
        line(left, bottom, right, bottom);
    }
    if walled(Face::YMax) {
        line(left, top, right, top);
    }
    Picture {
        width: w,
        height,
        rgb,
    }
}

/// Writes `picture` as an 8-bit RGB PNG.
pub fn write_png(out: impl Write, picture: &Picture) -> io::Result<()> {
    let mut encoder = png::Encoder::new(out, picture.width, picture.height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(io::Error::other)?;
    writer
        .write_image_data(&picture.rgb)
        .map_err(io::Error::other)
}

/// Writes `frames` (all of one size) as an animated GIF that loops, `delay` hundredths of a
/// second per frame.
pub fn write_gif(out: impl Write, frames: &[Picture], delay: u16) -> io::Result<()> {
    let Some(first) = frames.first() else {
        return Err(io::Error::other("no frame"));
    };
    let (w, h) = (first.width as u16, first.height as u16);
    let mut encoder = gif::Encoder::new(out, w, h, &[]).map_err(io::Error::other)?;
    encoder
        .set_repeat(gif::Repeat::Infinite)
        .map_err(io::Error::other)?;
    for p in frames {
        let mut frame = gif::Frame::from_rgb_speed(w, h, &p.rgb, 10);
        frame.delay = delay;
        encoder.write_frame(&frame).map_err(io::Error::other)?;
    }
    Ok(())
}

/// The smallest and largest value `colour` takes on the active particles (a range for
/// [`render`]; `(0, 1)` when there are none).
pub fn value_range(world: &World, colour: Colour) -> (f64, f64) {
    let v = world.particles();
    let density = crate::densities(world);
    let values = (0..v.count)
        .filter(|&i| v.status[i] == 0)
        .map(|i| value(&v, colour, i, &density))
        .filter(|x| x.is_finite());
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
        (lo.min(x), hi.max(x))
    });
    if lo <= hi {
        (lo, hi)
    } else {
        (0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mpm_gimp::{
        memory_requirements, ColliderDef, ColliderShape, Effects, HeapBuffer, World, WorldDef,
    };

    /// The colliders drawn from their boxes are the pixels a query at every pixel finds
    /// inside one: a sphere, a turned box, a capsule crossing the picture's edge, a cylinder
    /// and a turned half-space, in 2D and 3D (the grid's middle plane), at two widths.
    #[test]
    fn colliders_drawn_from_their_bounds_are_those_every_pixel_finds() {
        for three_d in [false, true] {
            let def = WorldDef {
                dimension: if three_d {
                    Dimension::ThreeD
                } else {
                    Dimension::Plane2D
                },
                cells: [24, 16, if three_d { 8 } else { 1 }],
                cell_size: 0.05,
                particle_capacity: 64,
                effects: Effects {
                    collider_capacity: 5,
                    ..Effects::NONE
                },
                ..WorldDef::DEFAULT
            };
            let mut buf = HeapBuffer::new(memory_requirements(&def).unwrap().bytes);
            let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
            let turn = |a: f32| [0.0, 0.0, (0.5 * a).sin() as Real, (0.5 * a).cos() as Real];
            let z = 0.2;
            for c in [
                ColliderDef {
                    shape: ColliderShape::Sphere { radius: 0.13 },
                    position: Vec3::new(0.3, 0.4, z),
                    ..ColliderDef::DEFAULT
                },
                ColliderDef {
                    shape: ColliderShape::Box {
                        half_extents: Vec3::new(0.2, 0.05, 0.1),
                    },
                    position: Vec3::new(0.7, 0.5, z),
                    rotation: turn(0.6),
                    ..ColliderDef::DEFAULT
                },
                ColliderDef {
                    shape: ColliderShape::Capsule {
                        half_length: 0.2,
                        radius: 0.05,
                    },
                    position: Vec3::new(1.15, 0.7, z),
                    rotation: turn(1.1),
                    ..ColliderDef::DEFAULT
                },
                ColliderDef {
                    shape: ColliderShape::Cylinder {
                        half_length: 0.1,
                        radius: 0.08,
                        inner_radius: 0.04,
                    },
                    position: Vec3::new(0.4, 0.15, z),
                    ..ColliderDef::DEFAULT
                },
                ColliderDef {
                    position: Vec3::new(0.0, 0.1, 0.0),
                    rotation: turn(-0.2),
                    ..ColliderDef::DEFAULT
                },
            ] {
                world.add_collider(&c).unwrap();
            }
            for width in [97, 240] {
                let scale = width as f64 / (def.cells[0] as f64 * def.cell_size as f64);
                let height = (def.cells[1] as f64 * def.cell_size as f64 * scale).round() as u32;
                let mut drawn = vec![0u8; 3 * (width * height) as usize];
                draw_colliders(&world, scale, height, &mut drawn);
                let mut every = vec![0u8; drawn.len()];
                let zc = def.origin.z as f64 + 0.5 * def.cells[2] as f64 * def.cell_size as f64;
                for y in 0..height as usize {
                    let wy = def.origin.y as f64 + (height as f64 - y as f64 - 0.5) / scale;
                    for x in 0..width as usize {
                        let wx = def.origin.x as f64 + (x as f64 + 0.5) / scale;
                        let p = Vec3::new(wx as Real, wy as Real, zc as Real);
                        if (0..5).any(|id| world.collider_distance(id, p).is_ok_and(|d| d <= 0.0)) {
                            let at = 3 * (y * width as usize + x);
                            every[at..at + 3].copy_from_slice(&[120, 110, 100]);
                        }
                    }
                }
                let inside = every.iter().filter(|&&c| c != 0).count();
                assert!(inside > 0, "3D {three_d}, width {width}: something drawn");
                assert!(drawn == every, "3D {three_d}, width {width}");
            }
        }
    }
}
