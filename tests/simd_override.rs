//! `mpm_gimp::simd::use_baseline_only` is process-wide, so it is tested in its own test binary:
//! after it, no step takes the AVX2 instance, and stepping gives the same state as a step
//! forced to the baseline instance.

mod common;

use common::{buffer_for, free_space};
use mpm_gimp::simd::{has_avx2, use_baseline_only, Simd};
use mpm_gimp::{Dimension, MaterialDef, Vec3, World};

#[test]
fn use_baseline_only_turns_the_avx2_instance_off() {
    let def = free_space(Dimension::Plane2D, 16, 0.1);
    let mut buf_a = buffer_for(&def);
    let mut buf_b = buffer_for(&def);
    let mut worlds = [buf_a.as_mut_bytes(), buf_b.as_mut_bytes()].map(|bytes| {
        let mut w = World::init(&def, bytes).expect("init");
        let m = w.add_material(&MaterialDef::DEFAULT).expect("material");
        w.fill_box(
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::new(1.1, 0.9, 0.0),
            m,
            Vec3::new(1.0, -2.0, 0.0),
        )
        .expect("fill");
        w
    });
    use_baseline_only();
    assert!(!has_avx2(), "use_baseline_only must turn detection off");
    assert!(!Simd::Detect.uses_avx2());
    let [a, b] = &mut worlds;
    let x0 = a.particles().position[0][0];
    for _ in 0..20 {
        a.step(1.0e-3).expect("step");
        b.step_with_simd(1.0e-3, Simd::Baseline).expect("step");
    }
    let (pa, pb) = (a.particles(), b.particles());
    assert_ne!(pa.position[0][0], x0, "the block did not move");
    for axis in 0..2 {
        for (x, y) in pa.position[axis].iter().zip(pb.position[axis]) {
            assert_eq!(x.to_bits(), y.to_bits());
        }
    }
}
