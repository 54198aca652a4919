//! Conservation: mass exactly, linear momentum to round-off, for every shape function and
//! update order, in 2D and 3D (except linear shapes with USL, unstable by nature).

use crate::common::*;
use mpm_gimp::{Dimension, MaterialDef, ParticleBatch, Real, ShapeFunction, UpdateOrder, World};

/// A block with translation, spin and shear (so stress develops), no gravity, open faces,
/// 60 steps. Exact: the particles' total mass never changes (bit for bit), and total
/// momentum is constant because `sum_i f_i = -sum_p m_p tau_p . sum_i G_ip = 0` and the PIC
/// blend moves momentum between particles only. Tolerance 1e-6 of the momentum scale
/// `sum m |v|`: f32 round-off of the grid sums over 60 steps (measured ~1e-7).
#[test]
fn mass_exact_and_momentum_conserved_for_every_shape_order_and_dimension() {
    for dim in [Dimension::Plane2D, Dimension::ThreeD] {
        for shape in SHAPES {
            for order in ORDERS {
                if shape == ShapeFunction::Linear && order == UpdateOrder::Usl {
                    // Classic MPM's cell-crossing instability: see the hard-case test
                    // `linear_usl_cell_crossing_instability_is_contained`.
                    continue;
                }
                let mut def = free_space(dim, 24, 0.05);
                def.shape = shape;
                def.update_order = order;
                let mut buf = buffer_for(&def);
                let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
                let mat = w.add_material(&MaterialDef::DEFAULT).unwrap();
                let d = def.axes();
                let (lo, hi) = (0.4 as Real, 0.8 as Real);
                let s = def.cell_size / 2.0;
                let n = ((hi - lo) / s).round() as usize;
                let mut c: [Vec<Real>; 6] = Default::default();
                for k in 0..if d == 3 { n } else { 1 } {
                    for j in 0..n {
                        for i in 0..n {
                            let x = [
                                lo + (i as Real + 0.5) * s,
                                lo + (j as Real + 0.5) * s,
                                if d == 3 {
                                    lo + (k as Real + 0.5) * s
                                } else {
                                    0.0
                                },
                            ];
                            let r = [x[0] - 0.6, x[1] - 0.6, x[2] - 0.6];
                            let v = [
                                1.0 - 3.0 * r[1] + 2.0 * r[0] * r[0],
                                -0.5 + 3.0 * r[0],
                                if d == 3 {
                                    0.3 + r[0] * r[1] * 10.0
                                } else {
                                    0.0
                                },
                            ];
                            for a in 0..3 {
                                c[a].push(x[a]);
                                c[3 + a].push(v[a]);
                            }
                        }
                    }
                }
                let count = c[0].len();
                let vol = s.powi(d as i32);
                let mass = vec![1000.0 * vol; count];
                let volume = vec![vol; count];
                let mats = vec![mat; count];
                w.add_particles(&ParticleBatch {
                    position: [&c[0], &c[1], &c[2]],
                    velocity: [&c[3], &c[4], &c[5]],
                    mass: &mass,
                    volume: &volume,
                    material: &mats,
                })
                .unwrap();
                let m0: Vec<Real> = w.particles().mass.to_vec();
                let p0 = w.diagnostics().momentum;
                let view = w.particles();
                let scale: f64 = (0..count)
                    .map(|i| {
                        let v2: f64 = (0..d).map(|a| (view.velocity[a][i] as f64).powi(2)).sum();
                        view.mass[i] as f64 * v2.sqrt()
                    })
                    .sum();
                for _ in 0..60 {
                    w.step(w.stable_dt()).unwrap();
                }
                let label = format!("{dim:?} {shape:?} {order:?}");
                assert_eq!(w.particles().mass, &m0[..], "{label}: masses changed");
                assert!(all_finite(&w), "{label}: non-finite state");
                assert_eq!(
                    w.diagnostics().mass,
                    m0.iter().map(|&m| m as f64).sum::<f64>()
                );
                let p1 = w.diagnostics().momentum;
                for a in 0..d {
                    let rel = (p1[a] - p0[a]).abs() / scale;
                    assert!(
                        rel < 1e-6,
                        "{label}: momentum[{a}] {} -> {} (rel {rel:e})",
                        p0[a],
                        p1[a]
                    );
                }
            }
        }
    }
}
