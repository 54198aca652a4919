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
/// `scale`) by `height` pixels.
fn draw_colliders(world: &World, scale: f64, height: u32, rgb: &mut [u8]) {
    let def = world.def();
    let n = world.collider_count();
    if n == 0 {
        return;
    }
    let w = rgb.len() / 3 / height.max(1) as usize;
    let z = def.origin.z as f64 + 0.5 * def.cells[2] as f64 * def.cell_size as f64;
    let solid = [120u8, 110, 100];
    let ids = 0..n as u32;
    for y in 0..height as usize {
        let wy = def.origin.y as f64 + (height as f64 - y as f64 - 0.5) / scale;
        for x in 0..w {
            let wx = def.origin.x as f64 + (x as f64 + 0.5) / scale;
            let p = Vec3::new(wx as Real, wy as Real, z as Real);
            if ids
                .clone()
                .any(|id| world.collider_distance(id, p).is_ok_and(|d| d <= 0.0))
            {
                let at = 3 * (y * w + x);
                rgb[at..at + 3].copy_from_slice(&solid);
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
