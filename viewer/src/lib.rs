//! The samples viewer's state and drawing, apart from the window (`main.rs` owns the window and
//! turns its keys and mouse into an [`Input`]), so that tests run it without a display.
//!
//! - [`Sim`]: one scene of the registry ([`mpm_gimp_output::scenes::ALL`]) in a world of its
//!   own, its definition copied with particle forces declared so the mouse can push it; it
//!   steps a frame at a time on every core ([`tasks`]), timing each step.
//! - [`App`]: the viewer: the chosen scene and colour, pause and single step, the mouse drag,
//!   and [`App::draw`], which draws the panel (scene menu, live figures, help) and the picture
//!   into a [`Frame`].

pub mod text;

use mpm_gimp::{
    Dimension, Error, HeapBuffer, Real, Serial, StepReport, TaskSystem, Vec3, World, WorldDef,
    MAX_WORKERS,
};
use mpm_gimp_output::picture::{self, Colour, Picture};
use mpm_gimp_output::scenes::{Scene, ALL};
use mpm_gimp_rayon::RayonTasks;
use std::collections::VecDeque;
use std::sync::OnceLock;
use std::time::Instant;

/// Window width, pixels.
pub const WIDTH: usize = 1280;
/// Window height, pixels.
pub const HEIGHT: usize = 800;
/// Width of the panel at the left (menu, figures, help), pixels; the picture is right of it.
pub const PANEL: usize = 480;
/// Colour of the panel (0RGB).
pub const PANEL_BACKGROUND: u32 = 0x20_24_28;
/// Colour around the picture.
pub const AREA_BACKGROUND: u32 = 0x3a_3f_44;
const TEXT: u32 = 0xe8_e8_e8;
const DIM: u32 = 0x9a_a0_a6;
const HIGHLIGHT: u32 = 0xff_d0_40;
const ALERT: u32 = 0xff_60_50;
const SELECTED: u32 = 0x3c_4a_5c;

/// The colourings, in the order `c` cycles through them.
pub const COLOURS: [Colour; 4] = [
    Colour::Speed,
    Colour::Pressure,
    Colour::Temperature,
    Colour::Material,
];

/// The name of a colouring on screen.
pub fn colour_name(c: Colour) -> &'static str {
    match c {
        Colour::Speed => "speed",
        Colour::Pressure => "stress (pressure)",
        Colour::Temperature => "temperature",
        Colour::Material => "material",
    }
}

/// A value of colouring `c` with its unit.
fn with_unit(c: Colour, x: f64) -> String {
    match c {
        Colour::Speed => format!("{x:.2} m/s"),
        Colour::Pressure => format!("{:.1} kPa", x / 1e3),
        Colour::Temperature => format!("{x:.0} K"),
        Colour::Material => format!("{x:.0}"),
    }
}

/// An RGB picture in 0RGB pixels, rows top to bottom: what the window shows.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// `width * height` pixels, `0x00RRGGBB`.
    pub pixels: Vec<u32>,
}

impl Frame {
    /// A frame of one colour.
    pub fn new(width: usize, height: usize, colour: u32) -> Frame {
        Frame {
            width,
            height,
            pixels: vec![colour; width * height],
        }
    }

    /// Fills the rectangle at (`x`, `y`) of `w` by `h` pixels, clipped to the frame.
    pub fn fill_rect(&mut self, x: usize, y: usize, w: usize, h: usize, colour: u32) {
        for row in y.min(self.height)..(y + h).min(self.height) {
            let line = &mut self.pixels[row * self.width..(row + 1) * self.width];
            line[x.min(self.width)..(x + w).min(self.width)].fill(colour);
        }
    }

    /// Copies `p` with its top left corner at (`x`, `y`), clipped to the frame.
    pub fn blit(&mut self, p: &Picture, x: usize, y: usize) {
        for row in 0..(p.height as usize).min(self.height.saturating_sub(y)) {
            for col in 0..(p.width as usize).min(self.width.saturating_sub(x)) {
                let at = 3 * (row * p.width as usize + col);
                let [r, g, b] = [p.rgb[at], p.rgb[at + 1], p.rgb[at + 2]];
                self.pixels[(y + row) * self.width + x + col] =
                    (r as u32) << 16 | (g as u32) << 8 | b as u32;
            }
        }
    }

    /// The frame as an RGB [`Picture`] (for [`picture::write_png`]).
    pub fn to_picture(&self) -> Picture {
        let rgb = self
            .pixels
            .iter()
            .flat_map(|&p| [(p >> 16) as u8, (p >> 8) as u8, p as u8])
            .collect();
        Picture {
            width: self.width as u32,
            height: self.height as u32,
            rgb,
        }
    }
}

/// The rayon pool every scene steps on, made on first use: one thread per core the process
/// may use ([`std::thread::available_parallelism`], at most [`MAX_WORKERS`]), shared by the
/// scenes; none (the calling thread alone) if the cores are unknown or the pool cannot be
/// made. The results are the same either way.
fn pool() -> Option<&'static RayonTasks> {
    static POOL: OnceLock<Option<RayonTasks>> = OnceLock::new();
    POOL.get_or_init(|| {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let threads = cores.min(MAX_WORKERS as usize);
        (threads > 1)
            .then(|| RayonTasks::new(threads).ok())
            .flatten()
    })
    .as_ref()
}

/// The task system every scene steps on ([`pool`], or [`Serial`] without one).
pub fn tasks() -> &'static dyn TaskSystem {
    match pool() {
        Some(pool) => pool,
        None => &Serial,
    }
}

/// Steps `world` by `dt` on [`tasks`], from a thread of the pool (`RayonTasks::install`: the
/// passes then start on the pool's own threads).
fn step_on_every_core(world: &mut World<'_>, dt: Real) -> Result<StepReport, Error> {
    match pool() {
        Some(pool) => pool.install(|| world.step_with_tasks(dt, pool)),
        None => world.step(dt),
    }
}

/// Where the picture of a world of `def` sits in the window: its top left corner, size and
/// pixels per metre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PictureRect {
    /// Left edge, pixels.
    pub x: usize,
    /// Top edge, pixels.
    pub y: usize,
    /// Width, pixels (what [`picture::render`] is asked for).
    pub width: usize,
    /// Height, pixels (what [`picture::render`] makes of the width).
    pub height: usize,
    /// Pixels per metre.
    pub scale: f64,
    /// The grid's lowest corner (x, y), m.
    pub origin: [f64; 2],
}

impl PictureRect {
    /// The largest picture of the grid's x-y box that fits right of the panel with a margin,
    /// centred there.
    pub fn of(def: &WorldDef) -> PictureRect {
        let margin = 16;
        let (area_w, area_h) = (WIDTH - PANEL - 2 * margin, HEIGHT - 2 * margin);
        let (bw, bh) = (
            def.cells[0] as f64 * def.cell_size as f64,
            def.cells[1] as f64 * def.cell_size as f64,
        );
        let width = (area_w as f64).min(area_h as f64 * bw / bh).floor() as usize;
        let scale = width as f64 / bw;
        // As `picture::render` rounds it.
        let height = (bh * scale).round().max(1.0) as usize;
        PictureRect {
            x: PANEL + (WIDTH - PANEL - width) / 2,
            y: (HEIGHT - height) / 2,
            width,
            height,
            scale,
            origin: [def.origin.x as f64, def.origin.y as f64],
        }
    }

    /// The point (x, y) of the world, m, at window pixel (`px`, `py`), if the pixel is on the
    /// picture.
    pub fn to_world(&self, px: f64, py: f64) -> Option<[f64; 2]> {
        let (u, v) = (px - self.x as f64, py - self.y as f64);
        let inside =
            (0.0..self.width as f64).contains(&u) && (0.0..self.height as f64).contains(&v);
        inside.then(|| {
            [
                self.origin[0] + u / self.scale,
                self.origin[1] + (self.height as f64 - v) / self.scale,
            ]
        })
    }

    /// The window pixel (x, y) of the world's point `p`, m.
    pub fn to_window(&self, p: [f64; 2]) -> [f64; 2] {
        [
            self.x as f64 + (p[0] - self.origin[0]) * self.scale,
            self.y as f64 + self.height as f64 - (p[1] - self.origin[1]) * self.scale,
        ]
    }
}

/// The mouse pushing material: where the cursor is and how fast it moves, in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drag {
    /// The cursor's point (x, y), m.
    pub at: [f64; 2],
    /// The cursor's velocity (x, y), m/s (clamped to [`DRAG_SPEED`]).
    pub velocity: [f64; 2],
}

/// Radius of the drag's reach, m (at least [`DRAG_CELLS`] cells).
pub const DRAG_RADIUS: f64 = 0.08;
/// The drag's reach in cells, at least.
pub const DRAG_CELLS: f64 = 3.0;
/// Time in which the drag brings a particle at the cursor to the cursor's velocity, s: the
/// rate of its spring on the velocity difference. Each of a 60 Hz frame's [`DRAG_CALLS`] steps
/// (1/240 s) then closes 0.42 of the difference under a constant force: no overshoot.
pub const DRAG_TIME: f64 = 0.01;
/// Step calls a frame is split into while the mouse pushes, the forces set before each.
pub const DRAG_CALLS: usize = 4;
/// Largest cursor speed the drag follows, m/s: faster material would need more substeps than
/// a frame may take.
pub const DRAG_SPEED: f64 = 4.0;

/// One scene running in a world of its own.
pub struct Sim {
    /// The scene of the registry.
    pub scene: &'static Scene,
    /// The scene's definition with particle forces declared (the drag's force column) and
    /// sized for the workers of [`tasks`].
    pub def: WorldDef,
    storage: HeapBuffer,
    forces: [Vec<Real>; 3],
    /// The mouse acted in the last frame (forces set, or a collider carried).
    forces_set: bool,
    timings: VecDeque<f64>,
    /// The last step's report.
    pub last: StepReport,
    /// Particles frozen since the start or the last reset.
    pub frozen: u32,
}

/// How many frames' timings the median is taken over.
const TIMINGS: usize = 60;

impl Sim {
    /// The scene filled and at rest, time 0.
    pub fn new(scene: &'static Scene) -> Result<Sim, Error> {
        let mut def = (scene.def)();
        def.effects.particle_forces = true;
        def.workers = tasks().worker_count() as u32;
        let mut sim = Sim {
            scene,
            def,
            storage: Scene::storage(&def)?,
            forces: Default::default(),
            forces_set: false,
            timings: VecDeque::new(),
            last: StepReport::default(),
            frozen: 0,
        };
        sim.reset()?;
        Ok(sim)
    }

    /// Makes the scene anew in the same buffer.
    pub fn reset(&mut self) -> Result<(), Error> {
        let mut world = World::init(&self.def, self.storage.as_mut_bytes())?;
        (self.scene.fill)(&mut world)?;
        self.forces_set = false;
        self.timings.clear();
        self.last = StepReport::default();
        self.frozen = 0;
        Ok(())
    }

    /// The world, opened from its buffer (a constant-time check of the header).
    pub fn world(&mut self) -> World<'_> {
        World::reopen(self.storage.as_mut_bytes()).expect("the viewer's own world")
    }

    /// Steps one frame of the scene on [`tasks`], timing the steps. While the mouse pushes, the frame is
    /// stepped in [`DRAG_CALLS`] calls, the drag's forces set anew before each (a force the
    /// step holds constant changes a particle's velocity by less than half its difference from
    /// the cursor's at most, see [`DRAG_TIME`]). The report sums the calls' substeps and counts.
    pub fn advance(&mut self, drag: Option<Drag>) -> Result<&StepReport, Error> {
        let calls = if drag.is_some() { DRAG_CALLS } else { 1 };
        let dt = self.scene.frame_dt / calls as Real;
        let mut total = StepReport::default();
        let mut ns = 0.0;
        let mut particle_steps = 0.0;
        for _ in 0..calls {
            self.set_drag(drag)?;
            let mut world = World::reopen(self.storage.as_mut_bytes())?;
            (self.scene.host)(&mut world, dt)?;
            let n = world.particle_count();
            let start = Instant::now();
            let report = step_on_every_core(&mut world, dt)?;
            ns += start.elapsed().as_nanos() as f64;
            particle_steps += n as f64 * report.substeps as f64;
            total.substeps += report.substeps;
            total.substep_dt = report.substep_dt;
            total.stopped += report.stopped;
            total.escaped += report.escaped;
            total.frozen += report.frozen;
            total.runaway += report.runaway;
            for &id in &report.first_frozen {
                let _ = total.first_frozen.push(id);
            }
        }
        if particle_steps > 0.0 {
            if self.timings.len() == TIMINGS {
                self.timings.pop_front();
            }
            self.timings.push_back(ns / particle_steps);
        }
        self.frozen += total.frozen;
        self.last = total;
        Ok(&self.last)
    }

    /// The median wall time of the last frames' steps per particle and substep, ns, on all the
    /// workers of [`tasks`] (`None` before the first step).
    pub fn ns_per_particle_step(&self) -> Option<f64> {
        let mut t: Vec<f64> = self.timings.iter().copied().collect();
        if t.is_empty() {
            return None;
        }
        t.sort_by(f64::total_cmp);
        Some(t[t.len() / 2])
    }

    /// The drag's force on each particle within its reach: `m w (v_cursor - v) / DRAG_TIME`,
    /// `w = 1 - r / reach` falling to 0 at the reach (out of plane, `-m w v_z / DRAG_TIME`).
    /// The forces are set once more when the drag ends, to zero.
    fn set_drag(&mut self, drag: Option<Drag>) -> Result<(), Error> {
        // Nothing to do while the mouse neither drags nor has just let go.
        if drag.is_none() && !self.forces_set {
            return Ok(());
        }
        self.forces_set = drag.is_some();
        // A scene with a collider: the mouse carries the first one, at the cursor's velocity;
        // let go, it stays there at rest (its own motion otherwise left as the scene set it).
        let mut world = World::reopen(self.storage.as_mut_bytes())?;
        if world.collider_count() > 0 {
            let mut c = world.collider(0)?.def;
            match drag {
                Some(drag) => {
                    c.position = Vec3::new(drag.at[0] as Real, drag.at[1] as Real, c.position.z);
                    c.velocity = Vec3::new(drag.velocity[0] as Real, drag.velocity[1] as Real, 0.0);
                }
                None => c.velocity = Vec3::ZERO,
            }
            return world.set_collider(0, &c);
        }
        let reach = DRAG_RADIUS.max(DRAG_CELLS * self.def.cell_size as f64);
        let v = world.particles();
        let n = v.count;
        for f in &mut self.forces {
            f.clear();
            f.resize(n, 0.0);
        }
        if let Some(drag) = drag {
            for i in (0..n).filter(|&i| v.status[i] == 0) {
                let d = [
                    v.position[0][i] as f64 - drag.at[0],
                    v.position[1][i] as f64 - drag.at[1],
                ];
                let r = (d[0] * d[0] + d[1] * d[1]).sqrt();
                if r >= reach {
                    continue;
                }
                let w = v.mass[i] as f64 * (1.0 - r / reach) / DRAG_TIME;
                for a in 0..2 {
                    self.forces[a][i] = (w * (drag.velocity[a] - v.velocity[a][i] as f64)) as Real;
                }
                if v.dimension == Dimension::ThreeD {
                    self.forces[2][i] = (-w * v.velocity[2][i] as f64) as Real;
                }
            }
        }
        let [fx, fy, fz] = &self.forces;
        world.set_particle_forces(0, [fx, fy, fz])?;
        Ok(())
    }
}

/// What the viewer is told to do (the window maps its keys to these).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Command {
    /// Pause or run.
    TogglePause,
    /// One frame while paused (pauses if running).
    Step,
    /// The scene anew.
    Reset,
    /// The next colouring of [`COLOURS`].
    NextColour,
    /// This colouring.
    Colour(Colour),
    /// The scene of [`ALL`] at this index.
    Scene(usize),
    /// The scene before or after this one in the menu (-1 or +1).
    SceneBy(isize),
}

/// The window's input of one frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Input {
    /// Commands from keys.
    pub commands: Vec<Command>,
    /// Cursor position in the window, pixels, if it is over it.
    pub mouse: Option<(f32, f32)>,
    /// Whether the left button is down.
    pub left_down: bool,
}

/// Top of the scene menu, pixels.
const MENU_TOP: usize = 72;
/// Height of a menu line, pixels.
const MENU_LINE: usize = 26;
/// Left margin of the panel's text, pixels.
const PANEL_MARGIN: usize = 16;

/// The title of scene `k` as the menu shows it beside the scene's number and name: in at most
/// two lines that end before the panel's right margin; and whether they hold all of it.
pub fn menu_title(k: usize) -> (Vec<String>, bool) {
    let name = format!("{} {}", k + 1, ALL.get(k).map_or("", |s| s.name));
    let start = PANEL_MARGIN + name.chars().count() * 2 * text::GLYPH + 12;
    let title = ALL.get(k).map_or("", |s| s.title);
    text::wrap(title, PANEL.saturating_sub(PANEL_MARGIN / 2 + start), 1, 2)
}

/// The keys the panel lists at its foot.
pub const HELP: [&str; 4] = [
    "space pause/run    n or . single step    r reset",
    "c next colour, or s speed  p stress  t temp  m material",
    "drag on the picture: push material or move a collider",
    "esc or q: quit",
];

/// The scene menu's line at window pixel (`x`, `y`), if any.
pub fn menu_line_at(x: f32, y: f32) -> Option<usize> {
    if x < 0.0 || x >= PANEL as f32 || y < MENU_TOP as f32 {
        return None;
    }
    let k = (y as usize - MENU_TOP) / MENU_LINE;
    (k < ALL.len()).then_some(k)
}

/// The viewer: a running scene, its colouring, pause and the mouse.
pub struct App {
    /// The running scene (index into [`ALL`]).
    pub scene: usize,
    /// The scene's world.
    pub sim: Sim,
    /// The colouring.
    pub colour: Colour,
    /// Whether the simulation waits (single steps still step).
    pub paused: bool,
    /// The range of a colouring other than the scene's own: grown to every value seen since it
    /// was chosen (or the scene was reset), so that colours keep their meaning while it runs.
    auto_range: Option<(f64, f64)>,
    step_once: bool,
    was_down: bool,
    dragging: bool,
    last_cursor: Option<[f64; 2]>,
    /// The drag of the last frame (drawn as a circle).
    pub drag: Option<Drag>,
    /// Frames stepped since the scene started or was reset.
    pub frames: u64,
    /// The last error, shown in the panel.
    pub message: Option<String>,
}

impl App {
    /// The viewer on scene `scene` of [`ALL`], running, in the scene's colouring.
    pub fn new(scene: usize) -> Result<App, Error> {
        let s = &ALL[scene];
        Ok(App {
            scene,
            sim: Sim::new(s)?,
            colour: s.colour,
            paused: false,
            auto_range: None,
            step_once: false,
            was_down: false,
            dragging: false,
            last_cursor: None,
            drag: None,
            frames: 0,
            message: None,
        })
    }

    fn select(&mut self, scene: usize) {
        match Sim::new(&ALL[scene]) {
            Ok(sim) => {
                self.scene = scene;
                self.sim = sim;
                self.colour = ALL[scene].colour;
                self.after_reset();
            }
            Err(e) => self.message = Some(format!("{}: {e:?}", ALL[scene].name)),
        }
    }

    fn after_reset(&mut self) {
        self.auto_range = None;
        self.frames = 0;
        self.message = None;
    }

    /// Carries out `command`.
    pub fn command(&mut self, command: Command) {
        match command {
            Command::TogglePause => self.paused = !self.paused,
            Command::Step => {
                self.paused = true;
                self.step_once = true;
            }
            Command::Reset => {
                match self.sim.reset() {
                    Ok(()) => self.after_reset(),
                    Err(e) => self.message = Some(format!("reset: {e:?}")),
                };
            }
            Command::NextColour => {
                let k = COLOURS.iter().position(|&c| c == self.colour).unwrap_or(0);
                self.command(Command::Colour(COLOURS[(k + 1) % COLOURS.len()]));
            }
            Command::Colour(c) => {
                self.colour = c;
                self.auto_range = None;
            }
            Command::Scene(k) if k < ALL.len() => self.select(k),
            Command::Scene(_) => {}
            Command::SceneBy(d) => {
                let n = ALL.len() as isize;
                self.select((self.scene as isize + d).rem_euclid(n) as usize);
            }
        }
    }

    /// One frame: the commands, a click on the menu, the drag, and a step unless paused.
    pub fn update(&mut self, input: &Input) {
        for &c in &input.commands {
            self.command(c);
        }
        let pressed = input.left_down && !self.was_down;
        self.was_down = input.left_down;
        let rect = PictureRect::of(&self.sim.def);
        let cursor = input
            .mouse
            .and_then(|(x, y)| rect.to_world(x as f64, y as f64));
        if pressed {
            if let Some(k) = input.mouse.and_then(|(x, y)| menu_line_at(x, y)) {
                self.command(Command::Scene(k));
            }
            // A drag starts on the picture and goes on wherever the cursor goes in it.
            self.dragging = cursor.is_some();
            self.last_cursor = None;
        }
        self.dragging &= input.left_down;
        let dt = self.sim.scene.frame_dt as f64;
        self.drag = match (self.dragging, cursor) {
            (true, Some(at)) => {
                let mut velocity = match self.last_cursor {
                    Some(last) => [(at[0] - last[0]) / dt, (at[1] - last[1]) / dt],
                    None => [0.0; 2],
                };
                let speed = velocity[0].hypot(velocity[1]);
                if speed > DRAG_SPEED {
                    velocity = velocity.map(|v| v * DRAG_SPEED / speed);
                }
                Some(Drag { at, velocity })
            }
            _ => None,
        };
        self.last_cursor = cursor.filter(|_| self.dragging);
        if !self.paused || self.step_once {
            self.step_once = false;
            match self.sim.advance(self.drag) {
                Ok(_) => self.frames += 1,
                Err(e) => {
                    self.paused = true;
                    self.message = Some(format!("step: {e:?} (r resets)"));
                }
            }
        }
    }

    /// The colour range: the scene's own for its colouring; for another, every value seen
    /// since it was chosen (the material ids for material).
    pub fn range(&mut self) -> (f64, f64) {
        if self.colour == self.sim.scene.colour {
            return self.sim.scene.range;
        }
        let world = self.sim.world();
        if self.colour == Colour::Material {
            return (0.0, (world.material_count() as f64 - 1.0).max(1.0));
        }
        let (lo, hi) = picture::value_range(&world, self.colour);
        let (lo, hi) = match self.auto_range {
            Some((a, b)) => (a.min(lo), b.max(hi)),
            None => (lo, hi),
        };
        self.auto_range = Some((lo, hi));
        (lo, hi)
    }

    /// Draws the panel and the picture into `frame` ([`WIDTH`] x [`HEIGHT`]).
    pub fn draw(&mut self, frame: &mut Frame) {
        frame.fill_rect(0, 0, PANEL, frame.height, PANEL_BACKGROUND);
        frame.fill_rect(PANEL, 0, frame.width - PANEL, frame.height, AREA_BACKGROUND);
        let range = self.range();
        let rect = PictureRect::of(&self.sim.def);
        {
            let world = self.sim.world();
            let p = picture::render(&world, self.colour, range, rect.width as u32);
            frame.blit(&p, rect.x, rect.y);
        }
        if let Some(drag) = self.drag {
            let reach = DRAG_RADIUS.max(DRAG_CELLS * self.sim.def.cell_size as f64);
            let c = rect.to_window(drag.at);
            circle(frame, c, reach * rect.scale, 0xd0_30_30);
        }
        self.draw_panel(frame, range);
    }

    fn draw_panel(&mut self, frame: &mut Frame, range: (f64, f64)) {
        let x = PANEL_MARGIN;
        text::draw(frame, x, 16, 3, HIGHLIGHT, "mpm-gimp samples");
        text::draw(frame, x, 52, 1, DIM, "scenes: 1-9, up/down or click");
        for (k, s) in ALL.iter().enumerate() {
            let y = MENU_TOP + k * MENU_LINE;
            let current = k == self.scene;
            if current {
                frame.fill_rect(0, y, PANEL, MENU_LINE, SELECTED);
            }
            let colour = if current { HIGHLIGHT } else { TEXT };
            let line = format!("{} {}", k + 1, s.name);
            let end = text::draw(frame, x, y + 5, 2, colour, &line) + 12;
            let (lines, _) = menu_title(k);
            let top = if lines.len() == 1 { y + 9 } else { y + 4 };
            for (k, l) in lines.iter().enumerate() {
                text::draw(frame, end, top + 10 * k, 1, DIM, l);
            }
        }
        let mut y = MENU_TOP + ALL.len() * MENU_LINE + 20;
        let mut line = |frame: &mut Frame, colour: u32, s: &str| {
            text::draw(frame, x, y, 2, colour, s);
            y += 24;
        };
        let (n, time, heat) = {
            let world = self.sim.world();
            let heat = !world.particles().temperature.is_empty();
            (world.particle_count(), world.time(), heat)
        };
        let state = if self.paused { "PAUSED" } else { "running" };
        line(frame, if self.paused { HIGHLIGHT } else { TEXT }, state);
        line(
            frame,
            TEXT,
            &format!("t {time:.3} s  frame {}", self.frames),
        );
        let threads = tasks().worker_count();
        line(frame, TEXT, &format!("particles {n}  threads {threads}"));
        line(
            frame,
            TEXT,
            &format!("substeps {} / frame", self.sim.last.substeps),
        );
        let ns = self
            .sim
            .ns_per_particle_step()
            .map_or("-".to_string(), |t| format!("{t:.1}"));
        line(frame, TEXT, &format!("ns/particle-step {ns}"));
        let frozen = self.sim.frozen;
        line(
            frame,
            if frozen > 0 { ALERT } else { TEXT },
            &format!("frozen {frozen}"),
        );
        y += 8;
        let name = if self.colour == Colour::Temperature && !heat {
            "temperature (no heat)"
        } else {
            colour_name(self.colour)
        };
        text::draw(frame, x, y, 2, TEXT, &format!("colour: {name}"));
        y += 24;
        // The legend: the colour map across 256 pixels, the range's ends below it.
        for k in 0..256 {
            let [r, g, b] = picture::colour_map(k as f64 / 255.0);
            let c = (r as u32) << 16 | (g as u32) << 8 | b as u32;
            frame.fill_rect(x + k, y, 1, 14, c);
        }
        y += 18;
        let lo = with_unit(self.colour, range.0);
        let hi = with_unit(self.colour, range.1);
        text::draw(frame, x, y, 1, DIM, &lo);
        text::draw(frame, x + 256 - 8 * hi.len(), y, 1, DIM, &hi);
        y += 24;
        if let Some(m) = &self.message {
            let (lines, _) = text::wrap(m, PANEL - 2 * x, 1, 3);
            for (k, l) in lines.iter().enumerate() {
                text::draw(frame, x, y + 10 * k, 1, ALERT, l);
            }
        }
        let help = HELP;
        for (k, h) in help.iter().enumerate() {
            text::draw(
                frame,
                x,
                frame.height - 16 - 14 * (help.len() - k),
                1,
                DIM,
                h,
            );
        }
    }
}

/// A circle outline of `radius` pixels around `c`.
fn circle(frame: &mut Frame, c: [f64; 2], radius: f64, colour: u32) {
    let steps = (radius * 8.0).max(16.0) as usize;
    for k in 0..steps {
        let a = k as f64 * std::f64::consts::TAU / steps as f64;
        let (x, y) = (c[0] + radius * a.cos(), c[1] + radius * a.sin());
        if x >= 0.0 && y >= 0.0 {
            frame.fill_rect(x as usize, y as usize, 2, 2, colour);
        }
    }
}
