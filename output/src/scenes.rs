//! The example scenes, defined once for the programs that run, draw or render them (the
//! kernel's `drop` example, the `pictures` example, the samples viewer).
//!
//! [`ALL`] is the registry: each [`Scene`] names its definition, its fill, its frame length,
//! its default colouring and duration. A new scene is one more entry there (and its two
//! functions); the viewer's menu, the `pictures` example and the registry's test
//! (`output/tests/scenes.rs`) pick it up from the list.
//!
//! Stiffness is chosen for a substep budget, as a game would: each scene's stiffest material is
//! the stiffest that its [`Scene::substeps`] substeps a frame step at the speeds it reaches
//! ([`crate::stiffness`]). Softer would be cheaper and squash more; stiffer, dearer.

use crate::picture::Colour;
use crate::stiffness::{modulus_for_substeps, youngs_modulus};
use crate::tap::Tap;
use mpm_gimp::{
    memory_requirements, Boundary, ColliderDef, ColliderShape, Contact, Dimension, Error, Face,
    HeapBuffer, MaterialDef, MaterialModel, Real, Removal, ScalarBoundary, ScalarField, StepReport,
    Transfer, Transport, Vec3, World, WorldDef,
};

/// One example scene: how to make it, how to show it, how long it runs.
#[derive(Clone, Copy, Debug)]
pub struct Scene {
    /// Short name for command lines and file names (`drop` writes `drop.gif`).
    pub name: &'static str,
    /// A line saying what it shows, for menus.
    pub title: &'static str,
    /// The world's definition.
    pub def: fn() -> WorldDef,
    /// Fills a world made from `def` (materials, particles, their scalars); returns how many
    /// particles it added.
    pub fill: fn(&mut World) -> Result<usize, Error>,
    /// What the host does before each frame of the given length (s): most scenes nothing
    /// ([`no_host`]); the tap pours and drains ([`crate::tap::Tap::frame`]). [`Scene::frame`]
    /// calls it.
    pub host: fn(&mut World, Real) -> Result<(), Error>,
    /// Simulated time of one frame, s (one [`World::step`] call).
    pub frame_dt: Real,
    /// Substeps a frame its materials were chosen for: its stiffest material is the stiffest
    /// that this many substeps step at the speeds the scene reaches
    /// ([`crate::stiffness::modulus_for_substeps`]); a frame where a particle outruns them
    /// takes one or two more. Snow stiffens as it packs: the snowball's is what its packed
    /// snow takes. The registry's test checks that the default run averages no more.
    pub substeps: u32,
    /// Frames of its default run (the pictures' length; the registry's test runs them all
    /// and checks that no particle froze).
    pub frames: usize,
    /// What colours its particles by default.
    pub colour: Colour,
    /// The range of that colour, dark to light, one scale for the whole run.
    pub range: (f64, f64),
    /// Whether the README shows it: the `pictures` example renders these unless asked for
    /// one scene or `--all`.
    pub in_readme: bool,
}

impl Scene {
    /// A zeroed, aligned buffer large enough for a world of `def` (the scene's definition,
    /// or a copy the host changed, such as the viewer's with particle forces declared).
    pub fn storage(def: &WorldDef) -> Result<HeapBuffer, Error> {
        Ok(HeapBuffer::new(memory_requirements(def)?.bytes))
    }

    /// One frame of `dt` (s; the scene's [`Scene::frame_dt`], or a part of it): the host's
    /// work between steps ([`Scene::host`]), then the step.
    pub fn frame(&self, world: &mut World, dt: Real) -> Result<StepReport, Error> {
        (self.host)(world, dt)?;
        world.step(dt)
    }
}

/// The host of a scene that needs none between frames.
pub fn no_host(_: &mut World, _: Real) -> Result<(), Error> {
    Ok(())
}

/// Frames between two reorders of a long scene's particles ([`sorting_host`]).
pub const SORT_EVERY: u64 = 30;

/// The host of a long scene whose material mixes (water, sand, a drum): every [`SORT_EVERY`]
/// frames it reorders the particles by cell ([`World::sort_particles`]), which gives the
/// step back the order it is fastest in (benches/PERFORMANCE.md, "Reordering particles").
/// The particles' ids change then; a reader that follows one takes the permutation.
pub fn sorting_host(world: &mut World, _: Real) -> Result<(), Error> {
    let frame = (world.time() / FRAME as f64).round() as u64;
    if frame > 0 && frame.is_multiple_of(SORT_EVERY) {
        world.sort_particles(&mut vec![0; world.particle_count()])?;
    }
    Ok(())
}

/// Every example scene, in menu order.
pub const ALL: &[Scene] = &[
    Scene {
        name: "drop",
        title: "Rubber block dropped on a stick floor",
        def: || drop_def(false, false),
        fill: drop_fill,
        host: no_host,
        frame_dt: FRAME,
        substeps: DROP_SUBSTEPS,
        frames: 60,
        // Speeds from rest to the fall's 2.7 m/s at the floor.
        colour: Colour::Speed,
        range: (0.0, 2.5),
        in_readme: true,
    },
    Scene {
        name: "drop3d",
        title: "The same block in 3D, seen along z",
        def: || drop_def(true, false),
        fill: drop_fill,
        host: no_host,
        frame_dt: FRAME,
        substeps: DROP_SUBSTEPS,
        frames: 60,
        colour: Colour::Speed,
        range: (0.0, 2.5),
        in_readme: true,
    },
    Scene {
        name: "collide",
        title: "Two rubber disks collide (APIC)",
        def: collide_def,
        fill: collide_fill,
        host: no_host,
        frame_dt: FRAME,
        substeps: COLLIDE_SUBSTEPS,
        frames: 90,
        colour: Colour::Speed,
        range: (0.0, 1.5),
        in_readme: false,
    },
    Scene {
        name: "beam",
        title: "Cantilever sags under gravity",
        def: beam_def,
        fill: beam_fill,
        host: no_host,
        frame_dt: FRAME,
        substeps: BEAM_SUBSTEPS,
        frames: 90,
        // Bending stress at the root: about +-30 kPa of pressure as it swings (3 rho g L^2 / h
        // = 43 kPa of axial stress at the fibres when it hangs still).
        colour: Colour::Pressure,
        range: (-3.0e4, 3.0e4),
        in_readme: false,
    },
    Scene {
        name: "heat",
        title: "Block warmed by a hot floor",
        def: heat_def,
        fill: heat_fill,
        host: no_host,
        frame_dt: FRAME,
        substeps: HEAT_SUBSTEPS,
        frames: 120,
        colour: Colour::Temperature,
        range: (HEAT_COLD as f64, HEAT_HOT as f64),
        in_readme: false,
    },
    Scene {
        name: "water",
        title: "Wooden block dropped into a water tank",
        def: water_def,
        fill: water_fill,
        host: sorting_host,
        frame_dt: FRAME,
        substeps: WATER_SUBSTEPS,
        frames: 90,
        // Water (material 0) dark, wood (1) light: flat colours keep its GIF small, where the
        // sloshing speeds made it 0.8 MB.
        colour: Colour::Material,
        range: (0.0, 1.0),
        in_readme: true,
    },
    Scene {
        name: "sand",
        title: "Sand column collapses into a pile",
        def: sand_def,
        fill: sand_fill,
        host: sorting_host,
        frame_dt: FRAME,
        substeps: SAND_SUBSTEPS,
        frames: 75,
        colour: Colour::Speed,
        range: (0.0, 1.5),
        in_readme: true,
    },
    Scene {
        name: "snowball",
        title: "Snowball thrown at a wall",
        def: snowball_def,
        fill: snowball_fill,
        host: no_host,
        frame_dt: FRAME,
        substeps: SNOWBALL_PACKED_SUBSTEPS,
        frames: 60,
        colour: Colour::Speed,
        range: (0.0, 6.0),
        in_readme: true,
    },
    Scene {
        name: "metal",
        title: "Weight dropped on a soft-metal cantilever bends it for good",
        def: metal_def,
        fill: metal_fill,
        host: no_host,
        frame_dt: FRAME,
        substeps: METAL_SUBSTEPS,
        frames: 60,
        // The bending stress at the root passes the yield stress (83 kPa) and stays there.
        colour: Colour::Pressure,
        range: (-1.0e5, 1.0e5),
        in_readme: true,
    },
    Scene {
        name: "paddle",
        title: "A turning paddle stirs a water tank",
        def: paddle_def,
        fill: paddle_fill,
        host: sorting_host,
        frame_dt: FRAME,
        substeps: WATER_SUBSTEPS,
        frames: 120,
        // One flat colour keeps its GIF small (by speed it was 1.4 MB).
        colour: Colour::Material,
        range: (0.0, 1.0),
        in_readme: true,
    },
    Scene {
        name: "drum",
        title: "Sand tumbles in a turning drum",
        def: drum_def,
        fill: drum_fill,
        host: sorting_host,
        frame_dt: FRAME,
        substeps: SAND_SUBSTEPS,
        frames: 120,
        // As the paddle's.
        colour: Colour::Material,
        range: (0.0, 1.0),
        in_readme: true,
    },
    Scene {
        name: "plough",
        title: "A plough pushes a layer of snow into a bank",
        def: plough_def,
        fill: plough_fill,
        host: no_host,
        frame_dt: FRAME,
        substeps: SNOWBALL_PACKED_SUBSTEPS,
        frames: 60,
        colour: Colour::Material,
        range: (0.0, 1.0),
        in_readme: true,
    },
    Scene {
        name: "punch",
        title: "A punch presses a dent into a soft-metal plate",
        def: punch_def,
        fill: punch_fill,
        host: no_host,
        frame_dt: FRAME,
        substeps: METAL_SUBSTEPS,
        frames: 60,
        colour: Colour::Pressure,
        range: (-2.0e5, 2.0e5),
        in_readme: true,
    },
    Scene {
        name: "tap",
        title: "A tap pours water into a basin that drains",
        def: water_def,
        fill: tap_fill,
        host: tap_host,
        frame_dt: FRAME,
        substeps: WATER_SUBSTEPS,
        frames: 120,
        colour: Colour::Speed,
        range: (0.0, 5.0),
        in_readme: true,
    },
];

/// The frame of every scene: 1/60 s.
const FRAME: Real = 1.0 / 60.0;

/// Young's modulus (Pa) of the stiffest solid of `density` and Poisson's ratio `nu` that a
/// world of `def` steps in `substeps` substeps a [`FRAME`] while no particle is faster than
/// `max_speed` (m/s).
fn budget_modulus(def: &WorldDef, density: Real, nu: Real, substeps: u32, max_speed: Real) -> Real {
    youngs_modulus(
        modulus_for_substeps(def, density, FRAME, substeps, max_speed),
        nu,
    )
}

/// The scene named `name`, if [`ALL`] has it.
pub fn find(name: &str) -> Option<&'static Scene> {
    ALL.iter().find(|s| s.name == name)
}

/// The drop scene's definition: a 1 m box of 40 cells per axis (2D, or 3D with `three_d`)
/// whose floor is a stick wall; `classic` switches to classic MPM (linear shape functions with
/// USL, unstable where particles cross cells).
pub fn drop_def(three_d: bool, classic: bool) -> WorldDef {
    let mut def = WorldDef {
        cells: [40, 40, if three_d { 40 } else { 1 }],
        cell_size: 0.025,
        particle_capacity: 100_000,
        dimension: if three_d {
            Dimension::ThreeD
        } else {
            Dimension::Plane2D
        },
        ..WorldDef::DEFAULT
    };
    def.faces[Face::YMin as usize] = Boundary::Stick;
    if classic {
        def.shape = mpm_gimp::ShapeFunction::Linear;
        def.update_order = mpm_gimp::UpdateOrder::Usl;
    }
    def
}

/// Substeps a frame of the drop scenes: their rubber's budget, at up to 4 m/s (the block meets
/// the floor at 2.7 m/s; parts of it rebound faster).
const DROP_SUBSTEPS: u32 = 20;

/// Fills a world made from [`drop_def`]: a soft rubber block at rest, 0.4 m by 0.3 m (by
/// 0.3 m) with its bottom 0.4 m above the floor. The rubber (neo-Hookean, 1000 kg/m^3, nu = 0.3)
/// is the stiffest that [`DROP_SUBSTEPS`] substeps a frame carry: E = 90 kPa in the scene's
/// 40-cell box (its own weight shortens it by about 1 %; it squashes by a fifth when it lands).
/// Returns how many particles it holds.
pub fn drop_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let rubber = world.add_material(&MaterialDef {
        youngs_modulus: budget_modulus(&def, 1000.0, 0.3, DROP_SUBSTEPS, 4.0),
        ..MaterialDef::DEFAULT
    })?;
    let (lo, hi) = if world.def().dimension == Dimension::ThreeD {
        (Vec3::new(0.35, 0.4, 0.35), Vec3::new(0.65, 0.7, 0.65))
    } else {
        (Vec3::new(0.3, 0.4, 0.0), Vec3::new(0.7, 0.7, 0.0))
    };
    Ok(world.fill_box(lo, hi, rubber, Vec3::ZERO)?.len())
}

/// Two disks in a 1 m box of 48 cells without gravity, APIC transfer (it conserves the angular
/// momentum the off-centre impact gives them).
fn collide_def() -> WorldDef {
    WorldDef {
        cells: [48, 48, 1],
        cell_size: 1.0 / 48.0,
        transfer: Transfer::Apic,
        gravity: Vec3::ZERO,
        ..WorldDef::DEFAULT
    }
}

/// Substeps a frame of the collide scene: its stiffer rubber's budget, at up to 2 m/s.
const COLLIDE_SUBSTEPS: u32 = 20;

/// Two rubber disks of radius 0.15 m (two materials: the right one, E = 82 kPa, the stiffest
/// that [`COLLIDE_SUBSTEPS`] substeps a frame carry; the left one half as stiff), moving at
/// 1 m/s towards each other, their centres 0.1 m apart across the line of motion: they
/// collide off centre about 0.1 s in, bounce and spin.
fn collide_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let e = budget_modulus(&def, 1000.0, 0.3, COLLIDE_SUBSTEPS, 2.0);
    let soft = world.add_material(&MaterialDef {
        youngs_modulus: e / 2.0,
        ..MaterialDef::DEFAULT
    })?;
    let stiff = world.add_material(&MaterialDef {
        youngs_modulus: e,
        ..MaterialDef::DEFAULT
    })?;
    let a = world.fill_disk(
        Vec3::new(0.25, 0.55, 0.0),
        0.15,
        soft,
        Vec3::new(1.0, 0.0, 0.0),
    )?;
    let b = world.fill_disk(
        Vec3::new(0.75, 0.45, 0.0),
        0.15,
        stiff,
        Vec3::new(-1.0, 0.0, 0.0),
    )?;
    Ok(a.len() + b.len())
}

/// A 1 m box of 40 cells whose left wall sticks: the clamp of the cantilever.
fn beam_def() -> WorldDef {
    let mut def = WorldDef {
        cells: [40, 40, 1],
        cell_size: 1.0 / 40.0,
        ..WorldDef::DEFAULT
    };
    def.faces[Face::XMin as usize] = Boundary::Stick;
    def
}

/// Substeps a frame of the beam scene: its rubber's budget, at up to 2 m/s.
const BEAM_SUBSTEPS: u32 = 24;

/// A rubber beam 0.45 m long and 0.14 m deep, its left end against the stick wall, starting
/// straight and at rest: it falls and swings about its sagged shape. The rubber is the stiffest
/// that [`BEAM_SUBSTEPS`] substeps a frame carry, E = 190 kPa; the beam is short and deep
/// for it (beam theory's static deflection at the tip, `3 rho g L^4 / (2 E h^2)`, is 0.16 m;
/// released from straight it swings down to about 1.5 times that).
fn beam_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    // The wall plane: one cell of margin in from the grid's face.
    let wall = def.origin.x + def.shape.margin_cells() as Real * def.cell_size;
    let rubber = world.add_material(&MaterialDef {
        youngs_modulus: budget_modulus(&def, 1000.0, 0.3, BEAM_SUBSTEPS, 2.0),
        ..MaterialDef::DEFAULT
    })?;
    Ok(world
        .fill_box(
            Vec3::new(wall, 0.56, 0.0),
            Vec3::new(wall + 0.45, 0.7, 0.0),
            rubber,
            Vec3::ZERO,
        )?
        .len())
}

/// The block's starting temperature, K.
const HEAT_COLD: Real = 300.0;
/// The floor's temperature, K.
const HEAT_HOT: Real = 500.0;

/// A 1 m box of 40 cells with a stick floor held at [`HEAT_HOT`] and every other face
/// insulated.
fn heat_def() -> WorldDef {
    let mut def = drop_def(false, false);
    let mut heat = Transport::INSULATED;
    heat.faces[Face::YMin as usize] = ScalarBoundary::Fixed(HEAT_HOT);
    def.effects.heat = Some(heat);
    def
}

/// Substeps a frame of the heat scene: its block's budget, at up to 0.5 m/s (it settles under
/// its weight; the conduction's own bound asks for 5).
const HEAT_SUBSTEPS: u32 = 16;

/// A block (0.5 m by 0.4 m; E = 98 kPa, the stiffest that [`HEAT_SUBSTEPS`] substeps a frame
/// carry: its weight shortens it by 1.5 %) resting on the hot floor at [`HEAT_COLD`]: it warms
/// from below, the front diffusing up through it within a few seconds (a thermal diffusivity
/// of 0.02 m^2/s, far above any real solid's, to be seen), and it expands a little as it warms.
fn heat_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let floor = def.origin.y + def.shape.margin_cells() as Real * def.cell_size;
    let block = world.add_material(&MaterialDef {
        youngs_modulus: budget_modulus(&def, 1000.0, 0.3, HEAT_SUBSTEPS, 0.5),
        conductivity: 2.0e4,
        thermal_expansion: 2.0e-4,
        reference_temperature: HEAT_COLD,
        ..MaterialDef::DEFAULT
    })?;
    let ids = world.fill_box(
        Vec3::new(0.25, floor, 0.0),
        Vec3::new(0.75, floor + 0.4, 0.0),
        block,
        Vec3::ZERO,
    )?;
    let cold = vec![HEAT_COLD; ids.len()];
    world.set_particle_scalar(ScalarField::Temperature, ids.start, &cold)?;
    Ok(ids.len())
}

/// Fills `world` from wall to wall with still water `depth` m deep above its floor (the
/// water scenes' fluid, with bulk modulus `k`, Pa, and a little viscosity), and returns the
/// water's material and the height of its surface, m.
pub fn still_water(world: &mut World, k: Real, depth: Real) -> Result<(u32, Real), Error> {
    let def = world.def();
    let margin = def.shape.margin_cells() as Real * def.cell_size;
    let (left, right) = (
        def.origin.x + margin,
        def.origin.x + def.cells[0] as Real * def.cell_size - margin,
    );
    let surface = floor(&def) + depth;
    let water = world.add_material(&MaterialDef {
        bulk_modulus: k,
        ..water(&def)
    })?;
    world.fill_box(
        Vec3::new(left, floor(&def), 0.0),
        Vec3::new(right, surface, 0.0),
        water,
        Vec3::ZERO,
    )?;
    Ok((water, surface))
}

/// Which water [`floating_box`] cuts out to make room for the box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cut {
    /// Every particle whose domain reaches into the box or touches it (`Removal::Collider`):
    /// the water starts clear of the box.
    Domains,
    /// The particles whose centre lies inside the box, as a host that tests points would cut:
    /// the water next to the box overlaps it by up to half a particle's width.
    Centres,
}

/// Floats a box `width` by `height` m of `density` kg/m^3 (2D, per metre of thickness) at
/// Archimedes' depth below still water whose surface is at `surface` (m), its centre at x =
/// 0.5 m, tilted `tilt` rad: cuts the water out of its place (`cut`) and adds it as a dynamic
/// collider that the step moves (free to turn with `turn`), and returns the collider's id and
/// Archimedes' depth (m) it was placed at, for water of 1000 kg/m^3 ([`still_water`]'s).
#[allow(clippy::too_many_arguments)]
pub fn floating_box(
    world: &mut World,
    surface: Real,
    [width, height]: [Real; 2],
    density: Real,
    tilt: Real,
    turn: bool,
    cut: Cut,
) -> Result<(u32, Real), Error> {
    let draft = density / 1000.0 * height;
    let centre = Vec3::new(0.5, surface - draft + height / 2.0, 0.0);
    let half = Vec3::new(width / 2.0, height / 2.0, 0.5);
    let mass = density * width * height;
    let inertia = mass * (width * width + height * height) / 12.0;
    let id = world.add_collider(&ColliderDef {
        shape: ColliderShape::Box { half_extents: half },
        position: centre,
        rotation: [0.0, 0.0, (tilt / 2.0).sin(), (tilt / 2.0).cos()],
        mass,
        inertia: Vec3::new(0.0, 0.0, if turn { inertia } else { 0.0 }),
        ..ColliderDef::DEFAULT
    })?;
    if cut == Cut::Domains {
        world.remove_particles(Removal::Collider(id))?;
        return Ok((id, draft));
    }
    let p = world.particles();
    let inside: Vec<u32> = (0..p.count)
        .filter(|&i| {
            let x = Vec3::new(p.position[0][i], p.position[1][i], 0.0);
            world.collider_distance(id, x).is_ok_and(|d| d < 0.0)
        })
        .map(|i| i as u32)
        .collect();
    world.remove_particles(Removal::List(&inside))?;
    Ok((id, draft))
}

/// The height of a 2D water surface, m, over the particles whose x `far` keeps (away from a
/// floating body, say): the top of each column of particles one particle spacing wide (its
/// highest centre plus half a spacing), and the median of those tops. The median, not the
/// highest particle: a particle the wall or the transfer's noise lifts a fraction of a
/// spacing above its neighbours is not the level (the highest one drifts up by 3 mm over
/// four minutes in the floating-box tank while the median holds to 0.2 mm). `None` when
/// `far` keeps no particle.
pub fn surface_height(world: &World, far: impl Fn(Real) -> bool) -> Option<Real> {
    let def = world.def();
    let spacing = def.cell_size / def.particles_per_cell as Real;
    let p = world.particles();
    let mut tops = std::collections::BTreeMap::<i64, Real>::new();
    for i in (0..p.count).filter(|&i| far(p.position[0][i])) {
        let column = (p.position[0][i] / spacing).floor() as i64;
        let top = tops.entry(column).or_insert(Real::MIN);
        *top = top.max(p.position[1][i]);
    }
    let mut tops: Vec<Real> = tops.into_values().collect();
    tops.sort_by(Real::total_cmp);
    Some(*tops.get(tops.len() / 2)? + spacing / 2.0)
}

/// The floor of a world: its lower y wall plane, m.
fn floor(def: &WorldDef) -> Real {
    def.origin.y + def.shape.margin_cells() as Real * def.cell_size
}

/// A 1 m box of 50 cells with slip walls, APIC (the transfer for fluids: no particle noise
/// near the walls, little numerical viscosity).
fn water_def() -> WorldDef {
    WorldDef {
        cells: [50, 50, 1],
        cell_size: 0.02,
        transfer: Transfer::Apic,
        ..WorldDef::DEFAULT
    }
}

/// Substeps a frame of the water scene: the budget of both its materials, at up to 2.5 m/s (the
/// block meets the water at 2.4 m/s).
const WATER_SUBSTEPS: u32 = 20;

/// Water 0.35 m deep across the box and a wooden block (fixed-corotated, 600 kg/m^3, so it
/// floats) 0.2 m square dropped from 0.3 m above the surface. Both are the stiffest that
/// [`WATER_SUBSTEPS`] substeps a frame carry: the water is weakly compressible, K = 90 kPa (a
/// sound speed of 9.5 m/s, with a little viscosity; its weight compresses the column by
/// `rho g H / K` = 3.8 % at the bottom), the wood E = 40 kPa.
fn water_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let (y0, wall) = (floor(&def), floor(&def));
    let water = world.add_material(&water(&def))?;
    let wood = world.add_material(&MaterialDef {
        model: MaterialModel::FixedCorotated,
        youngs_modulus: budget_modulus(&def, 600.0, 0.3, WATER_SUBSTEPS, 2.5),
        density: 600.0,
        ..MaterialDef::DEFAULT
    })?;
    let a = world.fill_box(
        Vec3::new(wall, y0, 0.0),
        Vec3::new(1.0 - wall, y0 + 0.35, 0.0),
        water,
        Vec3::ZERO,
    )?;
    let b = world.fill_box(
        Vec3::new(0.4, y0 + 0.65, 0.0),
        Vec3::new(0.6, y0 + 0.85, 0.0),
        wood,
        Vec3::ZERO,
    )?;
    Ok(a.len() + b.len())
}

/// A 1 m box of 50 cells with a rough (stick) floor; plasticity declared.
fn sand_def() -> WorldDef {
    let mut def = WorldDef {
        cells: [50, 50, 1],
        cell_size: 0.02,
        ..WorldDef::DEFAULT
    };
    def.faces[Face::YMin as usize] = Boundary::Stick;
    def.effects.plasticity = true;
    def
}

/// Substeps a frame of the sand scene: its sand's budget, at up to 2.5 m/s.
const SAND_SUBSTEPS: u32 = 20;

/// A column of dry sand (Drucker-Prager, friction angle 30 degrees, 1600 kg/m^3; E = 107 kPa,
/// the stiffest that [`SAND_SUBSTEPS`] substeps a frame carry: the column's weight compresses
/// it by 4 % at the bottom), 0.2 m wide and 0.4 m high against the left wall, released: it
/// collapses and spreads into a pile whose slope its friction holds.
fn sand_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let (y0, wall) = (floor(&def), floor(&def));
    let sand = world.add_material(&sand(&def))?;
    Ok(world
        .fill_box(
            Vec3::new(wall, y0, 0.0),
            Vec3::new(wall + 0.2, y0 + 0.4, 0.0),
            sand,
            Vec3::ZERO,
        )?
        .len())
}

/// A 1 m box of 50 cells whose right wall and floor are stick walls; plasticity declared.
fn snowball_def() -> WorldDef {
    let mut def = WorldDef {
        cells: [50, 50, 1],
        cell_size: 0.02,
        ..WorldDef::DEFAULT
    };
    def.faces[Face::XMax as usize] = Boundary::Stick;
    def.faces[Face::YMin as usize] = Boundary::Stick;
    def.effects.plasticity = true;
    def
}

/// Substeps a frame of the snowball in flight: its snow's budget before it packs, at up to
/// 6.5 m/s.
const SNOWBALL_SUBSTEPS: u32 = 30;

/// Substeps a frame of the snowball scene once the snow has packed against the wall (30 in
/// flight). Packed snow's wave speed is `exp(xi (1 - J_p) / 2)` times the fresh snow's, and the
/// throw, not E, sets how stiff it packs: the packed stress, about `theta_c M`, times the
/// packing `1 - J_p` takes up the ball's `rho v^2 / 2`, so that a softer snow packs further.
/// The hardening `xi` and the throw's speed are the knobs here.
const SNOWBALL_PACKED_SUBSTEPS: u32 = 125;

/// A snowball of radius 0.1 m thrown at 6 m/s at the right wall: it flattens and packs harder
/// where it hits (its moduli harden as it compacts), and stays stuck to the wall. Stomakhin et
/// al.'s snow (nu = 0.2, 400 kg/m^3, critical compression 2.5 %, stretch 0.75 %) in their softer
/// variants: E = 47 kPa, the stiffest that [`SNOWBALL_SUBSTEPS`] substeps a frame carry in
/// flight (their lower E is 48 kPa), and hardening 5 (their lower: their reference snow, E =
/// 140 kPa and hardening 10, packs to twice the wave speed, 266 substeps a frame).
fn snowball_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let snow = world.add_material(&snow(&def))?;
    Ok(world
        .fill_disk(
            Vec3::new(0.3, 0.6, 0.0),
            0.1,
            snow,
            Vec3::new(6.0, 1.0, 0.0),
        )?
        .len())
}

/// A 1 m box of 40 cells whose left wall sticks (the cantilever's clamp); plasticity
/// declared.
fn metal_def() -> WorldDef {
    let mut def = beam_def();
    def.effects.plasticity = true;
    def
}

/// Substeps a frame of the metal scene: its metal's budget, at up to 2.5 m/s.
const METAL_SUBSTEPS: u32 = 64;

/// The metal's yield strain, yield stress over E: 2 %, far above a real metal's (a few tenths of
/// a percent at most), so that a beam the budget affords holds its own weight and bends for good
/// under a weight.
const METAL_YIELD_STRAIN: Real = 0.02;

/// A cantilever of a soft metal 0.3 m long and 0.1 m deep, and a weight dropped on its outer
/// half: the bending stress at the root (72 kPa from the beam's own weight, below the yield
/// stress; 60 kPa more from the weight's, more while it lands) passes the yield stress, and
/// the beam springs back only partly: it stays bent. The metal (von Mises, 2700 kg/m^3) is the
/// stiffest that [`METAL_SUBSTEPS`] substeps a frame carry, E = 4.1 MPa, with a yield stress of
/// [`METAL_YIELD_STRAIN`] times that (83 kPa) and a hardening modulus of a tenth of it; a
/// cantilever that holds its own weight below the yield stress needs
/// `E >= 3 rho g L^2 / (h eps_y)`, which sets the budget. The weight (3000 kg/m^3, von Mises
/// with a yield stress of 20 kPa) dents where it lands instead of bouncing off.
fn metal_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let wall = def.origin.x + def.shape.margin_cells() as Real * def.cell_size;
    let metal = world.add_material(&soft_metal(&def))?;
    let weight = world.add_material(&MaterialDef {
        model: MaterialModel::VonMises,
        youngs_modulus: 1.0e6,
        density: 3000.0,
        yield_stress: 2.0e4,
        ..MaterialDef::DEFAULT
    })?;
    let a = world.fill_box(
        Vec3::new(wall, 0.6, 0.0),
        Vec3::new(wall + 0.3, 0.7, 0.0),
        metal,
        Vec3::ZERO,
    )?;
    let b = world.fill_box(
        Vec3::new(wall + 0.15, 0.8, 0.0),
        Vec3::new(wall + 0.3, 0.9, 0.0),
        weight,
        Vec3::new(0.0, -2.0, 0.0),
    )?;
    Ok(a.len() + b.len())
}

/// The water scene's box, with room for one collider.
fn paddle_def() -> WorldDef {
    let mut def = water_def();
    def.effects.collider_capacity = 1;
    def
}

/// Water 0.45 m deep (as the water scene's, in two layers of two materials) and a paddle, a
/// box 0.5 m by 0.06 m centred 0.4 m above the floor, turning at 4 rad/s about its centre: a
/// kinematic collider that moves on its own (no call between frames), separating contact
/// with some friction.
fn paddle_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let (y0, wall) = (floor(&def), floor(&def));
    let water = water(&def);
    // The same water twice, the lower layer and the upper one, so that the picture shows
    // them mix.
    let (lower, upper) = (world.add_material(&water)?, world.add_material(&water)?);
    let centre = Vec3::new(0.5, y0 + 0.4, 0.0);
    world.add_collider(&ColliderDef {
        shape: ColliderShape::Box {
            half_extents: Vec3::new(0.25, 0.03, 0.5),
        },
        position: centre,
        angular_velocity: Vec3::new(0.0, 0.0, 4.0),
        contact: Contact::Separate,
        friction: 0.2,
        ..ColliderDef::DEFAULT
    })?;
    // The water around the paddle: the box cut where the paddle lies at rest.
    let (below, above) = (centre.y - 0.035, centre.y + 0.035);
    let mut n = 0;
    for (lo, hi, m) in [
        (y0, y0 + 0.2, lower),
        (y0 + 0.2, below, upper),
        (above, y0 + 0.45, upper),
    ] {
        n += world
            .fill_box(
                Vec3::new(wall, lo, 0.0),
                Vec3::new(1.0 - wall, hi, 0.0),
                m,
                Vec3::ZERO,
            )?
            .len();
    }
    for (lo, hi) in [(wall, centre.x - 0.26), (centre.x + 0.26, 1.0 - wall)] {
        n += world
            .fill_box(
                Vec3::new(lo, below, 0.0),
                Vec3::new(hi, above, 0.0),
                upper,
                Vec3::ZERO,
            )?
            .len();
    }
    Ok(n)
}

/// The sand scene's box (plasticity declared), with room for the drum.
fn drum_def() -> WorldDef {
    let mut def = sand_def();
    def.effects.collider_capacity = 1;
    def
}

/// A drum, the shell of a cylinder of radii 0.4 m and 0.45 m about the box's centre turned so
/// that its axis is the plane's normal, turning at 1.5 rad/s (a kinematic collider, sticking
/// with friction 0.6), and dry sand (as the sand scene's, its halves two materials) filling its
/// lower part: the sand is carried up the wall until its slope fails and it tumbles.
fn drum_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let sand = sand(&def);
    // The same sand twice, left and right, so that the picture shows it mix.
    let (left, right) = (world.add_material(&sand)?, world.add_material(&sand)?);
    let centre = Vec3::new(0.5, 0.5, 0.0);
    let half = core::f64::consts::FRAC_1_SQRT_2 as Real;
    world.add_collider(&ColliderDef {
        shape: ColliderShape::Cylinder {
            half_length: 1.0,
            radius: 0.46,
            inner_radius: 0.4,
        },
        position: centre,
        // A quarter turn about x: the cylinder's axis (its frame's y) along z.
        rotation: [half, 0.0, 0.0, half],
        angular_velocity: Vec3::new(0.0, 0.0, 1.5),
        contact: Contact::Separate,
        friction: 0.6,
        ..ColliderDef::DEFAULT
    })?;
    // The lower part of the drum's hole, less a margin from its wall: the sites of the fills'
    // lattice (`particles_per_cell` per cell and axis) below the centre.
    let spacing = def.cell_size as f64 / def.particles_per_cell as f64;
    let (r, c) = (0.38, [centre.x as f64, centre.y as f64]);
    let mut x = [Vec::new(), Vec::new(), Vec::new()];
    let steps = (r / spacing).ceil() as i64;
    for j in -steps..0 {
        for i in -steps..steps {
            let p = [(i as f64 + 0.5) * spacing, (j as f64 + 0.5) * spacing];
            if p[0] * p[0] + p[1] * p[1] < r * r {
                x[0].push((c[0] + p[0]) as Real);
                x[1].push((c[1] + p[1]) as Real);
            }
        }
    }
    let n = x[0].len();
    x[2] = vec![0.0; n];
    let zeros = vec![0.0 as Real; n];
    let volume = vec![(spacing * spacing) as Real; n];
    let mass: Vec<Real> = volume.iter().map(|v| 1600.0 * v).collect();
    world.add_particles(&mpm_gimp::ParticleBatch {
        position: [&x[0], &x[1], &x[2]],
        velocity: [&zeros, &zeros, &zeros],
        mass: &mass,
        volume: &volume,
        material: &x[0]
            .iter()
            .map(|&px| if px < centre.x { left } else { right })
            .collect::<Vec<u32>>(),
    })?;
    Ok(n)
}

/// The snowball's box (a stick floor, plasticity declared) with a slip right wall and room for
/// the plough.
fn plough_def() -> WorldDef {
    let mut def = snowball_def();
    def.faces[Face::XMax as usize] = Boundary::Slip;
    def.effects.collider_capacity = 1;
    def
}

/// A layer of the snowball's snow, 0.12 m deep, and a plough: a blade (a box 0.04 m by
/// 0.25 m, tilted back 20 degrees) moving right at 0.5 m/s (a kinematic collider, separating,
/// friction 0.2). The snow packs and heaps up in front of it.
fn plough_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let (y0, wall) = (floor(&def), floor(&def));
    let snow = snow(&def);
    // Two layers of the same snow, so that the picture shows how the bank folds them.
    let (lower, upper) = (world.add_material(&snow)?, world.add_material(&snow)?);
    let tilt: Real = -0.35 / 2.0;
    world.add_collider(&ColliderDef {
        shape: ColliderShape::Box {
            half_extents: Vec3::new(0.02, 0.125, 0.5),
        },
        position: Vec3::new(0.1, y0 + 0.13, 0.0),
        rotation: [0.0, 0.0, tilt.sin(), tilt.cos()],
        velocity: Vec3::new(0.5, 0.0, 0.0),
        contact: Contact::Separate,
        friction: 0.2,
        ..ColliderDef::DEFAULT
    })?;
    let mut n = 0;
    for (lo, hi, m) in [(y0, y0 + 0.06, lower), (y0 + 0.06, y0 + 0.12, upper)] {
        n += world
            .fill_box(
                Vec3::new(0.2, lo, 0.0),
                Vec3::new(1.0 - wall, hi, 0.0),
                m,
                Vec3::ZERO,
            )?
            .len();
    }
    Ok(n)
}

/// The metal scene's box (plasticity declared) with a stick floor and room for the punch.
fn punch_def() -> WorldDef {
    let mut def = metal_def();
    def.faces[Face::XMin as usize] = Boundary::Slip;
    def.faces[Face::YMin as usize] = Boundary::Stick;
    def.effects.collider_capacity = 1;
    def
}

/// A plate of the metal scene's soft metal, 0.15 m thick on the floor, and a punch: a capsule
/// 0.1 m wide pressing down at 0.1 m/s (a kinematic collider, stick): the metal yields under
/// it, flows aside and keeps the dent.
fn punch_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let (y0, wall) = (floor(&def), floor(&def));
    let metal = world.add_material(&soft_metal(&def))?;
    let top = y0 + 0.15;
    world.add_collider(&ColliderDef {
        shape: ColliderShape::Capsule {
            half_length: 0.05,
            radius: 0.05,
        },
        position: Vec3::new(0.5, top + 0.1, 0.0),
        velocity: Vec3::new(0.0, -0.1, 0.0),
        contact: Contact::Stick,
        ..ColliderDef::DEFAULT
    })?;
    Ok(world
        .fill_box(
            Vec3::new(wall, y0, 0.0),
            Vec3::new(1.0 - wall, top, 0.0),
            metal,
            Vec3::ZERO,
        )?
        .len())
}

/// Water 0.05 m deep across the box's floor, which the tap ([`tap`]) fills and its drain
/// empties. The stream lands at 4.7 m/s (2.5 m/s out of the nozzle, 0.8 m of fall): the
/// water is the stiffest that [`WATER_SUBSTEPS`] substeps carry at 5 m/s.
fn tap_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let (y0, wall) = (floor(&def), floor(&def));
    let water = world.add_material(&MaterialDef {
        bulk_modulus: modulus_for_substeps(&def, 1000.0, FRAME, WATER_SUBSTEPS, 5.0),
        ..water(&def)
    })?;
    let ids = world.fill_box(
        Vec3::new(wall, y0, 0.0),
        Vec3::new(1.0 - wall, y0 + 0.05, 0.0),
        water,
        Vec3::ZERO,
    )?;
    Ok(ids.len())
}

/// The tap scene's tap: a stream 2 cm wide (a cell) leaving a nozzle 0.8 m above the floor
/// at 2.5 m/s (50 litres a second per metre of thickness), and a drain in the floor's right
/// fifth, 5 cm deep. A falling stream stretches as it speeds up: leaving at 2.5 m/s it lands
/// at 4.7, its rows 1.9 times as far apart, still within a cell (from 1 m/s it would land
/// 4 times as far apart, two cells: a dotted line on the grid). The basin settles where the
/// drain takes what the tap gives (`cargo run --release --example tap`).
fn tap(def: &WorldDef) -> Tap {
    let (y0, wall) = (floor(def), floor(def));
    Tap {
        nozzle: Vec3::new(0.3, y0 + 0.8, 0.0),
        width: 0.02,
        speed: 2.5,
        material: 0,
        density: 1000.0,
        spacing: def.cell_size / def.particles_per_cell as Real,
        drain: (
            Vec3::new(0.8, y0, 0.0),
            Vec3::new(1.0 - wall, y0 + 0.05, 0.0),
        ),
    }
}

fn tap_host(world: &mut World, dt: Real) -> Result<(), Error> {
    tap(&world.def()).frame(world, dt).map(|_| ())
}

/// The water of the water and paddle scenes: weakly compressible, the stiffest that
/// [`WATER_SUBSTEPS`] substeps a frame carry at 2.5 m/s, with a little viscosity.
fn water(def: &WorldDef) -> MaterialDef {
    MaterialDef {
        model: MaterialModel::Fluid,
        bulk_modulus: modulus_for_substeps(def, 1000.0, FRAME, WATER_SUBSTEPS, 2.5),
        viscosity: 1.0,
        ..MaterialDef::DEFAULT
    }
}

/// The dry sand of the sand and drum scenes (see [`sand_fill`]).
fn sand(def: &WorldDef) -> MaterialDef {
    MaterialDef {
        model: MaterialModel::DruckerPrager,
        youngs_modulus: budget_modulus(def, 1600.0, 0.3, SAND_SUBSTEPS, 2.5),
        density: 1600.0,
        friction_angle: 30.0,
        ..MaterialDef::DEFAULT
    }
}

/// The snow of the snowball and plough scenes (see [`snowball_fill`]).
fn snow(def: &WorldDef) -> MaterialDef {
    MaterialDef {
        model: MaterialModel::Snow,
        youngs_modulus: budget_modulus(def, 400.0, 0.2, SNOWBALL_SUBSTEPS, 6.5),
        poisson_ratio: 0.2,
        density: 400.0,
        hardening_coefficient: 5.0,
        ..MaterialDef::DEFAULT
    }
}

/// The soft metal of the metal and punch scenes (see [`metal_fill`]).
fn soft_metal(def: &WorldDef) -> MaterialDef {
    let e = budget_modulus(def, 2700.0, 0.3, METAL_SUBSTEPS, 2.5);
    MaterialDef {
        model: MaterialModel::VonMises,
        youngs_modulus: e,
        poisson_ratio: 0.3,
        density: 2700.0,
        yield_stress: METAL_YIELD_STRAIN * e,
        hardening_modulus: 0.1 * e,
        ..MaterialDef::DEFAULT
    }
}
