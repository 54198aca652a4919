//! Renders scenes headless to an animated GIF (and PNG frames with `--png`): the pictures in
//! the README.
//!
//! `cargo run --release -p mpm-gimp-output --example pictures` renders the scenes of the
//! registry (`mpm_gimp_output::scenes::ALL`) the README shows into `results/pictures/`,
//! `NAME.gif` each (`-- --all`: every scene); `-- --scene drop3d --frames 90 --width 320 --out dir --png` picks one scene, the length
//! (default: the scene's own), the size, the directory, and also writes the frames as PNG
//! (`NAME_0000.png`, ...). `-- --list` prints the scenes.

use mpm_gimp::World;
use mpm_gimp_output::picture::{render, write_gif, write_png};
use mpm_gimp_output::scenes::{find, Scene, ALL};
use std::path::PathBuf;

fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|k| args.get(k + 1).cloned())
}

fn main() -> std::io::Result<()> {
    if std::env::args().any(|a| a == "--list") {
        for s in ALL {
            println!("{:10} {}", s.name, s.title);
        }
        return Ok(());
    }
    let frames: Option<usize> = arg("--frames").map(|s| s.parse().expect("--frames N"));
    let width: u32 = arg("--width").map_or(200, |s| s.parse().expect("--width N"));
    let out = PathBuf::from(arg("--out").unwrap_or_else(|| "results/pictures".into()));
    let png = std::env::args().any(|a| a == "--png");
    let scenes: Vec<&Scene> = match arg("--scene") {
        Some(name) => vec![find(&name).unwrap_or_else(|| {
            let names: Vec<_> = ALL.iter().map(|s| s.name).collect();
            panic!("unknown scene {name}: one of {names:?}")
        })],
        None if std::env::args().any(|a| a == "--all") => ALL.iter().collect(),
        None => ALL.iter().filter(|s| s.in_readme).collect(),
    };
    std::fs::create_dir_all(&out)?;
    for scene in scenes {
        let def = (scene.def)();
        let mut storage = Scene::storage(&def).expect("valid definition");
        let mut world = World::init(&def, storage.as_mut_bytes()).expect("buffer fits");
        (scene.fill)(&mut world).expect("scene fits");
        let frames = frames.unwrap_or(scene.frames);
        let mut pictures = vec![];
        for k in 0..frames {
            // One colour scale for every frame: the scene's.
            let picture = render(&world, scene.colour, scene.range, width);
            if png {
                let path = out.join(format!("{}_{k:04}.png", scene.name));
                write_png(std::fs::File::create(path)?, &picture)?;
            }
            pictures.push(picture);
            scene
                .frame(&mut world, scene.frame_dt)
                .expect("a frame's substeps");
        }
        let path = out.join(format!("{}.gif", scene.name));
        write_gif(std::fs::File::create(&path)?, &pictures, 3)?;
        println!(
            "{}: {frames} frames, {} x {} px",
            path.display(),
            pictures[0].width,
            pictures[0].height
        );
    }
    Ok(())
}
