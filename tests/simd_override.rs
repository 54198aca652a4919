//! The caps `mpm_gimp::simd::use_avx2_at_most` and `use_baseline_only` are process-wide and
//! irreversible, so they are tested in their own test binary, in one test that sets them in
//! turn: after each, no step takes a wider instance, and stepping gives the same state as a
//! step forced to the baseline instance.

mod common;

use common::{buffer_for, free_space};
use mpm_gimp::simd::{has_avx2, has_avx512, use_avx2_at_most, use_baseline_only, Instance, Simd};
use mpm_gimp::{Dimension, MaterialDef, Vec3, World};

/// Steps two copies of a moving block 20 times, one with `World::step` (the instance the caps
/// allow) and one forced to the baseline instance, and checks that their positions are
/// bit-identical.
fn steps_like_the_baseline() {
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

#[test]
fn the_caps_turn_the_wider_instances_off() {
    let widest = Simd::Detect.instance();
    eprintln!("widest instance on this CPU: {}", widest.name());
    use_avx2_at_most();
    assert!(!has_avx512(), "use_avx2_at_most must turn AVX-512 off");
    assert_eq!(Simd::Detect.instance(), widest.min(Instance::Avx2));
    steps_like_the_baseline();
    use_baseline_only();
    assert!(!has_avx2(), "use_baseline_only must turn detection off");
    assert_eq!(Simd::Detect.instance(), Instance::Baseline);
    assert_eq!(Simd::Avx2.instance(), Instance::Baseline);
    // A cap is never raised again.
    use_avx2_at_most();
    assert_eq!(Simd::Detect.instance(), Instance::Baseline);
    steps_like_the_baseline();
}
