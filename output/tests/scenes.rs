//! The scene registry: every scene builds, fills and runs its default duration stably.

use mpm_gimp::World;
use mpm_gimp_output::picture::{render, value_range};
use mpm_gimp_output::scenes::{find, Scene, ALL};

/// Every registered scene's definition makes a world, its fill adds particles, and its
/// default run (`frames` frames of `frame_dt`) freezes no particle and keeps every particle
/// in the box with finite state, in no more substeps a frame on average than the budget its
/// materials were chosen for; its default colouring paints some of them inside its range.
#[test]
fn every_scene_runs_its_default_duration_stably() {
    assert!(ALL.len() >= 5, "{} scenes", ALL.len());
    for scene in ALL {
        let def = (scene.def)();
        let mut storage = Scene::storage(&def).unwrap();
        let mut world = World::init(&def, storage.as_mut_bytes()).unwrap();
        let n = (scene.fill)(&mut world).unwrap();
        assert!(n > 100, "{}: {n} particles", scene.name);
        assert_eq!(world.particle_count(), n, "{}", scene.name);
        let mut substeps = 0;
        for f in 0..scene.frames {
            let report = scene.frame(&mut world, scene.frame_dt).unwrap();
            assert_eq!(report.frozen, 0, "{} frame {f}: {report:?}", scene.name);
            assert_eq!(report.escaped, 0, "{} frame {f}", scene.name);
            substeps += report.substeps;
        }
        // The budget holds: the stiffest material and the fastest particle fit in it (a frame
        // where a particle outruns the speed the scene allowed for takes one or two more).
        assert!(
            substeps as usize <= scene.substeps as usize * scene.frames,
            "{}: {substeps} substeps in {} frames, over its budget of {} a frame",
            scene.name,
            scene.frames,
            scene.substeps
        );
        let v = world.particles();
        let finite = (0..v.count).all(|i| {
            v.status[i] == 0
                && (0..def.axes())
                    .all(|a| v.position[a][i].is_finite() && v.velocity[a][i].is_finite())
        });
        assert!(finite, "{}: a particle left or is not finite", scene.name);
        let (lo, hi) = value_range(&world, scene.colour);
        // Something moved or warmed: the field is not uniform at the end, and it overlaps the
        // scene's colour range.
        assert!(
            hi > lo,
            "{}: {:?} uniform at {lo}",
            scene.name,
            scene.colour
        );
        assert!(
            hi > scene.range.0 && lo < scene.range.1,
            "{}: {:?} spans {lo}..{hi}, range {:?}",
            scene.name,
            scene.colour,
            scene.range
        );
        let p = render(&world, scene.colour, scene.range, 100);
        assert!(p.width == 100 && p.height > 0);
        println!(
            "{}: {n} particles, {} frames, {substeps} substeps (budget {} a frame), {:?} \
             {lo:.3e}..{hi:.3e}",
            scene.name, scene.frames, scene.substeps, scene.colour
        );
    }
}

/// Names are unique and found by [`find`]; an unknown name is not.
#[test]
fn scene_names_are_unique_and_found() {
    for (k, scene) in ALL.iter().enumerate() {
        assert!(!scene.name.is_empty() && !scene.title.is_empty());
        assert!(
            ALL[..k].iter().all(|s| s.name != scene.name),
            "{}",
            scene.name
        );
        assert_eq!(find(scene.name).map(|s| s.name), Some(scene.name));
    }
    assert!(find("no such scene").is_none());
}
