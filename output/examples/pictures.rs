//! Renders scenes headless to an animated GIF (and PNG frames with `--png`): the pictures in
//! the README.
//!
//! `cargo run --release -p mpm-gimp-output --example pictures` renders every scene into
//! `results/pictures/`; `-- --scene drop3d --frames 90 --width 320 --out dir --png` picks one
//! scene, the length, the size, the directory, and also writes the frames as PNG.
//!
//! Scenes: `drop` (an elastic block dropped on a stick floor, 2D, coloured by speed) and
//! `drop3d` (the same in 3D, seen along z).

use mpm_gimp::{memory_requirements, HeapBuffer, World};
use mpm_gimp_output::picture::{render, write_gif, write_png, Colour};
use mpm_gimp_output::scenes::{drop_def, drop_fill};
use std::path::PathBuf;

const SCENES: [&str; 2] = ["drop", "drop3d"];

fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|k| args.get(k + 1).cloned())
}

fn main() -> std::io::Result<()> {
    let frames: usize = arg("--frames").map_or(60, |s| s.parse().expect("--frames N"));
    let width: u32 = arg("--width").map_or(200, |s| s.parse().expect("--width N"));
    let out = PathBuf::from(arg("--out").unwrap_or_else(|| "results/pictures".into()));
    let png = std::env::args().any(|a| a == "--png");
    let scenes: Vec<String> = match arg("--scene") {
        Some(s) => vec![s],
        None => SCENES.iter().map(|s| s.to_string()).collect(),
    };
    std::fs::create_dir_all(&out)?;
    for scene in scenes {
        let three_d = match scene.as_str() {
            "drop" => false,
            "drop3d" => true,
            other => panic!("unknown scene {other}: one of {SCENES:?}"),
        };
        let def = drop_def(three_d, false);
        let mut storage = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
        let mut world = World::init(&def, storage.as_mut_bytes()).expect("buffer fits");
        drop_fill(&mut world).expect("block fits");
        // Speeds from rest to the fall's 2.2 m/s at the floor, one colour scale for every frame.
        let range = (0.0, 2.5);
        let mut pictures = vec![];
        for k in 0..frames {
            let picture = render(&world, Colour::Speed, range, width);
            if png {
                let path = out.join(format!("{scene}_{k:04}.png"));
                write_png(std::fs::File::create(path)?, &picture)?;
            }
            pictures.push(picture);
            world.step(1.0 / 60.0).expect("a frame's substeps");
        }
        let path = out.join(format!("{scene}.gif"));
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
