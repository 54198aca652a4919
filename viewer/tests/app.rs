//! The viewer without a window: every scene draws, the keys' commands do what they say, the
//! mouse pushes material and picks scenes, and the timings are measured.

use mpm_gimp_output::picture::{Colour, BACKGROUND};
use mpm_gimp_output::scenes::ALL;
use mpm_gimp_viewer::{
    menu_line_at, App, Command, Frame, Input, PictureRect, AREA_BACKGROUND, COLOURS, HEIGHT, PANEL,
    PANEL_BACKGROUND, WIDTH,
};

fn rgb(c: [u8; 3]) -> u32 {
    (c[0] as u32) << 16 | (c[1] as u32) << 8 | c[2] as u32
}

/// Pixels right of the panel that are neither background nor wall: the particles.
fn particle_pixels(f: &Frame) -> usize {
    let plain = [AREA_BACKGROUND, rgb(BACKGROUND), 0x5a_5a_5a];
    (0..f.height)
        .flat_map(|y| (PANEL..f.width).map(move |x| (x, y)))
        .filter(|&(x, y)| !plain.contains(&f.pixels[y * f.width + x]))
        .count()
}

/// Pixels of the panel that are not its background: text, the menu's bar, the legend.
fn panel_pixels(f: &Frame) -> usize {
    (0..f.height)
        .flat_map(|y| (0..PANEL).map(move |x| (x, y)))
        .filter(|&(x, y)| f.pixels[y * f.width + x] != PANEL_BACKGROUND)
        .count()
}

fn run(app: &mut App, frames: usize) {
    for _ in 0..frames {
        app.update(&Input::default());
    }
}

/// Every scene of the registry steps in the viewer and draws: its particles cover more than
/// 1 % of the picture area, the panel has its text, and no particle froze.
#[test]
fn every_scene_steps_and_draws() {
    for (k, scene) in ALL.iter().enumerate() {
        let mut app = App::new(k).unwrap();
        run(&mut app, 3);
        assert_eq!(app.frames, 3);
        assert_eq!(app.sim.frozen, 0, "{}", scene.name);
        let mut f = Frame::new(WIDTH, HEIGHT, 0);
        app.draw(&mut f);
        let area = (WIDTH - PANEL) * HEIGHT;
        let painted = particle_pixels(&f);
        assert!(painted * 100 > area, "{}: {painted} px", scene.name);
        assert!(panel_pixels(&f) > 5000, "{}", scene.name);
    }
}

/// Space pauses (the time stands), `n` steps exactly one frame and stays paused, space runs
/// again; `r` brings the time back to 0 with the same particles.
#[test]
fn pause_single_step_and_reset() {
    let mut app = App::new(0).unwrap();
    let dt = ALL[0].frame_dt as f64;
    let n = app.sim.world().particle_count();
    run(&mut app, 2);
    let t = |app: &mut App| app.sim.world().time();
    assert!((t(&mut app) - 2.0 * dt).abs() < 1e-9);
    app.command(Command::TogglePause);
    run(&mut app, 5);
    assert!((t(&mut app) - 2.0 * dt).abs() < 1e-9, "paused yet stepped");
    app.command(Command::Step);
    run(&mut app, 5);
    assert!(app.paused);
    assert!(
        (t(&mut app) - 3.0 * dt).abs() < 1e-9,
        "one step: {}",
        t(&mut app)
    );
    app.command(Command::TogglePause);
    run(&mut app, 1);
    assert!((t(&mut app) - 4.0 * dt).abs() < 1e-9);
    app.command(Command::Reset);
    assert_eq!(t(&mut app), 0.0);
    assert_eq!(app.frames, 0);
    assert_eq!(app.sim.world().particle_count(), n);
}

/// `c` cycles through the four colourings and back; a chosen one sticks; a scene starts in
/// its own colouring, and an unknown scene index changes nothing.
#[test]
fn colour_and_scene_commands() {
    let mut app = App::new(0).unwrap();
    let first = app.colour;
    let mut seen = vec![first];
    for _ in 0..COLOURS.len() {
        app.command(Command::NextColour);
        seen.push(app.colour);
    }
    assert_eq!(seen.last(), Some(&first));
    for c in COLOURS {
        assert!(seen.contains(&c), "{c:?} never shown");
    }
    app.command(Command::Colour(Colour::Material));
    assert_eq!(app.colour, Colour::Material);
    let heat = ALL.iter().position(|s| s.name == "heat").unwrap();
    app.command(Command::Scene(heat));
    assert_eq!((app.scene, app.colour), (heat, Colour::Temperature));
    app.command(Command::Scene(ALL.len()));
    assert_eq!(app.scene, heat);
    app.command(Command::SceneBy(1));
    assert_eq!(app.scene, (heat + 1) % ALL.len());
    app.command(Command::SceneBy(-1));
    assert_eq!(app.scene, heat);
}

/// A click on the menu's third line starts the third scene; a click below the menu does not
/// change it.
#[test]
fn a_click_on_the_menu_picks_a_scene() {
    let mut app = App::new(0).unwrap();
    let (x, y) = (40.0, 72.0 + 2.5 * 26.0);
    assert_eq!(menu_line_at(x, y), Some(2));
    let click = |app: &mut App, y: f32| {
        for down in [true, false] {
            app.update(&Input {
                commands: vec![],
                mouse: Some((x, y)),
                left_down: down,
            });
        }
    };
    click(&mut app, y);
    assert_eq!(app.scene, 2);
    assert_eq!(menu_line_at(x, HEIGHT as f32 - 20.0), None);
    click(&mut app, HEIGHT as f32 - 20.0);
    assert_eq!(app.scene, 2);
}

/// The window pixel of a world point maps back to it, and pixels off the picture map to none.
#[test]
fn window_and_world_coordinates_agree() {
    for s in ALL {
        let def = (s.def)();
        let r = PictureRect::of(&def);
        assert!(r.x >= PANEL && r.x + r.width <= WIDTH && r.y + r.height <= HEIGHT);
        let p = [0.3, 0.6];
        let w = r.to_window(p);
        let back = r.to_world(w[0], w[1]).unwrap();
        assert!((back[0] - p[0]).abs() < 1e-9 && (back[1] - p[1]).abs() < 1e-9);
        assert_eq!(r.to_world(PANEL as f64 - 1.0, 100.0), None);
    }
}

/// The particles within 0.05 m of `at`.
fn near(app: &mut App, at: [f64; 2]) -> Vec<usize> {
    let world = app.sim.world();
    let v = world.particles();
    let near: Vec<usize> = (0..v.count)
        .filter(|&i| {
            (v.position[0][i] as f64 - at[0]).hypot(v.position[1][i] as f64 - at[1]) < 0.05
        })
        .collect();
    assert!(near.len() > 10);
    near
}

/// Mean velocity along axis `a` of particles `ids`.
fn mean_velocity(app: &mut App, ids: &[usize], a: usize) -> f64 {
    let world = app.sim.world();
    let v = world.particles();
    ids.iter().map(|&i| v.velocity[a][i] as f64).sum::<f64>() / ids.len() as f64
}

/// Dragging with the left button from a point of a scene's material at 1.5 m/s drags the
/// particles that were under the cursor along, at least at half that speed more than the same
/// frames without the drag give them; the drag ends when the button is released.
#[test]
fn dragging_pushes_material() {
    // Free bodies: the falling block, dragged to the right for 12 frames (it lands 0.28 s in); a
    // flying disk, dragged up across its flight by a cursor that keeps up with it (1 m/s to
    // the right) for the 6 frames before it meets the other disk (at 0.11 s). Along its
    // flight a drag at 1.5 m/s could add no more than 0.5 m/s to its 1 m/s.
    for (name, start, cursor, axis, frames) in [
        ("drop", [0.5, 0.55], [1.5, 0.0], 0, 12),
        ("collide", [0.25, 0.55], [1.0, 1.5], 1, 6),
    ] {
        let k = ALL.iter().position(|s| s.name == name).unwrap();
        let dt = ALL[k].frame_dt as f64;
        let mut moved = App::new(k).unwrap();
        let mut still = App::new(k).unwrap();
        let ids = near(&mut moved, start);
        let rect = PictureRect::of(&moved.sim.def);
        let mut at = start;
        for _ in 0..frames {
            let w = rect.to_window(at);
            moved.update(&Input {
                commands: vec![],
                mouse: Some((w[0] as f32, w[1] as f32)),
                left_down: true,
            });
            assert!(moved.drag.is_some());
            still.update(&Input::default());
            at[0] += cursor[0] * dt;
            at[1] += cursor[1] * dt;
        }
        let pushed = mean_velocity(&mut moved, &ids, axis);
        let free = mean_velocity(&mut still, &ids, axis);
        println!("{name}: {pushed:.3} m/s pushed, {free:.3} m/s free");
        assert!(
            pushed - free > 0.75,
            "{name}: {pushed} m/s pushed, {free} free"
        );
        assert_eq!(moved.sim.frozen, 0);
        moved.update(&Input::default());
        assert!(moved.drag.is_none());
    }
}

/// After some frames the median step cost per particle and substep is known, positive and
/// below a millisecond, and the last step's substeps are counted.
#[test]
fn timings_are_measured() {
    let mut app = App::new(0).unwrap();
    assert!(app.sim.ns_per_particle_step().is_none());
    run(&mut app, 5);
    let ns = app.sim.ns_per_particle_step().unwrap();
    assert!(ns > 0.0 && ns < 1e6, "{ns} ns");
    assert!(app.sim.last.substeps >= 1);
}

/// The panel's text fits the panel: every scene's title whole in the menu's two lines beside
/// its name, the help lines within the panel's margins, and a long line wrapped to its width.
#[test]
fn the_panel_text_fits_the_panel() {
    use mpm_gimp_viewer::{menu_title, text, HELP};
    for (k, scene) in ALL.iter().enumerate() {
        let (lines, whole) = menu_title(k);
        assert!(whole && lines.len() <= 2, "{}: {lines:?}", scene.name);
        assert_eq!(lines.join(" "), scene.title);
    }
    for h in HELP {
        assert!(16 + h.len() * text::GLYPH <= PANEL - 8, "{h}");
    }
    let (lines, whole) = text::wrap("a bb ccc dddd eeeee", 5 * text::GLYPH, 1, 2);
    assert_eq!((lines, whole), (vec!["a bb".into(), "ccc..".into()], false));
    let (lines, whole) = text::wrap("abcdefgh ij", 4 * text::GLYPH, 1, 3);
    assert_eq!((lines, whole), (vec!["abcd".into(), "ij".into()], false));
}
