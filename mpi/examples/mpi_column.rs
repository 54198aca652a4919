//! A column of sand collapsing onto a rough floor, split over the ranks of `mpirun` by slabs
//! across the run-out (the scene of `examples/collapse.rs`: Drucker-Prager, friction angle 30
//! degrees, a column 0.2 m wide and twice as high, 20 cells across, FLIP), stepped bit for bit
//! as one world would be.
//!
//! ```text
//! cargo build --release -p mpm-gimp-mpi --examples
//! mpirun -np 4 target/release/examples/mpi_column
//! ```
//!
//! Each rank writes the particles it owns every `--every` s (0.1) to `--out DIR`
//! (`target/mpi_column`): `column_rank<R>_<frame>.vtp` and its own series `column_rank<R>.pvd`;
//! rank 0 also writes `column.pvd`, which lists every rank's frame as a part of one time step,
//! so that ParaView opens the whole scene as one. At the end rank 0 prints the run-out
//! `(L - L0) / L0` and the final height over `L0` (Lube et al. 2005 and Lajeunesse et al. 2005
//! measured 2.4 to 3.6 and about 1.3 at this aspect ratio), the substeps, and the halo: bytes
//! and messages a rank sent per substep, how many substeps rebuilt a rank's list, and how
//! often the slabs were cut again as the sand spread (`Split::rebalance`).
//! Options: `--seconds S` (2), `--every S`, `--out DIR`, `--cells N` (across the column).

use mpi::collective::SystemOperation;
use mpi::traits::*;
use mpm_gimp::{
    memory_requirements, Boundary, Face, HeapBuffer, MaterialDef, MaterialModel, Real, Removal,
    Vec3, World, WorldDef,
};
use mpm_gimp_mpi::{Split, SplitError};
use mpm_gimp_output::Series;
use std::fmt::Write as _;
use std::path::PathBuf;

const USAGE: &str = "usage: mpi_column [--seconds S] [--every S] [--out DIR] [--cells N]";

/// The column's width, m, and its height over its width.
const L0: f64 = 0.2;
const ASPECT: f64 = 2.0;

fn main() {
    let universe = mpi::initialize().expect("MPI initialises");
    let comm = universe.world();
    let (rank, ranks) = (comm.rank() as usize, comm.size() as usize);
    let (mut seconds, mut every, mut cells) = (2.0f64, 0.1f64, 20.0f64);
    let mut out = PathBuf::from("target/mpi_column");
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let value = args.next();
        let number = || match value.as_deref().map(str::parse::<f64>) {
            Some(Ok(v)) if v.is_finite() && v > 0.0 => v,
            _ => usage(rank),
        };
        match a.as_str() {
            "--seconds" => seconds = number(),
            "--every" => every = number(),
            "--cells" => cells = number().round().max(4.0),
            "--out" => out = PathBuf::from(value.unwrap_or_else(|| usage(rank))),
            _ => usage(rank),
        }
    }
    let mut storage = HeapBuffer::new(0);
    let scene = column(cells, &mut storage);
    let wall = scene.def().shape.margin_cells() as f64 * scene.def().cell_size as f64;
    let mut split = match Split::new(comm.duplicate(), &scene, 0) {
        Ok(split) => split,
        Err(e) => fail(rank, e),
    };
    let mut series =
        Series::new(&out, &format!("column_rank{rank}")).expect("the output directory");
    let mut times = Vec::new();
    let (mut substeps, mut bytes, mut messages, mut rebuilt) = (0u64, 0u64, 0u64, 0u64);
    let mut recuts = 0u64;
    let frames = (seconds / every).round().max(1.0) as usize;
    for frame in 0..=frames {
        let end = frame as f64 * every;
        // Up to the frame's time in substeps of at most the scene's stable step.
        loop {
            let left = end - split.view().time();
            if left <= 1e-9 {
                break;
            }
            let dt = (split.stable_dt() as f64).min(left) as Real;
            match split.step(dt) {
                Ok(report) => {
                    substeps += 1;
                    bytes += report.bytes_sent;
                    messages += report.messages_sent as u64;
                    rebuilt += report.rebuilt as u64;
                    recuts += report.rebalanced as u64;
                }
                Err(e) => fail(rank, e),
            }
        }
        write_owned(&mut split, &mut series);
        times.push(split.view().time());
    }
    if rank == 0 {
        write_collection(&out, ranks, &times);
    }
    // The deposit's shape, from every particle gathered on rank 0.
    let gathered = match split.gather_to_root() {
        Ok(g) => g,
        Err(e) => fail(rank, e),
    };
    let mut halo = [0u64; 3];
    comm.all_reduce_into(
        &[bytes, messages, rebuilt][..],
        &mut halo[..],
        SystemOperation::max(),
    );
    if let Some(g) = gathered {
        let h = split.view().def().cell_size as f64;
        let (front, height) = shape(&g.state(), wall, h);
        println!(
            "{ranks} ranks, {} particles, {substeps} substeps to {:.2} s: run-out (L - L0) / L0 \
             {:.2} (measured 2.4 to 3.6), height / L0 {:.2}; per substep at most {:.0} bytes \
             and {:.1} messages sent by a rank, {} substeps rebuilt a rank's list, the slabs cut \
             again {recuts} times, last {:?}; {} (ParaView)",
            split.total(),
            split.view().time(),
            (front - L0) / L0,
            height / L0,
            halo[0] as f64 / substeps.max(1) as f64,
            halo[1] as f64 / substeps.max(1) as f64,
            halo[2],
            split.bounds(),
            out.join("column.pvd").display(),
        );
    }
}

/// The scene, built alike on every rank: a sand column against the left wall on a stick
/// floor, `cells` cells across, with room for its run-out.
fn column(cells: f64, storage: &mut HeapBuffer) -> World<'_> {
    let h = L0 / cells;
    let width = L0 * (4.0 + 3.0 * ASPECT.powf(2.0 / 3.0));
    let mut def = WorldDef {
        cells: [
            (width / h).ceil() as u32 + 4,
            (ASPECT * L0 / h).ceil() as u32 + 5,
            1,
        ],
        cell_size: h as Real,
        particle_capacity: (cells * cells * ASPECT * 4.0) as u32 + 1000,
        ..WorldDef::DEFAULT
    };
    def.faces[Face::YMin as usize] = Boundary::Stick;
    def.effects.plasticity = true;
    *storage = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, storage.as_mut_bytes()).expect("buffer fits");
    let sand = world
        .add_material(&MaterialDef {
            model: MaterialModel::DruckerPrager,
            density: 1600.0,
            friction_angle: 30.0,
            ..MaterialDef::DEFAULT
        })
        .expect("sand");
    let wall = (def.shape.margin_cells() as f64 * h) as Real;
    world
        .fill_box(
            Vec3::new(wall, wall, 0.0),
            Vec3::new(wall + L0 as Real, wall + (ASPECT * L0) as Real, 0.0),
            sand,
            Vec3::ZERO,
        )
        .expect("column");
    world
}

/// Writes the particles this rank owns as the next frame of its series: a copy of its world
/// without the ghosts it holds for its neighbours.
fn write_owned(split: &mut Split, series: &mut Series) {
    let bytes = split.world().as_bytes().to_vec();
    let mut copy = HeapBuffer::new(bytes.len());
    copy.as_mut_bytes().copy_from_slice(&bytes);
    let mut world = World::reopen(copy.as_mut_bytes()).expect("a copy of a world");
    let mut owned = split.owned().iter().peekable();
    let ghosts: Vec<u32> = (0..split.ids().len() as u32)
        .filter(|i| owned.next_if_eq(&i).is_none())
        .collect();
    world
        .remove_particles(Removal::List(&ghosts))
        .expect("ghosts are particles");
    series.write_frame(&world).expect("the frame is written");
}

/// `column.pvd`: at each time, every rank's frame as one part.
fn write_collection(out: &std::path::Path, ranks: usize, times: &[f64]) {
    let mut pvd = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n",
    );
    for (frame, t) in times.iter().enumerate() {
        for r in 0..ranks {
            let _ = writeln!(
                pvd,
                "<DataSet timestep=\"{t:?}\" part=\"{r}\" file=\"column_rank{r}_{frame:04}.vtp\"/>"
            );
        }
    }
    pvd.push_str("</Collection>\n</VTKFile>\n");
    std::fs::write(out.join("column.pvd"), pvd).expect("column.pvd is written");
}

/// The deposit's front (the 99.5th percentile of the particles' distance from the wall, so
/// that a stray grain does not count; `examples/collapse.rs`'s measure) and its height at the
/// wall (the highest particle within two cells of it), m.
fn shape(p: &mpm_gimp::ParticleState<'_>, wall: f64, h: f64) -> (f64, f64) {
    let x = |i: usize| p.position[0][i] as f64 - wall;
    let mut xs: Vec<f64> = (0..p.count).map(x).collect();
    xs.sort_by(f64::total_cmp);
    let height = (0..p.count)
        .filter(|&i| x(i) < 2.0 * h)
        .map(|i| p.position[1][i] as f64 - wall)
        .fold(0.0, f64::max);
    (xs[(xs.len() as f64 * 0.995) as usize], height)
}

fn usage(rank: usize) -> ! {
    if rank == 0 {
        eprintln!("{USAGE}");
    }
    std::process::exit(2)
}

fn fail(rank: usize, e: SplitError) -> ! {
    if rank == 0 {
        eprintln!("mpi_column: {e}");
    }
    std::process::exit(1)
}
