//! The samples viewer: every example scene of mpm-gimp in a window.
//!
//! `cargo run --release -p mpm-gimp-viewer` opens it on the first scene. Keys: 1-9 (or
//! up/down, or a click on the menu) choose a scene; space pauses and runs; n or . steps one
//! frame; r resets; c cycles the colouring, s p t m choose speed, stress (pressure),
//! temperature, material; dragging with the left button on the picture pushes material;
//! esc or q quits. The scenes step on every core (a rayon pool of one thread per core, see
//! `mpm_gimp_viewer::tasks`); the panel shows the thread count.
//!
//! Options: `--scene NAME` starts on that scene; `--frames N` runs N frames, prints the
//! median wall time of a frame's step (with the host's work between steps), drawing and
//! window update, and exits; `--screenshot FILE.png` (with `--frames`) then writes what the
//! window shows as PNG; `--list` prints the scenes and exits.

use minifb::{Key, KeyRepeat, MouseButton, MouseMode, Window, WindowOptions};
use mpm_gimp_output::picture::{write_png, Colour};
use mpm_gimp_output::scenes::ALL;
use mpm_gimp_viewer::{App, Command, Frame, Input, HEIGHT, PANEL_BACKGROUND, WIDTH};
use std::process::ExitCode;
use std::time::Instant;

/// The median of `t`, ms (0 for none).
fn median_ms(t: &mut [f64]) -> f64 {
    t.sort_by(f64::total_cmp);
    t.get(t.len() / 2).map_or(0.0, |s| s * 1e3)
}

struct Options {
    scene: usize,
    frames: Option<u64>,
    screenshot: Option<String>,
}

fn options() -> Result<Option<Options>, String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut o = Options {
        scene: 0,
        frames: None,
        screenshot: None,
    };
    let mut k = 0;
    while k < args.len() {
        let value = |k: usize| {
            args.get(k + 1)
                .cloned()
                .ok_or(format!("{} needs a value", args[k]))
        };
        match args[k].as_str() {
            "--list" => {
                for s in ALL {
                    println!("{:10} {}", s.name, s.title);
                }
                return Ok(None);
            }
            "--scene" => {
                let name = value(k)?;
                o.scene = ALL.iter().position(|s| s.name == name).ok_or_else(|| {
                    let names: Vec<_> = ALL.iter().map(|s| s.name).collect();
                    format!("unknown scene {name}: one of {}", names.join(", "))
                })?;
                k += 1;
            }
            "--frames" => {
                let n = value(k)?;
                o.frames = Some(n.parse().map_err(|_| format!("--frames {n}: a count"))?);
                k += 1;
            }
            "--screenshot" => {
                o.screenshot = Some(value(k)?);
                k += 1;
            }
            "-h" | "--help" => {
                println!(
                    "mpm-gimp-viewer [--scene NAME] [--frames N [--screenshot FILE.png]] [--list]"
                );
                return Ok(None);
            }
            other => return Err(format!("unknown argument {other} (--help)")),
        }
        k += 1;
    }
    if o.screenshot.is_some() && o.frames.is_none() {
        return Err("--screenshot needs --frames N".into());
    }
    Ok(Some(o))
}

/// The keys of this frame as commands; `None` to quit.
fn commands(window: &Window) -> Option<Vec<Command>> {
    let mut out = vec![];
    let digits = [
        (Key::Key1, Key::NumPad1),
        (Key::Key2, Key::NumPad2),
        (Key::Key3, Key::NumPad3),
        (Key::Key4, Key::NumPad4),
        (Key::Key5, Key::NumPad5),
        (Key::Key6, Key::NumPad6),
        (Key::Key7, Key::NumPad7),
        (Key::Key8, Key::NumPad8),
        (Key::Key9, Key::NumPad9),
    ];
    for key in window.get_keys_pressed(KeyRepeat::No) {
        let c = match key {
            Key::Escape | Key::Q => return None,
            Key::Space => Command::TogglePause,
            Key::N | Key::Period => Command::Step,
            Key::R => Command::Reset,
            Key::C => Command::NextColour,
            Key::S => Command::Colour(Colour::Speed),
            Key::P => Command::Colour(Colour::Pressure),
            Key::T => Command::Colour(Colour::Temperature),
            Key::M => Command::Colour(Colour::Material),
            Key::Up => Command::SceneBy(-1),
            Key::Down => Command::SceneBy(1),
            k => match digits.iter().position(|&(a, b)| k == a || k == b) {
                Some(d) => Command::Scene(d),
                None => continue,
            },
        };
        out.push(c);
    }
    Some(out)
}

fn run(o: Options) -> Result<(), String> {
    let mut app = App::new(o.scene).map_err(|e| format!("{}: {e:?}", ALL[o.scene].name))?;
    let mut window = Window::new("mpm-gimp samples", WIDTH, HEIGHT, WindowOptions::default())
        .map_err(|e| format!("no window: {e}"))?;
    // Interactive: at most 60 frames a second. A bounded run goes as fast as it steps.
    window.set_target_fps(if o.frames.is_some() { 0 } else { 60 });
    let mut frame = Frame::new(WIDTH, HEIGHT, PANEL_BACKGROUND);
    // Seconds each frame spent stepping, drawing and updating the window.
    let (mut step, mut draw, mut show) = (Vec::new(), Vec::new(), Vec::new());
    while window.is_open() {
        let Some(commands) = commands(&window) else {
            break;
        };
        let input = Input {
            commands,
            mouse: window.get_mouse_pos(MouseMode::Discard),
            left_down: window.get_mouse_down(MouseButton::Left),
        };
        let start = Instant::now();
        app.update(&input);
        let stepped = Instant::now();
        app.draw(&mut frame);
        let drawn = Instant::now();
        window
            .update_with_buffer(&frame.pixels, frame.width, frame.height)
            .map_err(|e| format!("window update: {e}"))?;
        step.push((stepped - start).as_secs_f64());
        draw.push((drawn - stepped).as_secs_f64());
        show.push(drawn.elapsed().as_secs_f64());
        if o.frames.is_some_and(|n| app.frames >= n) {
            break;
        }
        if let (Some(_), Some(m)) = (o.frames, &app.message) {
            return Err(format!("{}: {m}", ALL[app.scene].name));
        }
    }
    if o.frames.is_some() {
        println!(
            "{}: {} frames; a frame's medians: step {:.2} ms, draw {:.2} ms, window {:.2} ms",
            ALL[app.scene].name,
            app.frames,
            median_ms(&mut step),
            median_ms(&mut draw),
            median_ms(&mut show)
        );
    }
    if let Some(path) = &o.screenshot {
        // What the window showed last: the buffer it was given.
        let file = std::fs::File::create(path).map_err(|e| format!("{path}: {e}"))?;
        write_png(std::io::BufWriter::new(file), &frame.to_picture())
            .map_err(|e| format!("{path}: {e}"))?;
        println!(
            "{path}: {} x {} px, after {} frames",
            frame.width, frame.height, app.frames
        );
    }
    Ok(())
}

fn main() -> ExitCode {
    match options().and_then(|o| o.map_or(Ok(()), run)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("mpm-gimp-viewer: {e}");
            ExitCode::FAILURE
        }
    }
}
