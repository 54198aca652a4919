//! The viewer program in a real window: it starts, runs a scene, and the screenshot of what
//! its window showed has the scene's particles and the panel's text.
//!
//! Needs an X display (CI runs it under `xvfb-run` with `MPM_REQUIRE_DISPLAY=1`). Without
//! `DISPLAY` the window test says so and passes, unless `MPM_REQUIRE_DISPLAY=1`, which makes a
//! missing display a failure.

use mpm_gimp_output::picture::BACKGROUND;
use mpm_gimp_output::scenes::ALL;
use mpm_gimp_viewer::{AREA_BACKGROUND, HEIGHT, PANEL, PANEL_BACKGROUND, WIDTH};
use std::path::PathBuf;
use std::process::Command;

const VIEWER: &str = env!("CARGO_BIN_EXE_mpm-gimp-viewer");

fn display() -> bool {
    let required = std::env::var("MPM_REQUIRE_DISPLAY").is_ok_and(|v| v == "1");
    let present = std::env::var_os("DISPLAY").is_some_and(|d| !d.is_empty());
    assert!(
        present || !required,
        "MPM_REQUIRE_DISPLAY=1 but no DISPLAY: run under xvfb-run"
    );
    if !present {
        eprintln!("no DISPLAY: the window test is skipped (xvfb-run runs it)");
    }
    present
}

/// The PNG at `path` as 0RGB pixels, with its size.
fn decode(path: &PathBuf) -> (usize, usize, Vec<u32>) {
    let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let px = buf[..info.buffer_size()]
        .chunks(3)
        .map(|c| (c[0] as u32) << 16 | (c[1] as u32) << 8 | c[2] as u32)
        .collect();
    (info.width as usize, info.height as usize, px)
}

/// `--scene drop --frames 30 --screenshot FILE` opens the window, runs 30 frames, writes what
/// the window shows and exits 0: a 1280 x 800 picture whose area right of the panel is more
/// than 1 % particles (neither background nor wall) and whose panel has text.
#[test]
fn the_window_shows_the_scene() {
    if !display() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("mpm-gimp-viewer-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let shot = dir.join("shot.png");
    let out = Command::new(VIEWER)
        .args(["--scene", "drop", "--frames", "30", "--screenshot"])
        .arg(&shot)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{:?}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let (w, h, px) = decode(&shot);
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!((w, h), (WIDTH, HEIGHT));
    let plain = [AREA_BACKGROUND, rgb(BACKGROUND), 0x5a_5a_5a];
    let particles = (0..h)
        .flat_map(|y| (PANEL..w).map(move |x| y * w + x))
        .filter(|&k| !plain.contains(&px[k]))
        .count();
    let area = (w - PANEL) * h;
    assert!(
        particles * 100 > area,
        "{particles} particle pixels of {area}"
    );
    let text = (0..h)
        .flat_map(|y| (0..PANEL).map(move |x| y * w + x))
        .filter(|&k| px[k] != PANEL_BACKGROUND)
        .count();
    assert!(text > 5000, "{text} panel pixels");
    println!("screenshot: {particles} particle pixels of {area}, {text} panel pixels");
}

fn rgb(c: [u8; 3]) -> u32 {
    (c[0] as u32) << 16 | (c[1] as u32) << 8 | c[2] as u32
}

/// `--list` prints every scene (no window needed); an unknown scene or argument is an error
/// that names the choices.
#[test]
fn the_command_line() {
    let out = Command::new(VIEWER).arg("--list").output().unwrap();
    assert!(out.status.success());
    let list = String::from_utf8(out.stdout).unwrap();
    assert_eq!(list.lines().count(), ALL.len());
    for s in ALL {
        assert!(list.contains(s.name), "{} missing", s.name);
    }
    let out = Command::new(VIEWER)
        .args(["--scene", "nothing"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("drop"));
    let out = Command::new(VIEWER).arg("--bogus").output().unwrap();
    assert!(!out.status.success());
    let out = Command::new(VIEWER)
        .args(["--screenshot", "x.png"])
        .output()
        .unwrap();
    assert!(!out.status.success(), "--screenshot without --frames");
}
