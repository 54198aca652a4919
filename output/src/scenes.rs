//! The example scenes, defined once for the programs that run, draw or render them (the
//! kernel's `drop` example, the `pictures` example, the samples viewer).
//!
//! [`ALL`] is the registry: each [`Scene`] names its definition, its fill, its frame length,
//! its default colouring and duration. A new scene is one more entry there (and its two
//! functions); the viewer's menu, the `pictures` example and the registry's test
//! (`output/tests/scenes.rs`) pick it up from the list.

use crate::picture::Colour;
use mpm_gimp::{
    memory_requirements, Boundary, Dimension, Error, Face, HeapBuffer, MaterialDef, MaterialModel,
    Real, ScalarBoundary, ScalarField, Transfer, Transport, Vec3, World, WorldDef,
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
    /// Simulated time of one frame, s (one [`World::step`] call).
    pub frame_dt: Real,
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
}

/// Every example scene, in menu order.
pub const ALL: &[Scene] = &[
    Scene {
        name: "drop",
        title: "Rubber block dropped on a stick floor",
        def: || drop_def(false, false),
        fill: drop_fill,
        frame_dt: 1.0 / 60.0,
        frames: 60,
        // Speeds from rest to the fall's 2.2 m/s at the floor.
        colour: Colour::Speed,
        range: (0.0, 2.5),
        in_readme: true,
    },
    Scene {
        name: "drop3d",
        title: "The same block in 3D, seen along z",
        def: || drop_def(true, false),
        fill: drop_fill,
        frame_dt: 1.0 / 60.0,
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
        frame_dt: 1.0 / 60.0,
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
        frame_dt: 1.0 / 60.0,
        frames: 90,
        // Bending stress at the root: about +-70 kPa of pressure (3 rho g L^2 / h = 106 kPa
        // of axial stress at the fibres).
        colour: Colour::Pressure,
        range: (-6.0e4, 6.0e4),
        in_readme: false,
    },
    Scene {
        name: "heat",
        title: "Block warmed by a hot floor",
        def: heat_def,
        fill: heat_fill,
        frame_dt: 1.0 / 60.0,
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
        frame_dt: 1.0 / 60.0,
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
        frame_dt: 1.0 / 60.0,
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
        frame_dt: 1.0 / 60.0,
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
        frame_dt: 1.0 / 60.0,
        frames: 60,
        // The bending stress at the root passes the yield stress (1 MPa) and stays there.
        colour: Colour::Pressure,
        range: (-1.0e6, 1.0e6),
        in_readme: true,
    },
];

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

/// Fills a world made from [`drop_def`]: a soft rubber block (E = 200 kPa) at rest, 0.4 m by
/// 0.3 m (by 0.3 m) with its bottom 0.4 m above the floor. Returns how many particles it holds.
pub fn drop_fill(world: &mut World) -> Result<usize, Error> {
    let rubber = world.add_material(&rubber())?;
    let (lo, hi) = if world.def().dimension == Dimension::ThreeD {
        (Vec3::new(0.35, 0.4, 0.35), Vec3::new(0.65, 0.7, 0.65))
    } else {
        (Vec3::new(0.3, 0.4, 0.0), Vec3::new(0.7, 0.7, 0.0))
    };
    Ok(world.fill_box(lo, hi, rubber, Vec3::ZERO)?.len())
}

/// The soft rubber of the scenes: E = 200 kPa, neo-Hookean, 1000 kg/m^3.
fn rubber() -> MaterialDef {
    MaterialDef {
        youngs_modulus: 2.0e5,
        ..MaterialDef::DEFAULT
    }
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

/// Two rubber disks of radius 0.15 m (two materials, the right one twice as stiff), moving at
/// 1 m/s towards each other, their centres 0.1 m apart across the line of motion: they
/// collide off centre about 0.2 s in, bounce and spin.
fn collide_fill(world: &mut World) -> Result<usize, Error> {
    let soft = world.add_material(&rubber())?;
    let stiff = world.add_material(&MaterialDef {
        youngs_modulus: 4.0e5,
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

/// A 1 m box of 80 cells whose left wall sticks: the clamp of the cantilever.
fn beam_def() -> WorldDef {
    let mut def = WorldDef {
        cells: [80, 80, 1],
        cell_size: 1.0 / 80.0,
        ..WorldDef::DEFAULT
    };
    def.faces[Face::XMin as usize] = Boundary::Stick;
    def
}

/// A rubber beam (E = 1 MPa) 0.6 m long and 0.1 m deep, its left end against the stick wall,
/// starting straight and at rest: it falls and swings about its sagged shape (beam theory's
/// static deflection at the tip, `3 rho g L^4 / (2 E h^2)`, is 0.2 m; released from straight it
/// swings to about twice that).
fn beam_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    // The wall plane: one cell of margin in from the grid's face.
    let wall = def.origin.x + def.shape.margin_cells() as Real * def.cell_size;
    let rubber = world.add_material(&MaterialDef::DEFAULT)?;
    Ok(world
        .fill_box(
            Vec3::new(wall, 0.6, 0.0),
            Vec3::new(wall + 0.6, 0.7, 0.0),
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

/// A block (0.5 m by 0.4 m) resting on the hot floor at [`HEAT_COLD`]: it warms from below,
/// the front diffusing up through it within a few seconds (a thermal diffusivity of 0.02
/// m^2/s, far above any real solid's, to be seen), and it expands a little as it warms.
fn heat_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let floor = def.origin.y + def.shape.margin_cells() as Real * def.cell_size;
    let block = world.add_material(&MaterialDef {
        youngs_modulus: 1.0e6,
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

/// Water 0.35 m deep across the box (weakly compressible: K = 100 kPa, a sound speed of 10
/// m/s, with a little viscosity) and a wooden block (fixed-corotated, 600 kg/m^3, so it floats)
/// 0.2 m square dropped from 0.3 m above the surface.
fn water_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let (y0, wall) = (floor(&def), floor(&def));
    let water = world.add_material(&MaterialDef {
        model: MaterialModel::Fluid,
        bulk_modulus: 1.0e5,
        viscosity: 1.0,
        ..MaterialDef::DEFAULT
    })?;
    let wood = world.add_material(&MaterialDef {
        model: MaterialModel::FixedCorotated,
        youngs_modulus: 1.0e6,
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

/// A column of dry sand (Drucker-Prager, friction angle 30 degrees, 1600 kg/m^3), 0.2 m wide
/// and 0.4 m high against the left wall, released: it collapses and spreads into a pile whose
/// slope its friction holds.
fn sand_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let (y0, wall) = (floor(&def), floor(&def));
    let sand = world.add_material(&MaterialDef {
        model: MaterialModel::DruckerPrager,
        youngs_modulus: 1.0e6,
        density: 1600.0,
        friction_angle: 30.0,
        ..MaterialDef::DEFAULT
    })?;
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

/// A snowball of radius 0.1 m (Stomakhin et al.'s snow: E = 140 kPa, nu = 0.2, 400 kg/m^3,
/// critical compression 2.5 %, stretch 0.75 %, hardening 10) thrown at 6 m/s at the right
/// wall: it flattens and packs harder where it hits (its moduli harden as it compacts), and
/// stays stuck to the wall.
fn snowball_fill(world: &mut World) -> Result<usize, Error> {
    let snow = world.add_material(&MaterialDef {
        model: MaterialModel::Snow,
        youngs_modulus: 1.4e5,
        poisson_ratio: 0.2,
        density: 400.0,
        ..MaterialDef::DEFAULT
    })?;
    Ok(world
        .fill_disk(
            Vec3::new(0.3, 0.6, 0.0),
            0.1,
            snow,
            Vec3::new(6.0, 1.0, 0.0),
        )?
        .len())
}

/// A 1 m box of 80 cells whose left wall sticks (the cantilever's clamp); plasticity
/// declared.
fn metal_def() -> WorldDef {
    let mut def = beam_def();
    def.effects.plasticity = true;
    def
}

/// A cantilever of a soft metal (von Mises: E = 50 MPa, yield stress 1 MPa, hardening 5
/// MPa; scaled down from a real metal so that the scene steps fast) 0.6 m long and 0.05 m
/// deep, and a rubber weight dropped on its tip: the bending stress at the root (about 0.6
/// MPa from the beam's own weight, as much again from the weight's, more while it lands)
/// passes the yield stress, and the beam springs back only partly: it stays bent.
fn metal_fill(world: &mut World) -> Result<usize, Error> {
    let def = world.def();
    let wall = def.origin.x + def.shape.margin_cells() as Real * def.cell_size;
    let metal = world.add_material(&MaterialDef {
        model: MaterialModel::VonMises,
        youngs_modulus: 5.0e7,
        poisson_ratio: 0.3,
        density: 2700.0,
        yield_stress: 1.0e6,
        hardening_modulus: 5.0e6,
        ..MaterialDef::DEFAULT
    })?;
    let weight = world.add_material(&MaterialDef {
        youngs_modulus: 1.0e6,
        density: 3000.0,
        ..MaterialDef::DEFAULT
    })?;
    let a = world.fill_box(
        Vec3::new(wall, 0.6, 0.0),
        Vec3::new(wall + 0.6, 0.65, 0.0),
        metal,
        Vec3::ZERO,
    )?;
    let b = world.fill_box(
        Vec3::new(wall + 0.45, 0.75, 0.0),
        Vec3::new(wall + 0.6, 0.85, 0.0),
        weight,
        Vec3::new(0.0, -2.0, 0.0),
    )?;
    Ok(a.len() + b.len())
}
