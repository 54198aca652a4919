//! Particle output of an [`mpm_gimp::World`], outside the `no_std` kernel:
//!
//! - [`write_vtp`]: one frame as VTK XML PolyData (`.vtp`, ASCII), every particle a vertex
//!   carrying every column the world has, for ParaView;
//! - [`Series`]: frames in a directory plus the `.pvd` file that lists them with their times
//!   (ParaView opens it as one time series);
//! - [`write_csv`]: one frame as CSV, a row per particle, for spreadsheets and scripts;
//! - [`picture`]: pictures without a window, PNG frames and animated GIFs;
//! - [`scenes`]: the example scenes, defined once;
//! - [`stiffness`]: the modulus that lets a material run in a chosen number of substeps a frame;
//! - [`tap`]: a source that adds a stream of particles and a drain that removes them.
//!
//! The columns ([`columns`]): the position (`position + position_low`, in f64), velocity, mass,
//! initial volume, material, status, `J`, the displacement gradient `H = F - I` (row major),
//! the Cauchy stress (`rho0 / J` times the stored Kirchhoff stress over density), and each
//! declared effect's columns (particle forces, damping rates, temperature and concentration
//! with the grid's values at the particles, the hoop stretch, APIC's moment matrix).
//!
//! ```no_run
//! # fn run(world: &mpm_gimp::World) -> std::io::Result<()> {
//! let mut series = mpm_gimp_output::Series::new("out", "drop")?;
//! series.write_frame(world)?; // out/drop_0000.vtp, out/drop.pvd
//! mpm_gimp_output::write_csv(std::fs::File::create("out/drop.csv")?, world)?;
//! # Ok(()) }
//! ```
#![deny(missing_docs)]

pub mod picture;
pub mod scenes;
pub mod stiffness;
pub mod tap;

use mpm_gimp::{Dimension, Real, World};
use std::fmt::Write as _;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// The values of one column, a row per particle.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    /// Floating-point values, `components` per particle.
    Float(Vec<f64>),
    /// Integer values (material ids, status codes), one per particle.
    Int(Vec<u32>),
}

/// One output column: its name, its number of components per particle and its values.
#[derive(Clone, Debug, PartialEq)]
pub struct Column {
    /// Name in the VTK file; in CSV, with `_x`, `_xx` or `_0` suffixes per component.
    pub name: &'static str,
    /// Names of the components (empty for a scalar).
    pub components: &'static [&'static str],
    /// `components.len().max(1)` values per particle, particle by particle.
    pub values: Values,
}

const XYZ: &[&str] = &["x", "y", "z"];
const TENSOR: &[&str] = &["xx", "xy", "xz", "yx", "yy", "yz", "zx", "zy", "zz"];
// ParaView's order for a symmetric tensor.
const SYMMETRIC: &[&str] = &["xx", "yy", "zz", "xy", "yz", "xz"];

/// The world's particle columns, the position first: every column the world has (a column of
/// an effect that is not declared is left out). 2D vectors and tensors get zero z entries.
pub fn columns(world: &World) -> Vec<Column> {
    let v = world.particles();
    let n = v.count;
    let d = if v.dimension == Dimension::ThreeD {
        3
    } else {
        2
    };
    let float = |k: usize, f: &dyn Fn(usize, usize) -> f64| {
        Values::Float(
            (0..n)
                .flat_map(|i| (0..k).map(move |c| (i, c)))
                .map(|(i, c)| f(i, c))
                .collect(),
        )
    };
    let vector = |col: &[&[Real]; 3]| float(3, &|i, a| if a < d { col[a][i] as f64 } else { 0.0 });
    let scalar = |col: &[Real]| float(1, &|i, _| col[i] as f64);
    let tensor = |col: &[[&[Real]; 3]; 3]| {
        float(9, &|i, k| {
            let (a, b) = (k / 3, k % 3);
            if a < d && b < d {
                col[a][b][i] as f64
            } else {
                0.0
            }
        })
    };
    let mut out = vec![
        Column {
            name: "position",
            components: XYZ,
            values: float(3, &|i, a| {
                if a < d {
                    v.position[a][i] as f64 + v.position_low[a][i] as f64
                } else {
                    0.0
                }
            }),
        },
        Column {
            name: "velocity",
            components: XYZ,
            values: vector(&v.velocity),
        },
        Column {
            name: "mass",
            components: &[],
            values: scalar(v.mass),
        },
        Column {
            name: "volume0",
            components: &[],
            values: scalar(v.volume0),
        },
        Column {
            name: "material",
            components: &[],
            values: Values::Int(v.material.to_vec()),
        },
        Column {
            name: "status",
            components: &[],
            values: Values::Int(v.status.to_vec()),
        },
        Column {
            name: "J",
            components: &[],
            values: float(1, &|i, _| v.jacobian(i) as f64),
        },
        Column {
            name: "H",
            components: TENSOR,
            values: tensor(&v.displacement_gradient),
        },
    ];
    // Stored stress components: 2D xx, yy, xy, zz; 3D xx, yy, zz, xy, xz, yz.
    let stored: [Option<usize>; 6] = if d == 2 {
        [Some(0), Some(1), Some(3), Some(2), None, None]
    } else {
        [Some(0), Some(1), Some(2), Some(3), Some(5), Some(4)]
    };
    let rho0 = densities(world);
    out.push(Column {
        name: "stress",
        components: SYMMETRIC,
        values: float(6, &|i, k| match stored[k] {
            Some(s) => {
                let density = rho0.get(v.material[i] as usize).copied().unwrap_or(0.0);
                v.stress[s][i] as f64 * density / v.jacobian(i) as f64
            }
            None => 0.0,
        }),
    });
    let optional: [(&'static str, &[Real]); 5] = [
        ("temperature", v.temperature),
        ("grid_temperature", v.grid_temperature),
        ("concentration", v.concentration),
        ("grid_concentration", v.grid_concentration),
        ("hoop_stretch", v.hoop),
    ];
    if !v.force[0].is_empty() {
        out.push(Column {
            name: "force",
            components: XYZ,
            values: vector(&v.force),
        });
    }
    if !v.damping[0].is_empty() {
        let (g, p) = (v.damping[0], v.damping[1]);
        out.push(Column {
            name: "damping",
            components: &["grid", "particle"],
            values: float(2, &|i, k| if k == 0 { g[i] as f64 } else { p[i] as f64 }),
        });
    }
    for (name, col) in optional {
        if !col.is_empty() {
            out.push(Column {
                name,
                components: &[],
                values: scalar(col),
            });
        }
    }
    if !v.affine[0][0].is_empty() {
        out.push(Column {
            name: "apic_moment",
            components: TENSOR,
            values: tensor(&v.affine),
        });
    }
    out
}

/// Each material's initial density, kg/m^3, by material id (what turns the stored stress
/// over density into stress).
pub(crate) fn densities(world: &World) -> Vec<f64> {
    (0..world.material_count() as u32)
        .map(|m| world.material(m).map_or(0.0, |m| m.density as f64))
        .collect()
}

/// A float written so that it reads back to the same f64 (Rust's shortest round trip).
fn number(text: &mut String, x: f64) {
    let _ = write!(text, "{x:?}");
}

/// Writes the world's particles as one VTK XML PolyData file (ASCII): a vertex per particle,
/// its position as the point, every column of [`columns`] as point data (tensors with 9 or 6
/// components, in ParaView's order).
pub fn write_vtp(mut out: impl Write, world: &World) -> io::Result<()> {
    let cols = columns(world);
    let n = world.particle_count();
    let mut text = String::new();
    text.push_str("<?xml version=\"1.0\"?>\n");
    text.push_str("<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<PolyData>\n");
    let _ = writeln!(
        text,
        "<Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{n}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">"
    );
    let array = |text: &mut String, col: &Column, name: bool| {
        let k = col.components.len().max(1);
        let (kind, body) = match &col.values {
            Values::Float(v) => (
                "Float64",
                v.iter().fold(String::new(), |mut s, &x| {
                    number(&mut s, x);
                    s.push(' ');
                    s
                }),
            ),
            Values::Int(v) => (
                "UInt32",
                v.iter().fold(String::new(), |mut s, x| {
                    let _ = write!(s, "{x} ");
                    s
                }),
            ),
        };
        let name = if name {
            format!(" Name=\"{}\"", col.name)
        } else {
            String::new()
        };
        let _ = writeln!(
            text,
            "<DataArray type=\"{kind}\"{name} NumberOfComponents=\"{k}\" format=\"ascii\">\n{}\n</DataArray>",
            body.trim_end()
        );
    };
    text.push_str("<Points>\n");
    array(&mut text, &cols[0], false);
    text.push_str("</Points>\n<Verts>\n");
    let ids = (0..n).fold(String::new(), |mut s, i| {
        let _ = write!(s, "{i} ");
        s
    });
    let offsets = (1..=n).fold(String::new(), |mut s, i| {
        let _ = write!(s, "{i} ");
        s
    });
    let _ = writeln!(
        text,
        "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n{}\n</DataArray>",
        ids.trim_end()
    );
    let _ = writeln!(
        text,
        "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n{}\n</DataArray>",
        offsets.trim_end()
    );
    text.push_str("</Verts>\n<PointData>\n");
    for col in &cols {
        array(&mut text, col, true);
    }
    text.push_str("</PointData>\n</Piece>\n</PolyData>\n</VTKFile>\n");
    out.write_all(text.as_bytes())
}

/// Writes the world's particles as CSV: a header row of column names (a vector's components
/// as `velocity_x`, a tensor's as `H_xy`), then a row per particle.
pub fn write_csv(mut out: impl Write, world: &World) -> io::Result<()> {
    let cols = columns(world);
    let mut text = String::new();
    let mut names = vec![];
    for col in &cols {
        if col.components.is_empty() {
            names.push(col.name.to_string());
        } else {
            names.extend(col.components.iter().map(|c| format!("{}_{c}", col.name)));
        }
    }
    text.push_str(&names.join(","));
    text.push('\n');
    for i in 0..world.particle_count() {
        let mut first = true;
        for col in &cols {
            let k = col.components.len().max(1);
            for c in 0..k {
                if !first {
                    text.push(',');
                }
                first = false;
                match &col.values {
                    Values::Float(v) => number(&mut text, v[i * k + c]),
                    Values::Int(v) => {
                        let _ = write!(text, "{}", v[i * k + c]);
                    }
                }
            }
        }
        text.push('\n');
    }
    out.write_all(text.as_bytes())
}

/// A time series for ParaView: frames `<stem>_0000.vtp`, `<stem>_0001.vtp`, ... in a
/// directory, and `<stem>.pvd` listing them with their times, rewritten after every frame so
/// that it is complete whenever the run stops.
#[derive(Debug)]
pub struct Series {
    dir: PathBuf,
    stem: String,
    frames: Vec<(f64, String)>,
}

impl Series {
    /// A series in `dir` (created if missing) with file names starting with `stem`.
    pub fn new(dir: impl AsRef<Path>, stem: &str) -> io::Result<Series> {
        std::fs::create_dir_all(dir.as_ref())?;
        Ok(Series {
            dir: dir.as_ref().to_path_buf(),
            stem: stem.to_string(),
            frames: vec![],
        })
    }

    /// Writes the world as the next frame, at its current time, and the updated `.pvd`;
    /// returns the frame's path.
    pub fn write_frame(&mut self, world: &World) -> io::Result<PathBuf> {
        let name = format!("{}_{:04}.vtp", self.stem, self.frames.len());
        let path = self.dir.join(&name);
        write_vtp(io::BufWriter::new(std::fs::File::create(&path)?), world)?;
        self.frames.push((world.time(), name));
        let mut pvd = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n",
        );
        for (time, file) in &self.frames {
            let _ = write!(pvd, "<DataSet timestep=\"");
            number(&mut pvd, *time);
            let _ = writeln!(pvd, "\" part=\"0\" file=\"{file}\"/>");
        }
        pvd.push_str("</Collection>\n</VTKFile>\n");
        std::fs::write(self.pvd_path(), pvd)?;
        Ok(path)
    }

    /// The `.pvd` file's path.
    pub fn pvd_path(&self) -> PathBuf {
        self.dir.join(format!("{}.pvd", self.stem))
    }
}
