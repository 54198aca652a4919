//! Long runs to a static state with an exact solution: a column of elastic material between
//! frictionless side walls, released under gravity onto a floor and damped until it rests.
//!
//! Exact solution: at rest every horizontal section carries the weight of the material above
//! it, and the side walls carry no shear, so the vertical Cauchy stress of a particle is
//! `sigma_yy = -rho0 g (Y_top - Y_p)` per unit area, with `Y_p` the particle's height and
//! `Y_top` the column's top, both in the starting (reference) configuration: the mass above a
//! particle does not change as the column compresses. This holds for any material law and any
//! strain, so the same bound applies to both materials, every shape function and every order.
//!
//! Tolerance: the particle stresses of MPM satisfy the balance of forces at the nodes, not at
//! each particle, with an error of the order of one cell's weight near the floor and the free
//! top. The bound is the weight of one cell layer, `rho0 g h`; measured (f32 and f64 alike):
//! at most 0.48 of it in 2D (linear MPM; uGIMP 0.30, the B-splines 0.23) and 0.36 in 3D. Before
//! the walls mirrored the nodes past them (`Geom::for_each_wall_image`), the B-splines were
//! off by 9 to 12 cell weights in the particles next to the floor.

use crate::common::*;
use mpm_gimp::{
    Boundary, Damping, Dimension, Face, MaterialDef, MaterialModel, ParticleStatus, Real, Schedule,
    ShapeFunction, UpdateOrder, Vec3, World, WorldDef,
};

const RHO: Real = 1000.0;
const G: Real = 9.81;
/// Column height, m.
const HEIGHT: Real = 1.0;

/// Runs the column for one second (about 2300 steps at 32 cells per height) and returns the
/// largest error of `sigma_yy` in units of one cell layer's weight and the fastest particle.
fn settle(
    dim: Dimension,
    shape: ShapeFunction,
    order: UpdateOrder,
    model: MaterialModel,
    floor: Boundary,
    cells_per_height: u32,
) -> (f64, f64) {
    let three = dim == Dimension::ThreeD;
    let h = HEIGHT / cells_per_height as Real;
    let m = shape.margin_cells();
    // The column's width in cells, between the side walls (slip: frictionless).
    let wide = if three { 4 } else { 8 };
    let mut def = WorldDef {
        dimension: dim,
        cells: [
            wide + 2 * m,
            cells_per_height + 2 * m + 4,
            if three { wide + 2 * m } else { 1 },
        ],
        cell_size: h,
        shape,
        update_order: order,
        gravity: Vec3::new(0.0, -G, 0.0),
        faces: [Boundary::Slip; 6],
        particle_capacity: 8 * wide * wide * cells_per_height,
        ..WorldDef::DEFAULT
    };
    def.faces[Face::YMin as usize] = floor;
    // Damping well below critical for the column's first mode (omega = 57.6 rad/s for
    // c = 36.7 m/s): it settles to rest within the second, to 1e-7 of the starting motion.
    def.effects.damping = Some(Damping {
        grid: Schedule::constant(60.0),
        ..Damping::NONE
    });
    let mut buf = buffer_for(&def);
    let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
    let id = w
        .add_material(&MaterialDef {
            model,
            youngs_modulus: 1.0e6,
            poisson_ratio: 0.3,
            density: RHO,
            ..MaterialDef::DEFAULT
        })
        .unwrap();
    let wall = m as Real * h;
    let top = wall + HEIGHT;
    let side = wall + wide as Real * h;
    w.fill_box(
        Vec3::new(wall, wall, if three { wall } else { 0.0 }),
        Vec3::new(side, top, if three { side } else { 0.0 }),
        id,
        Vec3::ZERO,
    )
    .unwrap();
    let y0: Vec<Real> = w.particles().position[1].to_vec();
    let mass0 = total_mass(&w);
    let mut t = 0.0;
    while t < 1.0 {
        let dt = w.stable_dt();
        w.step(dt).unwrap();
        t += dt as f64;
    }
    let label = format!("{dim:?} {shape:?} {order:?} {model:?} floor {floor:?}");
    assert!(all_finite(&w), "{label}: non-finite state");
    assert_eq!(total_mass(&w), mass0, "{label}: mass changed");
    assert_eq!(
        count_status(&w, ParticleStatus::Active),
        y0.len(),
        "{label}"
    );
    let v = w.particles();
    let layer = (RHO * G * h) as f64;
    let mut worst: f64 = 0.0;
    let mut fastest: f64 = 0.0;
    for (i, &y) in y0.iter().enumerate().take(v.count) {
        let sigma_yy = RHO as f64 / v.jacobian(i) as f64 * v.stress[1][i] as f64;
        let exact = -(RHO * G) as f64 * (top - y) as f64;
        worst = worst.max((sigma_yy - exact).abs() / layer);
        let speed: f64 = (0..def.axes())
            .map(|a| (v.velocity[a][i] as f64).powi(2))
            .sum();
        fastest = fastest.max(speed.sqrt());
    }
    (worst, fastest)
}

fn check(label: &str, (worst, fastest): (f64, f64)) {
    println!("{label}: sigma_yy off by {worst:.3} cell layers' weight, fastest {fastest:.1e} m/s");
    // At rest: the column falls at up to g / omega = 0.17 m/s at first.
    assert!(fastest < 1.0e-4, "{label}: still moving at {fastest} m/s");
    assert!(
        worst <= 1.0,
        "{label}: sigma_yy off by {worst:.2} cell layers' weight"
    );
}

#[test]
fn column_at_rest_carries_its_weight_for_every_shape_and_order_2d() {
    for shape in SHAPES {
        for order in ORDERS {
            let r = settle(
                Dimension::Plane2D,
                shape,
                order,
                MaterialModel::NeoHookean,
                Boundary::Slip,
                32,
            );
            check(&format!("2D {shape:?} {order:?} slip floor"), r);
        }
        // A stick floor holds the column the same way; the linear elastic law too.
        let r = settle(
            Dimension::Plane2D,
            shape,
            UpdateOrder::Musl,
            MaterialModel::LinearElastic,
            Boundary::Stick,
            32,
        );
        check(&format!("2D {shape:?} linear elastic, stick floor"), r);
    }
}

#[test]
fn column_at_rest_carries_its_weight_3d() {
    // Two pairs of side walls: the nodes past both (the column's vertical edges) mirror across
    // both walls.
    for shape in SHAPES {
        let r = settle(
            Dimension::ThreeD,
            shape,
            UpdateOrder::Musl,
            MaterialModel::NeoHookean,
            Boundary::Slip,
            16,
        );
        check(&format!("3D {shape:?}"), r);
    }
}
